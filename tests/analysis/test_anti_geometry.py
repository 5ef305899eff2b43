"""Anti geometry and view instant centres against Milliken & Milliken's side-view construction
and against virtual work.

* By hand (Milliken & Milliken, RCVD ch. 17): a wheel on one pivot axis (a semi-trailing arm)
  turns about that axis, so its side-view instant centre is where the axis pierces the wheel's
  side-view plane, ``tan(theta)`` is that point's height over its distance from the contact
  patch (outboard brakes) or the wheel centre (inboard drive), and anti-dive is
  ``brake_front tan(theta) L / h 100``; the front-view centre and the roll centre likewise.
* By virtual work, for any suspension: a longitudinal force at the contact patch E reaches the
  spring through ``dx_E / dz_E`` (E a point of the wheel body), so anti-dive is
  ``brake_front (dx_E / dz_E) L / h 100`` and the roll centre is where the line from E normal
  to E's front-view path meets y = 0, both from central differences of re-solved positions.
  The generic MacPherson's motion is a screw of large pitch (its bump steer and camber gain
  are large): the point where the screw axis pierces the view plane is not the view's instant
  centre there (it put the side-view centre 0.77 m under the ground, -239 % anti-dive).
"""

from __future__ import annotations

import numpy as np
import pytest
from analysis_helpers import EXAMPLES

import kinprop as kp
from kinprop.analysis.context import WheelSpec
from kinprop.analysis.drives import travel_input
from kinprop.analysis.outputs import evaluate_outputs
from kinprop.io import model_from_data
from kinprop.io.vehicle import anti_geometry, load_vehicle

NAMES = ("svic_x", "svic_z", "fvic_y", "fvic_z", "roll_centre_height", "anti_dive", "anti_lift", "anti_squat")


def _semi_trailing_arm(axle: str) -> kp.Model:
    """A wheel on a revolute to the chassis through A = (-2000, 400, -250) mm along d = (0.2, 1,
    0.1); wheel centre (0, 800, 0), contact patch 300 mm below."""
    data = {
        "kinprop": 1,
        "style": "hardpoints",
        "units": {"length": "mm", "angle": "deg", "axes": "ISO8855"},
        "bodies": {
            "chassis": {"fixed": True, "points": {"wheel_centre_ref": [0.0, 800.0, 0.0]}},
            "wheel": {"points": {"wheel_centre": [0.0, 800.0, 0.0], "spin_axis": [0.0, 801.0, 0.0],
                                 "contact_patch": [0.0, 800.0, -300.0]}},
        },
        "joints": {"ARM": {"type": "revolute", "bodies": ["chassis", "wheel"], "point": [-2000.0, 400.0, -250.0],
                           "axis": [0.2, 1.0, 0.1]}},
        "inputs": ["ARM"],
        "vehicle": {"wheelbase": 2800.0, "cg_height": 500.0, "brake_front": 0.6, "drive_front": 0.4, "axle": axle,
                    "brakes": "outboard", "drive": "inboard"},
    }  # fmt: skip
    return kp.assemble(model_from_data(data, "arm.yaml")).after


def test_a_semi_trailing_arm_by_milliken_construction():
    """The axis pierces y = 800 at X = (-1920, 800, -210): 90 mm above the ground, 1920 mm
    behind the contact patch; x = 0 at (0, 10400, 750). By hand: anti-dive 0.6 (90/1920) 2800/500
    100 = 15.75 %; anti-lift (inboard drive, from the wheel centre) 0.4 (-210/1920) 560 = -24.5 %;
    the roll centre on the line from (800, -300) through (10400, 750) at y = 0: -87.5 mm."""
    m = evaluate_outputs(_semi_trailing_arm("front"), list(NAMES[:-1]))
    assert (m["svic_x"], m["svic_z"]) == pytest.approx((-1920.0, -210.0), abs=1e-9)
    assert (m["fvic_y"], m["fvic_z"]) == pytest.approx((10400.0, 750.0), rel=1e-12)
    assert m["anti_dive"] == pytest.approx(15.75, abs=1e-10)
    assert m["anti_lift"] == pytest.approx(-24.5, abs=1e-10)
    assert m["roll_centre_height"] == pytest.approx(-87.5, abs=1e-9)
    # on a rear axle the centre is behind the wheel: anti-squat 0.6 (-210/-1920) 560, rising forward
    rear = evaluate_outputs(_semi_trailing_arm("rear"), ["anti_squat", "anti_lift"])
    assert rear["anti_squat"] == pytest.approx(0.6 * (-210.0 / 1920.0) * 560.0 * -1.0, abs=1e-10)
    assert rear["anti_lift"] == pytest.approx(0.4 * (90.0 / 1920.0) * 560.0 * -1.0, abs=1e-10)


def _rates(model: kp.Model, drive: str, h: float) -> dict[str, np.ndarray]:
    """Central differences (Richardson) of the wheel's contact patch and centre (points of the
    wheel body) over the travel input ``drive``, per unit of the input."""
    wheel = "upright_L" if "upright_L" in model.mechanism.body_names else "upright"
    pts = [f"point:{wheel}.contact_patch", f"point:{wheel}.wheel_centre"]
    q0 = float(model.coordinates[drive.split(".")[0]][0])

    def at(dq: float) -> np.ndarray:
        after = kp.propagate(model, {drive: q0 + dq}, tol=1e-13).after
        v = kp.evaluate_outputs(after, pts)
        return np.array([[v[f"{p}[{c}]"] for c in "xyz"] for p in pts])

    d1, d2 = (at(h) - at(-h)) / (2 * h), (at(h / 2) - at(-h / 2)) / h
    rates = (4 * d2 - d1) / 3
    return {"E": rates[0], "C": rates[1]}


@pytest.mark.parametrize("axle", ["front", "rear"])
def test_the_generic_vehicle_by_virtual_work(axle):
    """The generic vehicle (examples/vehicles/generic_vehicle.yaml): each axle's anti
    percentages and roll centre from the contact patch's and wheel centre's paths (central
    differences), the side- and front-view centres where the normals to those paths meet."""
    car = load_vehicle(EXAMPLES / "vehicles" / "generic_vehicle.yaml")
    model = getattr(car, axle)
    wheel = "upright_L"
    drive = travel_input(model, wheel)
    skip = "anti_squat" if axle == "front" else "anti_dive"
    names = [f"metric:{wheel}.{n}" for n in NAMES if n != skip]
    got = evaluate_outputs(model, names, wheels={wheel: WheelSpec(travel_input=drive)}, units="solver")
    m = {n.rsplit(".", 1)[1]: v for n, v in got.items()}
    r = _rates(model, drive, 1e-2)
    vE, vC = r["E"], r["C"]
    pts = kp.evaluate_outputs(model, [f"point:{wheel}.contact_patch", f"point:{wheel}.wheel_centre"])
    E = np.array([pts[f"point:{wheel}.contact_patch[{c}]"] for c in "xyz"])
    C = np.array([pts[f"point:{wheel}.wheel_centre[{c}]"] for c in "xyz"])
    v = model.vehicle
    lever = v.wheelbase / v.cg_height * 100.0
    if axle == "front":  # outboard brakes: the contact patch; drive_front 0
        assert m["anti_dive"] == pytest.approx(v.brake_front * vE[0] / vE[2] * lever, rel=1e-6)
        assert 0.0 < m["anti_dive"] < 30.0  # a production MacPherson's range
    else:  # rear: braking at the contact patch, the drive (inboard) at the wheel centre
        assert m["anti_lift"] == pytest.approx((1 - v.brake_front) * -vE[0] / vE[2] * lever, rel=1e-6)
        assert m["anti_squat"] == pytest.approx((1 - v.drive_front) * -vC[0] / vC[2] * lever, rel=1e-6)
    assert m["roll_centre_height"] == pytest.approx(E[1] * vE[1] / vE[2], rel=1e-6)
    # E and C lie in both view planes (zero camber, zero toe): the centres are where their normals meet
    for plane, (a, b), first in ((1, (0, 2), "svic_x"), (0, (1, 2), "fvic_y")):
        assert E[plane] == pytest.approx(C[plane], abs=1e-6)
        n_E, n_C = np.array([vE[b], -vE[a]]), np.array([vC[b], -vC[a]])  # normals to the paths
        t = np.linalg.solve(np.column_stack([n_E, -n_C]), C[[a, b]] - E[[a, b]])
        X = E[[a, b]] + t[0] * n_E
        second = "svic_z" if first == "svic_x" else "fvic_z"
        assert (m[first], m[second]) == pytest.approx(tuple(X), rel=1e-5)
    anti = anti_geometry(car)
    for n in ("anti_dive", "anti_lift") if axle == "front" else ("anti_lift", "anti_squat"):
        assert anti[f"{axle}.{n}"] == pytest.approx(m[n], rel=1e-12)


def test_the_hmmwv_corner_by_virtual_work():
    """The same truth on the HMMWV double wishbone (a small screw pitch)."""
    model = kp.load_model(EXAMPLES / "double_wishbone_hardpoints.yaml")
    m = kp.evaluate_outputs(model, ["anti_dive", "anti_lift", "roll_centre_height"])
    r = _rates(model, "LCA.q", 1e-2)
    vE = r["E"]
    pts = kp.evaluate_outputs(model, ["point:upright.contact_patch"])
    E = np.array([pts[f"point:upright.contact_patch[{c}]"] for c in "xyz"])
    v = model.vehicle
    lever = v.wheelbase / v.cg_height * 100.0
    assert m["anti_dive"] == pytest.approx(v.brake_front * vE[0] / vE[2] * lever, rel=1e-6)
    assert m["roll_centre_height"] == pytest.approx(E[1] * vE[1] / vE[2], rel=1e-6)
