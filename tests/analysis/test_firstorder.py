"""First-order suspension geometry (kinprop.analysis.firstorder) against independent truth:

* a double wishbone whose arm pivot axes are parallel (to x, or tilted by beta in the side
  view) and whose tie rod keeps the steer still: its wheel turns about the line parallel to
  the axes through the intersection of the arm lines in the view along them, so the FVIC,
  the roll centre (classical construction), the camber and half-track gains and the anti-dive
  (Milliken: tan(beta) L / h times the front braking share; 0 and an SVIC at infinity for
  beta = 0) follow in closed form;
* the spring's motion ratio on the lower arm by virtual work with instant centres (Kennedy);
* the shipped HMMWV double wishbone: every gain and motion ratio against central differences
  (Richardson) of re-solved positions.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import kinprop as kp
from kinprop.analysis.context import OutputContext
from kinprop.analysis.metrics import contact_point, suspension_metrics, wheel_first_order
from kinprop.analysis.outputs import evaluate_outputs
from kinprop.io import model_from_data

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
EX = np.array([1.0, 0.0, 0.0])

O_L, LBJ = np.array([0.0, 300.0, 0.0]), np.array([0.0, 750.0, -100.0])
O_U, UBJ = np.array([0.0, 420.0, 280.0]), np.array([-20.0, 700.0, 250.0])
C, RADIUS = np.array([0.0, 800.0, 50.0]), 350.0
T_O = np.array([-150.0, 720.0, 0.0])
S_C, S_A = np.array([30.0, 450.0, 330.0]), np.array([10.0, 610.0, -60.0])
WHEELBASE, CG, BRAKE = 2800.0, 500.0, 0.6


def _perp(v: np.ndarray, a: np.ndarray) -> np.ndarray:
    return v - (v @ a) * a


def _axis_point(a: np.ndarray) -> np.ndarray:
    """Where the arm lines meet in the view along the pivot axes ``a`` (a point of the wheel's axis)."""
    e1 = np.array([0.0, 1.0, 0.0])
    e2 = np.cross(a, e1)

    def p2(x: np.ndarray) -> np.ndarray:
        return np.array([x @ e1, x @ e2])

    dL, dU = p2(LBJ) - p2(O_L), p2(UBJ) - p2(O_U)
    t = np.linalg.solve(np.column_stack([dL, -dU]), p2(O_U) - p2(O_L))
    X = p2(O_L) + t[0] * dL
    return X[0] * e1 + X[1] * e2


def _model(beta_deg: float, metres: bool = False, right: bool = False, inputs: bool = True) -> kp.Model:
    """The parallel-axis double wishbone (mm and deg; or m and rad, the same suspension; or its
    mirror image, a right corner; without declared inputs)."""
    k = 1e-3 if metres else 1.0
    mirror = np.array([1.0, -1.0 if right else 1.0, 1.0])
    b = math.radians(beta_deg)
    a = np.array([math.cos(b), 0.0, math.sin(b)])
    c = _axis_point(a)
    # the tie rod lies along the perpendicular from the wheel's axis: no steer at this instant
    T_I = T_O - 0.45 * _perp(T_O - c, a)

    def v(x: np.ndarray) -> list[float]:
        return [float(y) * k for y in np.asarray(x) * mirror]

    data = {
        "kinprop": 1,
        "style": "hardpoints",
        "units": {"length": "m" if metres else "mm", "angle": "rad" if metres else "deg", "axes": "ISO8855",
                  "force": "N"},
        "bodies": {
            "chassis": {
                "fixed": True,
                "points": {"wheel_centre_ref": v(C), "contact_patch_ref": v(C - [0, 0, RADIUS])},
            },
            "lca": {},
            "uca": {},
            "upright": {
                "points": {
                    "wheel_centre": v(C),
                    "spin_axis": v(C + [0, 1, 0]),
                    "contact_patch": v(C - [0, 0, RADIUS]),
                    "kingpin_upper": v(UBJ),
                    "kingpin_lower": v(LBJ),
                }
            },
        },
        "joints": {
            "LCA": {"type": "revolute", "bodies": ["chassis", "lca"], "point": v(O_L), "axis": [float(y) for y in a]},
            "LBJ": {"type": "spherical", "bodies": ["lca", "upright"], "point": v(LBJ)},
            "UCA": {"type": "revolute", "bodies": ["chassis", "uca"], "point": v(O_U), "axis": [float(y) for y in a]},
            "UBJ": {"type": "spherical", "bodies": ["uca", "upright"], "cut": True, "point": v(UBJ)},
            "TR": {"type": "distance", "bodies": ["chassis", "upright"], "point_i": v(T_I), "point_j": v(T_O)},
        },
        "inputs": ["LCA"] if inputs else [],
        "elements": {
            "spring": {"type": "spring", "bodies": ["chassis", "lca"], "point_i": v(S_C), "point_j": v(S_A),
                       "stiffness": 50.0 / k},
        },
        "vehicle": {"wheelbase": WHEELBASE * k, "cg_height": CG * k, "brake_front": BRAKE, "axle": "front"},
    }  # fmt: skip
    return kp.assemble(model_from_data(data, "parallel.yaml")).after


@pytest.mark.parametrize("beta", [0.0, -5.0, 7.0])
def test_parallel_axes_follow_the_classical_constructions(beta: float) -> None:
    model = _model(beta)
    m = evaluate_outputs(model, [
        "fvic_y", "fvic_z", "fvsa_length", "svic_x", "svic_z", "svsa_length", "roll_centre_height", "anti_dive",
        "anti_lift", "camber_gain", "half_track_gain", "bump_steer", "motion_ratio:spring", "wheel_rate",
    ])  # fmt: skip
    b = math.radians(beta)
    a = np.array([math.cos(b), 0.0, math.sin(b)])
    c = _axis_point(a)
    E = C - [0, 0, RADIUS]
    # the front-view instant centre: the wheel's axis (through c along a) meets the plane x = x_E
    fvic = c + (E[0] - c[0]) / a[0] * a
    assert m["fvic_y"] == pytest.approx(fvic[1], rel=1e-9)
    assert m["fvic_z"] == pytest.approx(fvic[2], rel=1e-9)
    assert m["fvsa_length"] == pytest.approx(math.hypot(*(fvic - E)[1:]), rel=1e-9)
    # the roll centre: the line from the contact patch through the FVIC at y = 0
    rc = E[2] + (fvic[2] - E[2]) * (0.0 - E[1]) / (fvic[1] - E[1])
    assert m["roll_centre_height"] == pytest.approx(rc - E[2], rel=1e-9)
    # the side-view centre is at infinity (the axis is parallel to y = const), said so
    assert math.isnan(m["svic_x"]) and math.isnan(m["svic_z"]) and m["svsa_length"] == math.inf
    # anti-dive: the line to the SVIC is parallel to the axis: tan(theta) = -tan(beta)
    assert m["anti_dive"] == pytest.approx(BRAKE * -math.tan(b) * WHEELBASE / CG * 100.0, abs=1e-9)
    assert m["anti_lift"] == pytest.approx(0.0, abs=1e-12)  # drive_front 0
    # camber gain: rotation w about a; a_dot = w x e_y, travel rate (w x (C - c))_z
    w = a  # per unit rotation rate
    dz = np.cross(w, C - c)[2]
    assert m["camber_gain"] == pytest.approx(math.degrees(-np.cross(w, [0, 1, 0])[2]) / dz, rel=1e-9)
    # toe: a tilted axis also turns the spin axis in the ground plane: toe rate a_dot_x
    assert m["bump_steer"] == pytest.approx(math.degrees(np.cross(w, [0, 1, 0])[0]) / dz, rel=1e-9, abs=1e-14)
    # half-track gain: the contact point's lateral rate (the rolling point, zero camber)
    dE = np.cross(w, C - c) + RADIUS * np.cross(w, [0, 1, 0])[2] * np.array([0, 1.0, 0])
    assert m["half_track_gain"] == pytest.approx(dE[1] / dz, rel=1e-9)
    if beta == 0.0:
        assert m["half_track_gain"] == pytest.approx((c[2] - E[2]) / (C[1] - c[1]), rel=1e-9)
        assert m["camber_gain"] == pytest.approx(math.degrees(-1.0 / (C[1] - c[1])), rel=1e-9)


def test_motion_ratio_by_virtual_work() -> None:
    """Kennedy's instant centres in the front view (arm axes parallel to x): the lower arm turns
    at w_L about O_L, the upright at w_u about the FVIC c with v(LBJ) common; a vertical force
    F at the wheel centre and the spring force f do equal virtual work: f = F dz / dl."""
    model = _model(0.0)
    c = _axis_point(EX)
    w_L = 1.0
    v_lbj = np.cross(w_L * EX, LBJ - O_L)
    r = LBJ - c
    w_u = v_lbj[2] / r[1]  # v = w_u e_x x r: v_z = w_u r_y
    assert np.allclose(np.cross(w_u * EX, r), v_lbj, atol=1e-9)
    dz = np.cross(w_u * EX, C - c)[2]
    u = (S_A - S_C) / np.linalg.norm(S_A - S_C)
    dl = u @ np.cross(w_L * EX, S_A - O_L)
    mr = abs(dl / dz)
    m = evaluate_outputs(model, ["motion_ratio:spring", "wheel_rate"])
    assert m["motion_ratio:spring"] == pytest.approx(mr, rel=1e-10)
    assert m["wheel_rate"] == pytest.approx(50.0 * mr**2, rel=1e-10)


def _richardson(f, h: float) -> np.ndarray:
    d = lambda k: (f(k * h) - f(-k * h)) / (2 * k * h)  # noqa: E731
    return (4 * d(0.5) - d(1.0)) / 3


def test_hmmwv_gains_match_central_differences() -> None:
    base = kp.assemble(kp.load_model(EXAMPLES / "double_wishbone.yaml")).after
    ctx = OutputContext.of(base)
    first = wheel_first_order(ctx, "upright")
    spring = base.element("spring")

    def values(dq: float) -> np.ndarray:
        m = base if dq == 0 else kp.propagate(base, {"LCA.q": [float(base.coordinates["LCA"][0]) * 180 / math.pi + dq]},
                                             free=["q"], tol=1e-13).after  # fmt: skip
        s = suspension_metrics(m, "upright")
        kin = kp.compile(m).kinematics(m.design, m.coordinates)
        ends = [
            kin.r[b] + kin.A[b] @ np.array(p) for b, p in ((spring.body_i, spring.s_i), (spring.body_j, spring.s_j))
        ]
        cx = OutputContext.of(m)
        centre = cx.body_point("upright", "wheel_centre")
        E = contact_point(centre, cx.body_point("upright", "spin_axis") - centre, 470.0)
        return np.array([s["wheel_centre_dz"], s["camber"], s["toe"], s["caster"], E[1], E[0],
                         np.linalg.norm(ends[1] - ends[0])])  # fmt: skip

    d = _richardson(values, 0.2)  # per degree of lower arm
    dz = d[0]
    assert first["camber_gain"] == pytest.approx(d[1] / dz, rel=1e-8)
    assert first["bump_steer"] == pytest.approx(d[2] / dz, rel=1e-7)
    assert first["caster_gain"] == pytest.approx(d[3] / dz, rel=1e-8)
    assert first["half_track_gain"] == pytest.approx(d[4] / dz, rel=1e-8)
    assert first["contact_patch_dx_gain"] == pytest.approx(d[5] / dz, rel=1e-7)
    assert first["motion_ratio:spring"] == pytest.approx(abs(d[6] / dz), rel=1e-8)
    assert first["wheel_rate"] == pytest.approx(167.0 * first["motion_ratio:spring"] ** 2, rel=1e-12)
    # the documented values (docs/analysis/suspension.md)
    assert first["camber_gain"] == pytest.approx(-0.0237, abs=5e-5)
    assert first["bump_steer"] == pytest.approx(-0.0051, abs=5e-5)


def test_units_and_names() -> None:
    base = kp.assemble(kp.load_model(EXAMPLES / "double_wishbone.yaml")).after
    from kinprop.analysis.units import unit_of

    assert unit_of(base, "camber_gain") == "deg/mm"
    assert unit_of(base, "metric:upright.anti_dive") == "%"
    assert unit_of(base, "motion_ratio:spring") == ""
    assert unit_of(base, "wheel_rate") == "N/mm"
    assert unit_of(base, "roll_centre_height") == "mm"
    with pytest.raises(kp.AddressError, match="unknown element 'nope'"):
        evaluate_outputs(base, ["motion_ratio:nope"])


def test_results_do_not_depend_on_the_file_units() -> None:
    """The same suspension written in m and rad: every first-order metric converts exactly."""
    names = ["camber_gain", "bump_steer", "caster_gain", "fvic_y", "fvic_z", "fvsa_length", "roll_centre_height",
             "anti_dive", "half_track_gain", "half_track_change", "motion_ratio:spring", "wheel_rate"]  # fmt: skip
    mm = evaluate_outputs(_model(-5.0), names)
    m = evaluate_outputs(_model(-5.0, metres=True), names)
    per_mm_to_per_m = {"camber_gain": math.pi / 180 * 1e3, "bump_steer": math.pi / 180 * 1e3,
                       "caster_gain": math.pi / 180 * 1e3, "fvic_y": 1e-3, "fvic_z": 1e-3, "fvsa_length": 1e-3,
                       "roll_centre_height": 1e-3, "half_track_change": 1e-3, "wheel_rate": 1e3}  # fmt: skip
    for n in names:
        assert m[n] == pytest.approx(mm[n] * per_mm_to_per_m.get(n, 1.0), rel=1e-9, abs=1e-12), n


def test_first_order_targets_are_met() -> None:
    """Targets on camber gain, anti-dive and a motion ratio move the upper arm's pivots until
    the re-assembled design has them (checked by evaluating the metrics afresh)."""
    from kinprop.analysis.targets import propagate_targets

    base = kp.assemble(kp.load_model(EXAMPLES / "double_wishbone.yaml")).after
    res = propagate_targets(base, ["camber_gain=-0.025", "anti_dive=60", "motion_ratio:spring=0.46"],
                            ["hardpoint:UCA", "hardpoint:LCA"])  # fmt: skip
    assert res.targets_status == "met"
    got = evaluate_outputs(res.after, ["camber_gain", "anti_dive", "motion_ratio:spring"])
    assert got["camber_gain"] == pytest.approx(-0.025, rel=1e-8)
    assert got["anti_dive"] == pytest.approx(60.0, rel=1e-8)
    assert got["motion_ratio:spring"] == pytest.approx(0.46, rel=1e-8)
    rows = {r["output"].split(".")[-1]: r["unit"] for r in res.table()}
    assert rows["camber_gain"] == "deg/mm" and rows["anti_dive"] == "%"


def test_a_right_corner_and_no_declared_inputs_give_the_same_metrics() -> None:
    """The mirror image (y -> -y) is a right corner: every metric is the same (the signs are
    side-independent) except the FVIC's y; without declared inputs the bump motion is the
    mechanism's only degree of freedom, and nothing changes either."""
    names = ["camber_gain", "bump_steer", "caster_gain", "fvic_y", "fvic_z", "fvsa_length", "roll_centre_height",
             "anti_dive", "half_track_gain", "contact_patch_dx_gain", "motion_ratio:spring", "wheel_rate"]  # fmt: skip
    left = evaluate_outputs(_model(-5.0), names)
    right = evaluate_outputs(_model(-5.0, right=True), names)
    free = evaluate_outputs(_model(-5.0, inputs=False), names)
    for n in names:
        sign = -1.0 if n == "fvic_y" else 1.0
        assert right[n] == pytest.approx(sign * left[n], rel=1e-9, abs=1e-12), n
        assert free[n] == pytest.approx(left[n], rel=1e-9, abs=1e-12), n


FIRST_ORDER_OUTPUTS = ["camber_gain", "bump_steer", "caster_gain", "fvic_y", "fvic_z", "fvsa_length",
                       "roll_centre_height", "svic_x", "svic_z", "anti_dive", "anti_lift", "half_track_gain",
                       "contact_patch_dx_gain", "motion_ratio:spring", "motion_ratio:shock", "wheel_rate"]  # fmt: skip


def _change(model: kp.Model, column: str, h: float) -> dict[str, object]:
    """The by-address change moving one design column by ``h`` (a C column: ``exp`` of a
    body-frame rotation, as the retraction; a global hardpoint component: the point)."""
    from scipy.spatial.transform import Rotation

    from kinprop.analysis.points import joint_hardpoints

    if column.startswith("element:"):  # a global component of an element's end
        from kinprop.propagation.element_points import element_point

        engine = kp.compile(model)
        key = column[: column.index("[")]
        p = element_point(model, engine, engine.state_of(model), key)
        p["xyz".index(column[-2])] += h
        return {key: p}
    if column.startswith("hardpoint:"):
        key = column[len("hardpoint:") : column.index("[")]
        p = np.array(joint_hardpoints(model)[key], dtype=float)
        p["xyz".index(column[-2])] += h
        return {f"hardpoint:{key}": p}
    key = column.split("[")[0]
    if ".C_" in key:
        w = np.zeros(3)
        w[int(column[-2])] = h
        return {key: Rotation.from_rotvec(w).as_matrix() @ np.array(model.design[key], dtype=float)}
    v = np.array(model.design[key], dtype=float).ravel()
    v[int(column[-2]) if "[" in column else 0] += h
    return {key: v if v.size > 1 else float(v[0])}


def _check_exact_sensitivities(model: kp.Model, outs: list[str], wrt: list[str], h: float, rtol: float) -> None:
    """``output_sensitivity`` of first-order metrics (exact) against Richardson central
    differences of re-solved models (free q), column by column, in solver units."""
    from kinprop.analysis.sensitivity import EXACT, output_sensitivity

    D = output_sensitivity(model, outs, wrt, units="solver")
    assert set(D.attrs["method"].values()) == {EXACT}
    for column in D.columns:
        step = h * 1e-2 if ".C_" in column else h

        def f(t: float, column: str = column) -> np.ndarray:
            m = kp.propagate(model, _change(model, column, t), free=["q"], tol=1e-13).after
            v = evaluate_outputs(m, list(D.index), units="solver")
            return np.array([v[n] for n in D.index])

        fd = _richardson(f, step)
        got = D[column].to_numpy()
        assert np.allclose(got, fd, rtol=rtol, atol=rtol * 1e-3 * np.max(np.abs(fd))), (column, got, fd)


def test_exact_sensitivities_of_first_order_metrics_match_re_solved_models() -> None:
    """Every first-order metric of the HMMWV double wishbone with respect to points of tree
    and cut joints (s'), an arm's pivot-axis orientation (C), the tie rod's length and a global
    hardpoint, exact (``method``), against central differences of re-solved models."""
    base = kp.assemble(kp.load_model(EXAMPLES / "double_wishbone.yaml")).after
    wrt = ["LBJ.s_i[2]", "UBJ.s_j[0]", "TR.s_i[1]", "UCA.C_i[0]", "TR.length", "hardpoint:UBJ.i[z]"]
    outs = [*FIRST_ORDER_OUTPUTS, "half_track_change", "contact_patch_dx"]
    _check_exact_sensitivities(base, outs, wrt, 0.05, 1e-6)


def test_exact_sensitivities_with_respect_to_element_points() -> None:
    """Motion ratios and the wheel rate with respect to the spring's and the damper's global end
    points (``element:E.point_i|j[c]``: no body moves), exact, against central differences of
    models re-solved with the element point moved (``kp.propagate`` with ``element:`` changes);
    the kinematic metrics do not depend on them (0)."""
    base = kp.assemble(kp.load_model(EXAMPLES / "double_wishbone.yaml")).after
    wrt = ["element:spring.point_i", "element:spring.point_j[z]", "element:shock.point_j[x]", "hardpoint:UBJ.i[z]"]
    _check_exact_sensitivities(base, ["motion_ratio:spring", "motion_ratio:shock", "wheel_rate", "camber_gain"],
                               wrt, 0.05, 1e-6)  # fmt: skip
    D = kp.output_sensitivity(base, ["camber_gain"], wrt[:3])
    assert list(D.columns) == [*(f"element:spring.point_i[{c}]" for c in "xyz"), "element:spring.point_j[z]",
                               "element:shock.point_j[x]"]  # fmt: skip
    assert (D.to_numpy() == 0.0).all()


def test_exact_sensitivities_of_a_rear_corner_anti_squat() -> None:
    """The same corner declared a rear axle's (inboard drive): anti-lift and anti-squat, exact,
    against re-solved models."""
    import yaml

    path = EXAMPLES / "double_wishbone.yaml"
    data = yaml.safe_load(path.read_text())
    data["vehicle"]["axle"] = "rear"
    model = kp.assemble(model_from_data(data, str(path))).after
    _check_exact_sensitivities(model, ["anti_lift", "anti_squat"], ["UCA.s_i[2]", "LBJ.s_i[0]"], 0.05, 1e-6)


def test_exact_sensitivities_on_the_mcpherson_strut() -> None:
    """The paper's McPherson strut (a spherical-translational tree joint: Euler parameters and
    the slide; the tie rod a translational-distance cut joint whose rack is held), given wheel
    points: the gains, centres and ground metrics against re-solved models."""
    import yaml

    path = EXAMPLES / "mcpherson.yaml"
    data = yaml.safe_load(path.read_text())
    m0 = kp.assemble(kp.load_model(path)).after
    engine = kp.compile(m0)
    r, A, _, _ = engine.poses(engine.state_of(m0))
    b = engine.body_index["wheel"]
    C = np.array([0.0, 1.45, 0.0])

    def local(x: np.ndarray) -> list[float]:
        return (A[b].T @ (x - r[b])).tolist()

    data["bodies"]["wheel"] = {
        "points": {
            "wheel_centre": local(C),
            "spin_axis": local(C + EX[[1, 0, 2]]),
            "contact_patch": local(C - [0.0, 0.0, 0.33]),
        }
    }
    data["inputs"] = ["ST.q[4]"]  # the strut's slide; the rack TD.q is held
    model = kp.assemble(model_from_data(data, str(path))).after
    outs = ["camber_gain", "bump_steer", "fvic_y", "fvic_z", "fvsa_length", "roll_centre_height", "svic_x", "svic_z",
            "half_track_gain", "contact_patch_dx_gain"]  # fmt: skip
    assert np.isfinite(list(evaluate_outputs(model, outs).values())).all()
    _check_exact_sensitivities(
        model, outs, ["ST.s_i[0]", "RS.s_i[1]", "TD.s_j[2]", "RS.length", "TD.length"], 1e-4, 1e-6
    )


def test_sensitivity_cli_names_the_method() -> None:
    """``kinprop sensitivity --json``: ``method`` says which rows are exact; the matrix is the
    API's."""
    import json

    from typer.testing import CliRunner

    from kinprop.analysis.sensitivity import CENTRAL, EXACT
    from kinprop.cli import app

    path = EXAMPLES / "double_wishbone.yaml"
    args = ["sensitivity", str(path), "--wrt", "TR.s_i", "--of", "camber_gain", "--of", "toe", "--json"]
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 0, res.output
    obj = json.loads(res.stdout)
    assert obj["method"] == {"camber_gain": EXACT, "toe": CENTRAL}
    D = kp.output_sensitivity(kp.assemble(kp.load_model(path)).after, ["camber_gain", "toe"], ["TR.s_i"])
    np.testing.assert_allclose(obj["matrix"], D.to_numpy(), rtol=1e-9)


def test_target_jacobian_of_first_order_metrics_is_exact_along_the_tangent() -> None:
    """The targets' output Jacobian rows of first-order metrics (exact, per state column), applied
    to the implicit-function tangent of a design change, give the exact sensitivities (checked
    above against re-solved models) to round-off; central differences of the output map, the
    rows before, agree only to ~5e-10."""
    from kinprop.analysis.sensitivity import output_sensitivity_matrix
    from kinprop.analysis.targets import _config_jacobian
    from kinprop.propagation.sensitivity import design_sensitivity

    base = kp.assemble(kp.load_model(EXAMPLES / "double_wishbone.yaml")).after
    engine = kp.compile(base)
    names = [f"metric:upright.{n}" for n in ("camber_gain", "roll_centre_height", "anti_dive", "motion_ratio:spring")]
    wrt = ["UCA.s_i[2]", "TR.length"]
    D, _, _, _ = output_sensitivity_matrix(base, names, wrt, engine=engine, units="solver")
    sens = design_sensitivity(base, wrt, ["q"], engine=engine, units="solver")
    directions = np.zeros((engine.n_columns, len(wrt)))
    directions[sens.wrt_columns, np.arange(len(wrt))] = 1.0
    directions[sens.free_columns] = sens.matrix
    cols = np.flatnonzero(np.any(directions != 0.0, axis=1))
    G = _config_jacobian(base, engine, names)(engine.state_of(base), cols)
    np.testing.assert_allclose(G @ directions[cols], D, rtol=1e-12, atol=1e-14 * np.max(np.abs(D)))
