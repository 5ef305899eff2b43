"""Axles (issue 20, item 4): a corner mirrored into an axle with a rack; left and right equal
with mirrored signs, the axle roll centre, roll steer against two travel solves of the
independent solver, Ackermann of a planar trapezoid against its closed form."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml
from analysis_helpers import EXAMPLES
from dw_oracle import HMMWV, solve
from scipy.optimize import brentq

from kinprop import propagate
from kinprop.analysis.axle import ackermann, roll_centre, roll_gradients, steering_ratio, track_change
from kinprop.analysis.drives import outputs_at
from kinprop.analysis.metrics import suspension_metrics
from kinprop.analysis.outputs import evaluate_outputs
from kinprop.errors import AddressError
from kinprop.io import model_from_data
from kinprop.io.axle import mirror_corner

pytestmark = pytest.mark.filterwarnings("ignore::kinprop.SingularityWarning")


@pytest.fixture(scope="module")
def axle():
    data = yaml.safe_load((EXAMPLES / "double_wishbone_hardpoints.yaml").read_text())
    return model_from_data(mirror_corner(data, tie_rods=("TR",)), "axle.yaml")


def test_mirrored_wheels_are_equal_with_mirrored_signs(axle):
    assert axle.mechanism.inputs == ("LCA_L", "LCA_R", "RACK")
    after = propagate(axle, {"LCA_L.q": 4.0, "LCA_R.q": -4.0}, ["q"], tol=1e-9).after
    left, right = suspension_metrics(after, "upright_L"), suspension_metrics(after, "upright_R")
    for name, value in left.items():
        mirrored = -right[name] if name == "wheel_centre_dy" else right[name]
        assert value == pytest.approx(mirrored, abs=1e-9), name
    assert left["wheel_centre_dz"] == pytest.approx(solve(HMMWV, 4.0)["wheel_centre_dz"], abs=1e-7)
    assert left["camber"] == pytest.approx(solve(HMMWV, 4.0)["camber"], abs=1e-7)


def test_axle_roll_centre_at_design_is_the_corners(axle):
    rc = roll_centre(axle, "upright_L", "upright_R", {"upright_L": "LCA_L", "upright_R": "LCA_R"})
    corner = evaluate_outputs(axle, ["metric:upright_L.roll_centre_height"], units="solver")
    assert rc["y"] == pytest.approx(0.0, abs=1e-6)
    assert rc["height"] == pytest.approx(corner["metric:upright_L.roll_centre_height"], abs=1e-6)


def _theta_at(travel: float) -> float:
    return brentq(lambda t: solve(HMMWV, t)["wheel_centre_dz"] - travel, -8.0, 8.0, xtol=1e-13)


def _theta_rolled(phi_deg: float) -> float:
    """The left lower-arm angle at body roll ``phi``: the road plane turned by ``phi`` about the
    x axis through the midpoint of the wheel-centre references (y = 0, z = z_ref; the left side
    up for phi > 0), the wheel centre on the turned plane through its reference."""
    phi = math.radians(phi_deg)
    ref = HMMWV["WC"]
    n = np.array([0.0, math.sin(phi), math.cos(phi)])  # the plane's normal turned about -x
    p = np.array([ref[0], ref[1] * math.cos(phi), ref[2] - ref[1] * math.sin(phi)])

    def off(t):
        s = solve(HMMWV, t)
        return n @ (np.array([ref[0], s["centre_y"], s["centre_z"]]) - p)

    return brentq(off, -8.0, 8.0, xtol=1e-13)


def test_roll_steer_against_the_independent_solver_on_the_rolled_road_plane(axle):
    """Roll steer and camber: the oracle's toe and camber of the left wheel at body roll +-phi
    (its centre on the rolled plane, closed form), differenced centrally; the right wheel's
    roll steer is the left's mirrored."""
    phi = 1.0
    got = roll_gradients(axle, "upright_L", "upright_R", angle=phi)
    up, down = (solve(HMMWV, _theta_rolled(s * phi)) for s in (1, -1))
    assert up["wheel_centre_dz"] < 0 < down["wheel_centre_dz"]  # roll to the right: the left wheel droops
    assert got["roll_steer:upright_L"] == pytest.approx((up["toe"] - down["toe"]) / (2 * phi), abs=1e-8)
    assert got["roll_camber:upright_L"] == pytest.approx((up["camber"] - down["camber"]) / (2 * phi), abs=1e-8)
    assert got["roll_steer:upright_R"] == pytest.approx(-got["roll_steer:upright_L"], abs=1e-9)


def _trapezoid(track=1500.0, arm=150.0, beta_deg=15.0, rack_half=500.0, vehicle=None):
    """A planar trapezoidal steering linkage (all points in z = 0): kingpins vertical at
    y = +-track/2, steering arms behind them turned inboard by beta, a rack along y at x = -arm cos beta."""
    beta = math.radians(beta_deg)
    bodies = {"chassis": {"fixed": True}, "rack": {}}
    joints = {"RACK": {"type": "translational", "bodies": ["chassis", "rack"], "point": [0, 0, 0], "axis": [0, 1, 0]}}
    for sfx, s in (("_L", 1.0), ("_R", -1.0)):
        k = np.array([0.0, s * track / 2, 0.0])
        tip = k + arm * np.array([-math.cos(beta), -s * math.sin(beta), 0.0])
        bodies[f"knuckle{sfx}"] = {
            "points": {
                "wheel_centre": k.tolist(),
                "spin_axis": (k + [0, s, 0]).tolist(),
            }
        }
        joints[f"K{sfx}"] = {
            "type": "revolute",
            "bodies": ["chassis", f"knuckle{sfx}"],
            "point": k.tolist(),
            "axis": [0, 0, 1],
        }
        inner = np.array([tip[0], s * rack_half, 0.0])
        joints[f"TR{sfx}"] = {
            "type": "distance",
            "bodies": ["rack", f"knuckle{sfx}"],
            "point_i": inner.tolist(),
            "point_j": tip.tolist(),
            "cut": True,
        }
    units = {"length": "mm", "angle": "deg", "axes": "ISO8855"}
    data = {"kinprop": 1, "name": "trapezoid", "style": "hardpoints", "units": units,
            "bodies": bodies, "joints": joints, "inputs": ["RACK"]}  # fmt: skip
    if vehicle:
        data["vehicle"] = vehicle
    return model_from_data(data, "trapezoid.yaml"), (track, arm, beta, rack_half)


def _closed_steer(s: float, side: float, track, arm, beta, rack_half) -> float:
    """Road-wheel angle (rad, positive to the left) of one knuckle at rack travel s: the arm tip
    on the circle of radius arm about the kingpin meets the circle of the tie rod about its
    inner end (circle-circle intersection, the branch of the design position)."""
    k = np.array([0.0, side * track / 2])
    tip0 = k + arm * np.array([-math.cos(beta), -side * math.sin(beta)])
    inner0 = np.array([tip0[0], side * rack_half])
    rod = np.linalg.norm(tip0 - inner0)
    inner = inner0 + [0.0, s]
    d = inner - k
    dist = np.linalg.norm(d)
    a = (arm**2 - rod**2 + dist**2) / (2 * dist)
    h = math.sqrt(arm**2 - a**2)
    base = k + a * d / dist
    perp = np.array([-d[1], d[0]]) / dist
    cands = [base + h * perp, base - h * perp]
    tip = min(cands, key=lambda p: np.linalg.norm(p - tip0))
    ang = lambda v: math.atan2(v[1], v[0])  # noqa: E731
    return ang(tip - k) - ang(tip0 - k)


def test_ackermann_of_a_planar_trapezoid_against_its_closed_form():
    model, (track, arm, beta, rack_half) = _trapezoid()
    wheelbase = 2800.0
    s = 30.0  # rack to the left pulls the arms (behind the kingpins) left: a right turn, the right wheel inner
    got = ackermann(model, "knuckle_R", "knuckle_L", "RACK.q", s, wheelbase)
    d_i = abs(_closed_steer(s, -1.0, track, arm, beta, rack_half))
    d_o = abs(_closed_steer(s, 1.0, track, arm, beta, rack_half))
    assert d_i > d_o > 0
    d_ack = math.atan(1 / (1 / math.tan(d_i) + track / wheelbase))
    assert got == pytest.approx(100 * (d_i - d_o) / (d_i - d_ack), abs=1e-6)
    assert 0 < got < 200


@pytest.mark.parametrize(
    ("file", "arm"),
    [("hmmwv_front_axle.yaml", "LCA"), ("mcpherson_axle.yaml", "LCA"), ("multilink_rear_axle.yaml", "UA")],
)
def test_shipped_axles_are_mirror_images(file, arm):
    model = model_from_data(yaml.safe_load((EXAMPLES / file).read_text()), file)
    theta = 3.0
    after = propagate(model, {f"{arm}_L.q": theta, f"{arm}_R.q": -theta}, ["q"], tol=1e-11).after
    left, right = suspension_metrics(after, "upright_L"), suspension_metrics(after, "upright_R")
    assert left["wheel_centre_dz"] > 0
    for name, value in left.items():
        mirrored = -right[name] if name == "wheel_centre_dy" else right[name]
        assert value == pytest.approx(mirrored, abs=1e-9), name


def test_track_change_in_heave_and_roll_against_the_independent_solver(axle):
    """Half-track change (the contact point's lateral move, outboard positive) at a travel of
    each wheel, and the axle's track change in heave (both wheels) and roll: the oracle's
    contact point (470 mm below the centre in the wheel plane)."""
    ref = HMMWV["WC"][1]
    got = track_change(axle, "upright_L", "upright_R", travel=40.0)
    corner = solve(HMMWV, _theta_at(40.0))
    assert got["half_track_change:upright_L"] == pytest.approx(corner["contact_y"] - ref, abs=1e-7)
    assert got["track_change"] == pytest.approx(2 * (corner["contact_y"] - ref), abs=1e-7)
    rolled = track_change(axle, "upright_L", "upright_R", roll=2.0)
    left, right = (solve(HMMWV, _theta_rolled(s * 2.0)) for s in (1, -1))  # the right wheel mirrors the left at -roll
    assert rolled["half_track_change:upright_L"] == pytest.approx(left["contact_y"] - ref, abs=1e-7)
    assert rolled["half_track_change:upright_R"] == pytest.approx(right["contact_y"] - ref, abs=1e-7)
    assert rolled["track_change"] == pytest.approx(left["contact_y"] + right["contact_y"] - 2 * ref, abs=1e-7)


def test_steering_ratio_of_a_planar_trapezoid_against_its_closed_form():
    """360 / c over the mean road-wheel angle's slope in rack travel: the closed-form steer
    angles (circle intersections) differenced over the same +-1 mm, at the centre and at 40 mm."""
    c = 50.0  # mm of rack per steering-wheel turn
    model, geo = _trapezoid(vehicle={"wheelbase": 2800.0, "cg_height": 500.0, "rack_travel_per_turn": c})
    for at in (0.0, 40.0):
        slopes = [(_closed_steer(at + 1, side, *geo) - _closed_steer(at - 1, side, *geo)) / 2 for side in (1.0, -1.0)]
        truth = 360.0 / c / abs(math.degrees(sum(slopes) / 2))
        assert steering_ratio(model, "knuckle_L", "knuckle_R", at=at) == pytest.approx(truth, rel=1e-9)
    bare, _ = _trapezoid()
    with pytest.raises(AddressError, match="rack_travel_per_turn"):
        steering_ratio(bare, "knuckle_L", "knuckle_R")


def test_road_wheel_steer_as_the_drive_against_the_trapezoids_closed_form():
    """The inner wheel's steer angle driven in equal degrees (steer:knuckle_L, a revolute about
    the vertical and one dot-1 row): the outer wheel's angle and the rack travel against the
    closed form (the rack travel that turns the inner knuckle so far, by brentq)."""
    model, geo = _trapezoid()
    for delta in (5.0, 15.0):
        s = brentq(lambda x, d=delta: _closed_steer(x, 1.0, *geo) - math.radians(d), -40.0, 0.0, xtol=1e-13)
        names = [f"metric:knuckle_L.toe@steer:knuckle_L={delta}", f"metric:knuckle_R.toe@steer:knuckle_L={delta}",
                 f"RACK.q@steer:knuckle_L={delta}"]  # fmt: skip
        v = outputs_at(model, names)
        assert v[names[0]] == pytest.approx(-delta, abs=1e-9)  # the left wheel's steer is -toe
        outer = (math.degrees(_closed_steer(s, -1.0, *geo)) + 180.0) % 360.0 - 180.0
        assert v[names[1]] == pytest.approx(outer, abs=1e-8)  # the right wheel's steer is +toe
        assert 0 < outer < delta  # the outer wheel turns less (a trapezoid's Ackermann)
        assert v[names[2]] == pytest.approx(s, abs=1e-7)


TRAVEL_INPUTS = {"upright_L": "LCA_L", "upright_R": "LCA_R"}


def test_roll_centre_migrates_in_heave_and_roll(axle):
    """The roll centre at a heave travel is on the centre line at the corner's roll-centre
    height there (the corner metric, another construction); in body roll it is the roll centre
    of the axle posed by the independent solver's lower-arm angles of both wheels (the right
    wheel mirrors the left at the opposite roll), mirrored in y between +roll and -roll."""
    for t in (-30.0, 30.0):
        rc = roll_centre(axle, "upright_L", "upright_R", TRAVEL_INPUTS, travel=t)
        corner = outputs_at(axle, [f"metric:upright_L.roll_centre_height@travel={t}"])
        assert rc["y"] == pytest.approx(0.0, abs=1e-6)
        assert rc["height"] == pytest.approx(corner[f"metric:upright_L.roll_centre_height@travel={t}"], abs=1e-7)
    at = {}
    for phi in (2.0, -2.0):
        at[phi] = roll_centre(axle, "upright_L", "upright_R", TRAVEL_INPUTS, roll=phi)
        arms = {"LCA_L.q": _theta_rolled(phi), "LCA_R.q": -_theta_rolled(-phi)}
        posed = propagate(axle, arms, ["q"], tol=1e-12).after
        truth = roll_centre(posed, "upright_L", "upright_R", TRAVEL_INPUTS)
        for k in ("y", "z", "height"):
            assert at[phi][k] == pytest.approx(truth[k], abs=1e-6), (phi, k)
    assert abs(at[2.0]["y"]) > 10.0  # it does move off the centre line
    assert at[2.0]["y"] == pytest.approx(-at[-2.0]["y"], abs=1e-6)
    assert at[2.0]["height"] == pytest.approx(at[-2.0]["height"], abs=1e-6)
    with pytest.raises(AddressError, match="not both"):
        roll_centre(axle, "upright_L", "upright_R", TRAVEL_INPUTS, travel=1.0, roll=1.0)
