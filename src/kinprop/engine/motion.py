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
violate the constraints (a locked input), the status is ``singular`` (:class:`kinprop.Status`,
its message from the one table, :func:`kinprop.engine.status.message`) and every rate is NaN.
"""

from __future__ import annotations

import math
import threading
import weakref
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from kinprop.constraints.basic import DISTANCE, DOT1, DOT2, SPHERICAL
from kinprop.engine.status import Status, message
from kinprop.jit import njit
from kinprop.joints import composite, placement, universal
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
    J_COL_L,
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
from kinprop.solver import newton
from kinprop.spatial import Array

#: ``kinprop.engine.Engine`` and its ``State``: engine.py calls into this module (``Engine.motion``),
#: so this module names them without importing them (no import cycle, also for type checkers)
Engine = Any
State = Any

#: relative singular value below which the velocity system counts as singular
SINGULAR_RTOL = 1e-10
OK, SINGULAR = Status.OK, Status.SINGULAR


@dataclass(frozen=True)
class MotionState:
    """Rates and accelerations of one assembled state (solver units: radians, the model's
    length unit, per unit time). Arrays by layout q column and by body index."""

    #: ``ok``, ``singular`` or (:func:`kinprop.analysis.motion.motion`) ``not_assembled``
    status: Status
    message: str
    qdot: Array  # (n_q,)
    V: Array  # (nb, 6) spatial twists [v_O, omega]
    r: Array  # body positions
    A: Array  # body orientations
    P: Array  # joint frame origins (nj, 2, 3)
    R: Array  # joint frame axes (nj, 2, 3, 3)
    qddot: Array | None = None
    dV: Array | None = None  # (nb, 6) spatial accelerations [dv_O, alpha]
    #: smallest / largest singular value of the scaled velocity system (NaN: solved compiled by
    #: LU on the plan, :func:`velocity_solve`, which does not compute it)
    conditioning: float = 1.0
    #: ``||Phi||`` of the state (scaled as the solver's test): the rates are those of the
    #: tangent there; :func:`kinprop.analysis.motion.motion` refuses a state that is not an assembly
    residual: float = 0.0

    @property
    def ok(self) -> bool:
        return self.status is OK

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

    def __init__(self, engine: Engine, state: State, design: bool = False) -> None:
        st = state.writable()
        tb = engine.tables
        ws = kernels.workspace(tb)
        nq = engine.n_coordinates
        Phi, vals = np.zeros(engine.n_rows), np.zeros(engine.nnz)
        need = np.zeros(engine.n_columns, np.int8)
        need[: engine.n_columns if design else nq] = 1  # layout: q first; ``design``: the s', C twists too
        dummy = np.zeros(0, np.int64)
        kernels.evaluate(tb, st.Q, st.S, st.C, st.L, ws, Phi, vals, need, dummy, dummy)
        self.residual = float(np.linalg.norm(Phi * engine.row_scale))
        q, flat_q, _ = engine.dense_pattern
        # float64 also when there are no entries (bincount of nothing counts in int64): one kernel signature
        self.Phi_q = np.bincount(flat_q, weights=vals[q], minlength=engine.n_rows * nq).astype(float, copy=False)
        self.Phi_q = self.Phi_q.reshape(engine.n_rows, nq)
        self._vals = vals if design else None
        slots = (
            kernels.W_BODY_R,
            kernels.W_BODY_A,
            kernels.W_FRAME_P,
            kernels.W_FRAME_R,
            kernels.W_TWIST_Q,
            kernels.W_TWIST_D,
        )
        self.r, self.A, self.P, self.R, self.Tq, self.Td = (ws[k] for k in slots)  # this evaluation's own arrays
        self.state = st
        self._engine = engine

    def jacobian(self) -> Array:
        """``Phi_x`` (n_rows, n_columns) dense over every layout column (a ``design`` evaluation)."""
        if self._vals is None:
            raise ValueError("the design columns were not evaluated (design=False)")
        eng = self._engine
        flat = eng.dense_pattern[2]
        return (
            np.bincount(flat, weights=self._vals, minlength=eng.n_rows * eng.n_columns)
            .astype(float, copy=False)
            .reshape(eng.n_rows, -1)
        )


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


class _Factor:
    """The stacked velocity matrix ``[Phi_q ; E_D]`` (rows and columns scaled), factored once by
    SVD with a rank check; :meth:`solve` answers one right-hand side."""

    def __init__(self, engine: Engine, Phi_q: Array, cols: list[int]) -> None:
        n = Phi_q.shape[1]
        self.m, self.cols = Phi_q.shape[0], cols
        self.cs, self.rs = engine.col_scale[:n], engine.row_scale  # solver column -> scaled: x = cs^-1 xs
        E = np.zeros((len(cols), n))
        E[np.arange(len(cols)), cols] = 1.0
        self.M = np.vstack([Phi_q * self.rs[:, None], E]) / self.cs[None, :]
        if len(cols):
            self.M[self.m :] *= self.cs[None, cols].T  # driven rows: unit entries in scaled columns
        self.U, s, self.Vt = np.linalg.svd(self.M, full_matrices=False)
        self.s = s
        smax = float(s[0]) if s.size else 0.0
        rank = int(np.sum(s > SINGULAR_RTOL * smax)) if smax > 0 else 0
        self.conditioning = float(s[-1] / smax) if smax > 0 and s.size == n else 0.0
        self.message = "" if rank == n else message(SINGULAR, undetermined=n - rank)

    def solve(self, rhs_rows: Array, rhs_driven: Array | list[float]) -> tuple[Array, str]:
        """``x`` of ``[Phi_q ; E_D] x = [rhs_rows ; rhs_driven]`` (NaN and a message when singular
        or inconsistent)."""
        n = self.M.shape[1]
        if self.message:
            return np.full(n, np.nan), self.message
        b = np.concatenate([rhs_rows * self.rs, np.asarray(rhs_driven, dtype=float)])
        if len(self.cols):
            b[self.m :] *= self.cs[self.cols]
        xs = self.Vt.T @ ((self.U.T @ b) / self.s)
        resid, size = float(np.linalg.norm(self.M @ xs - b)), float(np.linalg.norm(b))
        if resid > 1e-8 * max(1.0, size):
            return np.full(n, np.nan), message(SINGULAR, mismatch=resid / size)
        return xs / self.cs, ""


def _field_rate(tb: Any, j: int, f: int, xdot: Array) -> Array | None:
    """Rate of joint ``j``'s design field ``f`` (0 ``s'_i``, 1 ``s'_j``, 2 ``xi'_i``, 3 ``xi'_j``;
    body-frame, the retraction's) in the state rate ``xdot`` (None: no such column, or zero)."""
    col = int(tb.joint[j, J_COL_S_I + f])
    if col < 0 or col >= xdot.shape[0]:
        return None
    r = xdot[col : col + 3]
    return r if (r[0] != 0.0 or r[1] != 0.0 or r[2] != 0.0) else None


def _chain(tb: Any, fr: _Frames, t: int, xdot: Array) -> list[tuple[Array, bool]]:
    """Twists ``T_k xdot_k`` a tree joint's variables give its child, in chain order from the
    parent (module docstring: ``s'_a``, ``xi'_a``, q, ``xi'_b``, ``s'_b``), each flagged whether
    it is the q one."""
    j = int(tb.tree[t, T_JOINT])
    q0, nq = int(tb.joint[j, J_QCOL]), int(tb.joint[j, J_NQ])
    a, b = (0, 1) if tb.tree[t, T_REVERSED] == 0 else (1, 0)
    out: list[tuple[Array, bool]] = []
    for f in (a, 2 + a, -1, 2 + b, b):
        if f < 0:
            if nq > 0:
                out.append((fr.Tq[t, :, :nq] @ xdot[q0 : q0 + nq], True))
            continue
        r = _field_rate(tb, j, f, xdot)
        if r is not None:
            out.append((fr.Td[t, f] @ r, False))
    return out


def _tree_velocities(engine: Engine, fr: _Frames, xdot: Array) -> Array:
    """Every body's twist for the state rate ``xdot`` (coordinates first; design columns, when
    ``xdot`` has them, through the kernel's M, N twists)."""
    tb = engine.tables
    V = np.zeros((tb.fixed.shape[0], 6))
    for t in range(tb.tree.shape[0]):
        par, chi = tb.tree[t, T_PARENT], tb.tree[t, T_CHILD]
        V[chi] = V[par]
        for U, _ in _chain(tb, fr, t, xdot):
            V[chi] = V[chi] + U
    return V


def _tree_bias(engine: Engine, fr: _Frames, xdot: Array, V: Array) -> Array:
    """Spatial accelerations of the bodies along the straight line ``retract(x, t xdot)`` with
    no second rates: each variable's twist turns with everything before it in the chain
    (``V_before x T_k xdot_k``) plus the joint's own second-order term."""
    tb, Q = engine.tables, fr.state.Q
    dV = np.zeros_like(V)
    for t in range(tb.tree.shape[0]):
        j, par, chi = tb.tree[t, T_JOINT], tb.tree[t, T_PARENT], tb.tree[t, T_CHILD]
        q0, nq = tb.joint[j, J_QCOL], tb.joint[j, J_NQ]
        acc, W = dV[par].copy(), V[par].copy()
        for U, _ in _chain(tb, fr, t, xdot):
            acc += spatial_cross(W, U)
            W = W + U
        dV[chi] = acc
        if nq <= 0:
            continue
        q, qd = Q[q0 : q0 + nq], xdot[q0 : q0 + nq]
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
        dV[chi] += sign * np.concatenate([R0 @ dt_loc_v + cross3(P0, R0 @ dH), R0 @ dH])
    return dV


def _gamma(engine: Engine, fr: _Frames, xdot: Array, V: Array, dV: Array) -> Array:
    """Haug's ``gamma`` of every row (module docstring) for the state rate ``xdot``: minus the
    second derivative of ``Phi`` along ``retract(x, t xdot)``. With design rates a joint frame's
    point moves in its body by ``A s'dot`` and its axes turn by ``A xi'dot``, a length by
    ``ldot``, a coupling coefficient by ``cdot``."""
    tb, Q, L = engine.tables, fr.state.Q, fr.state.L
    nx = xdot.shape[0]
    g = np.zeros(engine.n_rows)

    def kin(b: int, x: Array, sd: Array | None) -> tuple[Array, Array]:  # velocity and bias acceleration
        v = V[b, :3] + cross3(V[b, 3:], x)
        a = dV[b, :3] + cross3(dV[b, 3:], x) + cross3(V[b, 3:], v)
        if sd is None:
            return v, a
        u = fr.A[b] @ sd
        return v + u, a + 2.0 * cross3(V[b, 3:], u)

    def axis(b: int, a: Array, xi: Array | None) -> tuple[Array, Array]:  # rate and bias of a frame axis
        om, dom = V[b, 3:], dV[b, 3:]
        if xi is not None:
            u = fr.A[b] @ xi
            om, dom = om + u, dom + cross3(V[b, 3:], u)
        da = cross3(om, a)
        return da, cross3(dom, a) + cross3(om, da)

    for c in range(tb.cut.shape[0]):
        j, row = tb.cut[c, K_JOINT], tb.cut[c, K_ROW0]
        bi, bj = tb.joint[j, J_BODY_I], tb.joint[j, J_BODY_J]
        xi_i, xi_j = _field_rate(tb, j, 2, xdot), _field_rate(tb, j, 3, xdot)
        Ri, Rj = fr.R[j, 0], fr.R[j, 1]
        vi, ai = kin(bi, fr.P[j, 0], _field_rate(tb, j, 0, xdot))
        vj, aj = kin(bj, fr.P[j, 1], _field_rate(tb, j, 1, xdot))
        d, dd, ddd = fr.P[j, 1] - fr.P[j, 0], vj - vi, aj - ai
        if tb.joint[j, J_NQ] > 0:  # T-D: the point on body i slides along z''_i by its own coordinate
            qc = tb.joint[j, J_QCOL]
            e = Ri[:, 2]
            de, dde = axis(bi, e, xi_i)
            d = d - Q[qc] * e
            dd = dd - xdot[qc] * e - Q[qc] * de
            ddd = ddd - 2.0 * xdot[qc] * de - Q[qc] * dde
        r = row
        for bc in range(tb.cut[c, K_BASIC0], tb.cut[c, K_BASIC1]):
            kind, on_j, ax = tb.basic[bc, B_KIND], tb.basic[bc, B_ON_J], tb.basic_axes[bc]
            if kind == DOT1:
                a_i, a_j = Ri @ ax[:3], Rj @ ax[3:]
                da_i, dda_i = axis(bi, a_i, xi_i)
                da_j, dda_j = axis(bj, a_j, xi_j)
                g[r] = -(dda_i @ a_j + 2.0 * da_i @ da_j + a_i @ dda_j)
                r += 1
            elif kind == DOT2:
                b = bj if on_j else bi
                a = (Rj if on_j else Ri) @ ax[:3]
                da, dda = axis(b, a, xi_j if on_j else xi_i)
                g[r] = -(dda @ d + 2.0 * da @ dd + a @ ddd)
                r += 1
            elif kind == SPHERICAL:
                g[r : r + 3] = -ddd
                r += 3
            elif kind == DISTANCE:
                lc = tb.joint[j, J_COL_L]
                ldot = float(xdot[lc]) if 0 <= lc < nx else 0.0
                g[r] = -(2.0 * dd @ dd + 2.0 * d @ ddd) + 2.0 * ldot * ldot
                r += 1
    for e in range(tb.euler.shape[0]):
        col = tb.euler[e, E_COL]
        pd = xdot[col : col + 4]
        g[tb.euler[e, E_ROW]] = -2.0 * float(pd @ pd)
    for k in range(tb.coupling.shape[0]):
        qb, slot, cc = tb.coupling[k, CP_QB], tb.coupling[k, CP_L0], tb.coupling[k, CP_COL]
        x = Q[qb] - tb.coupling_q0[k, 1]
        c = L[slot : slot + 5]
        p2 = 2.0 * c[2] + 6.0 * c[3] * x + 12.0 * c[4] * x * x
        g[tb.coupling[k, CP_ROW]] = p2 * xdot[qb] ** 2
        if 0 <= cc < nx:  # p(x) = sum c_m x^m: the mixed term 2 x' sum m c'_m x^(m-1)
            cd = xdot[cc : cc + 5]
            dp = cd[1] + 2.0 * cd[2] * x + 3.0 * cd[3] * x * x + 4.0 * cd[4] * x**3
            g[tb.coupling[k, CP_ROW]] += 2.0 * xdot[qb] * dp
    return g


#: :func:`velocity_solve` outcomes
SOLVED, NEEDS_SVD, INCONSISTENT = 0, 1, 2
#: relative consistency residual of the driven rates above which the compiled solve gives up
CONSISTENCY_RTOL = 1e-8


@njit
def velocity_solve(tb, plan, Q, S, C, L, rates, need, rows, cols, row_scale, buf, qdot, V, out):
    """Rates of every coordinate and twists of every body at the state ``Q, S, C, L``, compiled,
    on the engine's plan of the free set (every coordinate column not driven;
    :mod:`kinprop.solver.plan`): ``Phi_F qdot_F = -Phi_D qdot_D`` is one Newton linear step
    (:func:`kinprop.solver.newton.newton_step`) with ``Phi_D qdot_D`` in place of ``Phi``.

    ``rates`` (n_q): the driven columns' rates, zero elsewhere (``plan.free`` must be the other
    coordinate columns); ``need`` (n_columns, int8): 1 on every coordinate column; ``rows``,
    ``cols``: the Jacobian's pattern (``Engine.pattern``); ``buf``: :func:`kinprop.solver.newton.buffers`
    of the plan (afterwards ``buf[B_WS]`` holds the poses and frames). Writes ``qdot`` (n_q),
    ``V`` (nb, 6: ``[v_O ; omega]``) and ``out[0] = ||row_scale Phi||``. Returns ``SOLVED``,
    ``NEEDS_SVD`` (a block is rectangular or singular: the caller takes the SVD path with its rank
    check) or ``INCONSISTENT`` (the driven rates violate rows the free columns do not reach)."""
    Phi, vals, ws, none = buf[newton.B_PHI], buf[newton.B_VALS], buf[newton.B_WS], buf[newton.B_NONE]
    nq = qdot.shape[0]
    kernels.evaluate(tb, Q, S, C, L, ws, Phi, vals, need, none, none)
    r2 = 0.0
    for i in range(Phi.shape[0]):
        r2 += (Phi[i] * row_scale[i]) ** 2
        Phi[i] = 0.0
    out[0] = np.sqrt(r2)
    for k in range(rows.shape[0]):  # Phi_D qdot_D
        c = cols[k]
        if c < nq and rates[c] != 0.0:
            Phi[rows[k]] += vals[k] * rates[c]
    if newton.newton_step(plan, Phi, vals, buf, np.bool_(False)) == 0:
        return NEEDS_SVD
    dx = buf[newton.B_DX]
    for c in range(nq):
        qdot[c] = rates[c]
    for f in range(plan.free.shape[0]):
        if not np.isfinite(dx[f]):
            return NEEDS_SVD
        qdot[plan.free[f]] = dx[f]
    for i in range(Phi.shape[0]):  # rows no free column reaches: the driven rates must satisfy them
        Phi[i] = 0.0
    scale = 0.0
    for k in range(rows.shape[0]):
        c = cols[k]
        if c < nq:
            Phi[rows[k]] += vals[k] * qdot[c]
            scale = max(scale, abs(vals[k] * qdot[c]) * row_scale[rows[k]])
    for i in range(Phi.shape[0]):
        if abs(Phi[i]) * row_scale[i] > CONSISTENCY_RTOL * max(1.0, scale):
            return INCONSISTENT
    Tq = ws[kernels.W_TWIST_Q]
    for b in range(V.shape[0]):
        for x in range(6):
            V[b, x] = 0.0
    for t in range(tb.tree.shape[0]):
        j, par, chi = tb.tree[t, T_JOINT], tb.tree[t, T_PARENT], tb.tree[t, T_CHILD]
        q0, n = tb.joint[j, J_QCOL], tb.joint[j, J_NQ]
        for x in range(6):
            v = V[par, x]
            for y in range(max(n, 0)):
                v += Tq[t, x, y] * qdot[q0 + y]
            V[chi, x] = v
    return SOLVED


#: per engine, per driven addresses and thread: their columns, the plan of the other
#: coordinate columns, the ``need`` of every coordinate column and the solve's buffers (built
#: once; the engine caches its plans too)
_PLANS: weakref.WeakKeyDictionary[Any, dict[tuple[Any, ...], tuple[list[int], Any, Array, Any]]] = (
    weakref.WeakKeyDictionary()
)


def _velocity_plan(engine: Engine, rates: Mapping[str, Any]) -> tuple[list[int], list[float], Any, Array, Any]:
    """``(driven columns, their rates, plan, need, buffers)`` of :func:`velocity_solve`."""
    per = _PLANS.get(engine)
    if per is None:
        per = _PLANS[engine] = {}
    key = (*rates, threading.get_ident())
    found = per.get(key)
    if found is None or not all(isinstance(v, (int, float)) for v in rates.values()):
        cols, vals = _driven_rows(engine, rates)
        nq = engine.n_coordinates
        need = np.zeros(engine.n_columns, np.int8)
        need[:nq] = 1
        keep = np.ones(nq, bool)
        keep[cols] = False
        plan = engine.plan(np.flatnonzero(keep))
        unique = len(set(cols)) == len(cols)  # a coordinate driven twice: the SVD path checks it
        found = per[key] = (cols, plan, need, newton.buffers(engine.tables, plan, engine.nnz) if unique else None)
        return cols, vals, plan, need, found[3]
    return found[0], [float(v) for v in rates.values()], found[1], found[2], found[3]


def _compiled_motion(engine: Engine, state: State, rates: Mapping[str, Any]) -> MotionState | None:
    """:func:`velocity_solve` on the engine's plan (None: the SVD path must decide)."""
    cols, vals, plan, need, buf = _velocity_plan(engine, rates)
    if buf is None:
        return None
    nq, tb = engine.n_coordinates, engine.tables
    rate = np.zeros(nq)
    for c, v in zip(cols, vals, strict=True):
        rate[c] = v
    rows, pcols = engine.pattern
    st = state.writable()
    qdot, V, out = np.zeros(nq), np.zeros((tb.fixed.shape[0], 6)), np.zeros(1)
    code = velocity_solve(
        tb, plan, st.Q, st.S, st.C, st.L, rate, need, rows, pcols, engine.row_scale, buf, qdot, V, out
    )
    if code != SOLVED:
        return None
    ws = buf[newton.B_WS]  # the buffers are reused: copy the poses out
    r, A, P, R = (ws[k].copy() for k in (kernels.W_BODY_R, kernels.W_BODY_A, kernels.W_FRAME_P, kernels.W_FRAME_R))
    return MotionState(OK, message(OK), qdot, V, r, A, P, R, conditioning=math.nan, residual=float(out[0]))


def motion_state(
    engine: Engine, state: State, rates: Mapping[str, Any], accelerations: Mapping[str, Any] | None = None
) -> MotionState:
    """Velocities and, when ``accelerations`` (of the same driven coordinates; missing ones 0)
    is given, accelerations of every coordinate and body (module docstring). Velocities alone
    are solved compiled on the engine's plan (:func:`velocity_solve`) when every block is square
    and regular; otherwise (and for accelerations) by the SVD with its rank check."""
    if accelerations is None:
        ms = _compiled_motion(engine, state, rates)
        if ms is not None:
            return ms
    return _motion(engine, _Frames(engine, state), rates, accelerations)[0]


def _motion(
    engine: Engine, fr: _Frames, rates: Mapping[str, Any], accelerations: Mapping[str, Any] | None
) -> tuple[MotionState, _Factor]:
    cols, vals = _driven_rows(engine, rates)
    fac = _Factor(engine, fr.Phi_q, cols)
    qdot, msg = fac.solve(np.zeros(engine.n_rows), vals)
    status, cond = (SINGULAR if msg else OK), fac.conditioning
    V = _tree_velocities(engine, fr, qdot)
    if msg or accelerations is None:
        nan = None if accelerations is None else np.full_like(qdot, np.nan)
        ms = MotionState(
            status,
            msg or message(OK),
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
        return ms, fac
    acc = {a: 0.0 for a in rates} | dict(accelerations)
    acols, avals = _driven_rows(engine, acc)
    if sorted(acols) != sorted(cols):
        raise ValueError("accelerations are given for the driven coordinates only (the ones with rates)")
    avals = [dict(zip(acols, avals, strict=True))[c] for c in cols]  # in the rates' row order
    dV0 = _tree_bias(engine, fr, qdot, V)
    gamma = _gamma(engine, fr, qdot, V, dV0)
    qddot, msg = fac.solve(gamma, avals)
    dV = dV0 + _tree_velocities(engine, fr, qddot)  # the q-ddot part is linear, like the twists
    ms = MotionState(
        SINGULAR if msg else OK, msg or message(OK), qdot, V, fr.r, fr.A, fr.P, fr.R, qddot, dV, cond, fr.residual
    )
    return ms, fac


@dataclass(frozen=True)
class MotionDerivatives:
    """First derivatives of a velocity state along ``k`` state directions ``dx`` (columns of
    ``directions``, solver units; :func:`motion_derivatives`)."""

    motion: MotionState
    #: (k, nb, 6) first-order change of every body's pose along each direction, as a twist
    #: ``[dv_O ; dpi]`` (a body point at P moves by ``dv_O + dpi x P``)
    pose: Array
    #: (k, n_q) derivative of the coordinate rates
    qdot: Array
    #: (k, nb, 6) derivative of every body's twist ``V = [v_O ; omega]``
    V: Array


def motion_derivatives(engine: Engine, state: State, rates: Mapping[str, Any], directions: Array) -> MotionDerivatives:
    """Exact derivatives of the velocity state (rates ``rates`` of the driven coordinates,
    held fixed) along each column ``dx`` of ``directions`` (``(n_columns, k)``, solver units;
    the state moves along ``retract(x, eps dx)``).

    With ``a = [qdot ; 0]`` and ``b = dx``: ``[Phi_q ; E_D] dqdot = [-Phi_xx[a, b] ; 0]``, the
    mixed second derivative by polarisation of the exact quadratic ``gamma``:
    ``-Phi_xx[a, b] = (gamma(a + b) - gamma(a - b)) / 4`` (``b`` rescaled to ``a``'s size first);
    the twists' derivative ``d(T a)/db = T dqdot + (dV0(a + b) - dV0(a - b)) / 4 + (T b) x (T a) / 2``
    (the polarised bias is the symmetric part; the spatial cross product of the two twists the
    antisymmetric one, the structure equation ``d_b T_a - d_a T_b = [T_b, T_a]``). Nothing is
    differenced."""
    fr = _Frames(engine, state, design=True)
    ms, fac = _motion(engine, fr, rates, None)
    X = np.asarray(directions, dtype=float).reshape(engine.n_columns, -1)
    k, nq, nb = X.shape[1], engine.n_coordinates, ms.V.shape[0]
    pose = np.stack([_tree_velocities(engine, fr, X[:, i]) for i in range(k)]) if k else np.zeros((0, nb, 6))
    if not ms.ok:
        return MotionDerivatives(ms, pose, np.full((k, nq), np.nan), np.full((k, nb, 6), np.nan))
    a = np.zeros(engine.n_columns)
    a[:nq] = ms.qdot
    Va, cs = ms.V, engine.col_scale
    na = float(np.linalg.norm(a * cs))
    dq, dV = np.zeros((k, nq)), np.zeros((k, nb, 6))
    zero = np.zeros(len(fac.cols))
    for i in range(k):
        nb_ = float(np.linalg.norm(X[:, i] * cs))
        s = na / nb_ if nb_ > 0 and na > 0 else 1.0  # polarise at comparable sizes (round-off)
        b, Vb = s * X[:, i], s * pose[i]
        dV_p, dV_m = _tree_bias(engine, fr, a + b, Va + Vb), _tree_bias(engine, fr, a - b, Va - Vb)
        rhs = 0.25 * (_gamma(engine, fr, a + b, Va + Vb, dV_p) - _gamma(engine, fr, a - b, Va - Vb, dV_m))
        dq[i], _ = fac.solve(rhs, zero)
        sym = 0.25 * (dV_p - dV_m)
        skew = np.stack([0.5 * spatial_cross(Vb[n], Va[n]) for n in range(nb)])
        dV[i] = _tree_velocities(engine, fr, dq[i]) + sym + skew
        dq[i] /= s
        dV[i] /= s
    return MotionDerivatives(ms, pose, dq, dV)


__all__ = [
    "MotionDerivatives",
    "MotionState",
    "cross3",
    "motion_derivatives",
    "motion_state",
    "spatial_cross",
    "velocity_solve",
]
