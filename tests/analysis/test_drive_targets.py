"""Targets at roll, steer and travel positions (issue 20 items 5-6, issue 24: one implementation
of the drives): a target configuration holds the same drive joints as ``sweep --drive``, so the
value a met target reports is the value an ordinary sweep of the changed design reaches at that
drive position (walked there in steps from the design position, not the target solver's path)."""

from __future__ import annotations

import pytest
from analysis_helpers import EXAMPLES

from kinprop import load_model, sweep
from kinprop.analysis.targets import propagate_targets
from kinprop.errors import AddressError

pytestmark = pytest.mark.filterwarnings("ignore::kinprop.SingularityWarning")
AXLE = EXAMPLES / "hmmwv_front_axle.yaml"


def _swept(model, drive: str, output: str) -> float:
    """``output`` at the last step of a sweep of ``drive`` (``NAME=START:STOP:STEPS``)."""
    return float(sweep(model, [drive], outputs=[output], tol=1e-12).frame[output].iloc[-1])


def test_a_toe_target_at_a_roll_angle_is_the_value_a_roll_sweep_reaches():
    axle = load_model(AXLE)
    before = _swept(axle, "roll=0:2:5", "metric:upright_L.toe")
    tp = propagate_targets(axle, ["metric:upright_L.toe@roll=2deg=0.05"], ["TR_L.s_i[2]"])
    assert tp.targets_status == "met", tp.result.message
    assert tp.configuration_names == ("roll=2",)
    assert tp.table()[0]["before"] == pytest.approx(before, abs=1e-9)
    assert _swept(tp.after, "roll=0:2:5", "metric:upright_L.toe") == pytest.approx(0.05, abs=1e-9)
    assert abs(tp.design_change["TR_L.s_i"][2]) < 5.0  # a millimetre-sized move of the tie rod's inner point


def test_a_toe_target_at_a_steer_angle_is_the_value_a_steer_sweep_reaches():
    """The outer (right) wheel's toe with the inner (left) road wheel steered 5 deg: an
    Ackermann-style target by the right tie rod's outer point."""
    axle = load_model(AXLE)
    before = _swept(axle, "steer:upright_L=0:5:5", "metric:upright_R.toe")
    tp = propagate_targets(axle, ["metric:upright_R.toe@steer:upright_L=5deg=5.1"], ["TR_R.s_j[0]"])
    assert tp.targets_status == "met", tp.result.message
    assert tp.table()[0]["before"] == pytest.approx(before, abs=1e-9)
    assert _swept(tp.after, "steer:upright_L=0:5:5", "metric:upright_R.toe") == pytest.approx(5.1, abs=1e-9)


def test_roll_travel_and_static_targets_in_one_solve():
    """Configurations on two drive models (roll; travel) and the base one share the design."""
    axle = load_model(AXLE)
    targets = ["metric:upright_L.toe@roll=2=0.05", "metric:upright_L.toe=0",
               "metric:upright_L.camber@travel:upright_L=30=-1"]  # fmt: skip
    tp = propagate_targets(axle, targets, ["hardpoint:TR_L.i", "hardpoint:UBJ_L"])
    assert tp.targets_status == "met", tp.result.message
    assert set(tp.configuration_names) == {"roll=2", "base", "travel:upright_L=30"}
    after = tp.after
    assert _swept(after, "roll=0:2:5", "metric:upright_L.toe") == pytest.approx(0.05, abs=1e-9)
    assert _swept(after, "travel:upright_L=0:30:7", "metric:upright_L.camber") == pytest.approx(-1.0, abs=1e-9)
    assert _swept(after, "RACK=0:0:1", "metric:upright_L.toe") == pytest.approx(0.0, abs=1e-9)
    # the written model is the base mechanism's: no drive joint
    assert not {"roll", "upright_L_travel"} & set(after.mechanism.joint_names)


def test_a_roll_slope_target_and_bad_drive_conditions():
    axle = load_model(AXLE)
    tp = propagate_targets(axle, ["slope:metric:upright_L.toe@roll=-2..2deg=0.05"], ["TR_L.s_i[2]"])
    assert tp.targets_status == "met", tp.result.message
    assert tp.unit(tp.specs[0]) == "deg/deg"
    lo, hi = (_swept(tp.after, f"roll=0:{r}:5", "metric:upright_L.toe") for r in (-2, 2))
    assert (hi - lo) / 4.0 == pytest.approx(0.05, abs=1e-9)
    assert tp.table()[0]["achieved"] == pytest.approx(0.05, abs=1e-9)
    with pytest.raises(AddressError, match="roll and a travel"):
        propagate_targets(axle, ["metric:upright_L.toe@roll=2&travel:upright_L=10=0"], ["TR_L.s_i[2]"])
    with pytest.raises(AddressError, match="no wheel body"):
        propagate_targets(axle, ["metric:upright_L.toe@steer:nope=2=0"], ["TR_L.s_i[2]"])
    with pytest.raises(AddressError, match="not an angle unit"):
        propagate_targets(axle, ["metric:upright_L.toe@roll=2mm=0"], ["TR_L.s_i[2]"])
