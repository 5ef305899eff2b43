"""Wheel travel as the drive and outputs at a drive position (issue 20, items 5-6): uniform
travel steps by one more constraint row, against the independent double-wishbone solver and
central differences of two travel solves."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
import yaml
from analysis_helpers import EXAMPLES
from dw_oracle import HMMWV, solve
from scipy.optimize import brentq

from kinprop import load_model, sweep
from kinprop.analysis.drives import outputs_at
from kinprop.analysis.targets import propagate_targets
from kinprop.errors import AddressError
from kinprop.io import model_from_data
from kinprop.io.commands import sensitivities

pytestmark = pytest.mark.filterwarnings("ignore::kinprop.SingularityWarning")
FILE = EXAMPLES / "double_wishbone_hardpoints.yaml"


def test_uniform_travel_steps_against_the_independent_solver():
    model = load_model(FILE)
    got = sweep(model, ["travel=-40:40:4"], outputs=["wheel_centre_dz", "camber", "toe", "caster"]).frame
    travels = np.linspace(-40.0, 40.0, 5)
    np.testing.assert_array_equal(got["travel"], travels)  # equal millimetre steps, the drive's own column
    np.testing.assert_allclose(got["wheel_centre_dz"], travels, atol=1e-8)
    assert "upright_travel.q" not in got.columns  # the drive joint is the travel column
    for k, theta in enumerate(got["LCA.q"]):  # degrees (the model's angle unit)
        truth = solve(HMMWV, float(theta))
        assert truth["wheel_centre_dz"] == pytest.approx(travels[k], abs=1e-7)
        for name in ("camber", "toe", "caster"):
            assert got[name][k] == pytest.approx(truth[name], abs=1e-7), (name, travels[k])


def test_slope_over_travel_is_the_difference_of_two_travel_solves():
    model = load_model(FILE)
    v = outputs_at(model, ["slope:toe@travel=-30..30", "toe@travel=-30", "toe@travel=30", "camber@travel=30mm"])
    assert v["slope:toe@travel=-30..30"] == pytest.approx((v["toe@travel=30"] - v["toe@travel=-30"]) / 60, abs=1e-12)
    lo, hi = (solve(HMMWV, _theta(model, t)) for t in (-30.0, 30.0))
    assert v["slope:toe@travel=-30..30"] == pytest.approx((hi["toe"] - lo["toe"]) / 60, abs=1e-9)
    assert v["camber@travel=30mm"] == pytest.approx(hi["camber"], abs=1e-7)


def _theta(model, travel: float) -> float:
    return outputs_at(model, [f"LCA.q@travel={travel}"])[f"LCA.q@travel={travel}"]


def test_plain_names_pass_through_and_bad_names_are_refused():
    model = load_model(FILE)
    v = outputs_at(model, ["kpi", "camber@travel=0"])
    assert v["kpi"] == pytest.approx(math.degrees(math.atan2(70.993, 333.6036)), abs=1e-9)
    assert v["camber@travel=0"] == pytest.approx(0.0, abs=1e-9)
    with pytest.raises(AddressError, match="no =VALUE"):
        outputs_at(model, ["camber=2@travel=3"])
    with pytest.raises(AddressError, match="expected travel, travel:WHEEL, roll"):
        outputs_at(model, ["camber@bogus=3"])
    with pytest.raises(AddressError, match="one condition range"):
        outputs_at(model, ["slope:camber@travel=3"])
    with pytest.raises(AddressError, match="axle of two wheels"):
        outputs_at(model, ["camber@roll=1"])


def _at_travel(hp, travel: float, name: str) -> float:
    theta = brentq(lambda t: solve(hp, t)["wheel_centre_dz"] - travel, -8.0, 8.0, xtol=1e-14)
    return solve(hp, theta)[name]


def test_sensitivity_at_a_travel_and_of_bump_steer_against_the_oracle_differenced():
    """d(camber at 30 mm) and d(bump steer over -30..30 mm) by a hardpoint, the travel held:
    central differences of the independent solver with the hardpoint moved (design position
    kept: the tie rod's length from its points)."""
    model = load_model(FILE)
    of = ["camber@travel=30", "slope:toe@travel=-30..30", "kpi"]
    sens = sensitivities(model, ["hardpoint:UBJ[y]", "hardpoint:TR.i[z]"], of, ("q",), None)
    assert sens.rows == of
    assert sens.units_of == ["deg", "deg/mm", "deg"]
    h = 1e-3
    for col, (key, axis) in enumerate((("UBJ", 1), ("TR_I", 2))):
        ends = []
        for sign in (1, -1):
            hp = {k: v.copy() for k, v in HMMWV.items()}
            hp[key][axis] += sign * h
            bump = (_at_travel(hp, 30.0, "toe") - _at_travel(hp, -30.0, "toe")) / 60.0
            ends.append(np.array([_at_travel(hp, 30.0, "camber"), bump]))
        truth = (ends[0] - ends[1]) / (2 * h)
        np.testing.assert_allclose(sens.matrix[:2, col], truth, rtol=1e-5, atol=1e-9)
    assert sens.matrix[2, 1] == 0.0  # the tie rod does not move the steering axis


def test_the_tie_rod_height_that_zeroes_bump_steer_is_the_oracles_root():
    """docs/analysis/suspension.md's worked example: the target solver's tie-rod inner height
    for zero bump steer over +-50 mm (static toe kept) is the root of the independent solver's
    bump steer in that height (scipy brentq)."""
    model = load_model(FILE)
    res = propagate_targets(
        model, ["slope:toe@travel=-50..50mm=0deg/m", "toe@travel=0=0"], ["TR.s_i[2]", "TR.length"], tol=1e-10
    )
    assert res.converged
    z = float(res.after.design["TR.s_i"][2])

    def bump(height: float) -> float:
        hp = {k: v.copy() for k, v in HMMWV.items()}
        hp["TR_I"][2] = height
        return (_at_travel(hp, 50.0, "toe") - _at_travel(hp, -50.0, "toe")) / 100.0

    truth = brentq(bump, 50.0, 70.0, xtol=1e-12)
    assert z == pytest.approx(truth, abs=1e-6)
    assert z == pytest.approx(59.7907, abs=1e-4)  # the number the guide prints
    assert outputs_at(res.after, ["slope:toe@travel=-50..50"])["slope:toe@travel=-50..50"] == pytest.approx(0, abs=1e-9)


def test_an_undriven_drive_joint_follows_the_wheel():
    """A rack position in the same call as a travel position: the travel joint, not driven
    there, follows the wheel (the rack steers with the arms held, as alone)."""
    axle = load_model(EXAMPLES / "hmmwv_front_axle.yaml")
    alone = outputs_at(axle, ["metric:upright_L.toe@RACK.q=10", "metric:upright_L.wheel_centre_dz@RACK.q=10"])
    mixed = outputs_at(axle, [*alone, "metric:upright_L.toe@travel:upright_L=30"])
    for k, v in alone.items():
        assert mixed[k] == pytest.approx(v, abs=1e-10)
    assert alone["metric:upright_L.wheel_centre_dz@RACK.q=10"] != 0.0  # steering moves the wheel centre: held arms


def test_sensitivity_of_gains_at_a_travel_against_re_solved_files():
    """d(camber gain at +50 mm), d(caster gain at +50 mm) and d(bump steer at -30 mm) by two
    hardpoints (the tangent with the travel held, the gains' exact design derivatives there)
    against central differences (Richardson) of the file re-loaded with the hardpoint moved and
    its gains evaluated at that travel."""
    data = yaml.safe_load(FILE.read_text())
    model = load_model(FILE)
    of = ["camber_gain@travel=50", "caster_gain@travel=50", "bump_steer@travel=-30"]
    wrt = [("UBJ", "point", 2), ("TR", "point_i", 2)]
    sens = sensitivities(model, [f"hardpoint:{'TR.i' if j == 'TR' else j}[z]" for j, _, _ in wrt], of, ("q",), None)
    assert sens.units_of == ["deg/mm", "deg/mm", "deg/mm"]

    def gains(joint: str, key: str, k: int, dp: float) -> np.ndarray:
        d = copy.deepcopy(data)
        d["joints"][joint][key][k] += dp
        v = outputs_at(model_from_data(d, str(FILE)), of, tol=1e-13)
        return np.array([v[o] for o in of])

    h = 0.5
    for col, (joint, key, k) in enumerate(wrt):
        d1 = (gains(joint, key, k, h) - gains(joint, key, k, -h)) / (2 * h)
        d2 = (gains(joint, key, k, h / 2) - gains(joint, key, k, -h / 2)) / h
        truth = (4 * d2 - d1) / 3
        np.testing.assert_allclose(sens.matrix[:, col], truth, rtol=1e-6, atol=1e-12)
        assert np.abs(truth).min() > 1e-6  # each gain does change
