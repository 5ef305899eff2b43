"""Exact rates of the loads of an assembled state along directions of the state: design
derivatives of reactions, rod tensions, element forces and input efforts (direct method).

A direction ``xdot`` (every layout column: coordinates and design variables; the caller
makes it tangent to the constraints, ``Phi_x xdot = 0``, e.g. ``e_k + dq/dp_k`` from the
implicit-function theorem) moves every body with a twist ``V`` and every joint frame with a
twist ``U``: in the tree ``U_a = V_parent + D_a``, ``U_b = U_a + T_t qdot_t``, ``V_child = U_b
- D_b``; on a cut joint ``U_s = V_body + D_s``, where ``D_s = [A s'dot + P x A xi'dot ; A
xi'dot]`` is the frame's own design motion on its body (the kernel's M and N twists, eq. 35).

Equilibrium ``G(x, y) = Phi_q^T lambda + Q + E_D^T tau = 0`` with ``y = (lambda, tau)`` is
linear in ``y``; along ``xdot``: ``[Phi_q^T  E_D^T] ydot = -((Phi_q^T lambda)_x + Q_x) xdot``
(the terms ``(Phi_q^T lambda)_q dq/dp + (Phi_q^T lambda)_p + dQ/dp``). The right-hand side is
written analytically in the twist form of :mod:`kinprop.engine.statics`: ``G_t = T_t^T
W_sub(t)`` with ``W`` every wrench (applied, elements, cut-joint ``Z^T lambda``), so ``dG_t =
dT_t^T W_sub + T_t^T dW_sub`` with

* ``dT_t = U_i x T_t + sign Ad_i dt_loc`` (``x`` the spatial cross product, ``U_i`` joint
  frame i's twist, ``dt_loc`` the rate of the joint's local twist ``[dd'' + d'' x H'' ; H'']``
  from its coordinates' rates: universal, spherical, S-T and free joints);
* a cut joint's wrench ``[-f ; f x P_i + m_i]`` on body i and ``[f ; -f x P_j + m_j]`` on
  body j (``f = Phi_d^T lambda``, ``m = Phi_w^T lambda``) with the basic constraints' partial
  rates: dot-1 ``d(a_i x a_j)``, dot-2 ``da``, ``d(a x d)``, distance ``2 dd``, spherical 0;
* loads at material points ``dM_O = v_P x F + P x dF`` (``dF = omega x F`` in body axes); a
  wheel's contact point moves as the lowest point of the wheel circle, not with the wheel;
  elements ``d(f u)`` with ``df = -k dL`` (0 for a force held at its preload);
* Euler rows ``2 pdot lambda``; coupling rows ``lambda d(Phi_qb)``; a T-D joint's own
  column ``-(df . e + f . de)``.

The same solve as the statics (SVD of the scaled matrix; a redundant mechanism's
undetermined components stay NaN, the determined ones have exact rates). The reactions'
rates follow from ``ydot``: ``dZ^T lambda + Z^T lambda_dot`` on cut joints, minus the
subtree sums' rates on tree joints, then moved to the joint points and into joint frame i.
Every rate is batched over the directions (leading axis ``K``). Tests check each against
central differences of re-solved models (tests/engine/test_statics_rates.py).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from kinprop.constraints.basic import DISTANCE, DOT1, DOT2, ROWS
from kinprop.engine.motion import _Frames
from kinprop.engine.statics import (
    Law,
    PointForces,
    StaticsState,
    _cross,
    _cut_rows,
    _reactions,
    _velocity,
    cut_arms,
    element_rates,
    equilibrium_system,
    load_rates,
    statics_state,
    subtree_sums,
)
from kinprop.joints import composite, placement, spherical, universal
from kinprop.joints import motion as joint_motion
from kinprop.kinematics import kernels
from kinprop.kinematics.tables import (
    B_KIND,
    B_ON_J,
    CP_COL,
    CP_L0,
    CP_QB,
    CP_ROW,
    E_COL,
    E_ROW,
    J_BODY_I,
    J_BODY_J,
    J_CODE,
    J_COL_S_I,
    J_NQ,
    J_QCOL,
    K_BASIC0,
    K_BASIC1,
    K_JOINT,
    K_ROW0,
    T_CHILD,
    T_JOINT,
    T_PARENT,
    T_REVERSED,
)
from kinprop.spatial import Array

if TYPE_CHECKING:
    from kinprop.engine.engine import Engine, State


@dataclass(frozen=True)
class StaticsRates:
    """The loads (``statics``) and their rates along ``K`` directions (leading axis): the
    arrays of :class:`~kinprop.engine.statics.StaticsState` per unit of each direction (NaN
    where the value is undetermined)."""

    statics: StaticsState
    efforts: Array  # (K, nd)
    wrench: Array  # (K, nj, 2, 6) about the origin
    at_point: Array  # (K, nj, 2, 6) force, moment about the joint's point (global)
    local: Array  # (K, nj, 2, 6) the same in joint frame i's axes
    member: Array  # (K, nj)
    element_force: Array  # (K, ne)
    element_length: Array  # (K, ne)
    #: (K, nj, 2, 3) rates of the joint frames' origins (the reactions' points)
    point_rates: Array
    #: (K, nb, 6) body twists
    V: Array


def _scross(U: Array, X: Array) -> Array:
    """Spatial cross products ``U x X`` of twists on the last axis."""
    v, w = _cross(U[..., 3:], X[..., :3]) + _cross(U[..., :3], X[..., 3:]), _cross(U[..., 3:], X[..., 3:])
    return np.concatenate([v, w], axis=-1)


def _design_twist(X: Array, col_s: int, col_c: int, A: Array, P: Array) -> Array:
    """(K, 6) twist of a joint frame on its body from its own design rates (s', xi')."""
    out = np.zeros((X.shape[0], 6))
    if col_s >= 0:
        out[:, :3] += X[:, col_s : col_s + 3] @ A.T
    if col_c >= 0:
        w = X[:, col_c : col_c + 3] @ A.T
        out[:, 3:] += w
        out[:, :3] += _cross(P, w)
    return out


def twists(engine: Engine, fr: _Frames, X: Array) -> tuple[Array, Array]:
    """``(V, U)``: body twists (K, nb, 6) and joint frame twists (K, nj, 2, 6) of the state
    directions ``X`` (K, n_columns) (module docstring)."""
    tb = engine.tables
    K = X.shape[0]
    V = np.zeros((K, tb.fixed.shape[0], 6))
    U = np.zeros((K, tb.joint.shape[0], 2, 6))
    for t in range(tb.tree.shape[0]):
        j, par, chi = tb.tree[t, T_JOINT], tb.tree[t, T_PARENT], tb.tree[t, T_CHILD]
        q0, nq = tb.joint[j, J_QCOL], tb.joint[j, J_NQ]
        a, b = (0, 1) if tb.tree[t, T_REVERSED] == 0 else (1, 0)
        cols = tb.joint[j, J_COL_S_I : J_COL_S_I + 4]
        Ua = V[:, par] + _design_twist(X, cols[a], cols[2 + a], fr.A[par], fr.P[j, a])
        Ub = Ua + (X[:, q0 : q0 + nq] @ fr.Tq[t, :, :nq].T if nq > 0 else 0.0)
        U[:, j, a], U[:, j, b] = Ua, Ub
        V[:, chi] = Ub - _design_twist(X, cols[b], cols[2 + b], fr.A[chi], fr.P[j, b])
    for c in range(tb.cut.shape[0]):
        j = tb.cut[c, K_JOINT]
        cols = tb.joint[j, J_COL_S_I : J_COL_S_I + 4]
        for s in range(2):
            body = tb.joint[j, J_BODY_I + s]
            U[:, j, s] = V[:, body] + _design_twist(X, cols[s], cols[2 + s], fr.A[body], fr.P[j, s])
    return V, U


def _E(p: Array) -> Array:
    """(K, 3, 4) ``E(p) = [-e, tilde(e) + e0 I]`` (eq. 40) of Euler parameters (K, 4)."""
    e0, e1, e2, e3 = p[:, 0], p[:, 1], p[:, 2], p[:, 3]
    return np.stack([np.stack([-e1, e0, -e3, e2], -1), np.stack([-e2, e3, e0, -e1], -1),
                     np.stack([-e3, -e2, e1, e0], -1)], axis=1)  # fmt: skip


def _local_rates(code: int, q: Array, qd: Array, App: Array, dpp: Array, dd: Array, H: Array) -> tuple[Array, Array]:
    """``(d dd'', d H'')`` (K, 3, nq): rates of a tree joint's motion columns (joint frame i)
    from its coordinates' rates ``qd`` (K, nq); zero for revolute, prismatic, cylindrical."""
    K, nq = qd.shape
    dH, ddd = np.zeros((K, 3, nq)), np.zeros((K, 3, nq))
    if code == universal.CODE:  # H[:, 1] = Rz(q0) e_y
        dH[:, :, 1] = qd[:, :1] * np.array([-np.cos(q[0]), -np.sin(q[0]), 0.0])
    elif code in (spherical.CODE, composite.ST_CODE):  # H = 2 E(p)
        dH[:, :, 0:4] = 2.0 * _E(qd[:, 0:4])
        if code == composite.ST_CODE:  # dd_y = -d'' x H_y (y < 4), dd_4 = A'' e_z
            dp = qd @ dd.T
            for y in range(4):
                ddd[:, :, y] = -(_cross(dp, H[:, y]) + _cross(dpp, dH[:, :, y]))
            ddd[:, :, 4] = _cross(qd @ H.T, App[:, 2])
    elif code == composite.FREE_CODE:  # H = 2 E(p) / (p.p)
        p = q[3:7]
        pp = float(p @ p)
        dH[:, :, 3:7] = 2.0 * _E(qd[:, 3:7]) / pp - (4.0 * (qd[:, 3:7] @ p) / pp**2)[:, None, None] * _E(p[None])
    return ddd, dH


def statics_rates(
    engine: Engine,
    state: State,
    loads: PointForces,
    X: Array,
    driven: Sequence[int] = (),
    laws: Sequence[Law] = (),
    held: Sequence[bool] | None = None,
) -> StaticsRates:
    """The loads of the assembled ``state`` and their exact rates along the directions ``X``
    (K, n_columns), tangent to the constraints (module docstring). ``held[k]``: element k's
    force does not change with its length (a preload given at the current pose)."""
    X = np.atleast_2d(np.asarray(X, dtype=float))
    K = X.shape[0]
    held = [False] * len(laws) if held is None else list(held)
    fr = _Frames(engine, state)
    tb, st = engine.tables, fr.state
    nb, nj, nq, m, nd = tb.fixed.shape[0], tb.joint.shape[0], engine.n_coordinates, engine.n_rows, len(driven)
    ss = statics_state(engine, state, loads.wrenches(nb), driven, laws, fr)
    ne = len(laws)
    if not ss.ok:
        nan = np.full((K, nj, 2, 6), np.nan)
        return StaticsRates(ss, np.full((K, nd), np.nan), nan, nan, nan, np.full((K, nj), np.nan),
                            np.full((K, ne), np.nan), np.full((K, ne), np.nan), np.full((K, nj, 2, 3), np.nan),
                            np.full((K, nb, 6), np.nan))  # fmt: skip
    lam = ss.lam
    V, U = twists(engine, fr, X)
    dW_el, df_el, dL_el = element_rates(laws, held, fr.r, fr.A, V, X[:, :nq], U[:, :, 0, 3:], fr.R, st.Q)
    dW_app = load_rates(loads, V) + dW_el  # applied wrenches' rates (loads and elements)
    W_cut, dW_cut = np.zeros((nb, 6)), np.zeros((K, nb, 6))
    dG = np.zeros((K, nq))
    cuts = []
    for c in range(tb.cut.shape[0]):
        j, r0 = tb.cut[c, K_JOINT], tb.cut[c, K_ROW0]
        bi, bj = tb.joint[j, J_BODY_I], tb.joint[j, J_BODY_J]
        Pi, d, Pd, Wi, Wj = _cut_rows(engine, fr.P, fr.R, st.Q, st.L, c)
        mc = Pd.shape[0]
        lc = lam[r0 : r0 + mc]
        wi, wj = U[:, j, 0, 3:], U[:, j, 1, 3:]
        vPi, vPj = _velocity(U[:, j, 0], fr.P[j, 0]), _velocity(U[:, j, 1], fr.P[j, 1])
        e = de = None
        if tb.joint[j, J_NQ] > 0:  # T-D: the point on body i slides along z''_i
            qc = tb.joint[j, J_QCOL]
            e = fr.R[j, 0, :, 2]
            de = _cross(wi, e)
            vPi = vPi + de * st.Q[qc] + X[:, qc : qc + 1] * e
        dd = vPj - vPi
        dPd, dWi, dWj = np.zeros((K, mc, 3)), np.zeros((K, mc, 3)), np.zeros((K, mc, 3))
        r = 0
        for bc in range(tb.cut[c, K_BASIC0], tb.cut[c, K_BASIC1]):
            kind, on_j, ax = tb.basic[bc, B_KIND], tb.basic[bc, B_ON_J], tb.basic_axes[bc]
            if kind == DOT1:
                ai, aj = fr.R[j, 0] @ ax[:3], fr.R[j, 1] @ ax[3:]
                dWi[:, r] = _cross(_cross(wi, ai), aj) + _cross(ai, _cross(wj, aj))
                dWj[:, r] = -dWi[:, r]
            elif kind == DOT2:
                a = (fr.R[j, 1] if on_j else fr.R[j, 0]) @ ax[:3]
                da = _cross(wj if on_j else wi, a)
                dPd[:, r] = da
                (dWj if on_j else dWi)[:, r] = _cross(da, d) + _cross(a, dd)
            elif kind == DISTANCE:
                dPd[:, r] = 2.0 * dd
            r += ROWS[kind]
        f, mi, mj = Pd.T @ lc, Wi.T @ lc, Wj.T @ lc
        df, dmi, dmj = dPd.transpose(0, 2, 1) @ lc, dWi.transpose(0, 2, 1) @ lc, dWj.transpose(0, 2, 1) @ lc
        Pj = fr.P[j, 1]
        W_cut[bi] += np.concatenate([-f, _cross(f, Pi) + mi])
        W_cut[bj] += np.concatenate([f, -_cross(f, Pj) + mj])
        dWi_c = np.concatenate([-df, _cross(df, Pi) + _cross(f, vPi) + dmi], axis=1)  # lambda held
        dWj_c = np.concatenate([df, -_cross(df, Pj) - _cross(f, vPj) + dmj], axis=1)
        dW_cut[:, bi] += dWi_c
        dW_cut[:, bj] += dWj_c
        if e is not None:
            dG[:, tb.joint[j, J_QCOL]] -= df @ e + de @ f
        cuts.append((c, j, r0, mc, d, dd, cut_arms(Pi, d, Pd, Wi, Wj), dWi_c, dWj_c))
    Ws = subtree_sums(engine, ss.applied + W_cut)
    dWs = subtree_sums(engine, dW_app + dW_cut)
    Q = st.Q
    for t in range(tb.tree.shape[0]):
        j, chi = tb.tree[t, T_JOINT], tb.tree[t, T_CHILD]
        q0, nqt = tb.joint[j, J_QCOL], tb.joint[j, J_NQ]
        if nqt <= 0:
            continue
        code = int(tb.joint[j, J_CODE])
        Tq = fr.Tq[t, :, :nqt]  # (6, nqt)
        qd = X[:, q0 : q0 + nqt]
        App, dpp = np.zeros((3, 3)), np.zeros(3)
        dd, H = np.zeros((3, kernels.MAX_Q)), np.zeros((3, kernels.MAX_Q))
        q = Q[q0 : q0 + nqt]
        placement(code, q, App, dpp)
        joint_motion(code, q, App, dpp, dd[:, :nqt], H[:, :nqt])
        dd, H = dd[:, :nqt], H[:, :nqt]
        ddd, dH = _local_rates(code, q, qd, App, dpp, dd, H)
        dp = qd @ dd.T  # rate of d''
        sign = -1.0 if tb.tree[t, T_REVERSED] else 1.0
        R0, P0 = fr.R[j, 0], fr.P[j, 0]
        for y in range(nqt):
            u_loc = ddd[:, :, y] + _cross(dp, H[:, y]) + _cross(dpp, dH[:, :, y])
            w = dH[:, :, y] @ R0.T
            adj = np.concatenate([u_loc @ R0.T + _cross(P0, w), w], axis=1)
            dT = _scross(U[:, j, 0], np.broadcast_to(Tq[:, y], (K, 6))) + sign * adj
            dG[:, q0 + y] += dT @ Ws[chi] + dWs[:, chi] @ Tq[:, y]
    for k in range(tb.euler.shape[0]):
        col = tb.euler[k, E_COL]
        dG[:, col : col + 4] += 2.0 * X[:, col : col + 4] * lam[tb.euler[k, E_ROW]]
    for k in range(tb.coupling.shape[0]):
        qb, l0, ccol = tb.coupling[k, CP_QB], tb.coupling[k, CP_L0], tb.coupling[k, CP_COL]
        x = Q[qb] - tb.coupling_q0[k, 1]
        c = st.L[l0 : l0 + 5]
        d2 = -(2.0 * c[2] + 6.0 * c[3] * x + 12.0 * c[4] * x * x)  # d(Phi_qb)/dq_b
        dc = -np.array([0.0, 1.0, 2.0 * x, 3.0 * x * x, 4.0 * x**3])  # d(Phi_qb)/dc_m
        dG[:, qb] += lam[tb.coupling[k, CP_ROW]] * (d2 * X[:, qb] + X[:, ccol : ccol + 5] @ dc)
    # [Phi_q^T E_D^T] ydot = -dG, solved as the statics are
    As, unscale, cs = equilibrium_system(engine, fr.Phi_q, driven)
    ys = np.linalg.lstsq(As, -(dG / cs).T, rcond=None)[0].T if K else np.zeros((0, m + nd))
    y = ys * unscale
    dlam, dtau = y[:, :m], y[:, m:]
    # reactions: cut joints dZ^T lambda + Z^T lambda_dot; tree joints minus the subtree sums
    wrench = _reactions(engine, [cu[6] for cu in cuts], lam, ss.applied)
    dwrench = np.zeros((K, nj, 2, 6))
    dW_all = dW_app + dW_cut
    dmember = np.full((K, nj), np.nan)
    for c, j, r0, mc, d, dd, (Zi, Zj), dWi_c, dWj_c in cuts:
        dl = dlam[:, r0 : r0 + mc]
        dwrench[:, j, 0], dwrench[:, j, 1] = dWi_c + dl @ Zi, dWj_c + dl @ Zj
        dW_all[:, tb.joint[j, J_BODY_I]] += dl @ Zi
        dW_all[:, tb.joint[j, J_BODY_J]] += dl @ Zj
        r = r0
        for bc in range(tb.cut[c, K_BASIC0], tb.cut[c, K_BASIC1]):
            kind = tb.basic[bc, B_KIND]
            if kind == DISTANCE:  # the rod's tension -2 lambda |d|
                length = float(np.linalg.norm(d))
                dmember[:, j] = -2.0 * (dlam[:, r] * length + lam[r] * (dd @ d) / length)
            r += ROWS[kind]
    dWs_all = subtree_sums(engine, dW_all)
    for t in range(tb.tree.shape[0]):
        j, chi = tb.tree[t, T_JOINT], tb.tree[t, T_CHILD]
        child_side = 0 if tb.tree[t, T_REVERSED] else 1
        dwrench[:, j, child_side] = -dWs_all[:, chi]
        dwrench[:, j, 1 - child_side] = dWs_all[:, chi]
    # at the joints' points, and in joint frame i
    vP = np.stack([_velocity(U[:, :, s].reshape(-1, 6), np.repeat(fr.P[None, :, s], K, 0).reshape(-1, 3))
                   .reshape(K, nj, 3) for s in range(2)], axis=2)  # fmt: skip
    F, MO = wrench[..., :3], wrench[..., 3:]
    dF, dMO = dwrench[..., :3], dwrench[..., 3:]
    dat = np.concatenate([dF, dMO - _cross(vP, F) - _cross(fr.P, dF)], axis=-1)
    G = np.concatenate([F, MO - _cross(fr.P, F)], axis=-1)
    wi = U[:, :, 0, 3:][:, :, None, :]  # frame i's rotation rate, both sides
    Ri = fr.R[:, 0]  # (nj, 3, 3): frame i's axes for both sides
    dloc = np.concatenate([np.einsum("jba,kjsb->kjsa", Ri, dat[..., :3] - _cross(wi, G[..., :3])),
                           np.einsum("jba,kjsb->kjsa", Ri, dat[..., 3:] - _cross(wi, G[..., 3:]))],
                          axis=-1)  # fmt: skip
    und = ss.undetermined
    dloc[:, und] = np.nan
    dat[:, np.isnan(ss.at_point)] = np.nan
    dwr = dwrench.copy()
    dwr[:, und.any(axis=2)] = np.nan
    dmember[:, np.isnan(ss.member)] = np.nan
    dtau = np.where(np.isnan(ss.efforts)[None], np.nan, dtau)
    return StaticsRates(ss, dtau, dwr, dat, dloc, dmember, df_el, dL_el, vP, V)


__all__ = ["StaticsRates", "statics_rates", "twists"]
