"""Numba kernels: forward kinematics, Phi and its Jacobian entries, Newton over free columns.

The kernels mirror :meth:`kinprop.kinematics.assembly.Assembly.evaluate` term by term (see
that module for the equations); :mod:`kinprop.fast.compiled` builds the flat tables they read.

Tables (int64 unless noted), one row per item:

* ``jint`` per joint: ``[type, body_i, body_j, q_col, n_q, col_s_i, col_s_j, col_C_i, col_C_j, col_l]``
  (``-1`` = not a layout variable);
* ``tint`` per tree joint, parent before child: ``[joint, parent, child, reversed]``;
* ``cint`` per cut joint: ``[joint, first_row, n_rows, first_basic, end_basic, first_path, end_path]``;
* ``bint`` per basic constraint: ``[kind, on_j]``; ``bflt`` (float) ``[a_i(3), a_j(3)]``;
* ``pint`` per loop-path entry: ``[tree index, side]`` (side 0 = body i's path, 1 = body j's);
* ``eint`` per normalisation row: ``[row, first Euler column]``;
* ``fixed`` per body (0/1), ``r0`` (nb, 3), ``A0`` (nb, 3, 3) poses of fixed bodies.

State of one variant: ``Q`` (layout q columns), ``S`` (nj, 2, 3) = s_i, s_j; ``C`` (nj, 2, 3, 3)
= C_i, C_j; ``L`` (nj,) lengths. Jacobian entries are emitted in a fixed order (the structure
does not depend on the values), so ``rows``/``cols`` are computed once.
"""

from __future__ import annotations

import numpy as np
from numba import get_num_threads, njit, prange

# joint type codes
REVOLUTE, PRISMATIC, CYLINDRICAL, UNIVERSAL, SPHERICAL, FIXED, FREE, ST, TD, CUTONLY = range(10)
# basic constraint codes
DOT1, DOT2, SPH, DIST = range(4)
# solver status codes
CONVERGED, NOT_CONVERGED, DIVERGED, NO_FREE, SINGULAR = range(5)


@njit(cache=True, error_model="numpy")
def _mat_E(p, out, scale):
    # E(p) = [-e, tilde(e) + e0 I] (eq. 40), times scale
    e0, e1, e2, e3 = p[0], p[1], p[2], p[3]
    out[0, 0], out[0, 1], out[0, 2], out[0, 3] = -e1 * scale, e0 * scale, -e3 * scale, e2 * scale
    out[1, 0], out[1, 1], out[1, 2], out[1, 3] = -e2 * scale, e3 * scale, e0 * scale, -e1 * scale
    out[2, 0], out[2, 1], out[2, 2], out[2, 3] = -e3 * scale, -e2 * scale, e1 * scale, e0 * scale


@njit(cache=True, error_model="numpy")
def _tilde(a):
    t = np.zeros((3, 3))
    t[0, 1], t[0, 2] = -a[2], a[1]
    t[1, 0], t[1, 2] = a[2], -a[0]
    t[2, 0], t[2, 1] = -a[1], a[0]
    return t


@njit(cache=True, error_model="numpy")
def _euler_A_into(p, out):
    # A(p) = E(p) G(p)^T, with p as given (never renormalised)
    e0, e1, e2, e3 = p[0], p[1], p[2], p[3]
    out[0, 0] = e0 * e0 + e1 * e1 - e2 * e2 - e3 * e3
    out[0, 1] = 2.0 * (e1 * e2 - e0 * e3)
    out[0, 2] = 2.0 * (e1 * e3 + e0 * e2)
    out[1, 0] = 2.0 * (e1 * e2 + e0 * e3)
    out[1, 1] = e0 * e0 - e1 * e1 + e2 * e2 - e3 * e3
    out[1, 2] = 2.0 * (e2 * e3 - e0 * e1)
    out[2, 0] = 2.0 * (e1 * e3 - e0 * e2)
    out[2, 1] = 2.0 * (e2 * e3 + e0 * e1)
    out[2, 2] = e0 * e0 - e1 * e1 - e2 * e2 + e3 * e3


@njit(cache=True, error_model="numpy")
def _eye_into(out):
    for a in range(3):
        for b in range(3):
            out[a, b] = 1.0 if a == b else 0.0


@njit(cache=True, error_model="numpy")
def _placement_into(code, q, A, d):
    """(A'', d'') of a tree joint in its frame i, written into ``A``, ``d``."""
    _eye_into(A)
    d[0], d[1], d[2] = 0.0, 0.0, 0.0
    if code in (REVOLUTE, CYLINDRICAL, UNIVERSAL):
        c, s = np.cos(q[0]), np.sin(q[0])
        A[0, 0], A[0, 1], A[1, 0], A[1, 1] = c, -s, s, c
        if code == CYLINDRICAL:
            d[2] = q[1]
        elif code == UNIVERSAL:
            c1, s1 = np.cos(q[1]), np.sin(q[1])
            # Rz(q0) @ Ry(q1)
            A[0, 0], A[0, 1], A[0, 2] = c * c1, -s, c * s1
            A[1, 0], A[1, 1], A[1, 2] = s * c1, c, s * s1
            A[2, 0], A[2, 1], A[2, 2] = -s1, 0.0, c1
    elif code == PRISMATIC:
        d[2] = q[0]
    elif code == SPHERICAL:
        _euler_A_into(q[0:4], A)
    elif code == FREE:
        _euler_A_into(q[3:7], A)
        d[0], d[1], d[2] = q[0], q[1], q[2]
    elif code == ST:
        _euler_A_into(q[0:4], A)
        for x in range(3):
            d[x] = A[x, 2] * q[4]


@njit(cache=True, error_model="numpy")
def _motion_into(code, q, n, A, d, dd, H):
    """(dd''/dq, H''), 3 x n, in frame i (``A``, ``d`` = the placement)."""
    for x in range(3):
        for y in range(n):
            dd[x, y] = 0.0
            H[x, y] = 0.0
    if code == REVOLUTE:
        H[2, 0] = 1.0
    elif code == PRISMATIC:
        dd[2, 0] = 1.0
    elif code == CYLINDRICAL:
        H[2, 0] = 1.0
        dd[2, 1] = 1.0
    elif code == UNIVERSAL:
        H[2, 0] = 1.0
        H[0, 1], H[1, 1] = -np.sin(q[0]), np.cos(q[0])
    elif code == SPHERICAL:
        _mat_E(q[0:4], H, 2.0)
    elif code == FREE:
        dd[0, 0], dd[1, 1], dd[2, 2] = 1.0, 1.0, 1.0
        _mat_E(q[3:7], H[:, 3:7], 2.0)
    elif code == ST:
        _mat_E(q[0:4], H, 2.0)
        # dd = -tilde(d) H (moment arm about the sphere centre); last column the strut axis
        for y in range(4):
            h0, h1, h2 = H[0, y], H[1, y], H[2, y]
            dd[0, y] = -(d[1] * h2 - d[2] * h1)
            dd[1, y] = -(d[2] * h0 - d[0] * h2)
            dd[2, y] = -(d[0] * h1 - d[1] * h0)
        for x in range(3):
            dd[x, 4] = A[x, 2]


@njit(cache=True, error_model="numpy")
def _mm(A, B, out):
    # out = A @ B for 3x3
    for a in range(3):
        for b in range(3):
            out[a, b] = A[a, 0] * B[0, b] + A[a, 1] * B[1, b] + A[a, 2] * B[2, b]


@njit(cache=True, error_model="numpy")
def _mmT(A, B, out):
    # out = A @ B.T for 3x3
    for a in range(3):
        for b in range(3):
            out[a, b] = A[a, 0] * B[b, 0] + A[a, 1] * B[b, 1] + A[a, 2] * B[b, 2]


@njit(cache=True, error_model="numpy")
def _mv(A, v, out):
    for a in range(3):
        out[a] = A[a, 0] * v[0] + A[a, 1] * v[1] + A[a, 2] * v[2]


@njit(cache=True, error_model="numpy")
def _copy_a(A, i, out):
    # out = A[i] for (n, 3, 3) without creating a view
    for a in range(3):
        for b in range(3):
            out[a, b] = A[i, a, b]


@njit(cache=True, error_model="numpy")
def _copy_c(C, j, side, out):
    # out = C[j, side] for (n, 2, 3, 3)
    for a in range(3):
        for b in range(3):
            out[a, b] = C[j, side, a, b]


@njit(cache=True, error_model="numpy")
def _copy_s(S, j, side, out):
    # out = S[j, side] for (n, 2, 3)
    for a in range(3):
        out[a] = S[j, side, a]


@njit(cache=True, error_model="numpy")
def _mv_row(M, F, row, off, out):
    # out = M @ F[row, off:off+3]
    for a in range(3):
        out[a] = M[a, 0] * F[row, off] + M[a, 1] * F[row, off + 1] + M[a, 2] * F[row, off + 2]


@njit(cache=True, error_model="numpy")
def _cross_row(a, b, out, row):
    out[row, 0] = a[1] * b[2] - a[2] * b[1]
    out[row, 1] = a[2] * b[0] - a[0] * b[2]
    out[row, 2] = a[0] * b[1] - a[1] * b[0]


@njit(cache=True, error_model="numpy")
def _cross_into(a, b, out):
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


@njit(cache=True, error_model="numpy")
def _tilde_mm(p, A, sign, out, r0, c0):
    # out[r0:r0+3, c0:c0+3] = sign * tilde(p) @ A
    for b in range(3):
        out[r0 + 0, c0 + b] = sign * (p[1] * A[2, b] - p[2] * A[1, b])
        out[r0 + 1, c0 + b] = sign * (p[2] * A[0, b] - p[0] * A[2, b])
        out[r0 + 2, c0 + b] = sign * (p[0] * A[1, b] - p[1] * A[0, b])


@njit(cache=True, error_model="numpy")
def _workspace(nb, nt):
    return (np.zeros((nb, 3)), np.zeros((nb, 3, 3)), np.zeros((nt, 6, 7)), np.zeros((nt, 4, 6, 3)),
            np.zeros((12, 3, 3)), np.zeros((12, 3)), np.zeros((2, 3, 7)), np.zeros((5, 6, 3)), np.zeros((2, 6, 6)),
            np.zeros(6))  # fmt: skip


@njit(cache=True, error_model="numpy")
def evaluate_entries(tb, Q, S, C, L, Phi, vals, write):
    """Fill ``Phi`` and the Jacobian entries ``vals`` (emitted in structure order); return the count.

    With ``write`` False only the count is returned (``vals`` may be empty).
    """
    ws = _workspace(tb[7].shape[0], tb[1].shape[0])
    return evaluate_ws(tb, Q, S, C, L, Phi, vals, write, ws, np.ones(_ncols(tb), np.int8))


@njit(cache=True, error_model="numpy")
def evaluate_ws(tb, Q, S, C, L, Phi, vals, write, ws, need):
    """:func:`evaluate_entries` with preallocated work arrays ``ws`` (no allocation).

    ``need`` (per layout column, int8): entries of variables whose first column is 0 there are
    skipped (left as they are in ``vals``); Newton passes its free columns.
    """
    jint, tint, cint, bint, bflt, pint, eint, fixed, r0, A0 = tb
    r, A, Tq, Td, M3, V3, MH, W6, ZZ, Pl = ws
    App, R_i, R_j, Ac, T1, R_u = M3[0], M3[1], M3[2], M3[3], M3[4], M3[5]
    dpp, P_i, P_j, rc, w3, a3, b3, d = V3[0], V3[1], V3[2], V3[3], V3[4], V3[5], V3[6], V3[7]
    # copies of per-joint data (indexing into scratch avoids a view, and its refcount, per use)
    A_i, A_j, Ci, Cj = M3[6], M3[7], M3[8], M3[9]
    s_i, s_j, rp = V3[8], V3[9], V3[10]
    Ap = A_i
    dd, H = MH[0], MH[1]
    PPi, Wi, Wj = W6[0], W6[1], W6[2]
    Zi, Zj = ZZ[0], ZZ[1]
    nb = fixed.shape[0]
    nt = tint.shape[0]
    for b in range(nb):
        if fixed[b]:
            for x in range(3):
                r[b, x] = r0[b, x]
                for y in range(3):
                    A[b, x, y] = A0[b, x, y]
    for t in range(nt):
        j, par, chi, rev = tint[t, 0], tint[t, 1], tint[t, 2], tint[t, 3]
        code, qc, nq = jint[j, 0], jint[j, 3], jint[j, 4]
        q = Q[qc : qc + nq] if nq > 0 else Q[0:0]
        _placement_into(code, q, App, dpp)
        _copy_a(A, par, Ap)
        for x in range(3):
            rp[x] = r[par, x]
        _copy_c(C, j, 0, Ci)
        _copy_c(C, j, 1, Cj)
        _copy_s(S, j, 0, s_i)
        _copy_s(S, j, 1, s_j)
        if rev == 0:
            _mv(Ap, s_i, w3)
            for x in range(3):
                P_i[x] = rp[x] + w3[x]
            _mm(Ap, Ci, R_i)
            _mv(R_i, dpp, w3)
            for x in range(3):
                P_j[x] = P_i[x] + w3[x]
            _mm(R_i, App, T1)
            _mmT(T1, Cj, Ac)
            _mv(Ac, s_j, w3)
            for x in range(3):
                rc[x] = P_j[x] - w3[x]
        else:
            _mv(Ap, s_j, w3)
            for x in range(3):
                P_j[x] = rp[x] + w3[x]
            _mm(Ap, Cj, R_j)
            _mmT(R_j, App, R_i)
            _mv(R_i, dpp, w3)
            for x in range(3):
                P_i[x] = P_j[x] - w3[x]
            _mmT(R_i, Ci, Ac)
            _mv(Ac, s_i, w3)
            for x in range(3):
                rc[x] = P_i[x] - w3[x]
        for x in range(3):
            r[chi, x] = rc[x]
            for y in range(3):
                A[chi, x, y] = Ac[x, y]
        sign = -1.0 if rev else 1.0
        if nq > 0:
            _motion_into(code, q, nq, App, dpp, dd, H)
            for y in range(nq):
                # w = R_i H[:, y]; v = R_i dd[:, y] + P_j x w
                for x in range(3):
                    a3[x] = R_i[x, 0] * H[0, y] + R_i[x, 1] * H[1, y] + R_i[x, 2] * H[2, y]
                    b3[x] = R_i[x, 0] * dd[0, y] + R_i[x, 1] * dd[1, y] + R_i[x, 2] * dd[2, y]
                _cross_into(P_j, a3, w3)
                for x in range(3):
                    Tq[t, x, y] = sign * (b3[x] + w3[x])
                    Tq[t, 3 + x, y] = sign * a3[x]
        # design twists (only for fields that are layout variables); 0 s_i, 1 s_j, 2 C_i, 3 C_j
        if jint[j, 5] >= 0 or jint[j, 6] >= 0 or jint[j, 7] >= 0 or jint[j, 8] >= 0:
            Tt = Td[t]
            pi_, ci_ = (0, 1) if rev == 0 else (1, 0)
            Ppar = P_i if rev == 0 else P_j
            Pchi = P_j if rev == 0 else P_i
            for x in range(3):
                for y in range(3):
                    Tt[pi_, x, y] = Ap[x, y]
                    Tt[pi_, 3 + x, y] = 0.0
                    Tt[ci_, x, y] = -Ac[x, y]
                    Tt[ci_, 3 + x, y] = 0.0
                    Tt[2 + pi_, 3 + x, y] = Ap[x, y]
                    Tt[2 + ci_, 3 + x, y] = -Ac[x, y]
            _tilde_mm(Ppar, Ap, 1.0, Tt[2 + pi_], 0, 0)
            _tilde_mm(Pchi, Ac, -1.0, Tt[2 + ci_], 0, 0)
    k = 0
    for c in range(cint.shape[0]):
        j, row0, m = cint[c, 0], cint[c, 1], cint[c, 2]
        code, bi, bj, qc, nq = jint[j, 0], jint[j, 1], jint[j, 2], jint[j, 3], jint[j, 4]
        _copy_a(A, bi, A_i)
        _copy_a(A, bj, A_j)
        _copy_c(C, j, 0, Ci)
        _copy_c(C, j, 1, Cj)
        _copy_s(S, j, 0, s_i)
        _copy_s(S, j, 1, s_j)
        _mm(A_i, Ci, R_i)
        _mm(A_j, Cj, R_j)
        _mv(A_i, s_i, w3)
        for x in range(3):
            P_i[x] = r[bi, x] + w3[x]
        _mv(A_j, s_j, w3)
        for x in range(3):
            P_j[x] = r[bj, x] + w3[x]
        for x in range(3):
            R_u[0, x] = 0.0
        if code == TD:
            for x in range(3):
                R_u[0, x] = R_i[x, 2] * Q[qc]
        Ru = R_u[0]
        for x in range(3):
            P_i[x] += Ru[x]
            d[x] = P_j[x] - P_i[x]
        length = L[j]
        for x in range(m):
            Pl[x] = 0.0
            for y in range(3):
                PPi[x, y] = 0.0
                Wi[x, y] = 0.0
                Wj[x, y] = 0.0
        rr = 0
        for bc in range(cint[c, 3], cint[c, 4]):
            kind = bint[bc, 0]
            if kind == DOT1:
                _mv_row(R_i, bflt, bc, 0, a3)
                _mv_row(R_j, bflt, bc, 3, b3)
                Phi[row0 + rr] = a3[0] * b3[0] + a3[1] * b3[1] + a3[2] * b3[2]
                _cross_row(a3, b3, Wi, rr)
                _cross_row(b3, a3, Wj, rr)
                rr += 1
            elif kind == DOT2:
                if bint[bc, 1] == 0:
                    _mv_row(R_i, bflt, bc, 0, a3)
                    _cross_row(a3, d, Wi, rr)
                else:
                    _mv_row(R_j, bflt, bc, 0, a3)
                    _cross_row(a3, d, Wj, rr)
                Phi[row0 + rr] = a3[0] * d[0] + a3[1] * d[1] + a3[2] * d[2]
                for x in range(3):
                    PPi[rr, x] = -a3[x]
                rr += 1
            elif kind == SPH:
                for x in range(3):
                    Phi[row0 + rr] = d[x]
                    PPi[rr, x] = -1.0
                    rr += 1
            else:
                Phi[row0 + rr] = d[0] * d[0] + d[1] * d[1] + d[2] * d[2] - length * length
                for x in range(3):
                    PPi[rr, x] = -2.0 * d[x]
                Pl[rr] = -2.0 * length
                rr += 1
        if write:
            # own columns: s_i, s_j, C_i, C_j, length, q (T-D)
            if jint[j, 5] >= 0 and not need[jint[j, 5]]:
                k += 3 * m
            elif jint[j, 5] >= 0:
                for x in range(m):
                    for y in range(3):
                        vals[k] = PPi[x, 0] * A_i[0, y] + PPi[x, 1] * A_i[1, y] + PPi[x, 2] * A_i[2, y]
                        k += 1
            if jint[j, 6] >= 0 and not need[jint[j, 6]]:
                k += 3 * m
            elif jint[j, 6] >= 0:
                for x in range(m):
                    for y in range(3):
                        vals[k] = -(PPi[x, 0] * A_j[0, y] + PPi[x, 1] * A_j[1, y] + PPi[x, 2] * A_j[2, y])
                        k += 1
            if jint[j, 7] >= 0 and not need[jint[j, 7]]:
                k += 3 * m
            elif jint[j, 7] >= 0:
                for x in range(m):
                    # row of (Phi_wi - Phi_Pi tilde(Ru)) A_i, with p^T tilde(u) = p x u
                    p0, p1, p2 = PPi[x, 0], PPi[x, 1], PPi[x, 2]
                    g0 = Wi[x, 0] - (p1 * Ru[2] - p2 * Ru[1])
                    g1 = Wi[x, 1] - (p2 * Ru[0] - p0 * Ru[2])
                    g2 = Wi[x, 2] - (p0 * Ru[1] - p1 * Ru[0])
                    for y in range(3):
                        vals[k] = g0 * A_i[0, y] + g1 * A_i[1, y] + g2 * A_i[2, y]
                        k += 1
            if jint[j, 8] >= 0 and not need[jint[j, 8]]:
                k += 3 * m
            elif jint[j, 8] >= 0:
                for x in range(m):
                    for y in range(3):
                        vals[k] = Wj[x, 0] * A_j[0, y] + Wj[x, 1] * A_j[1, y] + Wj[x, 2] * A_j[2, y]
                        k += 1
            if jint[j, 9] >= 0 and not need[jint[j, 9]]:
                k += m
            elif jint[j, 9] >= 0:
                for x in range(m):
                    vals[k] = Pl[x]
                    k += 1
            if nq > 0:
                for x in range(m):
                    vals[k] = PPi[x, 0] * R_i[0, 2] + PPi[x, 1] * R_i[1, 2] + PPi[x, 2] * R_i[2, 2]
                    k += 1
            for x in range(m):
                p0, p1, p2 = PPi[x, 0], PPi[x, 1], PPi[x, 2]
                Zi[x, 0], Zi[x, 1], Zi[x, 2] = p0, p1, p2
                Zj[x, 0], Zj[x, 1], Zj[x, 2] = -p0, -p1, -p2
                # p^T tilde(P) = p x P, so Zi = [p, P_i x p + Wi], Zj = [-p, -(P_j x p) + Wj]
                Zi[x, 3] = (P_i[1] * p2 - P_i[2] * p1) + Wi[x, 0]
                Zi[x, 4] = (P_i[2] * p0 - P_i[0] * p2) + Wi[x, 1]
                Zi[x, 5] = (P_i[0] * p1 - P_i[1] * p0) + Wi[x, 2]
                Zj[x, 3] = -(P_j[1] * p2 - P_j[2] * p1) + Wj[x, 0]
                Zj[x, 4] = -(P_j[2] * p0 - P_j[0] * p2) + Wj[x, 1]
                Zj[x, 5] = -(P_j[0] * p1 - P_j[1] * p0) + Wj[x, 2]
        else:
            k += m * (3 * ((jint[j, 5] >= 0) + (jint[j, 6] >= 0) + (jint[j, 7] >= 0) + (jint[j, 8] >= 0)))
            k += m * ((jint[j, 9] >= 0) + (nq > 0))
        for pe in range(cint[c, 5], cint[c, 6]):
            t, side = pint[pe, 0], pint[pe, 1]
            tj = tint[t, 0]
            ntq = jint[tj, 4]
            if write:
                Z = Zi if side == 0 else Zj
                if ntq > 0 and not need[jint[tj, 3]]:
                    k += m * ntq
                    ntq = 0
                for x in range(m):
                    for y in range(ntq):
                        s = 0.0
                        for z in range(6):
                            s += Z[x, z] * Tq[t, z, y]
                        vals[k] = s
                        k += 1
                for f in range(4):
                    if jint[tj, 5 + f] >= 0 and not need[jint[tj, 5 + f]]:
                        k += 3 * m
                    elif jint[tj, 5 + f] >= 0:
                        for x in range(m):
                            for y in range(3):
                                s = 0.0
                                for z in range(6):
                                    s += Z[x, z] * Td[t, f, z, y]
                                vals[k] = s
                                k += 1
            else:
                k += m * ntq
                for f in range(4):
                    if jint[tj, 5 + f] >= 0:
                        k += 3 * m
    for e in range(eint.shape[0]):
        row, col = eint[e, 0], eint[e, 1]
        s = 0.0
        for x in range(4):
            s += Q[col + x] * Q[col + x]
            if write:
                vals[k] = 2.0 * Q[col + x]
            k += 1
        Phi[row] = s - 1.0
    return k


@njit(cache=True, error_model="numpy")
def structure(tb, Q, S, C, L, m, nnz):
    """Row and column of every emitted Jacobian entry (same order as :func:`evaluate_entries`)."""
    jint, tint, cint, pint, eint = tb[0], tb[1], tb[2], tb[5], tb[6]
    rows = np.empty(nnz, dtype=np.int64)
    cols = np.empty(nnz, dtype=np.int64)
    k = 0
    for c in range(cint.shape[0]):
        j, row0, mc = cint[c, 0], cint[c, 1], cint[c, 2]
        own = [jint[j, 5], jint[j, 6], jint[j, 7], jint[j, 8]]
        for f in range(4):
            if own[f] >= 0:
                for x in range(mc):
                    for y in range(3):
                        rows[k], cols[k] = row0 + x, own[f] + y
                        k += 1
        if jint[j, 9] >= 0:
            for x in range(mc):
                rows[k], cols[k] = row0 + x, jint[j, 9]
                k += 1
        if jint[j, 4] > 0:
            for x in range(mc):
                rows[k], cols[k] = row0 + x, jint[j, 3]
                k += 1
        for pe in range(cint[c, 5], cint[c, 6]):
            tj = tint[pint[pe, 0], 0]
            ntq = jint[tj, 4]
            for x in range(mc):
                for y in range(ntq):
                    rows[k], cols[k] = row0 + x, jint[tj, 3] + y
                    k += 1
            for f in range(4):
                if jint[tj, 5 + f] >= 0:
                    for x in range(mc):
                        for y in range(3):
                            rows[k], cols[k] = row0 + x, jint[tj, 5 + f] + y
                            k += 1
    for e in range(eint.shape[0]):
        for x in range(4):
            rows[k], cols[k] = eint[e, 0], eint[e, 1] + x
            k += 1
    return rows, cols


@njit(cache=True, error_model="numpy")
def _exp_so3(w):
    th = np.sqrt(w @ w)
    W = _tilde(w)
    if th < 1e-8:
        a = 1.0 - th * th / 6.0
        b = 0.5 - th * th / 24.0
    else:
        a = np.sin(th) / th
        b = (1.0 - np.cos(th)) / (th * th)
    return np.eye(3) + a * W + b * (W @ W)


@njit(cache=True, error_model="numpy")
def retract(colinfo, dx, Q, S, C, L):
    """Apply a layout step: additive for q, s', l; ``C <- exp(tilde(dxi')) C`` per orientation.

    ``colinfo`` per layout column: ``[kind (0 q, 1 s, 2 C, 3 l), joint, side, component]``.
    """
    n = colinfo.shape[0]
    c = 0
    while c < n:
        kind = colinfo[c, 0]
        if kind == 0:
            Q[c] += dx[c]
            c += 1
        elif kind == 1:
            S[colinfo[c, 1], colinfo[c, 2], colinfo[c, 3]] += dx[c]
            c += 1
        elif kind == 3:
            L[colinfo[c, 1]] += dx[c]
            c += 1
        else:
            w = dx[c : c + 3]
            if w[0] != 0.0 or w[1] != 0.0 or w[2] != 0.0:
                j, side = colinfo[c, 1], colinfo[c, 2]
                C[j, side] = _exp_so3(w.copy()) @ C[j, side]
            c += 3


@njit(cache=True, error_model="numpy")
def n_cols(colinfo):
    return colinfo.shape[0]


@njit(cache=True, error_model="numpy")
def _ncols(tb):
    # layout columns: the largest column any joint uses, plus its size
    jint = tb[0]
    n = 0
    for j in range(jint.shape[0]):
        if jint[j, 3] >= 0:
            n = max(n, jint[j, 3] + jint[j, 4])
        for f in range(5, 9):
            if jint[j, f] >= 0:
                n = max(n, jint[j, f] + 3)
        if jint[j, 9] >= 0:
            n = max(n, jint[j, 9] + 1)
    return n


@njit(cache=True, error_model="numpy")
def retract_free(colinfo, free, dx, Q, S, C, L):
    """:func:`retract` visiting only the ``free`` columns (sorted); ``dx`` is zero elsewhere."""
    nf = free.shape[0]
    i = 0
    while i < nf:
        c = free[i]
        kind = colinfo[c, 0]
        if kind == 0:
            Q[c] += dx[c]
        elif kind == 1:
            S[colinfo[c, 1], colinfo[c, 2], colinfo[c, 3]] += dx[c]
        elif kind == 3:
            L[colinfo[c, 1]] += dx[c]
        else:
            c0 = c - colinfo[c, 3]
            w = np.array([dx[c0], dx[c0 + 1], dx[c0 + 2]])
            if w[0] != 0.0 or w[1] != 0.0 or w[2] != 0.0:
                j, side = colinfo[c, 1], colinfo[c, 2]
                C[j, side] = _exp_so3(w) @ C[j, side]
            while i + 1 < nf and free[i + 1] < c0 + 3:
                i += 1
        i += 1


@njit(cache=True, error_model="numpy")
def _lu_solve_inplace(M, b, x):
    """Solve ``M x = b`` by Gaussian elimination with partial pivoting (destroys M, b); False if singular."""
    n = M.shape[0]
    scale = 0.0
    for i in range(n):
        for j in range(n):
            scale = max(scale, abs(M[i, j]))
    if scale == 0.0:
        return False
    for col in range(n):
        piv = col
        big = abs(M[col, col])
        for i in range(col + 1, n):
            if abs(M[i, col]) > big:
                big = abs(M[i, col])
                piv = i
        if big <= 1e-13 * scale:
            return False
        if piv != col:
            for j in range(n):
                M[col, j], M[piv, j] = M[piv, j], M[col, j]
            b[col], b[piv] = b[piv], b[col]
        inv = 1.0 / M[col, col]
        for i in range(col + 1, n):
            f = M[i, col] * inv
            if f != 0.0:
                for j in range(col + 1, n):
                    M[i, j] -= f * M[col, j]
                b[i] -= f * b[col]
    for i in range(n - 1, -1, -1):
        s = b[i]
        for j in range(i + 1, n):
            s -= M[i, j] * x[j]
        x[i] = s / M[i, i]
    return True


@njit(cache=True, error_model="numpy")
def min_norm_step(Jf, Phi, out, M, rhs):
    """``out = -pinv(Jf) Phi``: pivoted LU when square and well conditioned, else SVD least squares.

    ``M`` (nf, nf) and ``rhs`` (nf,) are scratch space.
    """
    m, nf = Jf.shape
    if m == nf:
        for i in range(m):
            rhs[i] = Phi[i]
            for j in range(nf):
                M[i, j] = Jf[i, j]
        if _lu_solve_inplace(M, rhs, out):
            ok = True
            for i in range(nf):
                out[i] = -out[i]
                if not np.isfinite(out[i]):
                    ok = False
            if ok:
                return
    rcond = 2.220446049250313e-16 * max(m, nf)
    x, _, _, _ = np.linalg.lstsq(Jf, Phi, rcond)
    for i in range(nf):
        out[i] = -x[i]


@njit(cache=True, error_model="numpy")
def _buffers(m, n, nf, nnz, nb, nt):
    return (np.zeros(m), np.zeros(nnz), np.zeros((m, nf)), np.zeros(n), np.zeros(nf), np.zeros((nf, nf)), np.zeros(nf),
            -np.ones(n, dtype=np.int64), _workspace(nb, nt))  # fmt: skip


@njit(cache=True, error_model="numpy")
def _newton(tb, colinfo, rows, cols, free, Q, S, C, L, tol, max_iter, divergence, buf):
    Phi, vals, Jf, dx, step, M, rhs, fidx, ws = buf
    nnz = rows.shape[0]
    nf = free.shape[0]
    fidx[:] = -1
    need = np.zeros(n_cols(colinfo), np.int8)
    for i in range(nf):
        fidx[free[i]] = i
        need[free[i] - colinfo[free[i], 3]] = 1
    evaluate_ws(tb, Q, S, C, L, Phi, vals, True, ws, need)
    norm = np.sqrt(Phi @ Phi)
    first = max(norm, 1e-300)
    it = 0
    status = NOT_CONVERGED
    while norm >= tol and it < max_iter:
        if nf == 0:
            status = NO_FREE
            break
        Jf[:] = 0.0
        for k in range(nnz):
            f = fidx[cols[k]]
            if f >= 0:
                Jf[rows[k], f] += vals[k]
        min_norm_step(Jf, Phi, step, M, rhs)
        for i in range(nf):
            dx[free[i]] = step[i]
        retract_free(colinfo, free, dx, Q, S, C, L)
        for i in range(nf):
            dx[free[i]] = 0.0
        it += 1
        evaluate_ws(tb, Q, S, C, L, Phi, vals, True, ws, need)
        norm = np.sqrt(Phi @ Phi)
        if not np.isfinite(norm) or norm > divergence * first:
            status = DIVERGED
            break
    if norm < tol:
        status = CONVERGED
    return status, it, norm


@njit(cache=True, error_model="numpy")
def newton(tb, colinfo, rows, cols, m, n, free, Q, S, C, L, tol, max_iter, divergence):
    """Generalized-inverse Newton (as :func:`kinprop.solver.newton.newton`) on one variant, in place.

    Returns ``(status, iterations, residual norm)``.
    """
    buf = _buffers(m, n, free.shape[0], rows.shape[0], tb[7].shape[0], tb[1].shape[0])
    return _newton(tb, colinfo, rows, cols, free, Q, S, C, L, tol, max_iter, divergence, buf)


@njit(cache=True, error_model="numpy")
def newton_batch(
    tb, colinfo, rows, cols, m, n, free, Q, S, C, L, tol, max_iter, divergence, status, iterations, residual
):
    """:func:`newton` on every variant of a leading batch axis (each converges on its own)."""
    buf = _buffers(m, n, free.shape[0], rows.shape[0], tb[7].shape[0], tb[1].shape[0])
    for v in range(Q.shape[0]):
        st, it, nr = _newton(tb, colinfo, rows, cols, free, Q[v], S[v], C[v], L[v], tol, max_iter, divergence, buf)
        status[v], iterations[v], residual[v] = st, it, nr


@njit(parallel=True, error_model="numpy")
def newton_batch_parallel(
    tb, colinfo, rows, cols, m, n, free, Q, S, C, L, tol, max_iter, divergence, status, iterations, residual
):
    """:func:`newton_batch` split into one contiguous chunk per numba thread."""
    N = Q.shape[0]
    nth = max(1, min(get_num_threads(), N))
    for c in prange(nth):
        buf = _buffers(m, n, free.shape[0], rows.shape[0], tb[7].shape[0], tb[1].shape[0])
        for v in range(c * N // nth, (c + 1) * N // nth):
            st, it, nr = _newton(tb, colinfo, rows, cols, free, Q[v], S[v], C[v], L[v], tol, max_iter, divergence, buf)
            status[v], iterations[v], residual[v] = st, it, nr


@njit(cache=True, error_model="numpy")
def newton_sequence(
    tb,
    colinfo,
    rows,
    cols,
    m,
    n,
    free,
    Q,
    S,
    C,
    L,
    tol,
    max_iter,
    divergence,
    set_col,
    values,
    Qout,
    status,
    iterations,
    residual,
):
    """Continuation: for each value, set layout q column ``set_col`` and solve from the previous step."""
    buf = _buffers(m, n, free.shape[0], rows.shape[0], tb[7].shape[0], tb[1].shape[0])
    for s in range(values.shape[0]):
        Q[set_col] = values[s]
        st, it, nr = _newton(tb, colinfo, rows, cols, free, Q, S, C, L, tol, max_iter, divergence, buf)
        Qout[s] = Q
        status[s], iterations[s], residual[s] = st, it, nr


@njit(cache=True, error_model="numpy")
def evaluate_dense(tb, rows, cols, Q, S, C, L, Phi, J):
    """Phi (N, m) and the dense Jacobian (N, m, n) of every variant of a batch."""
    vals = np.zeros(rows.shape[0])
    for v in range(Q.shape[0]):
        evaluate_entries(tb, Q[v], S[v], C[v], L[v], Phi[v], vals, True)
        J[v] = 0.0
        for k in range(rows.shape[0]):
            J[v, rows[k], cols[k]] += vals[k]


@njit(cache=True, error_model="numpy")
def poses_batch(tb, Q, S, C, L, m, r_out, A_out):
    """Body poses ``r`` (N, nb, 3) and ``A`` (N, nb, 3, 3) of every variant (forward kinematics)."""
    ws = _workspace(tb[7].shape[0], tb[1].shape[0])
    Phi = np.zeros(m)
    vals = np.zeros(0)
    for v in range(Q.shape[0]):
        evaluate_ws(tb, Q[v], S[v], C[v], L[v], Phi, vals, False, ws, np.zeros(0, np.int8))
        r_out[v] = ws[0]
        A_out[v] = ws[1]
