"""`kinprop propagate --target`, `--set hardpoint:`, and bodies/joint_values in the JSON."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from kinprop import load_model
from kinprop.analysis.points import joint_hardpoints
from kinprop.cli import app

runner = CliRunner()


def run(*args: str):
    return runner.invoke(app, [str(a) for a in args])


def test_targets_met_from_the_cli_with_achieved_values(examples, tmp_path):
    out = tmp_path / "after.yaml"
    r = run("propagate", examples / "double_wishbone.yaml",
            "--target", "metric:camber@travel=50mm=-1.5deg", "--target", "slope:toe@travel=-50..50=0deg/m",
            "--free", "hardpoint:UBJ", "--free", "hardpoint:TR.i", "--json", "-o", out,
            "--csv", tmp_path / "after.csv")  # fmt: skip
    assert r.exit_code == 0, r.output
    obj = json.loads(r.stdout)
    assert obj["targets_status"] == "met"
    (camber, slope) = obj["targets"]
    assert camber["achieved"] == pytest.approx(-1.5, abs=1e-9) and camber["before"] == pytest.approx(-1.4405, abs=1e-4)
    assert slope["achieved"] == pytest.approx(0.0, abs=1e-12)
    assert set(obj["design_change"]) == {"UBJ.s_i", "UBJ.s_j", "TR.s_i"}
    assert set(obj["hardpoint_moves"]) == {"UBJ.i", "UBJ.j", "TR.i"}
    assert obj["configurations"] == ["travel:upright=50", "travel:upright=-50"]
    assert [t["unit"] for t in obj["targets"]] == ["deg", "deg/mm"]
    assert set(obj["bodies"]) == {"chassis", "lca", "uca", "upright"}
    assert set(obj["joint_values"]) == {"LCA", "LBJ", "UCA", "UBJ", "TR"}
    # the written model carries the new design: its tie-rod inner point moved as reported
    moved = np.array(joint_hardpoints(load_model(out))["TR.i"]) - np.array(
        joint_hardpoints(load_model(examples / "double_wishbone.yaml"))["TR.i"]
    )
    np.testing.assert_allclose(moved, obj["hardpoint_moves"]["TR.i"], atol=1e-6)
    rows = {line.split(",")[0]: line.split(",") for line in (tmp_path / "after.csv").read_text().splitlines()}
    assert float(rows["TR.s_i[2]"][4]) == pytest.approx(moved[2], abs=1e-9)  # chassis frame = global


def test_conflicting_targets_exit_1_and_name_the_conflict(examples):
    r = run("propagate", examples / "double_wishbone.yaml", "--target", "camber@travel=50=-1.5",
            "--target", "camber@travel=50=-1", "--free", "hardpoint:UBJ", "--json")  # fmt: skip
    assert r.exit_code == 1, r.output
    obj = json.loads(r.stdout)
    # the solve converged (to the compromise): status is a kinprop.Status, met/compromise beside it
    assert (obj["status"], obj["targets_status"]) == ("converged", "compromise")
    assert [t["miss"] for t in obj["targets"]] == pytest.approx([0.25, -0.25], abs=1e-9)
    assert {c["target"] for c in obj["conflicts"][0]} == {"camber@travel=50=-1.5", "camber@travel=50=-1"}


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--target", "camber@travel=50=-1.5"], "--target needs --free"),
        (["--target", "camber@travel=50=-1.5", "--free", "hardpoint:NOPE"], "unknown joint 'NOPE'"),
        (["--target", "camber@travel=50=-1.5kg", "--free", "hardpoint:UBJ"], "unit 'kg'"),
        (["--target", "wobble=1", "--free", "hardpoint:UBJ"], "unknown metric 'wobble'"),
    ],
)
def test_bad_target_input_is_one_located_line_and_exit_2(examples, args, message):
    r = run("propagate", examples / "double_wishbone.yaml", *args)
    assert r.exit_code == 2, r.output
    assert message in r.stderr and "Traceback" not in r.output
    assert len(r.stderr.strip().splitlines()) == 1 or message in r.stderr.replace("\n", "")


def test_set_global_hardpoint_and_poses_in_json(examples):
    m = load_model(examples / "double_wishbone.yaml")
    p = np.array(joint_hardpoints(m)["UBJ.i"]) + [0.0, 0.0, 10.0]
    r = run("propagate", examples / "double_wishbone.yaml", "--set", f"hardpoint:UBJ={p[0]},{p[1]},{p[2]}", "--json")
    assert r.exit_code == 0, r.output
    obj = json.loads(r.stdout)
    np.testing.assert_allclose(obj["hardpoints"]["UBJ.i"], p, atol=1e-7)
    np.testing.assert_allclose(obj["hardpoints"]["UBJ.j"], p, atol=1e-7)
    R = np.array(obj["bodies"]["upright"]["R"])
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
    # body pose and hardpoint agree: the upright's origin is the lower ball joint
    np.testing.assert_allclose(obj["bodies"]["upright"]["t"], obj["hardpoints"]["LBJ.j"], atol=1e-9)
    assert obj["joint_values"]["LCA"]["angle"] == pytest.approx(obj["coordinates"]["LCA"][0], abs=1e-12)
    assert obj["joint_values"]["TR"]["distance"] == pytest.approx(obj["design"]["TR.length"], abs=1e-7)


def test_an_unreachable_target_ends_as_a_compromise_near_the_design(examples):
    """A motion ratio of 5 by one element-point coordinate (the ratio peaks at 0.56): exit 1,
    ``compromise``, the point moved by a few hundred mm (it ran to 1.3e36 mm before the outer
    step had a trust region; tests/engine/test_unreachable_targets.py checks the peak)."""
    r = run("propagate", examples / "double_wishbone.yaml", "--target", "motion_ratio:spring=5",
            "--free", "element:spring.point_j[y]", "--json")  # fmt: skip
    assert r.exit_code == 1, r.output
    obj = json.loads(r.stdout)
    assert obj["targets_status"] == "compromise", obj["targets_message"]
    (dy,) = obj["design_change"]["element:spring.point_j[y]"]
    assert 10.0 < abs(dy) < 1000.0
    assert obj["targets"][0]["achieved"] == pytest.approx(0.5614, abs=1e-4)
