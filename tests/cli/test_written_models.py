"""Models written by ``-o`` continue where they stopped (issue 19 items 0 and 8).

Truth: one direct solve from the original file. A mechanism stepped through ``propagate -o``
files must reach the same pose (every named point, every joint frame) and report the same
input coordinates as propagating the original straight to the last value, in either style.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from kinprop.cli import app

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
runner = CliRunner()


def run(*args: object):
    r = runner.invoke(app, [str(a) for a in args])
    assert r.exit_code == 0, r.output
    return r


def solve(model: Path, *args: object) -> dict:
    return json.loads(run("propagate", model, *args, "--json").stdout)


def stepped(tmp_path: Path, model: Path, joint: str, values: list[float]) -> dict:
    """Propagate ``joint`` through ``values``, each step from the previous step's ``-o`` file."""
    src = model
    for k, v in enumerate(values[:-1]):
        out = tmp_path / f"step{k}{model.suffix}"
        run("propagate", src, "--set", f"{joint}.q={v}", "-o", out)
        src = out
    return solve(src, "--set", f"{joint}.q={values[-1]}")


def assert_same_pose(a: dict, b: dict, tol: float) -> None:
    assert a["points"].keys() == b["points"].keys()
    for k in a["points"]:
        np.testing.assert_allclose(a["points"][k], b["points"][k], atol=tol, err_msg=k)
    for k in a["hardpoints"]:
        np.testing.assert_allclose(a["hardpoints"][k], b["hardpoints"][k], atol=tol, err_msg=k)


@pytest.fixture(scope="module")
def fourbar_hardpoints(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("fb") / "fourbar_hp.yaml"
    asm = out.with_name("asm.yaml")
    run("assemble", EXAMPLES / "fourbar.yaml", "-o", asm)
    run("convert", asm, "--to", "hardpoints", "-o", out)
    return out


def test_hardpoint_double_wishbone_through_files(tmp_path):
    """The issue's reproduction: LCA = 5 then 6 from the file gave z = 73.976 mm (LCA = 11)."""
    model = EXAMPLES / "double_wishbone_hardpoints.yaml"
    direct = solve(model, "--set", "LCA.q=6")
    assert direct["points"]["upright.wheel_centre"][2] == pytest.approx(27.613, abs=5e-4)
    chain = stepped(tmp_path, model, "LCA", [2, 5, 6])
    assert chain["coordinates"]["LCA"] == pytest.approx([6.0], abs=1e-9)
    assert_same_pose(chain, direct, 1e-8)
    again = json.loads(run("assemble", tmp_path / "step1.yaml", "--json").stdout)
    assert again["coordinates"]["LCA"] == pytest.approx([5.0], abs=1e-9)


@pytest.mark.parametrize("style", ["frames", "hardpoints"])
def test_crank_rocker_through_files(tmp_path, style, fourbar_hardpoints):
    """Two ``-o`` steps put the crank 165 deg off in hardpoint style; both styles must agree
    with the direct solve, pose and crank angle."""
    model = EXAMPLES / "fourbar.yaml" if style == "frames" else fourbar_hardpoints
    direct = solve(model, "--set", "O2.q=150")
    chain = stepped(tmp_path, model, "O2", [90, 120, 150])
    assert chain["coordinates"]["O2"] == pytest.approx([150.0], abs=1e-9)
    assert_same_pose(chain, direct, 1e-10)
    # the crank pin at 150 deg, from the crank length 0.15 m (closed form)
    pin = direct["hardpoints"]["A.i"]
    np.testing.assert_allclose(pin[:2], [0.15 * np.cos(np.radians(150)), 0.15 * np.sin(np.radians(150))], atol=1e-12)


def test_design_change_then_drive_through_files(tmp_path):
    """A hardpoint moved with the coordinates free, written, then driven: the same as doing
    both in one model (the inputs' zero survives a re-assembled write)."""
    model = EXAMPLES / "double_wishbone_hardpoints.yaml"
    moved = tmp_path / "moved.yaml"
    run("propagate", model, "--set", "UBJ.s_i[2]=5", "--free", "q", "-o", moved)
    data = yaml.safe_load(moved.read_text())
    assert data["style"] == "hardpoints"
    chain = solve(moved, "--set", "LCA.q=4")
    direct = solve(model, "--set", "UBJ.s_i[2]=5", "--set", "LCA.q=4")
    assert chain["coordinates"]["LCA"] == pytest.approx([4.0], abs=1e-9)
    assert_same_pose(chain, direct, 1e-8)
