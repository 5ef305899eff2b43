"""What ``propagate --target`` reports (issue 19 item 4).

Checked: no literal rich markup; a failed run's top-level JSON status is not "converged"
and an unreachable configuration's achieved values are NaN (null), not the start's; the
moved hardpoints are listed once per joint, at the design position, and only those whose
attachment changed. Truth for the positions: the design-position model's own hardpoints
(the ``hardpoints`` of the same JSON, before = the input model's) and, for a point on the
fixed chassis, the design change itself.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from kinprop.cli import app

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
runner = CliRunner()
DW = EXAMPLES / "double_wishbone.yaml"
TARGETS = ["--target", "camber@travel=0mm=0deg", "--target", "camber@travel=50mm=-2deg", "--target",
           "toe@travel=0mm=0deg", "--free", "hardpoint:UBJ", "--free", "hardpoint:TR.i"]  # fmt: skip


def run(*args: object):
    return runner.invoke(app, [str(a) for a in args])


@pytest.fixture(scope="module")
def met():
    r = run("propagate", DW, *TARGETS, "--json")
    assert r.exit_code == 0, r.output
    return json.loads(r.stdout)


def test_text_report_has_no_markup_and_each_joint_once():
    r = run("propagate", DW, *TARGETS)
    assert r.exit_code == 0, r.output
    assert "[green]" not in r.stdout and "[red]" not in r.stdout
    assert "targets met" in r.stdout
    lines = [ln.strip() for ln in r.stdout.splitlines() if "(moved " in ln]
    assert [ln.split(":")[0] for ln in lines] == ["UBJ", "TR.i"]


def test_moves_are_at_the_design_position(met):
    moves = met["design_position_moves"]
    assert set(moves) == {"UBJ", "TR.i"}  # not UBJ.i and UBJ.j; not the carried TR.j, LBJ...
    before = json.loads(run("assemble", DW, "--json").stdout)["hardpoints"]
    for name, hp in (("UBJ", "UBJ.i"), ("TR.i", "TR.i")):
        np.testing.assert_allclose(moves[name]["before"], before[hp], atol=1e-9)
        np.testing.assert_allclose(moves[name]["after"], met["hardpoints"][hp], atol=1e-9)
    # TR.i is on the fixed chassis (identity orientation): it moves by the design change
    d = np.subtract(moves["TR.i"]["after"], moves["TR.i"]["before"])
    np.testing.assert_allclose(d, met["design_change"]["TR.s_i"], atol=1e-9)
    np.testing.assert_allclose(d, met["hardpoint_moves"]["TR.i"], atol=1e-9)


def test_unreachable_configuration_reports_nan_and_no_converged_status():
    r = run("propagate", DW, "--target", "camber@travel=0mm=0deg", "--target", "camber@travel=900mm=-2deg",
            "--free", "hardpoint:UBJ", "--json")  # fmt: skip
    assert r.exit_code == 1, r.output
    obj = json.loads(r.stdout)
    assert obj["targets_status"] == "not_converged" and obj["status"] != "converged"
    assert all(t["achieved"] is None and t["miss"] is None for t in obj["targets"])
    assert obj["targets"][0]["before"] == pytest.approx(0.0, abs=1e-6)  # travel 0 was reached
