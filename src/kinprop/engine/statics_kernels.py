"""Compiled loops of the kinetostatics (:mod:`kinprop.engine.statics`) and of their rates
(:mod:`kinprop.engine.statics_rates`): the formulas are those modules' docstrings, written
once here over the kernel's tables and workspace (poses, joint frames, tree twists); the
callers keep the linear algebra (SVD, least squares) and the bookkeeping.

Element laws are passed as a table: ``li`` (ne, 5) int ``[torsion, body_i, body_j, joint,
col]`` and ``lf`` (ne, 9) float ``[s_i (3), s_j (3), k, L0 (theta0), f0 (T0)]``. Point loads
as ``body`` (n,), ``P``, ``F``, ``M`` (n, 3), ``follows`` (n,), and the wheel terms ``radius``
(n,, 0: a material point), ``centre``, ``axis`` (n, 3), ``sae`` (n,).
"""

from __future__ import annotations

import math

import numpy as np

from kinprop.constraints.basic import DISTANCE, DOT1, DOT2, SPHERICAL, basic_rows
from kinprop.jit import kernel, njit
from kinprop.joints import motion, placement
from kinprop.joints.composite import FREE_CODE, ST_CODE, TD_CODE
from kinprop.joints.spherical import CODE as SPHERICAL_CODE
from kinprop.joints.universal import CODE as UNIVERSAL_CODE
from kinprop.kinematics.kernels import MAX_CUT_ROWS, MAX_Q
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

#: columns of the element-law tables ``li`` and ``lf``
L_TORSION, L_BODY_I, L_BODY_J, L_JOINT, L_COL = range(5)
LF_SI, LF_SJ, LF_K, LF_L0, LF_F0 = 0, 3, 6, 7, 8


@njit
def _cross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


@njit
def _mv(A, x):
    return np.array([A[0, 0] * x[0] + A[0, 1] * x[1] + A[0, 2] * x[2], A[1, 0] * x[0] + A[1, 1] * x[1] + A[1, 2] * x[2],
                     A[2, 0] * x[0] + A[2, 1] * x[1] + A[2, 2] * x[2]])  # fmt: skip


@njit
def _mtv(A, x):
    return np.array([A[0, 0] * x[0] + A[1, 0] * x[1] + A[2, 0] * x[2], A[0, 1] * x[0] + A[1, 1] * x[1] + A[2, 1] * x[2],
                     A[0, 2] * x[0] + A[1, 2] * x[1] + A[2, 2] * x[2]])  # fmt: skip


@njit
def _rows(kind):
    return 3 if kind == SPHERICAL else 1


@njit
def subtree_sums(tb, W):
    """``W_sub`` (nb, 6): each body's wrench plus those of every body below it in the tree."""
    Ws = W.copy()
    for t in range(tb.tree.shape[0] - 1, -1, -1):
        Ws[tb.tree[t, T_PARENT]] += Ws[tb.tree[t, T_CHILD]]
    return Ws


@njit
def subtree_sums_k(tb, W):
    """:func:`subtree_sums` of a batch (K, nb, 6)."""
    Ws = W.copy()
    for t in range(tb.tree.shape[0] - 1, -1, -1):
        Ws[:, tb.tree[t, T_PARENT]] += Ws[:, tb.tree[t, T_CHILD]]
    return Ws


@njit
def generalized_forces(tb, Tq, W, nq):
    """``Q_t = T_t^T W_sub(t)`` (nq,) of body wrenches ``W`` (nb, 6) about the origin."""
    Ws = subtree_sums(tb, W)
    Qg = np.zeros(nq)
    for t in range(tb.tree.shape[0]):
        j, chi = tb.tree[t, T_JOINT], tb.tree[t, T_CHILD]
        q0, n = tb.joint[j, J_QCOL], tb.joint[j, J_NQ]
        for y in range(n):
            s = 0.0
            for x in range(6):
                s += Tq[t, x, y] * Ws[chi, x]
            Qg[q0 + y] = s
    return Qg


@njit
def element_forces(li, lf, r, A, Q, P, R, nb):
    """``(f, lengths, ends (ne, 2, 3), W (nb, 6))`` of the element laws (a torsion spring's
    torque, angle and its joint's points)."""
    ne = li.shape[0]
    f, lengths, ends, W = np.zeros(ne), np.zeros(ne), np.zeros((ne, 2, 3)), np.zeros((nb, 6))
    for k in range(ne):
        bi, bj = li[k, L_BODY_I], li[k, L_BODY_J]
        if li[k, L_TORSION]:
            jn, q = li[k, L_JOINT], Q[li[k, L_COL]]
            f[k] = lf[k, LF_F0] + lf[k, LF_K] * (lf[k, LF_L0] - q)
            lengths[k] = q
            ends[k] = P[jn]
            for x in range(3):
                W[bj, 3 + x] += f[k] * R[jn, 0, x, 2]
                W[bi, 3 + x] -= f[k] * R[jn, 0, x, 2]
            continue
        Pi = r[bi] + _mv(A[bi], lf[k, LF_SI : LF_SI + 3])
        Pj = r[bj] + _mv(A[bj], lf[k, LF_SJ : LF_SJ + 3])
        d = Pj - Pi
        length = math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
        f[k] = lf[k, LF_F0] + lf[k, LF_K] * (lf[k, LF_L0] - length)
        lengths[k] = length
        ends[k, 0], ends[k, 1] = Pi, Pj
        if f[k] != 0.0:
            if length == 0.0:
                raise ValueError("an element with a force has zero length: its direction is undefined")
            F = f[k] * d / length  # on body j, pushing it away from i
            W[bj, :3] += F
            W[bj, 3:] += _cross(Pj, F)
            W[bi, :3] -= F
            W[bi, 3:] -= _cross(Pi, F)
    return f, lengths, ends, W


@njit
def point_wrenches(body, P, F, M, nb):
    """(nb, 6) ``[F ; M + P x F]`` summed by body."""
    W = np.zeros((nb, 6))
    for k in range(body.shape[0]):
        W[body[k], :3] += F[k]
        W[body[k], 3:] += M[k] + _cross(P[k], F[k])
    return W


@njit
def cut_terms(tb, P, R, Q, L):
    """Every cut joint's rows' partials: ``P_i`` (slid along ``z''_i`` by a T-D joint's own
    coordinate), ``d``, ``Phi_d``, ``Phi_wi``, ``Phi_wj`` (nc, MAX_CUT_ROWS, 3), the arms
    ``Z_i``, ``Z_j`` (nc, MAX_CUT_ROWS, 6), the rows per cut; and per joint its distance row
    (-1: none) with the rod's length."""
    nc, nj = tb.cut.shape[0], tb.joint.shape[0]
    Pi, d = np.zeros((nc, 3)), np.zeros((nc, 3))
    Pd, Wi, Wj = np.zeros((nc, MAX_CUT_ROWS, 3)), np.zeros((nc, MAX_CUT_ROWS, 3)), np.zeros((nc, MAX_CUT_ROWS, 3))
    Zi, Zj = np.zeros((nc, MAX_CUT_ROWS, 6)), np.zeros((nc, MAX_CUT_ROWS, 6))
    mrows = np.zeros(nc, np.int64)
    rod_row, rod_len = np.full(nj, -1, np.int64), np.full(nj, np.nan)
    Phi, Pl = np.zeros(MAX_CUT_ROWS), np.zeros(MAX_CUT_ROWS)
    for c in range(nc):
        j = tb.cut[c, K_JOINT]
        Pi[c] = P[j, 0]
        if tb.joint[j, J_CODE] == TD_CODE:
            Pi[c] += R[j, 0, :, 2] * Q[tb.joint[j, J_QCOL]]
        d[c] = P[j, 1] - Pi[c]
        m = 0
        for b in range(tb.cut[c, K_BASIC0], tb.cut[c, K_BASIC1]):
            kind = tb.basic[b, B_KIND]
            if kind == DISTANCE:
                rod_row[j] = tb.cut[c, K_ROW0] + m
                rod_len[j] = math.sqrt(d[c, 0] ** 2 + d[c, 1] ** 2 + d[c, 2] ** 2)
            m += basic_rows(kind, tb.basic[b, B_ON_J], tb.basic_axes[b], d[c], R[j, 0], R[j, 1], L[j], m, Phi,
                            Pd[c], Wi[c], Wj[c], Pl)  # fmt: skip
        mrows[c] = m
        for x in range(m):
            Zi[c, x, :3] = -Pd[c, x]
            Zi[c, x, 3:] = _cross(Pd[c, x], Pi[c]) + Wi[c, x]
            Zj[c, x, :3] = Pd[c, x]
            Zj[c, x, 3:] = Wj[c, x] - _cross(Pd[c, x], P[j, 1])
    return Pi, d, Pd, Wi, Wj, Zi, Zj, mrows, rod_row, rod_len


@njit
def reactions(tb, Zi, Zj, mrows, lam, W_applied):
    """Every joint's wrench (nj, 2, 6) on its bodies i and j, from the multipliers and the
    applied wrenches: ``Z^T lambda`` on cut joints, minus the subtree sums on tree joints."""
    nj = tb.joint.shape[0]
    out = np.zeros((nj, 2, 6))
    W = W_applied.copy()
    for c in range(tb.cut.shape[0]):
        j, r0 = tb.cut[c, K_JOINT], tb.cut[c, K_ROW0]
        for x in range(mrows[c]):
            out[j, 0] += Zi[c, x] * lam[r0 + x]
            out[j, 1] += Zj[c, x] * lam[r0 + x]
        W[tb.joint[j, J_BODY_I]] += out[j, 0]
        W[tb.joint[j, J_BODY_J]] += out[j, 1]
    Ws = subtree_sums(tb, W)
    for t in range(tb.tree.shape[0]):
        j, chi = tb.tree[t, T_JOINT], tb.tree[t, T_CHILD]
        side = 0 if tb.tree[t, T_REVERSED] else 1
        out[j, side] = -Ws[chi]
        out[j, 1 - side] = Ws[chi]
    return out


@njit
def at_points(W, P, R):
    """Joint wrenches (nj, 2, 6) as force and moment about the joint's point on each body:
    global axes, and joint frame i's axes (the same frame for both sides)."""
    G, loc = np.zeros(W.shape), np.zeros(W.shape)
    for j in range(W.shape[0]):
        for s in range(2):
            G[j, s, :3] = W[j, s, :3]
            G[j, s, 3:] = W[j, s, 3:] - _cross(P[j, s], W[j, s, :3])
            loc[j, s, :3] = _mtv(R[j, 0], G[j, s, :3])
            loc[j, s, 3:] = _mtv(R[j, 0], G[j, s, 3:])
    return G, loc


@kernel
def _xacc(a, b, out, s):
    """``out[:3] += s (a x b)``."""
    a0, a1, a2, b0, b1, b2 = a[0], a[1], a[2], b[0], b[1], b[2]
    out[0] += s * (a1 * b2 - a2 * b1)
    out[1] += s * (a2 * b0 - a0 * b2)
    out[2] += s * (a0 * b1 - a1 * b0)


@kernel
def _mvacc(A, x, out, s):
    """``out[:3] += s A x``."""
    x0, x1, x2 = x[0], x[1], x[2]
    for i in range(3):
        out[i] += s * (A[i, 0] * x0 + A[i, 1] * x1 + A[i, 2] * x2)


@kernel
def _mtvacc(A, x, out, s):
    """``out[:3] += s A^T x``."""
    x0, x1, x2 = x[0], x[1], x[2]
    for i in range(3):
        out[i] += s * (A[0, i] * x0 + A[1, i] * x1 + A[2, i] * x2)


@kernel
def _copy(src, dst):
    """``dst[:] = src`` (1-d, without a temporary)."""
    for x in range(dst.shape[0]):
        dst[x] = src[x]


@kernel
def _subtree_into(tb, Ws):
    """:func:`subtree_sums` in place on ``Ws`` (nb, 6)."""
    for t in range(tb.tree.shape[0] - 1, -1, -1):
        p, c = tb.tree[t, T_PARENT], tb.tree[t, T_CHILD]
        for x in range(6):
            Ws[p, x] += Ws[c, x]


@kernel
def _subtree_into_k(tb, Ws):
    """:func:`subtree_sums_k` in place on ``Ws`` (K, nb, 6)."""
    for t in range(tb.tree.shape[0] - 1, -1, -1):
        p, c = tb.tree[t, T_PARENT], tb.tree[t, T_CHILD]
        for k in range(Ws.shape[0]):
            for x in range(6):
                Ws[k, p, x] += Ws[k, c, x]


@kernel
def _dot3(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@kernel
def _design_twist(X, k, col_s, col_c, A, P, out, w, sign):
    """``out += sign *`` the twist of a joint frame on its body from its own design rates (``w``: scratch)."""
    if col_s >= 0:
        _mvacc(A, X[k, col_s : col_s + 3], out, sign)
    if col_c >= 0:
        w[:] = 0.0
        _mvacc(A, X[k, col_c : col_c + 3], w, 1.0)
        for x in range(3):
            out[3 + x] += sign * w[x]
        _xacc(P, w, out, sign)


@njit
def twists(tb, A, P, Tq, X):
    """``(V, U)``: body twists (K, nb, 6) and joint frame twists (K, nj, 2, 6) of the state
    directions ``X`` (K, n_columns)."""
    K = X.shape[0]
    V, U = np.zeros((K, tb.fixed.shape[0], 6)), np.zeros((K, tb.joint.shape[0], 2, 6))
    _twists_into(tb, A, P, Tq, X, V, U, np.zeros(3))
    return V, U


@kernel
def _twists_into(tb, A, P, Tq, X, V, U, w):
    """:func:`twists` into ``V``, ``U`` (zeroed; ``w``: scratch 3-vector)."""
    K = X.shape[0]
    for t in range(tb.tree.shape[0]):
        j, par, chi = tb.tree[t, T_JOINT], tb.tree[t, T_PARENT], tb.tree[t, T_CHILD]
        q0, nq = tb.joint[j, J_QCOL], tb.joint[j, J_NQ]
        a, b = (0, 1) if tb.tree[t, T_REVERSED] == 0 else (1, 0)
        ca, cb = J_COL_S_I + a, J_COL_S_I + b
        for k in range(K):
            Ua, Ub = U[k, j, a], U[k, j, b]
            _copy(V[k, par], Ua)
            _design_twist(X, k, tb.joint[j, ca], tb.joint[j, ca + 2], A[par], P[j, a], Ua, w, 1.0)
            _copy(Ua, Ub)
            for y in range(max(nq, 0)):
                xq = X[k, q0 + y]
                for x in range(6):
                    Ub[x] += Tq[t, x, y] * xq
            _copy(Ub, V[k, chi])
            _design_twist(X, k, tb.joint[j, cb], tb.joint[j, cb + 2], A[chi], P[j, b], V[k, chi], w, -1.0)
    for c in range(tb.cut.shape[0]):
        j = tb.cut[c, K_JOINT]
        for s in range(2):
            body = tb.joint[j, J_BODY_I + s]
            for k in range(K):
                _copy(V[k, body], U[k, j, s])
                _design_twist(X, k, tb.joint[j, J_COL_S_I + s], tb.joint[j, J_COL_S_I + 2 + s], A[body], P[j, s],
                              U[k, j, s], w, 1.0)  # fmt: skip


@njit
def element_rates(li, lf, held, r, A, V, qdot, frame_w, R, Q):
    """``(dW (K, nb, 6), df (K, ne), dL (K, ne))`` of the element laws under body twists ``V``
    (``qdot`` (K, n_q) and joint frame i's angular velocity ``frame_w`` (K, nj, 3) for torsion
    springs; ``held`` (ne,): a force held at its preload)."""
    K, ne = V.shape[0], li.shape[0]
    dW, df, dL = np.zeros(V.shape), np.zeros((K, ne)), np.zeros((K, ne))
    vi, vj, dd, du, dF = np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3)
    for e in range(ne):
        bi, bj, ks = li[e, L_BODY_I], li[e, L_BODY_J], lf[e, LF_K]
        if li[e, L_TORSION]:
            jn, col = li[e, L_JOINT], li[e, L_COL]
            a = R[jn, 0, :, 2]
            T = lf[e, LF_F0] + ks * (lf[e, LF_L0] - Q[col])
            for k in range(K):
                dL[k, e] = qdot[k, col]
                df[k, e] = 0.0 if held[e] else -ks * dL[k, e]
                for x in range(3):
                    dW[k, bj, 3 + x] += df[k, e] * a[x]
                    dW[k, bi, 3 + x] -= df[k, e] * a[x]
                _xacc(frame_w[k, jn], a, dW[k, bj, 3:], T)
                _xacc(frame_w[k, jn], a, dW[k, bi, 3:], -T)
            continue
        Pi = r[bi] + _mv(A[bi], lf[e, LF_SI : LF_SI + 3])
        Pj = r[bj] + _mv(A[bj], lf[e, LF_SJ : LF_SJ + 3])
        d = Pj - Pi
        length = math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
        if length == 0.0:
            continue
        u = d / length
        f = lf[e, LF_F0] + ks * (lf[e, LF_L0] - length)
        Fv = f * u
        for k in range(K):
            vi[:] = V[k, bi, :3]
            _xacc(V[k, bi, 3:], Pi, vi, 1.0)
            vj[:] = V[k, bj, :3]
            _xacc(V[k, bj, 3:], Pj, vj, 1.0)
            for x in range(3):
                dd[x] = vj[x] - vi[x]
            dl = _dot3(dd, u)
            dL[k, e] = dl
            df[k, e] = 0.0 if held[e] else -ks * dl
            for x in range(3):
                du[x] = (dd[x] - dl * u[x]) / length
                dF[x] = df[k, e] * u[x] + f * du[x]
                dW[k, bj, x] += dF[x]
                dW[k, bi, x] -= dF[x]
            _xacc(vj, Fv, dW[k, bj, 3:], 1.0)
            _xacc(Pj, dF, dW[k, bj, 3:], 1.0)
            _xacc(vi, Fv, dW[k, bi, 3:], -1.0)
            _xacc(Pi, dF, dW[k, bi, 3:], -1.0)
    return dW, df, dL


@kernel
def contact_rate(radius, centre, axis, sae, Vb, out, v):
    """``out`` (3,): velocity of a wheel load's contact point (the lowest point of the wheel
    circle ``centre + radius n``, ``n`` along ``-z`` projected onto the wheel plane; in SAE
    axes the lowest point of the z-mirrored circle) under the wheel body's twist ``Vb`` (6,)
    (``v``: scratch (4, 3))."""
    fz = -1.0 if sae else 1.0
    vc, da, a, dg = v[0], v[1], v[2], v[3]
    for x in range(3):
        vc[x], da[x], a[x] = Vb[x], 0.0, axis[x]
    _xacc(Vb[3:], centre, vc, 1.0)
    _xacc(Vb[3:], axis, da, 1.0)
    vc[2], da[2], a[2] = fz * vc[2], fz * da[2], fz * a[2]
    g0, g1, g2 = a[2] * a[0], a[2] * a[1], -1.0 + a[2] * a[2]
    ng = math.sqrt(g0 * g0 + g1 * g1 + g2 * g2)
    n0, n1, n2 = g0 / ng, g1 / ng, g2 / ng
    for x in range(3):
        dg[x] = da[2] * a[x] + a[2] * da[x]
    gn = dg[0] * n0 + dg[1] * n1 + dg[2] * n2
    out[0] = vc[0] + radius * (dg[0] - gn * n0) / ng
    out[1] = vc[1] + radius * (dg[1] - gn * n1) / ng
    out[2] = fz * (vc[2] + radius * (dg[2] - gn * n2) / ng)


@njit
def load_rates(body, P, F, M, follows, radius, centre, axis, sae, V):
    """(K, nb, 6) rates of the applied wrenches about the origin under body twists ``V``: a
    force at a material point has ``dM_O = v_P x F + P x dF`` (``dF = omega x F`` in body
    axes); a wheel load's contact point moves as :func:`contact_rate` says."""
    dW = np.zeros(V.shape)
    _load_rates_into(body, P, F, M, follows, radius, centre, axis, sae, V, dW, np.zeros((6, 3)))
    return dW


@kernel
def _load_rates_into(body, P, F, M, follows, radius, centre, axis, sae, V, dW, v):
    """:func:`load_rates` into ``dW`` (zeroed; ``v``: scratch (6, 3))."""
    vP, dF = v[0], v[1]
    for n in range(body.shape[0]):
        b = body[n]
        for k in range(V.shape[0]):
            w = V[k, b, 3:]
            if radius[n] > 0.0:
                contact_rate(radius[n], centre[n], axis[n], sae[n], V[k, b], vP, v[2:])
            else:
                _copy(V[k, b, :3], vP)
                _xacc(w, P[n], vP, 1.0)
            if follows[n]:
                dF[:] = 0.0
                _xacc(w, F[n], dF, 1.0)
                for x in range(3):
                    dW[k, b, x] += dF[x]
                _xacc(w, M[n], dW[k, b, 3:], 1.0)
                _xacc(P[n], dF, dW[k, b, 3:], 1.0)
            _xacc(vP, F[n], dW[k, b, 3:], 1.0)


@kernel
def _local_rates(code, q, qd, App, dpp, dd, H, nq, ddd, dH, v):
    """``(d dd'', d H'')`` into ``ddd``, ``dH`` (3, >= nq, zeroed here): rates of a tree joint's
    motion columns (joint frame i) from its coordinates' rates ``qd`` (nq,); zero for revolute,
    prismatic, cylindrical (``v``: scratch (2, 3))."""
    for x in range(3):
        for y in range(nq):
            ddd[x, y], dH[x, y] = 0.0, 0.0
    if code == UNIVERSAL_CODE:  # H[:, 1] = Rz(q0) e_y
        dH[0, 1], dH[1, 1] = -qd[0] * math.cos(q[0]), -qd[0] * math.sin(q[0])
    elif code == SPHERICAL_CODE or code == ST_CODE:  # noqa: SIM109 (numba)  H = 2 E(p)
        _E_acc(qd, 0, dH, 0, 2.0)
        if code == ST_CODE:  # dd_y = -d'' x H_y (y < 4), dd_4 = A'' e_z
            dp, hq = v[0], v[1]
            dp[:], hq[:] = 0.0, 0.0
            for y in range(nq):
                for x in range(3):
                    dp[x] += dd[x, y] * qd[y]
                    hq[x] += H[x, y] * qd[y]
            for y in range(4):
                _xacc(dp, H[:, y], ddd[:, y], -1.0)
                _xacc(dpp, dH[:, y], ddd[:, y], -1.0)
            _xacc(hq, App[:, 2], ddd[:, 4], 1.0)
    elif code == FREE_CODE:  # H = 2 E(p) / (p.p)
        pp = q[3] * q[3] + q[4] * q[4] + q[5] * q[5] + q[6] * q[6]
        qp = qd[3] * q[3] + qd[4] * q[4] + qd[5] * q[5] + qd[6] * q[6]
        _E_acc(qd, 3, dH, 3, 2.0 / pp)
        _E_acc(q, 3, dH, 3, -4.0 * qp / pp**2)


@kernel
def _E_acc(p, i, out, col, s):
    """``out[:, col:col + 4] += s E(p[i:i + 4])``, ``E(p) = [-e, tilde(e) + e0 I]`` (eq. 40)."""
    e0, e1, e2, e3 = s * p[i], s * p[i + 1], s * p[i + 2], s * p[i + 3]
    out[0, col] -= e1
    out[0, col + 1] += e0
    out[0, col + 2] -= e3
    out[0, col + 3] += e2
    out[1, col] -= e2
    out[1, col + 1] += e3
    out[1, col + 2] += e0
    out[1, col + 3] -= e1
    out[2, col] -= e3
    out[2, col + 1] -= e2
    out[2, col + 2] += e1
    out[2, col + 3] += e0


@njit
def rates_rhs(tb, P, R, Tq, Q, L, X, lam, V, U, Pi, d, Pd, Wi, Wj, mrows, W_applied, dW_applied, nq):
    """The equilibrium's rate ``dG`` (K, nq) (the right-hand side is ``-dG``) along the state
    directions ``X`` at fixed multipliers, and the cut joints' wrench rates at fixed
    multipliers ``dW_i``, ``dW_j`` (K, nc, 6), their ``dd`` (K, nc, 3) and every wrench's rate
    ``dW`` (K, nb, 6) (applied, elements and cut joints) (:mod:`kinprop.engine.statics_rates`)."""
    K, nb, nc = X.shape[0], V.shape[1], tb.cut.shape[0]
    W_cut, dW_all, Ws = np.zeros((nb, 6)), dW_applied.copy(), np.zeros((nb, 6))
    dG, dWs = np.zeros((K, nq)), np.zeros((K, nb, 6))
    dWi_c, dWj_c, ddc = np.zeros((K, nc, 6)), np.zeros((K, nc, 6)), np.zeros((K, nc, 3))
    _rates_rhs_into(tb, P, R, Tq, Q, L, X, lam, V, U, Pi, d, Pd, Wi, Wj, mrows, W_applied, W_cut, dW_all, Ws, dG,
                    dWs, dWi_c, dWj_c, ddc, np.zeros((5, MAX_CUT_ROWS, 3)), np.zeros((22, 3)),
                    np.zeros((4, 3, MAX_Q)), np.zeros((3, 3)))  # fmt: skip
    return dG, dWi_c, dWj_c, ddc, dW_all


@kernel
def _rates_rhs_into(tb, P, R, Tq, Q, L, X, lam, V, U, Pi, d, Pd, Wi, Wj, mrows, W_applied, W_cut, dW_all, Ws, dG,
                    dWs, dWi_c, dWj_c, ddc, S3, v3, M3, App):  # fmt: skip
    """:func:`rates_rhs` into the zeroed outputs (``dW_all`` holding the applied wrenches'
    rates; ``Ws``, ``dWs``: the subtree sums; ``S3``, ``v3``, ``M3``, ``App``: scratch)."""
    K, nc = X.shape[0], tb.cut.shape[0]
    dPd, dWi, dWj, AI, AJ = S3[0], S3[1], S3[2], S3[3], S3[4]
    f, mi, mj, e, vPi, vPj, de, dd, s1, s2, df = (
        v3[0],
        v3[1],
        v3[2],
        v3[3],
        v3[4],
        v3[5],
        v3[6],
        v3[7],
        v3[8],
        v3[9],
        v3[10],
    )
    dmi, dmj, dpp, dp, u_loc, w, v, sv, sw = v3[11], v3[12], v3[13], v3[14], v3[15], v3[16], v3[17], v3[18], v3[19]
    v2 = v3[20:22]
    ddm, Hm, ddd, dH = M3[0], M3[1], M3[2], M3[3]
    for c in range(nc):
        j, r0, mc = tb.cut[c, K_JOINT], tb.cut[c, K_ROW0], mrows[c]
        bi, bj = tb.joint[j, J_BODY_I], tb.joint[j, J_BODY_J]
        f[:], mi[:], mj[:] = 0.0, 0.0, 0.0
        for x in range(mc):
            for y in range(3):
                f[y] += Pd[c, x, y] * lam[r0 + x]
                mi[y] += Wi[c, x, y] * lam[r0 + x]
                mj[y] += Wj[c, x, y] * lam[r0 + x]
        Pj = P[j, 1]
        for y in range(3):
            W_cut[bi, y] -= f[y]
            W_cut[bj, y] += f[y]
            W_cut[bi, 3 + y] += mi[y]
            W_cut[bj, 3 + y] += mj[y]
        _xacc(f, Pi[c], W_cut[bi, 3:], 1.0)
        _xacc(f, Pj, W_cut[bj, 3:], -1.0)
        td = tb.joint[j, J_NQ] > 0  # T-D: the point on body i slides along z''_i
        qc = tb.joint[j, J_QCOL]
        _copy(R[j, 0, :, 2], e)
        r = 0
        for bc in range(tb.cut[c, K_BASIC0], tb.cut[c, K_BASIC1]):  # the rows' axes (global)
            kind, on_j, ax = tb.basic[bc, B_KIND], tb.basic[bc, B_ON_J], tb.basic_axes[bc]
            AI[r], AJ[r] = 0.0, 0.0
            if kind == DOT1:
                _mvacc(R[j, 0], ax[:3], AI[r], 1.0)
                _mvacc(R[j, 1], ax[3:6], AJ[r], 1.0)
            elif kind == DOT2:
                _mvacc(R[j, 1] if on_j else R[j, 0], ax[:3], AI[r], 1.0)
            r += _rows(kind)
        for k in range(K):
            wi, wj = U[k, j, 0, 3:], U[k, j, 1, 3:]
            _copy(U[k, j, 0, :3], vPi)
            _xacc(wi, P[j, 0], vPi, 1.0)
            _copy(U[k, j, 1, :3], vPj)
            _xacc(wj, P[j, 1], vPj, 1.0)
            de[:] = 0.0
            _xacc(wi, e, de, 1.0)
            if td:
                for x in range(3):
                    vPi[x] += de[x] * Q[qc] + X[k, qc] * e[x]
            for x in range(3):
                dd[x] = vPj[x] - vPi[x]
            dPd[:], dWi[:], dWj[:] = 0.0, 0.0, 0.0
            r = 0
            for bc in range(tb.cut[c, K_BASIC0], tb.cut[c, K_BASIC1]):
                kind, on_j = tb.basic[bc, B_KIND], tb.basic[bc, B_ON_J]
                if kind == DOT1:
                    s1[:], s2[:] = 0.0, 0.0
                    _xacc(wi, AI[r], s1, 1.0)
                    _xacc(wj, AJ[r], s2, 1.0)
                    _xacc(s1, AJ[r], dWi[r], 1.0)
                    _xacc(AI[r], s2, dWi[r], 1.0)
                    for x in range(3):
                        dWj[r, x] = -dWi[r, x]
                elif kind == DOT2:
                    _xacc(wj if on_j else wi, AI[r], dPd[r], 1.0)
                    tgt = dWj[r] if on_j else dWi[r]
                    _xacc(dPd[r], d[c], tgt, 1.0)
                    _xacc(AI[r], dd, tgt, 1.0)
                elif kind == DISTANCE:
                    for x in range(3):
                        dPd[r, x] = 2.0 * dd[x]
                r += _rows(kind)
            df[:], dmi[:], dmj[:] = 0.0, 0.0, 0.0
            for x in range(mc):
                lx = lam[r0 + x]
                for y in range(3):
                    df[y] += dPd[x, y] * lx
                    dmi[y] += dWi[x, y] * lx
                    dmj[y] += dWj[x, y] * lx
            wic, wjc = dWi_c[k, c], dWj_c[k, c]  # lambda held
            for y in range(3):
                wic[y], wic[3 + y] = -df[y], dmi[y]
                wjc[y], wjc[3 + y] = df[y], dmj[y]
            _xacc(df, Pi[c], wic[3:], 1.0)
            _xacc(f, vPi, wic[3:], 1.0)
            _xacc(df, Pj, wjc[3:], -1.0)
            _xacc(f, vPj, wjc[3:], -1.0)
            for y in range(6):
                dW_all[k, bi, y] += wic[y]
                dW_all[k, bj, y] += wjc[y]
            if td:
                dG[k, qc] -= _dot3(df, e) + _dot3(de, f)
            _copy(dd, ddc[k, c])
    for b in range(Ws.shape[0]):
        for x in range(6):
            Ws[b, x] = W_applied[b, x] + W_cut[b, x]
    _subtree_into(tb, Ws)
    for k in range(K):
        for b in range(Ws.shape[0]):
            for x in range(6):
                dWs[k, b, x] = dW_all[k, b, x]
    _subtree_into_k(tb, dWs)
    for t in range(tb.tree.shape[0]):
        j, chi = tb.tree[t, T_JOINT], tb.tree[t, T_CHILD]
        q0, nqt = tb.joint[j, J_QCOL], tb.joint[j, J_NQ]
        if nqt <= 0:
            continue
        code = tb.joint[j, J_CODE]
        q = Q[q0 : q0 + nqt]
        placement(code, q, App, dpp)
        motion(code, q, App, dpp, ddm[:, :nqt], Hm[:, :nqt])
        sign = -1.0 if tb.tree[t, T_REVERSED] else 1.0
        R0, P0 = R[j, 0], P[j, 0]
        Wc = Ws[chi]
        for k in range(K):
            qd = X[k, q0 : q0 + nqt]
            _local_rates(code, q, qd, App, dpp, ddm, Hm, nqt, ddd, dH, v2)
            dp[:] = 0.0  # rate of d''
            for y in range(nqt):
                for x in range(3):
                    dp[x] += ddm[x, y] * qd[y]
            Uk = U[k, j, 0]
            for y in range(nqt):
                _copy(ddd[:, y], u_loc)
                _xacc(dp, Hm[:, y], u_loc, 1.0)
                _xacc(dpp, dH[:, y], u_loc, 1.0)
                w[:], v[:] = 0.0, 0.0
                _mvacc(R0, dH[:, y], w, 1.0)
                _mvacc(R0, u_loc, v, 1.0)
                _xacc(P0, w, v, 1.0)
                Ty = Tq[t, :, y]
                sv[:], sw[:] = 0.0, 0.0  # U x T (spatial): [w_U x v_T + v_U x w_T ; w_U x w_T]
                _xacc(Uk[3:], Ty[:3], sv, 1.0)
                _xacc(Uk[:3], Ty[3:], sv, 1.0)
                _xacc(Uk[3:], Ty[3:], sw, 1.0)
                s = 0.0
                for x in range(3):
                    s += (sv[x] + sign * v[x]) * Wc[x] + (sw[x] + sign * w[x]) * Wc[3 + x]
                for x in range(6):
                    s += dWs[k, chi, x] * Ty[x]
                dG[k, q0 + y] += s
    for n in range(tb.euler.shape[0]):
        col, lr = tb.euler[n, E_COL], lam[tb.euler[n, E_ROW]]
        for k in range(K):
            for x in range(4):
                dG[k, col + x] += 2.0 * X[k, col + x] * lr
    for n in range(tb.coupling.shape[0]):
        qb, l0, ccol = tb.coupling[n, CP_QB], tb.coupling[n, CP_L0], tb.coupling[n, CP_COL]
        x = Q[qb] - tb.coupling_q0[n, 1]
        c2, c3, c4 = L[l0 + 2], L[l0 + 3], L[l0 + 4]
        d2 = -(2.0 * c2 + 6.0 * c3 * x + 12.0 * c4 * x * x)  # d(Phi_qb)/dq_b
        lr = lam[tb.coupling[n, CP_ROW]]
        for k in range(K):  # d(Phi_qb)/dc_m = -[0, 1, 2x, 3x^2, 4x^3]
            dcx = -(X[k, ccol + 1] + 2.0 * x * X[k, ccol + 2] + 3.0 * x * x * X[k, ccol + 3]
                    + 4.0 * x**3 * X[k, ccol + 4])  # fmt: skip
            dG[k, qb] += lr * (d2 * X[k, qb] + dcx)


@njit
def rate_reactions(tb, P, R, U, lam, dlam, wrench, Zi, Zj, mrows, d, ddc, dWi_c, dWj_c, dW_all):
    """Rates of the reactions along the directions: ``(dwrench, dat, dloc, dmember, vP)``
    (about the origin; at the joints' points in global axes and in joint frame i's axes; the
    rods' tensions (NaN: no rod); the joint points' velocities (K, nj, 2, 3))."""
    K, nj = dlam.shape[0], tb.joint.shape[0]
    dwrench, vP = np.zeros((K, nj, 2, 6)), np.zeros((K, nj, 2, 3))
    dat, dloc = np.zeros((K, nj, 2, 6)), np.zeros((K, nj, 2, 6))
    dmember = np.full((K, nj), np.nan)
    _rate_reactions_into(tb, P, R, U, lam, dlam, wrench, Zi, Zj, mrows, d, ddc, dWi_c, dWj_c, dW_all.copy(), dwrench,
                         dat, dloc, dmember, vP, np.zeros((3, 3)))  # fmt: skip
    return dwrench, dat, dloc, dmember, vP


@kernel
def _rate_reactions_into(tb, P, R, U, lam, dlam, wrench, Zi, Zj, mrows, d, ddc, dWi_c, dWj_c, dW, dwrench, dat, dloc,
                         dmember, vP, v3):  # fmt: skip
    """:func:`rate_reactions` into the outputs (zeroed; ``dmember`` NaN; ``dW`` the wrenches'
    rates at fixed multipliers, overwritten; ``v3``: scratch (3, 3))."""
    K, nj = dlam.shape[0], tb.joint.shape[0]
    for c in range(tb.cut.shape[0]):
        j, r0 = tb.cut[c, K_JOINT], tb.cut[c, K_ROW0]
        bi, bj = tb.joint[j, J_BODY_I], tb.joint[j, J_BODY_J]
        length = math.sqrt(d[c, 0] ** 2 + d[c, 1] ** 2 + d[c, 2] ** 2)
        for k in range(K):
            wi, wj = dwrench[k, j, 0], dwrench[k, j, 1]
            for y in range(6):
                wi[y], wj[y] = dWi_c[k, c, y], dWj_c[k, c, y]
            for x in range(mrows[c]):
                dl = dlam[k, r0 + x]
                for y in range(6):
                    wi[y] += dl * Zi[c, x, y]
                    wj[y] += dl * Zj[c, x, y]
                    dW[k, bi, y] += dl * Zi[c, x, y]
                    dW[k, bj, y] += dl * Zj[c, x, y]
            r = r0
            for bc in range(tb.cut[c, K_BASIC0], tb.cut[c, K_BASIC1]):
                kind = tb.basic[bc, B_KIND]
                if kind == DISTANCE:  # the rod's tension -2 lambda |d|
                    dmember[k, j] = -2.0 * (dlam[k, r] * length + lam[r] * _dot3(ddc[k, c], d[c]) / length)
                r += _rows(kind)
    _subtree_into_k(tb, dW)
    for t in range(tb.tree.shape[0]):
        j, chi = tb.tree[t, T_JOINT], tb.tree[t, T_CHILD]
        side = 0 if tb.tree[t, T_REVERSED] else 1
        for k in range(K):
            for y in range(6):
                dwrench[k, j, side, y] = -dW[k, chi, y]
                dwrench[k, j, 1 - side, y] = dW[k, chi, y]
    G3, s1, s2 = v3[0], v3[1], v3[2]
    for j in range(nj):
        for s in range(2):
            F, MO = wrench[j, s, :3], wrench[j, s, 3:]
            _copy(MO, G3)
            _xacc(P[j, s], F, G3, -1.0)
            for k in range(K):
                v = vP[k, j, s]
                _copy(U[k, j, s, :3], v)
                _xacc(U[k, j, s, 3:], P[j, s], v, 1.0)
                dF, dMO = dwrench[k, j, s, :3], dwrench[k, j, s, 3:]
                out = dat[k, j, s]
                for x in range(3):
                    out[x], out[3 + x] = dF[x], dMO[x]
                _xacc(v, F, out[3:], -1.0)
                _xacc(P[j, s], dF, out[3:], -1.0)
                wi = U[k, j, 0, 3:]
                _copy(out[:3], s1)
                _copy(out[3:], s2)
                _xacc(wi, F, s1, -1.0)
                _xacc(wi, G3, s2, -1.0)
                _mtvacc(R[j, 0], s1, dloc[k, j, s, :3], 1.0)
                _mtvacc(R[j, 0], s2, dloc[k, j, s, 3:], 1.0)


#: relative singular value below which a direction of [Phi_q^T E_D^T] counts as null
RANK_RTOL = 1e-10


@njit
def statics_core(tb, r, A, P, R, Tq, Q, L, Phi_q, rs, cs, driven, li, lf, W_applied):
    """The statics of one evaluated state in one call: element forces and every applied wrench
    ``W``; the system ``[Phi_q^T  E_D^T]`` with rows and columns scaled as the solver scales
    them (unknowns ``[lambda / rs ; tau / cs_D]``, right-hand side ``-Q / cs``), its SVD and
    rank; the minimum-norm multipliers and efforts with the residual of the solve and the
    size of its right-hand side; the reactions (about the origin, at the joints' points,
    in joint frame i), the rods' tensions and the cut joints' terms (:func:`cut_terms`)."""
    m, nq, nd, nb = Phi_q.shape[0], Phi_q.shape[1], driven.shape[0], r.shape[0]
    n = m + nd
    f, lengths, ends, W_el = element_forces(li, lf, r, A, Q, P, R, nb)
    W = W_applied + W_el
    Qg = generalized_forces(tb, Tq, W, nq)
    As = np.zeros((nq, n))  # unknowns [lambda / rs ; tau / cs_D]
    for i in range(m):
        for c in range(nq):
            As[c, i] = Phi_q[i, c] * rs[i] / cs[c]
    unscale = np.zeros(n)
    unscale[:m] = rs
    for k in range(nd):
        As[driven[k], m + k] = 1.0
        unscale[m + k] = cs[driven[k]]
    b = -Qg / cs
    U, s, Vt = np.linalg.svd(As)
    smax = s[0] if s.size and s[0] > 0 else 1.0
    rank = 0
    for x in range(s.size):
        if s[x] > RANK_RTOL * smax:
            rank += 1
    xs = _pinv_solve(U, s, Vt, rank, b)
    resid, bn = 0.0, 0.0
    for c in range(nq):
        e = -b[c]
        for i in range(n):
            e += As[c, i] * xs[i]
        resid += e * e
        bn += b[c] * b[c]
    ct = cut_terms(tb, P, R, Q, L)
    x = xs * unscale
    lam, tau = x[:m].copy(), x[m:].copy()
    wrench = reactions(tb, ct[5], ct[6], ct[7], lam, W)
    rod_row, rod_len = ct[8], ct[9]
    member = np.full(rod_row.shape[0], np.nan)
    for j in range(rod_row.shape[0]):
        if rod_row[j] >= 0:
            member[j] = -2.0 * lam[rod_row[j]] * rod_len[j]
    at_point, local = at_points(wrench, P, R)
    return (W, f, lengths, ends, unscale, U, s, Vt, rank, math.sqrt(resid), math.sqrt(bn), lam, tau, wrench,
            at_point, local, member, ct)  # fmt: skip


@njit
def _pinv_solve(U, s, Vt, rank, b):
    """``x = V_r S_r^-1 U_r^T b``: the minimum-norm least-squares solution on the first
    ``rank`` singular directions."""
    n = Vt.shape[1]
    x = np.zeros(n)
    for k in range(rank):
        c = 0.0
        for i in range(U.shape[0]):
            c += U[i, k] * b[i]
        c /= s[k]
        for i in range(n):
            x[i] += Vt[k, i] * c
    return x


@njit
def rates_core(tb, r, A, P, R, Tq, Q, L, X, lam, li, lf, held, body, lP, lF, lM, follows, radius, centre, axis, sae,
               W, ct, U_s, s, Vt, rank, unscale, cs, wrench):  # fmt: skip
    """The rates of the statics along the state directions ``X`` (K, n_columns) in one call
    (:mod:`kinprop.engine.statics_rates`), the equilibrium's rate solved on the statics' SVD
    ``U_s``, ``s``, ``Vt`` of rank ``rank``: ``(dtau, dwrench, dat, dloc, dmember, df, dL, vP, V)``."""
    K, nq, m = X.shape[0], cs.shape[0], lam.shape[0]
    Pi, d, Pd, Wi, Wj, Zi, Zj, mrows = ct[0], ct[1], ct[2], ct[3], ct[4], ct[5], ct[6], ct[7]
    V, U = twists(tb, A, P, Tq, X)
    qdot = np.ascontiguousarray(X[:, :nq])
    frame_w = np.ascontiguousarray(U[:, :, 0, 3:])
    dW_el, df_el, dL_el = element_rates(li, lf, held, r, A, V, qdot, frame_w, R, Q)
    dW_app = load_rates(body, lP, lF, lM, follows, radius, centre, axis, sae, V) + dW_el
    dG, dWi_c, dWj_c, ddc, dW_all = rates_rhs(tb, P, R, Tq, Q, L, X, lam, V, U, Pi, d, Pd, Wi, Wj, mrows, W, dW_app,
                                              nq)  # fmt: skip
    # [Phi_q^T E_D^T] ydot = -dG, solved as the statics are
    n = unscale.shape[0]
    dlam, dtau = np.zeros((K, m)), np.zeros((K, n - m))
    for k in range(K):
        y = _pinv_solve(U_s, s, Vt, rank, -dG[k] / cs) * unscale
        dlam[k] = y[:m]
        dtau[k] = y[m:]
    dwrench, dat, dloc, dmember, vP = rate_reactions(tb, P, R, U, lam, dlam, wrench, Zi, Zj, mrows, d, ddc, dWi_c,
                                                     dWj_c, dW_all)  # fmt: skip
    return dtau, dwrench, dat, dloc, dmember, df_el, dL_el, vP, V
