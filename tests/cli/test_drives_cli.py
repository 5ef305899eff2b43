"""Wheel travel and body roll as the drive of `sweep`, outputs at a drive position in `sweep
--out`, `study --out` and `sensitivity --of` (issue 20, items 5-6): against the independent
double-wishbone solver (tests/analysis/dw_oracle.py)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.optimize import brentq
from typer.testing import CliRunner

from kinprop.cli import app

sys.path.insert(0, str(Path(__file__).parents[1] / "analysis"))
from dw_oracle import HMMWV, solve

pytestmark = pytest.mark.filterwarnings("ignore::kinprop.SingularityWarning")
EXAMPLES = Path(__file__).parents[2] / "examples"
CORNER = EXAMPLES / "double_wishbone_hardpoints.yaml"
AXLE = EXAMPLES / "hmmwv_front_axle.yaml"
runner = CliRunner()


def run(*args: object):
    return runner.invoke(app, [str(a) for a in args])


def _at_travel(hp, travel: float, name: str) -> float:
    theta = brentq(lambda t: solve(hp, t)["wheel_centre_dz"] - travel, -8.0, 8.0, xtol=1e-14)
    return solve(hp, theta)[name]


def test_sweep_by_wheel_travel_in_equal_millimetre_steps(tmp_path):
    out = tmp_path / "travel.csv"
    r = run("sweep", CORNER, "--drive", "travel=-40:40:8", "--out", "camber", "--out", "toe",
            "--out", "toe@travel=20", "-o", out, "-q")  # fmt: skip
    assert r.exit_code == 0, r.output
    f = pd.read_csv(out)
    assert list(f.columns[:2]) == ["step", "travel [mm]"]
    np.testing.assert_array_equal(f["travel [mm]"], np.linspace(-40, 40, 9))
    for travel, camber, toe in zip(f["travel [mm]"], f["camber [deg]"], f["toe [deg]"],
                                   strict=True):  # fmt: skip
        assert camber == pytest.approx(_at_travel(HMMWV, travel, "camber"), abs=1e-7)
        assert toe == pytest.approx(_at_travel(HMMWV, travel, "toe"), abs=1e-7)
    np.testing.assert_allclose(f["toe@travel=20 [deg]"], _at_travel(HMMWV, 20.0, "toe"), atol=1e-7)


def test_first_order_metrics_in_a_travel_sweep_move_the_suspension_by_its_own_input():
    """camber_gain along a travel sweep (the velocity analysis drives the lower arm, not the
    held travel joint) against the oracle's camber differenced centrally in travel."""
    r = run("sweep", CORNER, "--drive", "travel=-40:40:2", "--out", "camber_gain", "--json")
    assert r.exit_code == 0, r.output
    h = 1e-3
    for row in json.loads(r.stdout)["rows"]:
        t = row["travel"]
        truth = (_at_travel(HMMWV, t + h, "camber") - _at_travel(HMMWV, t - h, "camber")) / (2 * h)
        assert row["camber_gain"] == pytest.approx(truth, abs=1e-7), t


def test_sweep_by_body_roll_moves_the_wheels_oppositely():
    r = run("sweep", AXLE, "--drive", "roll=-2:2:2", "--out", "metric:upright_L.wheel_centre_dz",
            "--out", "metric:upright_R.wheel_centre_dz", "--json")  # fmt: skip
    assert r.exit_code == 0, r.output
    rows = json.loads(r.stdout)["rows"]
    assert [row["roll"] for row in rows] == [-2.0, 0.0, 2.0]
    left = [row["metric:upright_L.wheel_centre_dz"] for row in rows]
    right = [row["metric:upright_R.wheel_centre_dz"] for row in rows]
    assert left[0] > 0 > left[2] and right[2] > 0 > right[0]  # rolled right (+): the left wheel droops
    assert left[0] == pytest.approx(right[2], abs=1e-9) and left[1] == pytest.approx(0.0, abs=1e-9)


def test_a_travel_and_the_rack_drive_together():
    """One wheel's travel with the rack: toe at each step against the rack alone at that
    travel (outputs at a drive position, the same engine)."""
    r = run("sweep", AXLE, "--drive", "travel:upright_L=-10:10:2", "--drive", "RACK=-5:5:2",
            "--out", "metric:upright_L.toe", "--json")  # fmt: skip
    assert r.exit_code == 0, r.output
    rows = json.loads(r.stdout)["rows"]
    assert [(x["travel:upright_L"], x["RACK.q"]) for x in rows] == [(-10.0, -5.0), (0.0, 0.0), (10.0, 5.0)]
    from kinprop import load_model
    from kinprop.analysis.drives import outputs_at

    axle = load_model(AXLE)
    for x in rows:
        name = f"metric:upright_L.toe@travel:upright_L={x['travel:upright_L']}&RACK.q={x['RACK.q']}"
        assert x["metric:upright_L.toe"] == pytest.approx(outputs_at(axle, [name])[name], abs=1e-9)


def test_study_outputs_at_a_travel_and_bump_steer_against_the_oracle(tmp_path):
    out = tmp_path / "study"
    r = run("study", CORNER, "--vary", "hardpoint:TR.i[z]=44:64", "--method", "grid", "--samples", "3",
            "--out", "slope:toe@travel=-30..30", "--out", "camber@travel=30", "-o", out)  # fmt: skip
    assert r.exit_code == 0, r.output
    f = pd.read_parquet(out).sort_values("variant")
    for z, bump, camber in zip(f["hardpoint:TR.i[z]"], f["slope:toe@travel=-30..30"], f["camber@travel=30"],
                               strict=True):  # fmt: skip
        hp = {k: v.copy() for k, v in HMMWV.items()}
        hp["TR_I"][2] = z  # the design position kept: the tie rod's length from its points
        truth = (_at_travel(hp, 30.0, "toe") - _at_travel(hp, -30.0, "toe")) / 60.0
        assert bump == pytest.approx(truth, abs=1e-9)
        assert camber == pytest.approx(_at_travel(hp, 30.0, "camber"), abs=1e-7)


def test_bad_drives_and_driven_outputs_exit_2():
    for args in (
        ("sweep", CORNER, "--drive", "roll=-1:1:2"),
        ("sweep", CORNER, "--drive", "travel:nowheel=-1:1:2"),
        ("sweep", CORNER, "--drive", "travel=-1:1:2", "--drive", "LCA=-1:1:2"),
        ("sweep", CORNER, "--drive", "travel=a:1:2"),
        ("sweep", CORNER, "--drive", "LCA=-1:1:2", "--out", "toe@travel=1..2"),
        ("sensitivity", CORNER, "--wrt", "hardpoint:UBJ[y]", "--of", "toe@bogus=3"),
        ("study", CORNER, "--vary", "TR.s_i[2]=50:60", "--samples", "2", "--out", "slope:toe@travel=5", "-o", "x"),
    ):
        r = run(*args)
        assert r.exit_code == 2, (args, r.output)
        assert "Traceback" not in r.output
