"""Velocity and acceleration analysis of an assembled state (Haug, *Computer-Aided Kinematics
and Dynamics of Mechanical Systems*, 1989, secs. 3.3-3.4, 7.1), on the compiled kernel's
Jacobian.

Velocity: with the driven coordinates' rates ``qdot_D`` (declared inputs or any coordinates),
``[Phi_q ; E_D] qdot = [0 ; qdot_D]`` (``E_D`` picks the driven columns); ``Phi_q`` is the
q block of the Jacobian :func:`kinprop.kinematics.kernels.evaluate` emits (every cut joint,
Euler normalisation and coupling row). Acceleration: ``[Phi_q ; E_D] qddot = [gamma ;
qddot_D]`` with Haug's right-hand side ``gamma = -(Phi_q qdot)_q qdot`` (eq. 3.3.9), written
analytically below; nothing is differenced.

Body velocities are spatial twists ``V = [v_O ; omega]`` (``v_O`` the velocity of the body
point at the global origin; a point P moves with ``v_O + omega x P``), the kernel's tree twists
``T`` (eq. 34: ``V_child = V_parent + T q_t``). Accelerations ``dV/dt`` (of ``v_O`` and
``omega``): ``dV_child = dV_parent + V_parent x T qdot_t + sign X_0 dt_loc + T qddot_t`` where
``x`` is the spatial cross product ``[w1 x v2 + v1 x w2 ; w1 x w2]``, ``X_0`` maps a twist
at the joint's frame i (``[u ; w]`` in its axes) to the global origin, and ``dt_loc`` is the
time derivative, at constant ``qdot``, of the joint's local twist ``[dd'' qdot + d'' x H''
qdot ; H'' qdot]`` (its second-order term, :func:`_local_bias`; zero for revolute,
prismatic, cylindrical and spherical joints).

``gamma`` of each basic constraint is minus its second time derivative with ``qddot = 0``
(Haug Table 3.3.x): dot-1 ``a_i'' a_j + 2 a_i' a_j' + a_i a_j''``; dot-2 ``a'' d + 2 a' d' +
a d''``; spherical ``d''``; distance ``2 d'.d' + 2 d.d''``; with ``a' = w x a``, ``a'' = alpha x a
+ w x a'`` and the points' accelerations from the bodies' bias accelerations; Euler
normalisation ``-2 p'.p'``; coupling ``p''(x) qdot_b^2``.

Singular configurations: the stacked matrix is factored by SVD (scaled rows and columns);
when it is rank deficient (the driven rates do not determine the motion) or the driven rates
violate the constraints (a locked input), the status is ``singular`` and every rate is NaN.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from kinprop.constraints.basic import DISTANCE, DOT1, DOT2, SPHERICAL
from kinprop.joints import composite, placement, universal
from kinprop.joints import motion as joint_motion
from kinprop.kinematics import kernels
from kinprop.kinematics.tables import (
    B_KIND,
    B_ON_J,
    CP_L0,
    CP_QB,
    CP_ROW,
    E_COL,
    E_ROW,
    J_BODY_I,
    J_BODY_J,
    J_CODE,
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

#: ``kinprop.engine.Engine`` and its ``State``: engine.py calls into this module (``Engine.motion``),
#: so this module names them without importing them (no import cycle, also for type checkers)
Engine = Any
State = Any

#: relative singular value below which the velocity system counts as singular
SINGULAR_RTOL = 1e-10
OK, SINGULAR = "ok", "singular"


@dataclass(frozen=True)
class MotionState:
    """Rates and accelerations of one assembled state (solver units: radians, the model's
    length unit, per unit time). Arrays by layout q column and by body index."""

    status: str
    message: str
    qdot: Array  # (n_q,)
    V: Array  # (nb, 6) spatial twists [v_O, omega]
    r: Array  # body positions
    A: Array  # body orientations
    P: Array  # joint frame origins (nj, 2, 3)
    R: Array  # joint frame axes (nj, 2, 3, 3)
    qddot: Array | None = None
    dV: Array | None = None  # (nb, 6) spatial accelerations [dv_O, alpha]
    #: smallest / largest singular value of the scaled velocity system
    conditioning: float = 1.0
    #: ``||Phi||`` of the state (scaled as the solver's test): the rates are those of the
    #: tangent there; :func:`kinprop.analysis.motion.motion` refuses a state that is not an assembly
    residual: float = 0.0

    @property
    def ok(self) -> bool:
        return self.status == OK

    def point_velocity(self, body: int, point: Array) -> Array:
        """Velocity of the body point now at global ``point``: ``v_O + omega x P``."""
        v, w = self.V[body, :3], self.V[body, 3:]
        return v + cross3(w, point)

    def point_acceleration(self, body: int, point: Array) -> Array:
        """``dv_O + alpha x P + omega x (v_O + omega x P)`` of the body point now at ``point``."""
        if self.dV is None:
            raise ValueError("no accelerations: give the driven accelerations")
        w = self.V[body, 3:]
        return self.dV[body, :3] + cross3(self.dV[body, 3:], point) + cross3(w, self.point_velocity(body, point))


def cross3(a: Array, b: Array) -> Array:
    """``a x b`` of two 3-vectors (numpy's ``cross`` costs ten times more on single vectors)."""
    a0, a1, a2 = float(a[0]), float(a[1]), float(a[2])
    b0, b1, b2 = float(b[0]), float(b[1]), float(b[2])
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def spatial_cross(V1: Array, V2: Array) -> Array:
    """``V1 x V2`` of twists ``[v ; w]``: ``[w1 x v2 + v1 x w2 ; w1 x w2]``."""
    return np.concatenate([cross3(V1[3:], V2[:3]) + cross3(V1[:3], V2[3:]), cross3(V1[3:], V2[3:])])


def _local_bias(code: int, q: Array, qd: Array, d: Array, dd_qd: Array, w: Array, A: Array) -> tuple[Array, Array]:
    """``(dD, dH)``: ``d/dt (dd''(q) qdot)`` and ``d/dt (H''(q) qdot)`` at constant ``qdot``, in
    joint frame i, of a tree joint of type ``code`` (``w = H'' qdot``, ``dd_qd = dd'' qdot``)."""
    zero = np.zeros(3)
    if code == universal.CODE:  # H[:, 1] = Rz(q0) e_y
        return zero, qd[0] * qd[1] * np.array([-np.cos(q[0]), -np.sin(q[0]), 0.0])
    if code == composite.ST_CODE:  # dd qdot = w x d + A e_z tdot, H constant in p-dot
        return cross3(w, dd_qd) + qd[4] * cross3(w, A[:, 2]), zero
    if code == composite.FREE_CODE:  # H = 2E(p)/(p.p): E(pdot) pdot = 0
        p, pd = q[3:7], qd[3:7]
        return zero, -2.0 * float(p @ pd) / float(p @ p) * w
    return zero, zero  # revolute, prismatic, cylindrical, spherical (E(pdot) pdot = 0), fixed


class _Frames:
    """The kernel's workspace after an evaluation: poses and tree twists."""

    def __init__(self, engine: Engine, state: State) -> None:
        st = state.writable()
        tb = engine.tables
        ws = kernels.workspace(tb)
        nq = engine.n_coordinates
        Phi, vals = np.zeros(engine.n_rows), np.zeros(engine.nnz)
        need = np.zeros(engine.n_columns, np.int8)
        need[:nq] = 1  # the coordinate columns only (layout: q first)
        dummy = np.zeros(0, np.int64)
        kernels.evaluate(tb, st.Q, st.S, st.C, st.L, ws, Phi, vals, need, dummy, dummy)
        rows, cols = engine.pattern
        q = cols < nq
        self.residual = float(np.linalg.norm(Phi * engine.row_scale))
        self.Phi_q = np.zeros((engine.n_rows, nq))
        np.add.at(self.Phi_q, (rows[q], cols[q]), vals[q])
        slots = (kernels.W_BODY_R, kernels.W_BODY_A, kernels.W_FRAME_P, kernels.W_FRAME_R, kernels.W_TWIST_Q)
        self.r, self.A, self.P, self.R, self.Tq = (np.array(ws[k]) for k in slots)
        self.state = st


def _driven_rows(engine: Engine, driven: Mapping[str, Any]) -> tuple[list[int], list[float]]:
    cols, vals = [], []
    for address, value in driven.items():
        t = engine.target(address)
        if t.group != "q":
            raise KeyError(f"{address!r}: a driven rate is a coordinate's (JOINT.q or JOINT.q[k])")
        v = np.atleast_1d(np.asarray(value, dtype=float)).ravel()
        idx = [t.start + t.index] if t.index is not None else list(range(t.start, t.start + t.size))
        if v.size == 1 and len(idx) > 1:
            v = np.full(len(idx), float(v[0]))
        if v.size != len(idx):
            raise ValueError(f"{address!r}: expected {len(idx)} rates, found {v.size}")
        cols += idx
        vals += [float(x) for x in v]
    return cols, vals


def _solve(
    engine: Engine, Phi_q: Array, cols: list[int], rhs_rows: Array, rhs_driven: list[float]
) -> tuple[Array, float, str]:
    """Least-squares solve of the stacked system with a rank and consistency check."""
    n = Phi_q.shape[1]
    E = np.zeros((len(cols), n))
    E[np.arange(len(cols)), cols] = 1.0
    cs = engine.col_scale[:n]  # solver column -> scaled: x = cs^-1 * xs
    rs = engine.row_scale
    M = np.vstack([Phi_q * rs[:, None], E]) / cs[None, :]
    b = np.concatenate([rhs_rows * rs, np.asarray(rhs_driven, dtype=float)])
    if len(cols):
        M[Phi_q.shape[0] :] *= cs[None, cols].T  # driven rows: unit entries in scaled columns
        b[Phi_q.shape[0] :] *= cs[cols]
    U, s, Vt = np.linalg.svd(M, full_matrices=False)
    smax = float(s[0]) if s.size else 0.0
    rank = int(np.sum(s > SINGULAR_RTOL * smax)) if smax > 0 else 0
    cond = float(s[-1] / smax) if smax > 0 and s.size == n else 0.0
    if rank < n:
        return (
            np.full(n, np.nan),
            cond,
            (
                f"singular: the driven rates leave {n - rank} direction(s) of motion "
                "undetermined (a singular configuration, or too few driven coordinates)"
            ),
        )
    xs = Vt.T @ ((U.T @ b) / s)
    resid = float(np.linalg.norm(M @ xs - b))
    if resid > 1e-8 * max(1.0, float(np.linalg.norm(b))):
        return (
            np.full(n, np.nan),
            cond,
            (
                "singular: the driven rates violate the constraints (residual "
                f"{resid:.3g}): a locked input or a singular configuration"
            ),
        )
    return xs / cs, cond, ""


def _tree_velocities(engine: Engine, fr: _Frames, qdot: Array) -> Array:
    tb = engine.tables
    V = np.zeros((tb.fixed.shape[0], 6))
    for t in range(tb.tree.shape[0]):
        j, par, chi = tb.tree[t, T_JOINT], tb.tree[t, T_PARENT], tb.tree[t, T_CHILD]
        q0, nq = tb.joint[j, J_QCOL], tb.joint[j, J_NQ]
        V[chi] = V[par] + (fr.Tq[t, :, :nq] @ qdot[q0 : q0 + nq] if nq > 0 else 0.0)
    return V


def _tree_bias(engine: Engine, fr: _Frames, qdot: Array, V: Array) -> Array:
    """Spatial accelerations of the bodies with ``qddot = 0``."""
    tb, Q = engine.tables, fr.state.Q
    dV = np.zeros_like(V)
    for t in range(tb.tree.shape[0]):
        j, par, chi = tb.tree[t, T_JOINT], tb.tree[t, T_PARENT], tb.tree[t, T_CHILD]
        q0, nq = tb.joint[j, J_QCOL], tb.joint[j, J_NQ]
        dV[chi] = dV[par]
        if nq <= 0:
            continue
        q, qd = Q[q0 : q0 + nq], qdot[q0 : q0 + nq]
        code = int(tb.joint[j, J_CODE])
        App, dpp = np.zeros((3, 3)), np.zeros(3)
        dd, H = np.zeros((3, kernels.MAX_Q)), np.zeros((3, kernels.MAX_Q))
        placement(code, q, App, dpp)
        joint_motion(code, q, App, dpp, dd[:, :nq], H[:, :nq])
        w, dd_qd = H[:, :nq] @ qd, dd[:, :nq] @ qd
        dD, dH = _local_bias(code, q, qd, dpp, dd_qd, w, App)
        dt_loc_v = dD + cross3(dd_qd, w) + cross3(dpp, dH)
        sign = -1.0 if tb.tree[t, T_REVERSED] else 1.0
        R0, P0 = fr.R[j, 0], fr.P[j, 0]
        X = np.concatenate([R0 @ dt_loc_v + cross3(P0, R0 @ dH), R0 @ dH])
        dV[chi] += spatial_cross(V[par], fr.Tq[t, :, :nq] @ qd) + sign * X
    return dV


def _gamma(engine: Engine, fr: _Frames, qdot: Array, V: Array, dV: Array) -> Array:
    """Haug's ``gamma`` of every row (module docstring)."""
    tb, Q, L = engine.tables, fr.state.Q, fr.state.L
    g = np.zeros(engine.n_rows)

    def kin(b: int, x: Array) -> tuple[Array, Array]:  # velocity and bias acceleration of a point
        v = V[b, :3] + cross3(V[b, 3:], x)
        return v, dV[b, :3] + cross3(dV[b, 3:], x) + cross3(V[b, 3:], v)

    def axis(b: int, a: Array) -> tuple[Array, Array]:  # rate and bias acceleration of a body axis
        da = cross3(V[b, 3:], a)
        return da, cross3(dV[b, 3:], a) + cross3(V[b, 3:], da)

    for c in range(tb.cut.shape[0]):
        j, row = tb.cut[c, K_JOINT], tb.cut[c, K_ROW0]
        bi, bj = tb.joint[j, J_BODY_I], tb.joint[j, J_BODY_J]
        Ri, Rj = fr.R[j, 0], fr.R[j, 1]
        vi, ai = kin(bi, fr.P[j, 0])
        vj, aj = kin(bj, fr.P[j, 1])
        d, dd, ddd = fr.P[j, 1] - fr.P[j, 0], vj - vi, aj - ai
        if tb.joint[j, J_NQ] > 0:  # T-D: the point on body i slides along z''_i by its own coordinate
            qc = tb.joint[j, J_QCOL]
            e = Ri[:, 2]
            de, dde = axis(bi, e)
            d = d - Q[qc] * e
            dd = dd - qdot[qc] * e - Q[qc] * de
            ddd = ddd - 2.0 * qdot[qc] * de - Q[qc] * dde
        r = row
        for bc in range(tb.cut[c, K_BASIC0], tb.cut[c, K_BASIC1]):
            kind, on_j, ax = tb.basic[bc, B_KIND], tb.basic[bc, B_ON_J], tb.basic_axes[bc]
            if kind == DOT1:
                a_i, a_j = Ri @ ax[:3], Rj @ ax[3:]
                da_i, dda_i = axis(bi, a_i)
                da_j, dda_j = axis(bj, a_j)
                g[r] = -(dda_i @ a_j + 2.0 * da_i @ da_j + a_i @ dda_j)
                r += 1
            elif kind == DOT2:
                b = bj if on_j else bi
                a = (Rj if on_j else Ri) @ ax[:3]
                da, dda = axis(b, a)
                g[r] = -(dda @ d + 2.0 * da @ dd + a @ ddd)
                r += 1
            elif kind == SPHERICAL:
                g[r : r + 3] = -ddd
                r += 3
            elif kind == DISTANCE:
                g[r] = -(2.0 * dd @ dd + 2.0 * d @ ddd)
                r += 1
    for e in range(tb.euler.shape[0]):
        col = tb.euler[e, E_COL]
        pd = qdot[col : col + 4]
        g[tb.euler[e, E_ROW]] = -2.0 * float(pd @ pd)
    for k in range(tb.coupling.shape[0]):
        qb, slot = tb.coupling[k, CP_QB], tb.coupling[k, CP_L0]
        x = Q[qb] - tb.coupling_q0[k, 1]
        c = L[slot : slot + 5]
        p2 = 2.0 * c[2] + 6.0 * c[3] * x + 12.0 * c[4] * x * x
        g[tb.coupling[k, CP_ROW]] = p2 * qdot[qb] ** 2
    return g


def motion_state(
    engine: Engine, state: State, rates: Mapping[str, Any], accelerations: Mapping[str, Any] | None = None
) -> MotionState:
    """Velocities and, when ``accelerations`` (of the same driven coordinates; missing ones 0)
    is given, accelerations of every coordinate and body (module docstring)."""
    fr = _Frames(engine, state)
    cols, vals = _driven_rows(engine, rates)
    qdot, cond, msg = _solve(engine, fr.Phi_q, cols, np.zeros(engine.n_rows), vals)
    status = SINGULAR if msg else OK
    V = _tree_velocities(engine, fr, qdot)
    if msg or accelerations is None:
        nan = None if accelerations is None else np.full_like(qdot, np.nan)
        return MotionState(
            status,
            msg or "ok",
            qdot,
            V,
            fr.r,
            fr.A,
            fr.P,
            fr.R,
            nan,
            None if nan is None else np.full_like(V, np.nan),
            cond,
            fr.residual,
        )
    acc = {a: 0.0 for a in rates} | dict(accelerations)
    acols, avals = _driven_rows(engine, acc)
    if sorted(acols) != sorted(cols):
        raise ValueError("accelerations are given for the driven coordinates only (the ones with rates)")
    dV0 = _tree_bias(engine, fr, qdot, V)
    gamma = _gamma(engine, fr, qdot, V, dV0)
    qddot, _, msg = _solve(engine, fr.Phi_q, acols, gamma, avals)
    dV = dV0 + _tree_velocities(engine, fr, qddot)  # the q-ddot part is linear, like the twists
    return MotionState(
        SINGULAR if msg else OK, msg or "ok", qdot, V, fr.r, fr.A, fr.P, fr.R, qddot, dV, cond, fr.residual
    )


__all__ = ["MotionState", "cross3", "motion_state", "spatial_cross"]
