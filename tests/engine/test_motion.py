"""Velocity and acceleration analysis (kinprop.engine.motion, kp.motion) against closed forms
(the four-bar's and the offset slider-crank's loop equations differentiated by hand, as in
Norton, Design of Machinery, secs. 6.7 and 7.3), against central differences of position
solves along the branch (every tree joint type, every cut type, couplings: seeded random
mechanisms), and the singular status at a dead centre."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg

import kinprop as kp
from kinprop.analysis.motion import motion

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from random_mechanisms import CUT_TYPES, TREE_TYPES, assembled_set

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
D = math.pi / 180.0


def _at(model: kp.Model, changes: dict[str, float]) -> kp.Model:
    prop = kp.propagate(model, changes, free=["q"], tol=1e-13)
    assert prop.result.status == "converged"
    return prop.after


def _loop_rates(a, b, c, t2, t3, t4, w2, al2):
    # velocity: i a w2 e2 + i b w3 e3 - i c w4 e4 = 0 -> [[-b s3, c s4], [b c3, -c c4]] [w3, w4] = [a w2 s2, -a w2 c2]
    M = np.array([[-b * math.sin(t3), c * math.sin(t4)], [b * math.cos(t3), -c * math.cos(t4)]])
    w3, w4 = np.linalg.solve(M, [a * w2 * math.sin(t2), -a * w2 * math.cos(t2)])
    # acceleration: (i al - w^2) terms
    rhs = [
        a * al2 * math.sin(t2) + a * w2**2 * math.cos(t2) + b * w3**2 * math.cos(t3) - c * w4**2 * math.cos(t4),
        -a * al2 * math.cos(t2) + a * w2**2 * math.sin(t2) + b * w3**2 * math.sin(t3) - c * w4**2 * math.sin(t4),
    ]
    al3, al4 = np.linalg.solve(M, rhs)
    return w3, w4, al3, al4


@pytest.mark.parametrize("crank_deg", [20.0, 60.0, 135.0, 250.0])
def test_fourbar_matches_closed_form(crank_deg: float) -> None:
    model = _at(kp.load_model(EXAMPLES / "fourbar.yaml"), {"O2.q": [crank_deg]})
    w2, al2 = 2.0, -3.0  # rad/s, rad/s^2 given as deg in the degree model
    mo = motion(model, {"O2": w2 / D}, {"O2": al2 / D})
    assert mo.ok
    t2 = crank_deg * D
    t3 = t2 + float(model.coordinates["A"][0])
    t4 = float(model.coordinates["O4"][0])
    w3, w4, al3, al4 = _loop_rates(0.15, 0.40, 0.30, t2, t3, t4, w2, al2)
    assert mo.rate("O4.q") * D == pytest.approx(w4, rel=1e-10, abs=1e-12)
    assert mo.body_twist("coupler").angular[2] * D == pytest.approx(w3, rel=1e-10, abs=1e-12)
    assert mo.acceleration("O4.q") * D == pytest.approx(al4, rel=1e-9, abs=1e-11)
    assert mo.body_acceleration("coupler").angular[2] * D == pytest.approx(al3, rel=1e-9, abs=1e-11)
    # the coupler point P: velocity of a point of a rotating body, from the closed form
    P = np.array([0.15 * math.cos(t2), 0.15 * math.sin(t2)]) + np.array(
        [0.2 * math.cos(t3) - 0.1 * math.sin(t3), 0.2 * math.sin(t3) + 0.1 * math.cos(t3)]
    )
    A = np.array([0.15 * math.cos(t2), 0.15 * math.sin(t2)])
    vA = 0.15 * w2 * np.array([-math.sin(t2), math.cos(t2)])
    vP = vA + w3 * np.array([-(P - A)[1], (P - A)[0]])
    assert np.allclose(mo.point_velocity("point:coupler.P")[:2], vP, rtol=1e-10, atol=1e-12)
    aA = 0.15 * al2 * np.array([-math.sin(t2), math.cos(t2)]) - 0.15 * w2**2 * np.array([math.cos(t2), math.sin(t2)])
    aP = aA + al3 * np.array([-(P - A)[1], (P - A)[0]]) - w3**2 * (P - A)
    assert np.allclose(mo.point_acceleration("point:coupler.P")[:2], aP, rtol=1e-9, atol=1e-11)
    # the coupler's instant centre (Kennedy): where the crank line O2-A meets the rocker line O4-B
    ic = mo.instant_centre("coupler")
    O4, B = np.array([0.40, 0.0]), np.array([0.40 + 0.30 * math.cos(t4), 0.30 * math.sin(t4)])
    s = np.linalg.solve(np.column_stack([A, -(B - O4)]), O4)
    assert np.allclose(ic[:2], s[0] * A, atol=1e-9)
    axis = mo.screw_axis("coupler", relative_to="crank")
    assert axis.pitch == pytest.approx(0.0, abs=1e-12) and np.allclose(axis.point[:2], A, atol=1e-12)


@pytest.mark.parametrize("crank_deg", [30.0, 100.0, 200.0, 300.0])
def test_offset_slider_crank_matches_closed_form(crank_deg: float) -> None:
    a, b, c = 0.10, 0.35, 0.05  # crank, rod, offset of the slider line y = c
    model = _at(kp.load_model(EXAMPLES / "slider_crank_offset.yaml"), {"O2.q": [crank_deg]})
    w2, al2 = -1.5, 4.0
    mo = motion(model, {"O2": w2 / D}, {"O2": al2 / D})
    t2 = crank_deg * D
    t3 = math.asin((c - a * math.sin(t2)) / b)
    assert math.remainder(t2 + float(model.coordinates["A"][0]) - t3, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)
    w3 = -a * w2 * math.cos(t2) / (b * math.cos(t3))
    xdot = -a * w2 * math.sin(t2) - b * w3 * math.sin(t3)
    al3 = (a * w2**2 * math.sin(t2) + b * w3**2 * math.sin(t3) - a * al2 * math.cos(t2)) / (b * math.cos(t3))
    xddot = -a * al2 * math.sin(t2) - a * w2**2 * math.cos(t2) - b * al3 * math.sin(t3) - b * w3**2 * math.cos(t3)
    assert mo.rate("P.q") == pytest.approx(xdot, rel=1e-10)
    assert mo.acceleration("P.q") == pytest.approx(xddot, rel=1e-9)
    assert mo.point_velocity("hardpoint:B.j")[0] == pytest.approx(xdot, rel=1e-10)
    assert mo.point_acceleration("hardpoint:B.i")[0] == pytest.approx(xddot, rel=1e-9)
    assert mo.screw_axis("slider").is_translation


class _NoTruthError(Exception):
    """The position solves cannot follow the drive (no central-difference truth there)."""


def _central(engine: kp.Engine, st: kp.State, cols: list[int], rates: np.ndarray, acc: np.ndarray, h: float):
    """qdot, qddot by central differences of position solves along q_D(t) = q_D + rates t + acc t^2 / 2,
    Richardson-extrapolated from steps h and h/2 (10 h and 5 h for qddot; error O(h^4))."""
    d1, _ = _central_once(engine, st, cols, rates, acc, h)
    e1, _ = _central_once(engine, st, cols, rates, acc, h / 2)
    _, d2 = _central_once(engine, st, cols, rates, acc, 10 * h)  # second differences: a larger step (round-off / h^2)
    _, e2 = _central_once(engine, st, cols, rates, acc, 5 * h)
    return (4 * e1 - d1) / 3, (4 * e2 - d2) / 3


def _central_once(engine: kp.Engine, st: kp.State, cols: list[int], rates: np.ndarray, acc: np.ndarray, h: float):
    labels = engine.column_labels
    Qs = []
    for t in (-h, 0.0, h):
        changes = {labels[c]: float(st.Q[c] + rates[k] * t + 0.5 * acc[k] * t * t) for k, c in enumerate(cols)}
        sol = engine.propagate(changes, free=["q"], start=st, tol=1e-15)
        if not sol.converged:
            raise _NoTruthError(sol.message)
        Qs.append(sol.state.Q)
    return (Qs[2] - Qs[0]) / (2 * h), (Qs[2] - 2 * Qs[1] + Qs[0]) / h**2


def _drivable(engine: kp.Engine, st: kp.State) -> list[int]:
    """Coordinate columns that, driven, determine the motion (Euler parameters last resort)."""
    J = engine.evaluate(st)[1][:, : engine.n_coordinates]
    _, s, Vt = np.linalg.svd(J)
    null = Vt[int(np.sum(s > 1e-9 * s[0])) :]
    weight = np.ones(engine.n_coordinates)
    for v in engine.layout.group("q"):
        jt = engine.mechanism.joint(v.joint).jtype
        if jt.euler is not None and v.joint in engine.topology.tree_joints:
            weight[v.start + jt.euler.start : v.start + jt.euler.stop] = 0.1
            weight[v.start + jt.euler.start] = 0.01  # e0 follows the others best
    N = null.T * weight[:, None]
    if null.shape[0] == 0:
        return []
    _, R, piv = scipy.linalg.qr(N.T, pivoting=True)
    k = null.shape[0]
    if abs(R[k - 1, k - 1]) < 1e-2 * abs(R[0, 0]):
        return []
    return [int(c) for c in piv[:k]]


RANDOM = assembled_set(40)


def _drivable_setup(rm):
    """``(engine, state, drivable columns, seeded generator)`` of a random mechanism (skips one
    that has none)."""
    engine = kp.compile(rm.model)
    st = engine.state_of(rm.model)
    cols = _drivable(engine, st)
    if not cols:
        pytest.skip("no drivable coordinates (mobility 0 or only Euler parameters)")
    return engine, st, cols, np.random.default_rng(rm.seed)


@pytest.mark.parametrize("rm", RANDOM, ids=lambda rm: f"seed{rm.seed}")
def test_random_mechanisms_match_central_differences(rm) -> None:
    engine, st, cols, rng = _drivable_setup(rm)
    rates, acc = rng.uniform(-1, 1, len(cols)), rng.uniform(-1, 1, len(cols))
    labels = engine.column_labels
    ms = engine.motion(
        st, {labels[c]: rates[k] for k, c in enumerate(cols)}, {labels[c]: acc[k] for k, c in enumerate(cols)}
    )
    assert ms.ok, ms.message
    try:
        qd, qdd = _central(engine, st, cols, rates, acc, 1e-4)
    except _NoTruthError as exc:
        pytest.skip(f"the position solves do not follow this drive ({exc}); no truth to compare with")
    scale = max(1.0, float(np.max(np.abs(qd))))
    assert np.max(np.abs(ms.qdot - qd)) < 1e-8 * scale
    assert np.max(np.abs(ms.qddot - qdd)) < 1e-6 * max(1.0, float(np.max(np.abs(qdd))))


def test_random_suite_covers_every_type() -> None:
    """The seeds above that are checked (drivable, and the position solves follow the drive)
    cover every tree type and every cut type."""
    tree, cut = set(), set()
    for rm in RANDOM:
        engine = kp.compile(rm.model)
        st = engine.state_of(rm.model)
        cols = _drivable(engine, st)
        try:
            _central_once(engine, st, cols, np.ones(len(cols)), np.zeros(len(cols)), 1e-4)
        except _NoTruthError:
            continue
        if cols:
            for j in rm.model.mechanism.joints:
                (tree if j.name.startswith("T") else cut).add(j.jtype.name)
    assert set(TREE_TYPES) <= tree, set(TREE_TYPES) - tree
    assert set(CUT_TYPES) <= cut, set(CUT_TYPES) - cut


@pytest.mark.parametrize(
    ("file", "drive"),
    [
        ("fourbar.yaml", "O2.q"),
        ("double_wishbone.yaml", "LCA.q"),
        ("slider_crank_offset.yaml", "O2.q"),
        ("fourbar_geared.yaml", "G.q"),
    ],
)
def test_shipped_models_match_central_differences(file: str, drive: str) -> None:
    model = kp.assemble(kp.load_model(EXAMPLES / file)).after
    engine = kp.compile(model)
    st = engine.state_of(model)
    c = engine.target(drive).start
    ms = engine.motion(st, {drive: 0.7}, {drive: -0.4})
    qd, qdd = _central(engine, st, [c], np.array([0.7]), np.array([-0.4]), 2e-3)
    assert np.allclose(ms.qdot, qd, rtol=1e-8, atol=1e-8 * np.max(np.abs(qd)))
    assert np.allclose(ms.qddot, qdd, rtol=1e-5, atol=1e-6 * max(1.0, np.max(np.abs(qdd))))


def test_dead_centre_is_singular_not_garbage() -> None:
    """The offset slider-crank at its outer dead centre (crank and rod in line): the slider's
    rate cannot drive the crank."""
    a, b, c = 0.10, 0.35, 0.05
    t2 = math.asin(c / (a + b))
    model = _at(kp.load_model(EXAMPLES / "slider_crank_offset.yaml"), {"O2.q": [t2 / D]})
    assert math.remainder(float(model.coordinates["A"][0]), 2 * math.pi) == pytest.approx(
        0.0, abs=1e-6
    )  # rod in line with the crank
    mo = motion(model, {"P": 1.0}, {"P": 0.0})
    assert mo.status == "singular" and "singular" in mo.message
    assert all(np.isnan(v).all() for v in mo.rates.values())
    assert mo.ok is False
    # the crank drives it fine there (the slider is at rest)
    mo = motion(model, {"O2": 1.0})
    assert mo.ok and mo.rate("P.q") == pytest.approx(0.0, abs=1e-12)


def test_velocity_ratios_of_outputs() -> None:
    """The slider-crank's d(slider)/d(crank) by the closed form, and a distance's rate."""
    a, b, c = 0.10, 0.35, 0.05
    model = _at(kp.load_model(EXAMPLES / "slider_crank_offset.yaml"), {"O2.q": [75.0]})
    mo = motion(model, {"O2": 1.0})
    t2 = 75.0 * D
    t3 = math.asin((c - a * math.sin(t2)) / b)
    w3 = -a * math.cos(t2) / (b * math.cos(t3))
    xdot = (-a * math.sin(t2) - b * w3 * math.sin(t3)) * D  # per degree of crank
    assert mo.ratio("P.q", "O2") == pytest.approx(xdot, rel=1e-10)
    assert mo.ratio("hardpoint:B.j[x]", "O2.q") == pytest.approx(xdot, rel=1e-10)
    # the distance from the crank pin to the slider: d/dt |B - A| = 0 (the rod is rigid)
    assert mo.output_rate("distance:hardpoint:A.i,hardpoint:B.j") == pytest.approx(0.0, abs=1e-12)


def test_an_unassembled_state_says_so() -> None:
    raw = kp.load_model(EXAMPLES / "fourbar.yaml")  # the file's estimates: not an assembly
    mo = motion(raw, {"O2": 1.0}, {"O2": 0.0})
    assert mo.status == "not_assembled" and "assemble" in mo.message
    assert all(np.isnan(v).all() for v in mo.rates.values())
    assert np.isnan(mo.body_twist("rocker").angular).all()


def _resolved_path(engine: kp.Engine, st: kp.State, col: int, rates: dict[str, float], h: float):
    """Design column ``col`` moved by ``t`` (retraction: additive, or ``exp`` for C), the
    coordinates re-solved (free q, closest assembly): the state direction, the rates' and the
    twists' derivatives along that path by Richardson central differences of re-solved models."""

    def at(t: float):
        dx = np.zeros(engine.n_columns)
        dx[col] = t
        sol = engine.solve(st, ("q",), target=engine.retract(st, dx), tol=1e-15)
        if not sol.converged:
            raise _NoTruthError(sol.message)
        ms = engine.motion(sol.state, rates)
        return sol.state.Q, ms.qdot, ms.V

    def d(k: float):
        plus, minus = at(k * h), at(-k * h)
        return [(p - m) / (2 * k * h) for p, m in zip(plus, minus, strict=True)]

    return [(4 * a - b) / 3 for a, b in zip(d(0.5), d(1.0), strict=True)]


@pytest.mark.parametrize("rm", RANDOM, ids=lambda rm: f"seed{rm.seed}")
def test_design_derivatives_of_rates_match_re_solved_models(rm) -> None:
    """``motion_derivatives``: the exact derivatives of every coordinate rate and body twist
    with respect to design variables (s', C, lengths, coupling coefficients: four seeded
    columns per mechanism) along the re-solved path, against Richardson central differences of
    velocity analyses of re-solved models."""
    from kinprop.engine.motion import motion_derivatives

    engine, st, cols, rng = _drivable_setup(rm)
    labels = engine.column_labels
    rates = {labels[c]: float(r) for c, r in zip(cols, rng.uniform(-1, 1, len(cols)), strict=True)}
    nq = engine.n_coordinates
    design = rng.choice(np.arange(nq, engine.n_columns), size=min(4, engine.n_columns - nq), replace=False)
    checked = 0
    for col in design:
        try:
            dQ, dqdot, dV = _resolved_path(engine, st, int(col), rates, 1e-4)
        except _NoTruthError:
            continue
        direction = np.zeros(engine.n_columns)
        direction[col], direction[:nq] = 1.0, dQ
        md = motion_derivatives(engine, st, rates, direction[:, None])
        assert md.motion.ok, md.motion.message
        sq, sv = max(1.0, float(np.max(np.abs(dqdot)))), max(1.0, float(np.max(np.abs(dV))))
        assert np.max(np.abs(md.qdot[0] - dqdot)) < 1e-7 * sq, labels[col]
        assert np.max(np.abs(md.V[0] - dV)) < 1e-7 * sv, labels[col]
        checked += 1
    if not checked:
        pytest.skip("the position solves do not follow these design changes; no truth to compare with")


def test_compiled_velocity_solve_agrees_with_the_svd_path() -> None:
    """``velocity_solve`` (compiled, LU on the engine's plan) gives the rates and twists of the
    SVD path on every random mechanism it takes (square regular blocks) and on the double
    wishbone; where it cannot decide (a rectangular or singular block) the SVD path answers."""
    from kinprop.engine.motion import _compiled_motion, _Frames, _motion

    model = kp.assemble(kp.load_model(EXAMPLES / "double_wishbone.yaml")).after
    cases = [(kp.compile(model), model, ["LCA.q"])] + [(kp.compile(rm.model), rm.model, None) for rm in RANDOM]
    taken = 0
    for engine, m, drive in cases:
        st = engine.state_of(m)
        cols = [engine.target(d).start for d in drive] if drive else _drivable(engine, st)
        if not cols:
            continue
        labels = engine.column_labels
        rates = {labels[c]: 0.3 + 0.1 * k for k, c in enumerate(cols)}
        fast = _compiled_motion(engine, st, rates)
        svd, _ = _motion(engine, _Frames(engine, st), rates, None)
        if fast is None:
            assert engine.motion(st, rates).qdot.tolist() == svd.qdot.tolist() or not svd.ok
            continue
        taken += 1
        assert svd.ok, svd.message
        scale = max(1.0, float(np.max(np.abs(svd.qdot))))
        assert np.max(np.abs(fast.qdot - svd.qdot)) < 1e-10 * scale
        assert np.max(np.abs(fast.V - svd.V)) < 1e-10 * max(1.0, float(np.max(np.abs(svd.V))))
        assert fast.residual == pytest.approx(svd.residual, rel=1e-6, abs=1e-14)
    assert taken >= 20


def test_gamma_of_a_length_rate_is_the_second_derivative_of_phi() -> None:
    """Haug's ``gamma`` along a state rate that changes a distance joint's length (the RSSR's
    coupler, ``coupler.length``) together with the coordinates and an attachment point: minus
    the second derivative of ``Phi(retract(x, t xdot))`` (central differences of the kernel's
    residual; revolute tree joints, so the straight line in q is the path). The distance row
    carries ``2 ldot^2``; the polarisation in ``motion_derivatives`` cancels it, so only this
    test sees it (removing the term misses by ``2 ldot^2 = 2``)."""
    from kinprop.builders import rssr
    from kinprop.engine.motion import _Frames, _gamma, _tree_bias, _tree_velocities

    model = kp.assemble(rssr()).after
    engine = kp.compile(model)
    st = engine.state_of(model)
    xdot = np.zeros(engine.n_columns)
    xdot[: engine.n_coordinates] = engine.motion(st, {"crank.q": 0.7}).qdot
    lcol = engine.target("coupler.length").start
    xdot[lcol] = 1.0
    xdot[engine.columns(["coupler.s_i"])] = [0.3, -0.2, 0.5]
    fr = _Frames(engine, st, design=True)
    V = _tree_velocities(engine, fr, xdot)
    gamma = _gamma(engine, fr, xdot, V, _tree_bias(engine, fr, xdot, V))

    def d2(h: float) -> np.ndarray:
        phi = [engine.evaluate(engine.retract(st, t * xdot))[0] for t in (-h, 0.0, h)]
        return (phi[0] - 2 * phi[1] + phi[2]) / h**2

    truth = (4 * d2(5e-4) - d2(1e-3)) / 3  # Richardson
    assert np.max(np.abs(gamma + truth)) < 1e-6 * max(1.0, float(np.max(np.abs(truth))))
    (tr,) = [r for r, lab in enumerate(engine.row_labels) if lab.startswith("coupler:")]
    without = gamma[tr] - 2.0 * xdot[lcol] ** 2  # the row without its length-rate term
    assert abs(without + truth[tr]) > 1.0
