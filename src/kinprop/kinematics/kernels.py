"""Compiled kinematics: forward kinematics (eq. 28), the B/M/N twists (eqs. 34-35), and the
assembled Phi with its Jacobian entries over every variable (eqs. 38-51). One implementation:
every solve, batch, sweep, sensitivity and report evaluates through :func:`evaluate`.

Tree recursion, for a tree joint from parent p to child c with joint frame a on p and b on c:
``R_a = A_p C_a``, ``P_a = r_p + A_p s'_a``; ``R_b = R_a A''(q)``, ``P_b = P_a + R_a d''(q)``
(frames swapped and A'', d'' inverted when the joint is traversed from its body j);
``A_c = R_b C_b^T``, ``r_c = P_b - A_c s'_b``. With the paper's convention (no child frame)
this is ``r_j = r_i + A_i s'_ij + d_ij``, ``A_j = A_i C_ij A''_ij``.

Twists ``[dr + tilde(r) dpi ; dpi]`` (the paper's ``z^``) that one unit of a tree variable gives
its subtree: ``B = [R_a dd'' + tilde(P_b) R_a H'' ; R_a H'']`` for q (eq. 34 with the dd/dq
term); ``M = [A_p ; 0]`` / ``[-A_c ; 0]`` for s' on the parent / child side; ``N =
[tilde(P_a) A_p ; A_p]`` / ``[-tilde(P_b) A_c ; -A_c]`` for C (xi' in the body frame).

Cut joint between bodies i and j (``P_i`` slid by ``R_i u`` for a T-D joint's own coordinate):
with the basic-constraint partials ``Phi_d``, ``Phi_wi``, ``Phi_wj``, ``Phi_l``
(:mod:`kinprop.constraints.basic`), the own columns are ``Phi_s'_i = -Phi_d A_i``,
``Phi_s'_j = Phi_d A_j``, ``Phi_xi'_i = (Phi_wi + Phi_d tilde(R_i u)) A_i`` (Table 1),
``Phi_xi'_j = Phi_wj A_j``, ``Phi_l``, ``Phi_qc = -Phi_d R_i du`` (eq. 57), and tree variables
enter through the loop paths from the junction (eqs. 43, 49-51) as ``Z_i T`` / ``Z_j T`` with
``Z_i = [-Phi_d, -Phi_d tilde(P_i) + Phi_wi]``, ``Z_j = [Phi_d, Phi_d tilde(P_j) + Phi_wj]``.
Tree variables above the junction move the loop rigidly and do not appear (eq. 48); for
spherical rows away from assembly this is the derivative in the junction body's axes
(tests/kinematics measures it; it converges better than the global one).

Jacobian entries are emitted in a fixed order that depends only on the tables, so the
sparsity pattern (``rows``, ``cols``) is recorded once by the same routine (``structure``).
"""

from __future__ import annotations

import numpy as np

from kinprop.constraints.basic import basic_rows
from kinprop.jit import inlined, kernel, njit
from kinprop.joints import motion, placement
from kinprop.joints.composite import TD_CODE
from kinprop.kinematics.couplings import ENTRIES as COUPLING_ENTRIES
from kinprop.kinematics.couplings import coupling_rows
from kinprop.kinematics.tables import (
    B_KIND,
    B_ON_J,
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
    K_NROWS,
    K_PATH0,
    K_PATH1,
    K_ROW0,
    P_SIDE,
    P_TREE,
    T_CHILD,
    T_JOINT,
    T_PARENT,
    T_REVERSED,
    V_COMPONENT,
    V_JOINT,
    V_KIND,
    V_SIDE,
    VAR_C,
    VAR_L,
    VAR_Q,
    VAR_S,
)
from kinprop.spatial import cross_into, exp_so3_into, mm_into, mmT_into, mv_into

#: most rows of one cut joint (a weld: spherical + three dot-1) and most tree coordinates (free)
MAX_CUT_ROWS, MAX_Q = 6, 7


#: Workspace slots, ``ws[W_*]`` (see :func:`workspace`): body positions ``r`` (nb, 3) and
#: orientations ``A`` (nb, 3, 3); global joint frame origins ``P`` (nj, 2, 3) and axes ``R``
#: (nj, 2, 3, 3); tree twists of the q columns ``Tq`` (nt, 6, MAX_Q) and of the s', C columns
#: ``Td`` (nt, 4, 6, 3); scratch 3x3 matrices (3, 3, 3) and 3-vectors (8, 3); motion columns
#: ``dd``, ``H`` (2, 3, MAX_Q); one cut joint's partial rows ``Phi_d``, ``Phi_wi``, ``Phi_wj``
#: (3, MAX_CUT_ROWS, 3) and ``Phi_l`` (MAX_CUT_ROWS); its arms ``Z_i``, ``Z_j`` (2, MAX_CUT_ROWS, 6).
W_BODY_R, W_BODY_A, W_FRAME_P, W_FRAME_R, W_TWIST_Q, W_TWIST_D, W_MAT, W_VEC, W_MOTION, W_PARTIAL, W_PHI_L, W_ARM = (
    range(12)
)
#: scratch 3-vectors ``ws[W_VEC][k]``: ``evaluate`` (and what it inlines) and ``retract`` use
#: ``k < VEC_CALLER``; the ones from ``VEC_CALLER`` on are left to their callers
VEC_CALLER = 5


@njit
def workspace(tb):
    """Per-call arrays, allocated once per solve, in the slots ``W_*`` (body poses, joint frames,
    tree twists, scratch)."""
    nb, nj, nt = tb.fixed.shape[0], tb.joint.shape[0], tb.tree.shape[0]
    return (np.zeros((nb, 3)), np.zeros((nb, 3, 3)), np.zeros((nj, 2, 3)), np.zeros((nj, 2, 3, 3)),
            np.zeros((nt, 6, MAX_Q)), np.zeros((nt, 4, 6, 3)), np.zeros((3, 3, 3)), np.zeros((8, 3)),
            np.zeros((2, 3, MAX_Q)), np.zeros((3, MAX_CUT_ROWS, 3)), np.zeros(MAX_CUT_ROWS),
            np.zeros((2, MAX_CUT_ROWS, 6)))  # fmt: skip


@inlined
def forward_kinematics(tb, Q, S, C, ws):
    """Body poses ``r``, ``A`` and global joint frames ``P``, ``R`` of every joint (eq. 28), into ``ws``."""
    r, A, P, R = ws[W_BODY_R], ws[W_BODY_A], ws[W_FRAME_P], ws[W_FRAME_R]
    joint, tree, cut, fixed, r0, A0 = tb.joint, tb.tree, tb.cut, tb.fixed, tb.r0, tb.A0
    Ap, App, T1 = ws[W_MAT][0], ws[W_MAT][1], ws[W_MAT][2]
    dpp, w = ws[W_VEC][0], ws[W_VEC][1]
    for b in range(fixed.shape[0]):
        if fixed[b]:
            for x in range(3):
                r[b, x] = r0[b, x]
                for y in range(3):
                    A[b, x, y] = A0[b, x, y]
    for t in range(tree.shape[0]):
        j, par, chi = tree[t, T_JOINT], tree[t, T_PARENT], tree[t, T_CHILD]
        q0, nq = joint[j, J_QCOL], joint[j, J_NQ]
        placement(joint[j, J_CODE], Q[max(q0, 0) : max(q0, 0) + nq], App, dpp)
        for x in range(3):
            for y in range(3):
                Ap[x, y] = A[par, x, y]
        a, b = (0, 1) if tree[t, T_REVERSED] == 0 else (1, 0)  # parent side a, child side b
        mv_into(Ap, S[j, a], w)
        for x in range(3):
            P[j, a, x] = r[par, x] + w[x]
        mm_into(Ap, C[j, a], R[j, a])
        if a == 0:
            mm_into(R[j, 0], App, R[j, 1])
            mv_into(R[j, 0], dpp, w)
            for x in range(3):
                P[j, 1, x] = P[j, 0, x] + w[x]
        else:
            mmT_into(R[j, 1], App, R[j, 0])
            mv_into(R[j, 0], dpp, w)
            for x in range(3):
                P[j, 0, x] = P[j, 1, x] - w[x]
        mmT_into(R[j, b], C[j, b], T1)
        for x in range(3):
            for y in range(3):
                A[chi, x, y] = T1[x, y]
        mv_into(T1, S[j, b], w)
        for x in range(3):
            r[chi, x] = P[j, b, x] - w[x]
    for c in range(cut.shape[0]):
        j = cut[c, K_JOINT]
        for side in range(2):
            body = joint[j, J_BODY_I + side]
            mv_into(A[body], S[j, side], w)
            for x in range(3):
                P[j, side, x] = r[body, x] + w[x]
            mm_into(A[body], C[j, side], R[j, side])


@inlined
def tree_twists(tb, Q, ws, need):
    """B (q columns) and M, N (s', C columns) of every tree joint as global twists (eqs. 34-35),
    into ``ws``; those of variables whose first column ``need`` (see :func:`evaluate`) is 0 are
    skipped."""
    A, P, R = ws[W_BODY_A], ws[W_FRAME_P], ws[W_FRAME_R]
    Tq, Td = ws[W_TWIST_Q], ws[W_TWIST_D]
    App, dd, H = ws[W_MAT][0], ws[W_MOTION][0], ws[W_MOTION][1]
    dpp, v, w, x3 = ws[W_VEC][0], ws[W_VEC][1], ws[W_VEC][2], ws[W_VEC][3]
    for t in range(tb.tree.shape[0]):
        j, par, chi = tb.tree[t, T_JOINT], tb.tree[t, T_PARENT], tb.tree[t, T_CHILD]
        q0, nq = tb.joint[j, J_QCOL], tb.joint[j, J_NQ]
        sign = -1.0 if tb.tree[t, T_REVERSED] else 1.0
        if nq > 0 and need[q0]:
            q = Q[q0 : q0 + nq]
            code = tb.joint[j, J_CODE]
            placement(code, q, App, dpp)
            motion(code, q, App, dpp, dd[:, :nq], H[:, :nq])
            for y in range(nq):
                mv_into(R[j, 0], H[:, y], w)
                mv_into(R[j, 0], dd[:, y], v)
                cross_into(P[j, 1], w, x3)
                for x in range(3):
                    Tq[t, x, y] = sign * (v[x] + x3[x])
                    Tq[t, 3 + x, y] = sign * w[x]
        needed = False
        for f in range(4):
            col = tb.joint[j, J_COL_S_I + f]
            needed = needed or (col >= 0 and need[col] != 0)
        if not needed:
            continue
        a, b = (0, 1) if tb.tree[t, T_REVERSED] == 0 else (1, 0)
        for x in range(3):
            for y in range(3):
                Td[t, a, x, y], Td[t, a, 3 + x, y] = A[par, x, y], 0.0
                Td[t, b, x, y], Td[t, b, 3 + x, y] = -A[chi, x, y], 0.0
                Td[t, 2 + a, 3 + x, y] = A[par, x, y]
                Td[t, 2 + b, 3 + x, y] = -A[chi, x, y]
        for y in range(3):
            cross_into(P[j, a], A[par, :, y], x3)
            for x in range(3):
                Td[t, 2 + a, x, y] = x3[x]
            cross_into(P[j, b], A[chi, :, y], x3)
            for x in range(3):
                Td[t, 2 + b, x, y] = -x3[x]


@kernel
def _emit(k, value, r, c, vals, rows, cols, record):
    vals[k] = value
    if record:
        rows[k], cols[k] = r, c
    return k + 1


@kernel
def evaluate(tb, Q, S, C, L, ws, Phi, vals, need, rows, cols):
    """Phi and the Jacobian entries at one state; returns the number of entries.

    ``need`` (per layout column, int8): entries of a variable whose first column is 0 there
    are skipped (left as they are); when ``rows``, ``cols`` are not empty the entries' rows
    and columns are written too (the sparsity pattern, same order). ``ws`` from
    :func:`workspace` holds the poses and frames afterwards.
    """
    record = rows.shape[0] > 0
    A, P, R = ws[W_BODY_A], ws[W_FRAME_P], ws[W_FRAME_R]
    Tq, Td = ws[W_TWIST_Q], ws[W_TWIST_D]
    forward_kinematics(tb, Q, S, C, ws)
    tree_twists(tb, Q, ws, need)
    Pd, Wi, Wj, Pl = ws[W_PARTIAL][0], ws[W_PARTIAL][1], ws[W_PARTIAL][2], ws[W_PHI_L]
    Zi, Zj = ws[W_ARM][0], ws[W_ARM][1]
    vec = ws[W_VEC]
    d, Ru, g, x3, Pi = vec[0], vec[1], vec[2], vec[3], vec[4]
    k = 0
    for c in range(tb.cut.shape[0]):
        j, row0, m = tb.cut[c, K_JOINT], tb.cut[c, K_ROW0], tb.cut[c, K_NROWS]
        bi, bj = tb.joint[j, J_BODY_I], tb.joint[j, J_BODY_J]
        qc = tb.joint[j, J_QCOL]
        Ru[:] = 0.0
        if tb.joint[j, J_CODE] == TD_CODE:  # the rack slides the point on body i along z''_i
            for x in range(3):
                Ru[x] = R[j, 0, x, 2] * Q[qc]
        for x in range(3):
            d[x] = P[j, 1, x] - P[j, 0, x] - Ru[x]
        Pd[:m], Wi[:m], Wj[:m], Pl[:m] = 0.0, 0.0, 0.0, 0.0
        rr = 0
        for bc in range(tb.cut[c, K_BASIC0], tb.cut[c, K_BASIC1]):
            rr += basic_rows(tb.basic[bc, B_KIND], tb.basic[bc, B_ON_J], tb.basic_axes[bc], d, R[j, 0], R[j, 1],
                             L[j], rr, Phi[row0:], Pd, Wi, Wj, Pl)  # fmt: skip
        # own columns: s'_i, s'_j, xi'_i, xi'_j, l, then the joint's own coordinate (T-D)
        for f in range(4):
            col = tb.joint[j, J_COL_S_I + f]
            if col < 0:
                continue
            if not need[col]:
                k += 3 * m
                continue
            body = bi if f % 2 == 0 else bj
            for x in range(m):
                if f == 0:
                    g[0], g[1], g[2] = -Pd[x, 0], -Pd[x, 1], -Pd[x, 2]
                elif f == 1:
                    g[0], g[1], g[2] = Pd[x, 0], Pd[x, 1], Pd[x, 2]
                elif f == 2:
                    cross_into(Pd[x], Ru, x3)
                    for y in range(3):
                        g[y] = Wi[x, y] + x3[y]
                else:
                    g[0], g[1], g[2] = Wj[x, 0], Wj[x, 1], Wj[x, 2]
                for y in range(3):  # row g^T A_body
                    val = g[0] * A[body, 0, y] + g[1] * A[body, 1, y] + g[2] * A[body, 2, y]
                    k = _emit(k, val, row0 + x, col + y, vals, rows, cols, record)
        col = tb.joint[j, J_COL_L]
        if col >= 0:
            for x in range(m):
                k = _emit(k, Pl[x], row0 + x, col, vals, rows, cols, record)
        if tb.joint[j, J_NQ] > 0:
            for x in range(m):
                val = -(Pd[x, 0] * R[j, 0, 0, 2] + Pd[x, 1] * R[j, 0, 1, 2] + Pd[x, 2] * R[j, 0, 2, 2])
                k = _emit(k, val, row0 + x, qc, vals, rows, cols, record)
        for x in range(3):
            Pi[x] = P[j, 0, x] + Ru[x]  # the point the constraint acts at on body i
        for x in range(m):
            cross_into(Pd[x], Pi, x3)  # -Phi_d tilde(P_i) = Phi_d x P_i (as a row)
            for y in range(3):
                Zi[x, y], Zi[x, 3 + y] = -Pd[x, y], x3[y] + Wi[x, y]
            cross_into(Pd[x], P[j, 1], x3)
            for y in range(3):
                Zj[x, y], Zj[x, 3 + y] = Pd[x, y], -x3[y] + Wj[x, y]
        for pe in range(tb.cut[c, K_PATH0], tb.cut[c, K_PATH1]):
            t = tb.path[pe, P_TREE]
            Z = Zi if tb.path[pe, P_SIDE] == 0 else Zj
            tj = tb.tree[t, T_JOINT]
            q0, nq = tb.joint[tj, J_QCOL], tb.joint[tj, J_NQ]
            if nq > 0 and not need[q0]:
                k += m * nq
            elif nq > 0:
                for x in range(m):
                    for y in range(nq):
                        s = 0.0
                        for z in range(6):
                            s += Z[x, z] * Tq[t, z, y]
                        k = _emit(k, s, row0 + x, q0 + y, vals, rows, cols, record)
            for f in range(4):
                col = tb.joint[tj, J_COL_S_I + f]
                if col < 0:
                    continue
                if not need[col]:
                    k += 3 * m
                    continue
                for x in range(m):
                    for y in range(3):
                        s = 0.0
                        for z in range(6):
                            s += Z[x, z] * Td[t, f, z, y]
                        k = _emit(k, s, row0 + x, col + y, vals, rows, cols, record)
    for e in range(tb.euler.shape[0]):
        row, col = tb.euler[e, E_ROW], tb.euler[e, E_COL]
        s = 0.0
        for x in range(4):
            s += Q[col + x] * Q[col + x]
            if need[col]:
                k = _emit(k, 2.0 * Q[col + x], row, col + x, vals, rows, cols, record)
            else:
                k += 1
        Phi[row] = s - 1.0
    if tb.coupling.shape[0] > 0:
        k = coupling_rows(tb, Q, L, Phi, vals, need, rows, cols, record, k)  # kinematics/couplings.py
    return k


def count_entries(tb) -> int:
    """Number of Jacobian entries :func:`evaluate` emits (structure only; plain numpy)."""
    joint = tb.joint
    own = 3 * (joint[:, J_COL_S_I : J_COL_S_I + 4] >= 0).sum(axis=1) + (joint[:, J_COL_L] >= 0) + (joint[:, J_NQ] > 0)
    moved = np.maximum(joint[:, J_NQ], 0) + 3 * (joint[:, J_COL_S_I : J_COL_S_I + 4] >= 0).sum(axis=1)
    m = tb.cut[:, K_NROWS]
    per_path = moved[tb.tree[tb.path[:, P_TREE], T_JOINT]] if tb.path.size else np.zeros(0, np.int64)
    path_sum = np.array([per_path[a:b].sum() for a, b in tb.cut[:, [K_PATH0, K_PATH1]]], dtype=np.int64)
    return int(np.sum(m * (own[tb.cut[:, K_JOINT]] + path_sum)) + 4 * tb.euler.shape[0]
               + COUPLING_ENTRIES * tb.coupling.shape[0])  # fmt: skip


@kernel
def retract(tb, free, dx, Q, S, C, L, ws):
    """``state (+) dx`` over the ``free`` columns (sorted): additive for q, s', l (Euler
    parameters too, never renormalised); ``C <- exp(tilde(dxi')) C`` for orientations
    (scratch from the workspace ``ws``)."""
    Cn, E, w = ws[W_MAT][0], ws[W_MAT][1], ws[W_VEC][0]
    i, nf = 0, free.shape[0]
    while i < nf:
        c = free[i]
        kind, j, side = tb.column[c, V_KIND], tb.column[c, V_JOINT], tb.column[c, V_SIDE]
        if kind == VAR_Q:
            Q[c] += dx[i]
        elif kind == VAR_S:
            S[j, side, tb.column[c, V_COMPONENT]] += dx[i]
        elif kind == VAR_L:
            L[j] += dx[i]
        else:  # VAR_C: the free components of one xi' (consecutive in ``free``)
            c0 = c - tb.column[c, V_COMPONENT]
            w[:] = 0.0
            while i < nf and free[i] < c0 + 3:
                w[free[i] - c0] = dx[i]
                i += 1
            i -= 1
            if w[0] != 0.0 or w[1] != 0.0 or w[2] != 0.0:
                exp_so3_into(w, E)
                mm_into(E, C[j, side], Cn)
                for x in range(3):
                    for y in range(3):
                        C[j, side, x, y] = Cn[x, y]
        i += 1


__all__ = [
    "VAR_C",
    "VEC_CALLER",
    "W_ARM",
    "W_BODY_A",
    "W_BODY_R",
    "W_FRAME_P",
    "W_FRAME_R",
    "W_MAT",
    "W_MOTION",
    "W_PARTIAL",
    "W_PHI_L",
    "W_TWIST_D",
    "W_TWIST_Q",
    "W_VEC",
    "count_entries",
    "evaluate",
    "forward_kinematics",
    "retract",
    "tree_twists",
    "workspace",
]
