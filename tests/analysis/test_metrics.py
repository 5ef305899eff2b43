"""Suspension metrics against closed forms on constructed wheels (ISO 8855 signs)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from kinprop import AddressError
from kinprop.analysis.metrics import (
    camber_toe,
    contact_point,
    ground_offsets,
    metric_names,
    steering_angles,
    suspension_metrics,
)
from kinprop.analysis.outputs import evaluate_outputs
from kinprop.model import Body, Design, Joint, Mechanism, Model, as_coordinates
from kinprop.spatial import matrix_to_euler, rot_x, rot_z

R = 0.3  # wheel radius


def wheel_model(side: int, camber: float, toe: float, centre=(0.1, 0.8, 0.3), kingpin=None, ref=None) -> Model:
    """A wheel body on a free joint, posed by camber then toe (radians, ISO 8855 signs).

    ``side`` +1 left (outboard +y), -1 right. Positive camber tops the wheel outboard:
    ``Rx(-side camber)``; toe-in turns the front inboard: ``Rz(-side toe)``.
    """
    A = rot_z(-side * toe) @ rot_x(-side * camber)
    points = [
        ("wheel_centre", (0.0, 0.0, 0.0)),
        ("spin_axis", (0.0, 2.0 * side, 0.0)),
        ("contact_patch", (0.0, 0.0, -R)),
    ]
    if kingpin is not None:
        points += [("kingpin_upper", kingpin[0]), ("kingpin_lower", kingpin[1])]
    chassis_points = () if ref is None else (("wheel_centre_ref", tuple(ref)),)
    mech = Mechanism(
        (Body("chassis", fixed=True, points=chassis_points), Body("wheel", points=tuple(points))),
        (Joint("F", "free", "chassis", "wheel"),),
    )
    q = np.concatenate([centre, matrix_to_euler(A)])
    return Model(mech, Design({}), as_coordinates({"F": q}))


@pytest.mark.parametrize("side", [1, -1])
@pytest.mark.parametrize(
    "camber_deg, toe_deg", [(0.0, 0.0), (-1.5, 0.0), (2.0, 0.0), (0.0, 0.3), (-1.2, -0.4), (3.0, 2.5)]
)
def test_camber_toe_exact_on_rotated_wheel(side, camber_deg, toe_deg):
    m = wheel_model(side, math.radians(camber_deg), math.radians(toe_deg))
    got = suspension_metrics(m)
    assert got["camber"] == pytest.approx(camber_deg, abs=1e-12)
    assert got["toe"] == pytest.approx(toe_deg, abs=1e-12)
    assert "caster" not in got  # no steering axis declared


def test_sign_conventions_left_and_right():
    # left wheel (outboard +y): top leaning inboard (-y) is negative camber
    assert camber_toe([0.0, math.cos(0.1), math.sin(0.1)])[0] < 0
    # right wheel (outboard -y): top leaning inboard (+y) is negative camber
    assert camber_toe([0.0, -math.cos(0.1), math.sin(0.1)])[0] < 0
    # toe-in: the front turned towards the centreline; the outboard axis then points forward (+x)
    assert camber_toe([0.05, 1.0, 0.0])[1] > 0 and camber_toe([0.05, -1.0, 0.0])[1] > 0


@pytest.mark.parametrize("side", [1, -1])
def test_caster_kpi_scrub_trail_closed_form(side):
    caster, kpi = math.radians(6.0), math.radians(11.0)
    centre = np.array([0.1, side * 0.8, R])  # wheel on the ground plane z = 0
    # steering axis meets the ground at G = contact + (trail, -side * scrub, 0)
    scrub, trail = 0.025, 0.018
    G = np.array([centre[0] + trail, centre[1] - side * scrub, 0.0])
    k = np.array([-math.tan(caster), -side * math.tan(kpi), 1.0])
    lower, upper = G + 0.1 * k, G + 0.5 * k
    # upright frame = global frame at the wheel centre (no camber or toe)
    m = wheel_model(side, 0.0, 0.0, centre=centre, kingpin=(tuple(upper - centre), tuple(lower - centre)))
    got = suspension_metrics(m)
    assert got["caster"] == pytest.approx(6.0, abs=1e-12)
    assert got["kpi"] == pytest.approx(11.0, abs=1e-12)
    assert got["scrub_radius"] == pytest.approx(scrub, abs=1e-14)
    assert got["trail"] == pytest.approx(trail, abs=1e-14)
    assert steering_angles(upper, lower, side) == pytest.approx((6.0, 11.0), abs=1e-12)


def test_contact_point_is_lowest_point_of_wheel_circle():
    a = np.array([0.0, math.cos(0.2), -math.sin(0.2)])  # cambered 0.2 rad, left
    c = contact_point(np.zeros(3), a, R)
    assert c @ a == pytest.approx(0.0, abs=1e-15) and np.linalg.norm(c) == pytest.approx(R)
    ang = np.linspace(0, 2 * np.pi, 721)
    u = np.cross(a, [1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    circle = R * (np.outer(np.cos(ang), [1.0, 0.0, 0.0]) + np.outer(np.sin(ang), u))
    assert c[2] <= circle[:, 2].min() + 1e-12
    assert ground_offsets(np.array([0, 0, 1.0]), np.zeros(3), np.zeros(3), np.array([0, 1.0, 0])) == (0.0, 0.0)


def test_wheel_centre_displacement_reference_point_and_model():
    ref = wheel_model(1, 0.0, 0.0, centre=(0.1, 0.8, 0.3))
    moved = wheel_model(1, 0.0, 0.0, centre=(0.1, 0.81, 0.35), ref=(0.1, 0.8, 0.3))
    got = suspension_metrics(moved)
    assert (got["wheel_centre_dx"], got["wheel_centre_dy"], got["wheel_centre_dz"]) == pytest.approx((0, 0.01, 0.05))
    moved_no_ref = wheel_model(1, 0.0, 0.0, centre=(0.1, 0.81, 0.35))
    assert "wheel_centre_dz" not in suspension_metrics(moved_no_ref)
    assert suspension_metrics(moved_no_ref, reference=ref)["wheel_centre_dz"] == pytest.approx(0.05)
    out = evaluate_outputs(moved_no_ref, ["wheel_travel"], reference=ref)
    assert out["wheel_travel"] == pytest.approx(0.05)
    with pytest.raises(AddressError, match="needs a reference"):
        evaluate_outputs(moved_no_ref, ["metric:wheel.wheel_centre_dz"])
    assert "metric:wheel.wheel_centre_dz" in metric_names(moved)


def test_double_wishbone_static_values(double_wishbone):
    got = suspension_metrics(double_wishbone)
    # zero static camber/toe by construction (spin axis along y at the published hardpoints)
    assert got["camber"] == pytest.approx(0.0, abs=1e-6) and got["toe"] == pytest.approx(0.0, abs=1e-6)
    # steering axis through the published ball joints (LCA_U, UCA_U), in closed form
    lbj = np.array([-35.56, 786.511, -118.11])
    ubj = np.array([-53.0352, 715.518, 215.4936])
    k = ubj - lbj
    assert got["caster"] == pytest.approx(math.degrees(math.atan2(-k[0], k[2])), abs=1e-5)
    assert got["kpi"] == pytest.approx(math.degrees(math.atan2(-k[1], k[2])), abs=1e-5)
    cp = np.array([-40.386, 909.701, -26.289 - 470.0])
    G = lbj + k * (cp[2] - lbj[2]) / k[2]
    assert got["scrub_radius"] == pytest.approx(cp[1] - G[1], abs=1e-4)
    assert got["trail"] == pytest.approx(G[0] - cp[0], abs=1e-4)
    assert got["wheel_centre_dz"] == pytest.approx(0.0, abs=1e-5)
