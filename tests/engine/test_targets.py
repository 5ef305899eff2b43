"""Propagation to targets against external truth: Freudenstein three-position synthesis,
Stewart-platform inverse kinematics, and a double-wishbone camber/toe curve confirmed by an
independent closed construction of the changed design (docs/guide/targets.md)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation

from kinprop import SingularityWarning, assemble, load_model
from kinprop.analysis.metrics import camber_toe
from kinprop.analysis.points import joint_hardpoints, named_points
from kinprop.analysis.targets import parse_target, propagate_targets
from kinprop.errors import AddressError
from kinprop.io import model_from_data
from kinprop.spatial import exp_so3, matrix_to_euler

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
pytestmark = pytest.mark.filterwarnings("ignore::kinprop.SingularityWarning")


def solved(name: str):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SingularityWarning)
        prop = assemble(load_model(EXAMPLES / name), tol=1e-12)
    assert prop.converged
    return prop.after


# --- Freudenstein three-position function generation --------------------------------------
def output_angle(a: float, b: float, c: float, d: float, t2: np.ndarray) -> np.ndarray:
    """Rocker angle of a four-bar (crank a at O2 = origin, rocker c at O4 = (d, 0), coupler b),
    open branch, by intersecting two circles (independent of Freudenstein's equation)."""
    A = np.stack([a * np.cos(t2), a * np.sin(t2)], axis=-1)
    O4 = np.array([d, 0.0])
    v = O4 - A
    L = np.linalg.norm(v, axis=-1)
    x = (L**2 + b**2 - c**2) / (2 * L)
    h = np.sqrt(b**2 - x**2)
    n = np.stack([v[:, 1], -v[:, 0]], axis=-1) / L[:, None]
    B = A + x[:, None] * v / L[:, None] - h[:, None] * n  # B above the ground line
    return np.arctan2(B[:, 1], B[:, 0] - d)


def freudenstein_synthesis(t2: np.ndarray, t4: np.ndarray, d: float) -> tuple[float, float, float]:
    """Closed form (Freudenstein 1955; Norton, Design of Machinery, sec. 5.13): solve
    ``K1 cos t4 - K2 cos t2 + K3 = cos(t2 - t4)`` at three precision points for K1..K3, then
    ``a = d/K1``, ``c = d/K2``, ``b^2 = a^2 + c^2 + d^2 - 2 a c K3``."""
    M = np.stack([np.cos(t4), -np.cos(t2), np.ones(3)], axis=1)
    K1, K2, K3 = np.linalg.solve(M, np.cos(t2 - t4))
    a, c = d / K1, d / K2
    return a, float(np.sqrt(a * a + c * c + d * d - 2 * a * c * K3)), c


def test_freudenstein_three_positions_equal_the_closed_form():
    model = solved("fourbar.yaml")  # a = 0.15, b = 0.40, c = 0.30, d = 0.40 [m]
    # precision points of the function psi = 60 + 0.6 (phi - 40) + 0.002 (phi - 40)^2 [deg]
    phi = np.array([40.0, 65.0, 90.0])
    psi = 60.0 + 0.6 * (phi - 40) + 0.002 * (phi - 40) ** 2
    a, b, c = freudenstein_synthesis(np.radians(phi), np.radians(psi), 0.40)
    assert all(x > 0 for x in (a, b, c))
    specs = [f"O4.q@O2.q={p:.17g}={s:.17g}" for p, s in zip(phi, psi, strict=True)]
    tp = propagate_targets(model, specs, ["A.s_i[0]", "B.s_i[0]", "B.s_j[0]"])
    assert tp.targets_status == "met", tp.result.message
    eng, st = tp.engine, tp.result.after[0]
    found = (eng.get(st, "A.s_i[0]"), eng.get(st, "B.s_i[0]"), eng.get(st, "B.s_j[0]"))
    np.testing.assert_allclose(found, (a, b, c), rtol=1e-9)
    # the synthesized linkage generates the precision points (circle intersection, not kinprop)
    np.testing.assert_allclose(np.degrees(output_angle(a, b, c, 0.40, np.radians(phi))), psi, atol=1e-8)
    # the achieved values, in the model's angle unit (deg)
    for row, s in zip(tp.table(), psi, strict=True):
        assert row["achieved"] == pytest.approx(s, abs=1e-9)
    # only the free lengths moved, in the plane
    assert set(tp.design_change) == {"A.s_i", "B.s_i", "B.s_j"}
    assert np.abs([v[1:] for v in tp.design_change.values()]).max() == 0


# --- Stewart platform: pose targets reproduce the inverse kinematics -------------------------
def test_stewart_pose_target_gives_inverse_kinematics_leg_lengths():
    model = solved("stewart.yaml")
    pos, rot = np.array([0.03, -0.02, 0.45]), exp_so3([0.05, -0.08, 0.1])
    p = matrix_to_euler(rot)
    specs = [f"P.q[{k}]={v:.17g}" for k, v in enumerate(pos)] + [f"P.q[{k + 4}]={v:.17g}" for k, v in enumerate(p[1:])]
    tp = propagate_targets(model, specs, ["l"])
    assert tp.targets_status == "met", tp.result.message
    eng, st = tp.engine, tp.result.after[0]
    for k in range(1, 7):
        s_i, s_j = model.design[f"L{k}.s_i"], model.design[f"L{k}.s_j"]
        ik = np.linalg.norm(pos + rot @ s_j - s_i)  # inverse kinematics of a 6-UPS platform
        assert float(eng.get(st, f"L{k}.length")[0]) == pytest.approx(ik, rel=1e-10)
    # the platform's pose in the result is the target pose
    body = tp.propagation.bodies["platform"]
    np.testing.assert_allclose(body["t"], pos, atol=1e-10)
    np.testing.assert_allclose(body["R"], rot, atol=1e-10)
    assert set(tp.design_change) == {f"L{k}.length" for k in range(1, 7)}


# --- double wishbone: camber/toe targets confirmed by an independent construction --------------
def rotate(p, origin, axis, angle):
    return origin + Rotation.from_rotvec(angle * axis / np.linalg.norm(axis)).apply(p - origin)


def closed_wheel(model, travel: float, z_ref: float) -> tuple[float, float]:
    """(camber, toe) [deg] of a double wishbone at ``travel`` [mm], by an independent closed
    construction from its global hardpoints (lower arm angle by a root on the wheel-centre
    height; upper arm and steer by 1-D roots), as tests/analysis/test_double_wishbone.py."""
    hp, pts = joint_hardpoints(model), named_points(model)
    lca_f, lca_b = np.add(pts["chassis.LCA.front"], 0), np.add(pts["chassis.LCA.rear"], 0)
    uca_f, uca_b = np.add(pts["chassis.UCA.front"], 0), np.add(pts["chassis.UCA.rear"], 0)
    lbj, ubj = np.array(hp["LBJ.i"]), np.array(hp["UBJ.i"])
    tr_c, tr_u = np.array(hp["TR.i"]), np.array(hp["TR.j"])
    centre0 = np.array(pts["upright.wheel_centre"])
    axis0 = np.array(pts["upright.spin_axis"]) - centre0
    r_kp, l_tr = np.linalg.norm(ubj - lbj), np.linalg.norm(tr_u - tr_c)

    def wheel(theta):
        lbj_t = rotate(lbj, lca_b, lca_f - lca_b, theta)
        phi = brentq(lambda a: np.linalg.norm(rotate(ubj, uca_b, uca_f - uca_b, a) - lbj_t) - r_kp, -0.6, 0.6)
        ubj_t = rotate(ubj, uca_b, uca_f - uca_b, phi)
        k1 = ubj_t - lbj_t
        R0 = Rotation.align_vectors([k1], [ubj - lbj])[0]

        def pose(psi):
            return Rotation.from_rotvec(psi * k1 / np.linalg.norm(k1)) * R0

        psi = brentq(lambda s: np.linalg.norm(lbj_t + pose(s).apply(tr_u - lbj) - tr_c) - l_tr, -0.5, 0.5)
        R = pose(psi)
        return lbj_t + R.apply(centre0 - lbj), R.apply(axis0)

    theta = brentq(lambda t: wheel(t)[0][2] - z_ref - travel, -0.2, 0.2)
    return camber_toe(wheel(theta)[1])


def test_double_wishbone_camber_and_toe_curve_met_and_confirmed_independently():
    model = solved("double_wishbone.yaml")
    z_ref = float(named_points(model)["chassis.wheel_centre_ref"][2])
    targets = {(-50.0, "camber"): 1.0, (50.0, "camber"): -1.6, (-50.0, "toe"): 0.0, (50.0, "toe"): 0.0}
    specs = [f"metric:{m}@travel={t:g}mm={v:g}deg" for (t, m), v in targets.items()]
    before = {(t, m): closed_wheel(model, t, z_ref)[m == "toe"] for (t, m) in targets}
    tp = propagate_targets(model, specs, ["hardpoint:UBJ", "hardpoint:TR.i"])
    assert tp.targets_status == "met", tp.result.message
    for row, key in zip(tp.table(), targets, strict=True):
        assert row["before"] == pytest.approx(before[key], abs=1e-7)  # kinprop's sweep vs construction
        assert row["achieved"] == pytest.approx(targets[key], abs=1e-9)
    after = tp.after
    for (t, m), v in targets.items():
        camber, toe = closed_wheel(after, t, z_ref)
        assert (camber, toe)[m == "toe"] == pytest.approx(v, abs=1e-7), (t, m)
    # the changed design moved the two hardpoints by millimetres, nothing else of the design
    moves = tp.hardpoint_moves()
    assert set(moves) == {"UBJ.i", "UBJ.j", "TR.i"}
    assert 0.1 < max(np.linalg.norm(v) for v in moves.values()) < 50.0


def test_conflicting_targets_give_the_least_squares_compromise_and_name_the_conflict():
    model = solved("double_wishbone.yaml")
    tp = propagate_targets(
        model, ["camber@travel=50=-1.5", "camber@travel=50=-1.0", "toe@travel=50=0"], ["hardpoint:UBJ", "TR.s_i"]
    )
    assert tp.targets_status == "compromise" and tp.converged  # converged to the compromise
    res = {r["target"]: r["miss"] for r in tp.table()}
    assert res["camber@travel=50=-1.5"] == pytest.approx(0.25, abs=1e-9)
    assert res["camber@travel=50=-1.0"] == pytest.approx(-0.25, abs=1e-9)
    assert res["toe@travel=50=0"] == pytest.approx(0.0, abs=1e-9)
    (group,) = tp.result.conflicts
    assert {n for n, _ in group} == {"camber@travel=50=-1.5", "camber@travel=50=-1.0"}
    assert all(abs(abs(w) - 2**-0.5) < 1e-6 for _, w in group)
    # the mechanism stays assembled in the compromise
    assert tp.result.hard_residual < 1e-8


def test_weights_trade_the_compromise():
    model = solved("double_wishbone.yaml")
    tp = propagate_targets(model, ["camber@travel=50=-1.5:3", "camber@travel=50=-1.0"], ["hardpoint:UBJ"])
    # weighted least squares of two rows on one value: (9 (-1.5) + 1 (-1.0)) / 10
    assert tp.table()[0]["achieved"] == pytest.approx(-1.45, abs=1e-9)


def test_slope_target_bump_steer():
    model = solved("double_wishbone.yaml")
    z_ref = float(named_points(model)["chassis.wheel_centre_ref"][2])
    tp = propagate_targets(model, ["slope:toe@travel=-50..50=0deg/m"], ["hardpoint:TR.i"])
    assert tp.targets_status == "met", tp.result.message
    lo, hi = closed_wheel(tp.after, -50, z_ref)[1], closed_wheel(tp.after, 50, z_ref)[1]
    assert hi - lo == pytest.approx(0.0, abs=1e-7)
    # only the tie rod's inner point moved
    assert set(tp.design_change) == {"TR.s_i"}


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("camber@travel=50", "expected OUTPUT"),
        ("camber@travel=50=-1.5m", "does not fit"),
        ("nope@travel=50=1", "unknown metric"),
        ("slope:toe@travel=50=0", "condition range"),
        ("camber=1:-2", "weight must be positive"),
    ],
)
def test_bad_target_specs_are_located(text, message):
    model = load_model(EXAMPLES / "double_wishbone.yaml")
    with pytest.raises(AddressError, match=message):
        parse_target(model, text)


def test_units_in_target_values():
    model = load_model(EXAMPLES / "double_wishbone.yaml")  # mm, deg
    assert parse_target(model, "camber@travel=0.05m=-0.0261799387799rad").value == pytest.approx(-1.5, abs=1e-9)
    assert parse_target(model, "camber@travel=0.05m=-1").conditions[0].value == pytest.approx(50.0)
    assert parse_target(model, "LCA.q=10").value == pytest.approx(np.radians(10))  # model angle unit: deg
    assert parse_target(model, "slope:toe@travel=-50..50=1deg/m").value == pytest.approx(1e-3)


def test_worked_example_script_writes_the_figure(tmp_path, capsys, monkeypatch):
    """examples/double_wishbone_targets.py (docs/guide/targets.md): targets met, figure written
    into the current directory (not a docs/img/ there, issue 19), and the after curve of the
    ordinary sweep passes through the targets."""
    import runpy
    import sys

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "argv", [str(EXAMPLES / "double_wishbone_targets.py")])
    runpy.run_path(str(EXAMPLES / "double_wishbone_targets.py"), run_name="__main__")
    out = tmp_path / "double_wishbone_targets.png"
    assert out.stat().st_size > 10_000 and not (tmp_path / "docs").exists()
    text = capsys.readouterr().out
    assert text.startswith("targets met")
    after = text.splitlines()[-2]
    assert "after: targets met" in after


def test_design_weights_shift_the_change_between_hardpoints():
    model = solved("double_wishbone.yaml")
    specs = ["camber@travel=50=-2", "camber@travel=0=0"]
    plain = propagate_targets(model, specs, ["hardpoint:UBJ.j", "hardpoint:TR.i"])
    heavy = propagate_targets(model, specs, ["hardpoint:UBJ.j", "hardpoint:TR.i"], weights={"hardpoint:TR.i": 100.0})
    assert plain.targets_status == heavy.targets_status == "met"
    n = {k: np.linalg.norm(tp.design_change["TR.s_i"]) for k, tp in (("plain", plain), ("heavy", heavy))}
    assert n["heavy"] > 2 * n["plain"]


def test_output_jacobian_of_a_hardpoint_is_the_body_rotation():
    """The output map's central difference against the analytic d(r + A s')/ds' = A."""
    from kinprop import compile
    from kinprop.engine.targets import output_jacobian
    from kinprop.propagation.hardpoints import body_rotation

    model = solved("double_wishbone.yaml")
    eng = compile(model)
    k = eng.joint_index["UBJ"]

    def f(st):
        return eng.poses(st)[2][k, 1]

    cols = eng.columns(["UBJ.s_j"])
    G = output_jacobian(eng, f, eng.reference, cols)
    np.testing.assert_allclose(G, body_rotation(eng, eng.reference, k, 1), atol=1e-9)


def test_targets_on_frame_style_and_hardpoint_style_models_agree():
    """The same targets and free hardpoints on both styles of the double wishbone: the joints
    end up at the same global points (body frames differ between the styles)."""
    specs = ["camber@travel=50=-2", "toe@travel=50=0"]
    # the same reading of a hardpoint edit (the paper's; the hardpoint file's default is
    # edits: design, which also frees the tie rod's length with its inner point)
    data = yaml.safe_load((EXAMPLES / "double_wishbone_hardpoints.yaml").read_text()) | {"edits": "mechanism"}
    models = [solved("double_wishbone.yaml"), assemble(model_from_data(data), tol=1e-9).after]
    res = [propagate_targets(m, specs, ["hardpoint:UBJ.j", "hardpoint:TR.i"]) for m in models]
    assert [r.targets_status for r in res] == ["met", "met"]
    pa, pb = (r.joint_positions(0) for r in res)
    for key in pa:
        np.testing.assert_allclose(pa[key][1], pb[key][1], atol=1e-6)
    for key in ("UBJ.j", "TR.i"):
        np.testing.assert_allclose(res[0].hardpoint_moves()[key], res[1].hardpoint_moves()[key], atol=1e-6)


def test_slope_range_unit_written_once_applies_to_both_ends():
    model = load_model(EXAMPLES / "double_wishbone.yaml")  # mm
    spec = parse_target(model, "slope:toe@travel=-0.05..50mm=0")
    (a,), (b,), span = spec.slope
    assert (a.value, b.value, span) == pytest.approx((-0.05, 50.0, 50.05))
    spec = parse_target(model, "slope:toe@travel=-5..5cm=0")
    assert spec.slope[2] == pytest.approx(100.0)


def _tangent(engine, state):
    """Projector onto the coordinates' tangent space: Euler-parameter blocks lose their radial
    direction (the engine's Phi_q and the analytic rows are tangent derivatives, exact there)."""
    T = np.eye(engine.n_columns)
    for v in engine.layout.group("q"):
        jt = engine.mechanism.joint(v.joint).jtype
        if jt.euler is not None and v.size == jt.n_coordinates:
            c = np.arange(v.start, v.start + v.size)[jt.euler]
            p = state.Q[c]
            T[np.ix_(c, c)] -= np.outer(p, p) / (p @ p)
    return T


def test_analytic_output_jacobians_match_central_differences_of_the_output_map():
    from kinprop import compile, propagate
    from kinprop.analysis.targets import _config_jacobian, _config_outputs
    from kinprop.engine.targets import output_jacobian

    model = solved("double_wishbone.yaml")
    eng = compile(model)
    moved = propagate(model, {"LCA.q": [0.08], "TR.s_i": [-248.0, 450.0, 58.0]}, ["q"], engine=eng).after
    st = eng.state_of(moved)
    names = ["metric:upright.camber", "metric:upright.toe", "metric:upright.wheel_centre_dz",
             "point:upright.wheel_centre[y]", "hardpoint:UBJ.j[z]", "hardpoint:TR.i[x]", "hardpoint:LBJ.j[x]",
             "distance:upright.wheel_centre,hardpoint:TR.i", "UCA.q", "TR.length", "TR.s_j[1]",
             "metric:upright.caster", "metric:upright.kpi"]  # fmt: skip
    cols = np.arange(eng.n_columns)
    G = _config_jacobian(model, eng, names)(st, cols)
    F = output_jacobian(eng, _config_outputs(model, eng, names), st, cols)
    T = _tangent(eng, st)
    scale = np.maximum(1.0, np.abs(F).max(axis=1, keepdims=True))
    np.testing.assert_allclose((G @ T) / scale, (F @ T) / scale, atol=2e-7)
    assert np.abs(G).max() > 1.0  # not trivially zero


def test_analytic_and_difference_jacobians_give_the_same_design():
    model = solved("double_wishbone.yaml")
    specs = ["camber@travel=50=-2", "slope:toe@travel=-50..50=0"]
    a = propagate_targets(model, specs, ["hardpoint:UBJ", "hardpoint:TR.i"])
    f = propagate_targets(model, specs, ["hardpoint:UBJ", "hardpoint:TR.i"], analytic=False)
    assert a.targets_status == f.targets_status == "met"
    # an underdetermined Newton's end point depends (weakly) on the step directions taken
    for key in a.design_change:
        np.testing.assert_allclose(a.design_change[key], f.design_change[key], atol=1e-5)


@pytest.mark.parametrize(("output", "column"), [("toe", "TR.s_i[2]"), ("caster", "UBJ.s_j[0]")])
def test_a_slope_targets_row_is_its_exact_derivative(output: str, column: str) -> None:
    """A slope target's row in the target solver, reduced to the free design column with both
    travel conditions held (``T_p - T_u pinv(H_u) H_p``, the difference of its two
    configurations' exact rows: toe from the spin axis, caster from the steering axis), against
    central differences (Richardson) of re-solved models' slopes at the converged design."""
    from kinprop import propagate
    from kinprop.analysis.drives import outputs_at

    model = solved("double_wishbone.yaml")
    name = f"slope:{output}@travel=-30..30"
    key, k = column.split("[")[0], int(column[-2])
    s0 = outputs_at(model, [name])[name]
    tp = propagate_targets(model, [f"{name}={s0 + 1e-5}"], [column])
    assert tp.targets_status == "met"
    H, T, nu = tp.result.row_jacobians
    row = T[:, nu:] - T[:, :nu] @ np.linalg.pinv(H[:, :nu]) @ H[:, nu:]
    at = tp.propagation.after

    def slope(dp: float) -> float:
        v = np.array(at.design[key], dtype=float)
        v[k] += dp
        return outputs_at(propagate(at, {key: v}, ["q"], tol=1e-13).after, [name])[name]

    h = 0.2
    d1, d2 = (slope(h) - slope(-h)) / (2 * h), (slope(h / 2) - slope(-h / 2)) / h
    assert float(row[0, 0]) == pytest.approx((4 * d2 - d1) / 3, rel=1e-6)
