"""Kinetostatics (kinprop.engine.statics) against independent truth: virtual work with the
point velocity ratios from central differences of position solves (seeded random mechanisms,
every joint type), the cut joints' body partials against the kernel's Jacobian, and the
balance of every joint's free directions (a joint transmits nothing along the motion it
allows, except the input effort)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg

import kinprop as kp
from kinprop.engine.motion import _Frames
from kinprop.engine.statics import _cut_partials, generalized_forces, statics_state
from kinprop.kinematics.tables import (
    E_COL,
    E_ROW,
    J_BODY_I,
    J_BODY_J,
    J_NQ,
    J_QCOL,
    K_JOINT,
    K_ROW0,
    T_CHILD,
    T_JOINT,
    T_REVERSED,
)

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from random_mechanisms import assembled_set

RANDOM = assembled_set(40)


def _drivable(engine: kp.Engine, st: kp.State) -> list[int]:
    """Coordinate columns that, driven, determine the motion (Euler parameters last resort)."""
    J = engine.evaluate(st)[1][:, : engine.n_coordinates]
    _, s, Vt = np.linalg.svd(J)
    null = Vt[int(np.sum(s > 1e-9 * s[0])) :]
    if null.shape[0] == 0:
        return []
    weight = np.ones(engine.n_coordinates)
    for v in engine.layout.group("q"):
        jt = engine.mechanism.joint(v.joint).jtype
        if jt.euler is not None and v.joint in engine.topology.tree_joints:
            weight[v.start + jt.euler.start : v.start + jt.euler.stop] = 0.1
            weight[v.start + jt.euler.start] = 0.01
    _, R, piv = scipy.linalg.qr((null.T * weight[:, None]).T, pivoting=True)
    k = null.shape[0]
    if abs(R[k - 1, k - 1]) < 1e-2 * abs(R[0, 0]):
        return []
    return [int(c) for c in piv[:k]]


def _random_loads(rng: np.random.Generator, engine: kp.Engine) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A force at a random body-frame point and a couple on every moving body: (s, F, M) per body."""
    nb = len(engine.mechanism.bodies)
    s, F, M = rng.normal(size=(nb, 3)), rng.normal(size=(nb, 3)), rng.normal(size=(nb, 3))
    moving = np.array([not b.fixed for b in engine.mechanism.bodies])
    return s, F * moving[:, None], M * moving[:, None], moving


def _wrenches(r, A, s, F, M) -> np.ndarray:
    P = r + np.einsum("bij,bj->bi", A, s)
    return np.hstack([F, M + np.cross(P, F)])


def _virtual_work_efforts(engine, st, cols, s, F, M, h=1e-5) -> np.ndarray:
    """``tau_k = -sum_b (F_b . dP_b/dq_k + M_b . dtheta_b/dq_k)`` with the point velocities and
    the bodies' angular velocity ratios from central differences of position solves
    (Richardson: steps h and h/2)."""
    labels = engine.column_labels

    def once(k: int, step: float) -> float:
        poses = []
        for t in (-step, step):
            changes = {labels[c]: float(st.Q[c] + (t if m == k else 0.0)) for m, c in enumerate(cols)}  # others held
            sol = engine.propagate(changes, free=["q"], start=st, tol=1e-15)
            if not sol.converged:
                raise RuntimeError(sol.message)
            r, A, _, _ = engine.poses(sol.state)
            poses.append((r.copy(), A.copy()))
        (r0, A0), (r1, A1) = poses
        P0 = r0 + np.einsum("bij,bj->bi", A0, s)
        P1 = r1 + np.einsum("bij,bj->bi", A1, s)
        dP = (P1 - P0) / (2 * step)
        Wd = np.einsum("bij,bkj->bik", (A1 - A0) / (2 * step), 0.5 * (A0 + A1))  # dA A^T = tilde(omega)
        w = np.stack([Wd[:, 2, 1], Wd[:, 0, 2], Wd[:, 1, 0]], axis=1)
        return -float(np.sum(F * dP) + np.sum(M * w))

    return np.array([(4 * once(k, h / 2) - once(k, h)) / 3 for k in range(len(cols))])


@pytest.mark.parametrize("rm", RANDOM, ids=lambda rm: f"seed{rm.seed}")
def test_random_efforts_match_virtual_work(rm) -> None:
    engine = kp.compile(rm.model)
    st = engine.state_of(rm.model)
    cols = _drivable(engine, st)
    if not cols:
        pytest.skip("no drivable coordinates (mobility 0 or only Euler parameters)")
    rng = np.random.default_rng(100 + rm.seed)
    s, F, M, _ = _random_loads(rng, engine)
    r, A, _, _ = engine.poses(st)
    ss = statics_state(engine, st, _wrenches(r, A, s, F, M), cols)
    assert ss.ok, ss.message
    try:
        truth = _virtual_work_efforts(engine, st, cols, s, F, M)
    except RuntimeError as exc:
        pytest.skip(f"the position solves do not follow this drive ({exc}); no truth to compare with")
    determined = ~np.isnan(ss.efforts)
    assert determined.any()
    scale = max(1.0, float(np.max(np.abs(truth))))
    assert np.max(np.abs(ss.efforts[determined] - truth[determined])) < 1e-6 * scale


@pytest.mark.parametrize("rm", RANDOM[:20], ids=lambda rm: f"seed{rm.seed}")
def test_cut_partials_chain_to_the_kernels_jacobian(rm) -> None:
    """``sum_path Z T`` of every cut joint equals the kernel's ``Phi_q`` on the tree columns:
    the constraint wrenches ``Z^T lambda`` do the virtual work ``lambda^T Phi_q dq``."""
    engine = kp.compile(rm.model)
    st = engine.state_of(rm.model).writable()
    fr = _Frames(engine, st)
    tb = engine.tables
    rng = np.random.default_rng(rm.seed)
    nb = tb.fixed.shape[0]
    for c in range(tb.cut.shape[0]):
        j, r0 = tb.cut[c, K_JOINT], tb.cut[c, K_ROW0]
        Zi, Zj = _cut_partials(engine, fr.P, fr.R, st.Q, st.L, c)
        lam = rng.normal(size=Zi.shape[0])
        W = np.zeros((nb, 6))
        bi, bj = (
            engine.body_index[rm.model.mechanism.joints[j].body_i],
            engine.body_index[rm.model.mechanism.joints[j].body_j],
        )
        W[bi] += Zi.T @ lam
        W[bj] += Zj.T @ lam
        Qg = generalized_forces(engine, fr.Tq, W)
        want = fr.Phi_q[r0 : r0 + Zi.shape[0]].T @ lam
        tree_cols = [tb.joint[tb.tree[t, T_JOINT], J_QCOL] + k for t in range(tb.tree.shape[0])
                     for k in range(max(tb.joint[tb.tree[t, T_JOINT], J_NQ], 0))]  # fmt: skip
        assert np.allclose(Qg[tree_cols], want[tree_cols], atol=1e-10 * max(1.0, np.max(np.abs(want))))


@pytest.mark.parametrize("rm", RANDOM[:20], ids=lambda rm: f"seed{rm.seed}")
def test_tree_joints_transmit_nothing_along_their_free_motion(rm) -> None:
    """Each tree joint's reaction on its child does no work along the joint's own motion
    (``T_t^T W = 0``) except at a driven coordinate, where it is the effort; every moving body
    is in balance (applied wrench plus the reactions of every joint on it)."""
    engine = kp.compile(rm.model)
    st = engine.state_of(rm.model)
    cols = _drivable(engine, st)
    if not cols:
        pytest.skip("no drivable coordinates")
    rng = np.random.default_rng(200 + rm.seed)
    s, F, M, moving = _random_loads(rng, engine)
    r, A, _, _ = engine.poses(st)
    ss = statics_state(engine, st, _wrenches(r, A, s, F, M), cols)
    assert ss.ok
    fr = _Frames(engine, st)
    tb = engine.tables
    effort = dict(zip(cols, ss.efforts, strict=True))
    coupled = bool(rm.model.mechanism.couplings)  # coupling torques act along the free motion: balances only
    for t in range(tb.tree.shape[0] if not coupled else 0):
        j = tb.tree[t, T_JOINT]
        nq = tb.joint[j, J_NQ]
        if nq <= 0 or np.isnan(ss.wrench[j]).any():
            continue
        child = 0 if tb.tree[t, T_REVERSED] else 1
        assert (
            tb.tree[t, T_CHILD]
            == engine.body_index[getattr(rm.model.mechanism.joints[j], "body_i" if child == 0 else "body_j")]
        )
        work = fr.Tq[t, :, :nq].T @ ss.wrench[j, child]
        q0 = tb.joint[j, J_QCOL]
        want = np.array([effort.get(q0 + k, 0.0) for k in range(nq)])
        for e in range(tb.euler.shape[0]):  # the normalisation row's multiplier: 2 p lambda_e
            col = tb.euler[e, E_COL]
            if q0 <= col < q0 + nq:
                want[col - q0 : col - q0 + 4] += 2.0 * st.Q[col : col + 4] * ss.lam[tb.euler[e, E_ROW]]
        scale = max(1.0, float(np.max(np.abs(ss.wrench[~np.isnan(ss.wrench)]))))
        assert np.allclose(work, want, atol=1e-9 * scale)
    total = np.array(ss.applied)
    for k, jt in enumerate(rm.model.mechanism.joints):
        total[engine.body_index[jt.body_i]] += ss.wrench[k, 0]
        total[engine.body_index[jt.body_j]] += ss.wrench[k, 1]
    bad = np.isnan(total).any(axis=1)
    assert np.allclose(total[moving & ~bad], 0.0, atol=1e-9 * max(1.0, float(np.nanmax(np.abs(ss.wrench)))))


def _random_point_forces(rng: np.random.Generator, engine: kp.Engine, r, A):
    from kinprop.engine.statics import ElementLaw, PointForces, TorsionLaw

    moving = [k for k, b in enumerate(engine.mechanism.bodies) if not b.fixed]
    fixed = [k for k, b in enumerate(engine.mechanism.bodies) if b.fixed]
    body = np.array(moving, np.int64)
    s = rng.normal(size=(len(moving), 3))
    P = r[body] + np.einsum("bij,bj->bi", A[body], s)
    follows = rng.uniform(size=len(moving)) < 0.5
    loads = PointForces(body, P, rng.normal(size=(len(moving), 3)), rng.normal(size=(len(moving), 3)), follows)
    local = [(s[k], A[body[k]].T @ loads.F[k], A[body[k]].T @ loads.M[k]) for k in range(len(moving))]
    laws = []
    for _ in range(2):
        bi = int(rng.choice(fixed + moving))
        bj = int(rng.choice([b for b in moving if b != bi]))
        laws.append(ElementLaw(bi, bj, rng.normal(size=3), rng.normal(size=3), float(rng.uniform(1, 5)),
                               float(rng.uniform(0.5, 2)), float(rng.normal())))  # fmt: skip
    tb = engine.tables
    for t in range(tb.tree.shape[0]):  # a torsion spring on every revolute and cylindrical tree joint's angle
        j = int(tb.tree[t, T_JOINT])
        if engine.mechanism.joints[j].jtype.name in ("revolute", "cylindrical"):
            laws.append(TorsionLaw(j, int(tb.joint[j, J_BODY_I]), int(tb.joint[j, J_BODY_J]), int(tb.joint[j, J_QCOL]),
                                   float(rng.uniform(1, 5)), float(rng.normal()), float(rng.normal())))  # fmt: skip
    return loads, local, laws


def _loads_at(engine, st, loads, local):
    """The same loads at another pose: material points; body-axes components turn, global ones do not."""
    from kinprop.engine.statics import PointForces

    r, A, _, _ = engine.poses(st)
    P = np.array([r[b] + A[b] @ local[k][0] for k, b in enumerate(loads.body)])
    F = np.array([A[b] @ local[k][1] if loads.follows[k] else loads.F[k] for k, b in enumerate(loads.body)])
    M = np.array([A[b] @ local[k][2] if loads.follows[k] else loads.M[k] for k, b in enumerate(loads.body)])
    return PointForces(loads.body, P, F, M, loads.follows).wrenches(r.shape[0])


@pytest.mark.parametrize("rm", RANDOM[:24], ids=lambda rm: f"seed{rm.seed}")
def test_reduced_stiffness_matches_central_differences(rm) -> None:
    """``K = d tau / d q_D`` (analytic, second-order kinematics) against central differences of
    the statics efforts at re-solved poses (other inputs held), springs and follower loads."""
    from kinprop.engine.statics import reduced_stiffness

    engine = kp.compile(rm.model)
    st = engine.state_of(rm.model)
    cols = _drivable(engine, st)
    if not cols or len(engine.mechanism.bodies) < 3:
        pytest.skip("no drivable coordinates")
    rng = np.random.default_rng(300 + rm.seed)
    r, A, _, _ = engine.poses(st)
    loads, local, laws = _random_point_forces(rng, engine, np.array(r), np.array(A))
    tau, K, msg = reduced_stiffness(engine, st, loads, cols, laws)
    assert msg == ""
    ss = statics_state(engine, st, loads.wrenches(len(r)), cols, laws)
    assert np.allclose(tau, ss.efforts, atol=1e-9 * max(1.0, np.max(np.abs(tau))))
    labels = engine.column_labels

    def efforts_at(m: int, t: float) -> np.ndarray:
        changes = {labels[c]: float(st.Q[c] + (t if k == m else 0.0)) for k, c in enumerate(cols)}
        sol = engine.propagate(changes, free=["q"], start=st, tol=1e-15)
        if not sol.converged:
            raise RuntimeError(sol.message)
        return statics_state(engine, sol.state, _loads_at(engine, sol.state, loads, local), cols, laws).efforts

    h = 1e-4
    try:
        half = [(efforts_at(m, h / 2) - efforts_at(m, -h / 2)) / h for m in range(len(cols))]
        full = [(efforts_at(m, h) - efforts_at(m, -h)) / (2 * h) for m in range(len(cols))]
        fd = np.column_stack([(4 * a - b) / 3 for a, b in zip(half, full, strict=True)])
    except RuntimeError as exc:
        pytest.skip(f"the position solves do not follow this drive ({exc})")
    scale = max(1.0, float(np.max(np.abs(fd))))
    assert np.max(np.abs(K - fd)) < 1e-6 * scale


@pytest.mark.parametrize("rm", RANDOM, ids=lambda rm: f"seed{rm.seed}")
def test_design_rates_match_central_differences_of_re_solved_models(rm) -> None:
    """Exact design derivatives (kinprop.engine.statics_rates, the differentiated equilibrium)
    of the efforts, every determined reaction component (global and joint-frame), the rods'
    tensions and the element forces, for design columns of every kind (s', C, lengths, coupling
    coefficients), against Richardson central differences of the statics at re-solved states
    (the design column changed, the inputs held, the other coordinates re-solved)."""
    from kinprop.engine.statics_rates import statics_rates

    engine = kp.compile(rm.model)
    st = engine.state_of(rm.model)
    cols = _drivable(engine, st)
    if not cols or len(engine.mechanism.bodies) < 3:
        pytest.skip("no drivable coordinates")
    rng = np.random.default_rng(400 + rm.seed)
    r, A, _, _ = engine.poses(st)
    loads, local, laws = _random_point_forces(rng, engine, np.array(r), np.array(A))
    nq = engine.n_coordinates
    free = np.array([c for c in range(nq) if c not in cols], np.int64)
    J = engine.evaluate(st)[1]
    X = np.eye(engine.n_columns)[nq:]
    X[:, free] = -np.linalg.lstsq(J[:, free], J[:, nq:], rcond=None)[0].T
    # design columns the coordinates can follow (a redundant mechanism's others break the assembly)
    tangent = np.flatnonzero(np.max(np.abs(J @ X.T), axis=0) < 1e-9 * max(1.0, float(np.max(np.abs(J)))))
    if tangent.size == 0:
        pytest.skip("no design column the coordinates can follow")
    pick = rng.choice(tangent, size=min(6, tangent.size), replace=False)
    design, X = nq + pick, X[pick]
    rates = statics_rates(engine, st, loads, X, cols, laws)
    ss = rates.statics
    assert ss.ok, ss.message

    def values(s, k: int | None = None) -> np.ndarray:
        arrays = (s.efforts, s.at_point, s.local, s.member, s.element_force)
        return np.concatenate([(a if k is None else a[k]).ravel() for a in arrays])

    def at(c: int, t: float) -> np.ndarray:
        dx = np.zeros(engine.n_columns)
        dx[c] = t
        sol = engine.solve(engine.retract(st, dx), free, tol=1e-15)
        if not sol.converged:
            raise RuntimeError(sol.message)
        return values(statics_state(engine, sol.state, _loads_at(engine, sol.state, loads, local), cols, laws))

    h = 3e-6  # small: some random poses are ill-conditioned (seed 28: derivatives 1e3 x the loads)
    got = np.array([values(rates, k) for k in range(design.size)])
    try:
        fd = np.array([(4 * (at(c, h / 2) - at(c, -h / 2)) / h - (at(c, h) - at(c, -h)) / (2 * h)) / 3 for c in design])
    except RuntimeError as exc:
        pytest.skip(f"the position solves do not follow this change ({exc})")
    known = ~np.isnan(values(ss))
    assert known.sum() > 10
    assert np.array_equal(~np.isnan(got), np.broadcast_to(known, got.shape))  # NaN exactly where undetermined
    scale = max(1.0, float(np.max(np.abs(fd[:, known]))))
    err = np.abs(got[:, known] - fd[:, known])
    assert np.max(err) < 3e-7 * scale, (engine.column_labels[design[np.argmax(err.max(axis=1))]], np.max(err) / scale)


@pytest.mark.parametrize("rm", RANDOM[:8], ids=lambda rm: f"seed{rm.seed}")
def test_design_rates_are_the_rates_along_the_held_input_response(rm) -> None:
    """``design_rates`` (one evaluation, the coordinates' response inside) gives the direction
    ``e_p + dq/dp`` with the inputs held (an independent least-squares solve on the engine's
    Jacobian here) and the rates of :func:`statics_rates` along it (checked against central
    differences of re-solved models above)."""
    from kinprop.engine.statics_rates import design_rates, statics_rates

    engine = kp.compile(rm.model)
    st = engine.state_of(rm.model)
    cols = _drivable(engine, st)
    if not cols or len(engine.mechanism.bodies) < 3:
        pytest.skip("no drivable coordinates")
    rng = np.random.default_rng(500 + rm.seed)
    r, A, _, _ = engine.poses(st)
    loads, _, laws = _random_point_forces(rng, engine, np.array(r), np.array(A))
    nq = engine.n_coordinates
    design = nq + rng.choice(engine.n_columns - nq, size=min(5, engine.n_columns - nq), replace=False)
    free = np.array([c for c in range(nq) if c not in cols], np.int64)
    J = engine.evaluate(st)[1]
    X = np.eye(engine.n_columns)[design]
    X[:, free] = -np.linalg.lstsq(J[:, free], J[:, design], rcond=None)[0].T
    got, Xg = design_rates(engine, st, loads, design, cols, laws)
    assert np.allclose(Xg, X, rtol=1e-9, atol=1e-9 * max(1.0, float(np.max(np.abs(X)))))
    ref = statics_rates(engine, st, loads, X, cols, laws)
    for name in ("efforts", "at_point", "local", "member", "element_force"):
        a, b = getattr(got, name), getattr(ref, name)
        assert np.array_equal(np.isnan(a), np.isnan(b))
        scale = max(1.0, float(np.nanmax(np.abs(b))) if np.isfinite(b).any() else 1.0)
        assert np.nanmax(np.abs(a - b), initial=0.0) < 1e-7 * scale, name
