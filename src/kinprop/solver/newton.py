"""The one generalized-inverse Newton-Raphson loop (eq. 5.2-5.3 and Fig. 3), compiled.

Each step is the minimum-norm correction over the free variables only,
``dx_free = -pinv(Phi_x[:, free]) Phi`` (weighted: ``argmin sum(dx^2 / w)``), everything else
frozen, split into the blocks of the free set's :class:`~kinprop.solver.plan.Plan`. The
stopping test ``||Phi||_2 < tol`` is checked after each update (PAPER-NOTES 5-6); the caller
passes ``tol = max(tol, round-off floor)``. Single solves, batches (serial or threaded) and
sequences (sweeps) all run this loop; it never prints and never raises for non-convergence:
it returns a :class:`Status` code, the iteration count and the residual history.
"""

from __future__ import annotations

from enum import StrEnum
from typing import NamedTuple

import numpy as np

from kinprop.jit import COMPILED, GELSD, LAPACK_INT, inlined, kernel, njit
from kinprop.kinematics.kernels import (
    VEC_CALLER,
    W_FRAME_R,
    W_MAT,
    W_VEC,
    evaluate,
    retract,
    workspace,
)
from kinprop.kinematics.tables import (
    R_AXIS_I,
    R_AXIS_J,
    R_JOINT,
    V_COMPONENT,
    V_JOINT,
    V_KIND,
    V_SIDE,
    VAR_C,
    VAR_L,
    VAR_Q,
    VAR_S,
)
from kinprop.spatial import exp_so3_into, mm_into, mmT_into

#: relative singular-value threshold for the rank (``s_k > RANK_RTOL * s_max``)
RANK_RTOL = 1e-9
_KIND_D = ord("d")  # LAPACK's double-precision routines


class Status(StrEnum):
    """Outcome of a solve or of an analysis at a pose, the one status vocabulary of kinprop
    (docs/results.md); the compiled loop returns the index of one of the first six."""

    CONVERGED = "converged"
    NOT_CONVERGED = "not_converged"
    DIVERGED = "diverged"
    NO_FREE = "no_free"
    #: a change that cannot be followed on the start's branch (the reached fraction is reported)
    INFEASIBLE = "infeasible"
    #: a documented cap (sub-steps of one change) was reached before the change was followed
    STEP_LIMIT = "step_limit"
    #: never returned by the compiled loop: the values could not be applied (outside their
    #: variable's domain, e.g. a length <= 0), so nothing was solved (a study's variant)
    INVALID = "invalid"
    #: never returned by the compiled loop: an analysis of a pose (velocities, loads) was asked
    #: at a state that is not an assembly (``||Phi||`` too large), so nothing was computed
    NOT_ASSEMBLED = "not_assembled"
    #: never returned by the compiled loop: an analysis at an assembled pose (``kp.motion``,
    #: ``kp.statics``; no iteration) has its unique answer
    OK = "ok"
    #: the velocity analysis at an assembled pose has no unique answer: the driven rates leave
    #: directions of motion undetermined, or violate the constraints (a locked input)
    SINGULAR = "singular"
    #: the statics at an assembled pose has no answer: the constraints and inputs do not hold
    #: the loads (the mechanism can move under them)
    UNBALANCED = "unbalanced"


STATUSES = tuple(Status)
CONVERGED, NOT_CONVERGED, DIVERGED, NO_FREE, INFEASIBLE, STEP_LIMIT = 0, 1, 2, 3, 4, 5
#: ``follow`` flags: the change was subdivided / a sub-step left the predicted branch / the
#: sign of det(Phi_free) flipped on a trial step (a singularity between two configurations) /
#: the start was not assembled (estimates: assembled at its own design before the change) /
#: a trial step landed on a root with a cut joint's rigid axis reversed (a pose the joint cannot
#: take: ``JointType.rigid_axes``) / the least change (closest assembly) was not reached
SUBDIVIDED, JUMPED, SIGN_FLIP, FROM_ESTIMATES, FLIPPED, LEAST_CHANGE_FAILED = 1, 2, 4, 8, 16, 32
#: a converged residual below this (scaled, ~ metres) is at round-off already: no polishing step
POLISHED = 1e-14
#: ``follow``'s ``start_sign`` when the caller does not know it (it is computed)
UNKNOWN_SIGN = 2


class Settings(NamedTuple):
    """Numbers the compiled loops read (``kinprop.engine`` builds them from its options)."""

    tol: float  # on the scaled residual ||diag(row_scale) Phi||
    max_iter: int  # Newton iterations per solve
    divergence: float  # stop when the residual grows beyond this factor of the first
    kappa: float  # jump test: corrections <= kappa |predictor| + jump_atol (col-scaled)
    jump_atol: float
    trust: float  # a predictor step longer than this (col-scaled: rad, or lengths / L) is subdivided
    min_step: float  # smallest sub-step (fraction of the change) before a change is infeasible
    max_substeps: int  # cap on the sub-steps of one change (bounded work on any input)
    polish: bool  # one more step after convergence (to round-off) when it lowers the residual
    branch: bool  # keep the start's branch (jump and det-sign tests, subdivision); False: plain Newton
    #: return the assembly closest to the start (``argmin sum (dx_k / sqrt_weights_k)^2``,
    #: Phi = 0) when the free set leaves freedom; False: the paper's iteration's own end point
    least_change: bool
    opt_tol: float  # on the optimality residual (length of the least-change correction, SI)


@kernel
def _lu_solve(M, b, x):
    """``M x = b`` by Gaussian elimination with partial pivoting (destroys M, b); returns the
    sign of det M (+1 or -1), 0 when singular."""
    n = M.shape[0]
    scale = 0.0
    for i in range(n):
        for j in range(n):
            scale = max(scale, abs(M[i, j]))
    if scale == 0.0:
        return 0
    sign = 1
    for col in range(n):
        piv, big = col, abs(M[col, col])
        for i in range(col + 1, n):
            if abs(M[i, col]) > big:
                big, piv = abs(M[i, col]), i
        if big <= 1e-13 * scale:
            return 0
        if piv != col:
            sign = -sign
            for j in range(n):
                M[col, j], M[piv, j] = M[piv, j], M[col, j]
            b[col], b[piv] = b[piv], b[col]
        if M[col, col] < 0.0:
            sign = -sign
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
    return sign


@kernel
def _lstsq(M, m, n, b, sv, rank):
    """LAPACK ``dgelsd`` (SVD, as ``numpy.linalg.lstsq``: singular values below ``eps max(m, n)
    s_max`` dropped) on the column-major ``m x n`` matrix in ``M`` (destroyed): ``b`` (at
    least ``max(m, n)`` long) holds the right side on entry and the minimum-norm least-squares
    solution in ``b[:n]`` on exit. ``sv``, ``rank``: scratch. Returns LAPACK's info (0: ok).
    Called through numba's own LAPACK binding, so it allocates nothing numba counts;
    uncompiled (:mod:`kinprop.jit`), through ``numpy.linalg.lstsq`` (the same routine)."""
    if not COMPILED:
        b[:n] = np.linalg.lstsq(M[: m * n].reshape((n, m)).T, b[:m], rcond=None)[0]
        return 0
    return GELSD(_KIND_D, m, n, 1, M.ctypes, max(m, 1), b.ctypes, max(m, n, 1), sv.ctypes,
                 2.220446049250313e-16 * max(m, n), rank.ctypes)  # fmt: skip


@njit
def _svd_step(J, rhs, out):
    """``out = -pinv(J) rhs`` by :func:`_lstsq`; destroys nothing."""
    m, n = J.shape
    out[:] = 0.0
    if m == 0 or n == 0:
        return
    M, b = np.empty(m * n), np.zeros(max(m, n))
    for i in range(m):
        b[i] = rhs[i]
        for y in range(n):
            M[y * m + i] = J[i, y]
    _lstsq(M, m, n, b, np.zeros(min(m, n)), np.zeros(1, LAPACK_INT))
    for i in range(n):
        out[i] = -b[i]


@njit
def min_norm_step(J, rhs, out):
    """``out = -pinv(J) rhs``: pivoted LU when square and well conditioned, else the SVD
    pseudo-inverse (:func:`_svd_step`). Returns the sign of det J when square and regular,
    else 0. (The solver's loop does the same block by block without allocating.)"""
    m, n = J.shape
    if n == 0:
        return 1
    if m == n:
        M, b = J.copy(), rhs.copy()
        sign = _lu_solve(M, b, out)
        if sign != 0:
            for i in range(n):
                out[i] = -out[i]
            if np.all(np.isfinite(out)):
                return sign
    _svd_step(J, rhs, out)
    return 0


#: slots of :func:`buffers`
B_PHI, B_VALS, B_STORE, B_DX, B_DISP, B_WS, B_DX1, B_LU, B_RHS, B_OUT, B_NONE, B_SV, B_RANK, B_U = range(14)
#: slots of the dense KKT step (:func:`kkt_step`; empty unless ``plan.second_order``)
B_KKT, B_KRHS, B_JF, B_JF2, B_G, B_LAM, B_PHI2, B_VALS2, B_U2, B_M3, B_W3 = range(14, 25)


@njit
def buffers(tb, plan, nnz):
    """Work arrays of one solve (slots ``B_*``), allocated once: Phi, entry values, block
    storage, step, displacement, the kinematics workspace, the first step; one block's
    weighted matrix, right side and solution; an empty index array (no sparsity pattern
    recorded); LAPACK's singular values and rank; the change from the least-change reference;
    then those of :func:`kkt_step` (``B_KKT`` ..)."""
    nf, nr = plan.free.shape[0], plan.n_rows
    big = max(nf, nr, 1)
    k = nf + nr if plan.second_order else 0  # the KKT system's size
    kj = nf * nr if plan.second_order else 0
    return np.zeros(nr), np.zeros(nnz), np.zeros(plan.store_ptr[-1]), np.zeros(nf), np.zeros(nf), \
        workspace(tb), np.zeros(nf), np.zeros(plan.store_ptr[-1]), np.zeros(big), np.zeros(nf), \
        np.zeros(0, np.int64), np.zeros(max(big, k)), np.zeros(1, LAPACK_INT), np.zeros(nf), \
        np.empty(k * k), np.empty(k), np.empty(kj), np.empty(kj), np.empty(nf if k else 0), \
        np.zeros(nr if k else 0), np.empty(nr if k else 0), np.empty(nnz if k else 0), np.empty(nf if k else 0), \
        np.empty((4, 3, 3)), np.empty(3)  # fmt: skip


@inlined
def _scatter(plan, vals, store):
    """The free Jacobian's blocks from the entry values (``plan.entry_slot``)."""
    store[:] = 0.0
    slot = plan.entry_slot
    for k in range(slot.shape[0]):
        if slot[k] >= 0:
            store[slot[k]] += vals[k]


@inlined
def _block_system(plan, Phi, vals, buf, b, colmajor):
    """Block ``b``'s weighted matrix ``J W^(1/2)`` into ``buf[B_LU]`` (row- or column-major) and
    its right side (Phi of its rows plus the coupling to the blocks already solved) into
    ``buf[B_RHS]``; returns its shape."""
    store, dx, M, rhs = buf[B_STORE], buf[B_DX], buf[B_LU], buf[B_RHS]
    r0, c0 = plan.row_ptr[b], plan.col_ptr[b]
    mb, nb = plan.row_ptr[b + 1] - r0, plan.col_ptr[b + 1] - c0
    s0 = plan.store_ptr[b]
    for i in range(mb):
        rhs[i] = Phi[plan.block_rows[r0 + i]]
    for e in range(plan.coupling_ptr[b], plan.coupling_ptr[b + 1]):  # solved blocks -> right side
        rhs[plan.coupling_row[e]] += vals[plan.coupling_entry[e]] * dx[plan.coupling_free[e]]
    for y in range(nb):
        w = plan.sqrt_weights[plan.block_cols[c0 + y]]
        for i in range(mb):
            M[y * mb + i if colmajor else i * nb + y] = store[s0 + i * nb + y] * w
    return mb, nb


@inlined
def _block_out(plan, buf, b, sign):
    """``dx`` of block ``b``'s columns from its solution in ``buf[B_OUT]`` (``-`` it when the
    solution is of ``J x = rhs``: ``sign`` -1)."""
    dx, out = buf[B_DX], buf[B_OUT]
    c0 = plan.col_ptr[b]
    for y in range(plan.col_ptr[b + 1] - c0):
        f = plan.block_cols[c0 + y]
        dx[f] = sign * out[y] * plan.sqrt_weights[f]


@inlined
def _lu_blocks(plan, Phi, vals, buf, b0):
    """Blocks ``b0, b0+1, ...`` solved by LU while square and regular; returns ``(the first
    block that needs the SVD or -1, sign of det over the blocks solved)``."""
    sign = 1
    for b in range(b0, plan.row_ptr.shape[0] - 1):
        mb, nb = _block_system(plan, Phi, vals, buf, b, False)
        if nb == 0:
            continue
        if mb != nb:
            return b, sign
        M = buf[B_LU][: mb * nb].reshape((mb, nb))
        s = _lu_solve(M, buf[B_RHS][:mb], buf[B_OUT][:nb])
        ok = s != 0
        for y in range(nb):
            ok = ok and np.isfinite(buf[B_OUT][y])
        if not ok:
            return b, sign
        sign *= s
        _block_out(plan, buf, b, -1.0)
    return -1, sign


@kernel
def _left_jacobian(u0, u1, u2, A):
    """``A = J_l(u)``, the left Jacobian of SO(3)'s exponential at the rotation vector ``u``:
    ``exp(u + d) = exp(J_l(u) d) exp(u)`` to first order in ``d``;
    ``J_l = I + (1 - cos t) / t^2 [u]x + (t - sin t) / t^3 [u]x^2``, ``t = |u|``."""
    t2 = u0 * u0 + u1 * u1 + u2 * u2
    if t2 < 1e-8:  # the series (error < 1e-18)
        a, c = 0.5 - t2 / 24.0, 1.0 / 6.0 - t2 / 120.0
    else:
        t = np.sqrt(t2)
        a, c = (1.0 - np.cos(t)) / t2, (t - np.sin(t)) / (t2 * t)
    u = (u0, u1, u2)
    for x in range(3):
        for y in range(3):
            A[x, y] = c * u[x] * u[y] + ((1.0 - c * t2) if x == y else 0.0)
    A[0, 1] -= a * u2
    A[1, 0] += a * u2
    A[0, 2] += a * u1
    A[2, 0] -= a * u1
    A[1, 2] -= a * u0
    A[2, 1] += a * u0


@inlined
def _rotation_block(plan, buf, b, mb, nb, A, after):
    """The least-change step's orientation columns of block ``b`` in the rotation vector ``u``
    from the reference (``C = exp(u) C_ref``; ``buf[B_U]``): before the solve (``after``
    False) the weighted matrix's columns become those of ``J J_l(u)``, the Jacobian in ``u``
    (the right side ``Phi - J u`` stays: ``J_l(u) u = u``); after it, the solution's change of
    ``u`` becomes the retraction's ``dxi' = J_l(u) du``. Gauss-Newton in ``u`` is the exact
    linearisation of the metric ``|u|^2`` (a step linear in ``xi'`` is not, far from the
    reference)."""
    u, c0 = buf[B_U], plan.col_ptr[b]
    for k in range(plan.rotations.shape[0]):
        if plan.rotations[k, 0] != b:
            continue
        f0 = plan.block_cols[c0 + plan.rotations[k, 1]]
        f1 = plan.block_cols[c0 + plan.rotations[k, 2]]
        f2 = plan.block_cols[c0 + plan.rotations[k, 3]]
        _left_jacobian(u[f0], u[f1], u[f2], A)
        if after:
            dx = buf[B_DX]
            d0, d1, d2 = dx[f0], dx[f1], dx[f2]
            dx[f0] = A[0, 0] * d0 + A[0, 1] * d1 + A[0, 2] * d2
            dx[f1] = A[1, 0] * d0 + A[1, 1] * d1 + A[1, 2] * d2
            dx[f2] = A[2, 0] * d0 + A[2, 1] * d1 + A[2, 2] * d2
        else:
            store, M, s0 = buf[B_STORE], buf[B_LU], plan.store_ptr[b]
            for i in range(mb):
                r = s0 + i * nb
                j0 = store[r + plan.rotations[k, 1]]
                j1 = store[r + plan.rotations[k, 2]]
                j2 = store[r + plan.rotations[k, 3]]
                for e in range(3):
                    y = plan.rotations[k, 1 + e]
                    w = plan.sqrt_weights[plan.block_cols[c0 + y]]
                    M[y * mb + i] = (j0 * A[0, e] + j1 * A[1, e] + j2 * A[2, e]) * w


@kernel
def newton_step(plan, Phi, vals, buf, project):
    """The minimum-norm step over the free columns (block by block, in the plan's order, each
    block's right side including the blocks solved before it) into ``buf[B_DX]`` (free order):
    pivoted LU for square regular blocks, ``dgelsd`` (the SVD pseudo-inverse) for the others.
    Returns the sign of det of the free Jacobian (product over square blocks; 0: unknown).

    ``project``: the least-change (Gauss-Newton) step from the reference instead, with ``u =
    x - x_ref`` in ``buf[B_U]``: ``dx = -u - W^1/2 pinv(J W^1/2) (Phi - J u)``, the step to
    ``argmin ||W^-1/2 (x + dx - x_ref)||`` subject to ``Phi + J dx = 0``, orientations measured
    by their rotation vector from the reference (:func:`_rotation_block`); it differs from the
    plain step only in the blocks with freedom (the SVD ones: a square regular block's
    solution is unique)."""
    _scatter(plan, vals, buf[B_STORE])
    b, sign = _lu_blocks(plan, Phi, vals, buf, 0)
    while b >= 0:  # a rectangular or singular block: the pseudo-inverse
        sign = 0
        mb, nb = _block_system(plan, Phi, vals, buf, b, True)
        rhs = buf[B_RHS]
        if project:  # Phi - J u over the block (J unweighted, from the block's storage)
            store, u, c0, s0 = buf[B_STORE], buf[B_U], plan.col_ptr[b], plan.store_ptr[b]
            for i in range(mb):
                for y in range(nb):
                    rhs[i] -= store[s0 + i * nb + y] * u[plan.block_cols[c0 + y]]
            _rotation_block(plan, buf, b, mb, nb, buf[B_WS][W_MAT][2], False)
        M, r0 = buf[B_LU], plan.row_ptr[b]
        for i in range(mb):  # rows in SI units: the fit and the rank do not depend on the length unit
            f = plan.row_scale[plan.block_rows[r0 + i]]
            if f != 1.0:
                rhs[i] *= f
                for y in range(nb):
                    M[y * mb + i] *= f
        for i in range(mb, rhs.shape[0]):
            rhs[i] = 0.0
        if _lstsq(buf[B_LU], mb, nb, rhs, buf[B_SV], buf[B_RANK]) != 0:
            for i in range(nb):  # LAPACK failed: a non-finite step (the solve reports it)
                rhs[i] = np.nan
        out = buf[B_OUT]
        for i in range(nb):
            out[i] = rhs[i]
        _block_out(plan, buf, b, -1.0)
        if project:
            _rotation_block(plan, buf, b, mb, nb, buf[B_WS][W_MAT][2], True)
            dx, u, c0 = buf[B_DX], buf[B_U], plan.col_ptr[b]
            for y in range(nb):
                f = plan.block_cols[c0 + y]
                dx[f] -= u[f]
        b, _ = _lu_blocks(plan, Phi, vals, buf, b + 1)
    return sign


@kernel
def displacement(tb, free, Q, S, C, L, ref, u, ws):
    """``u = x - x_ref`` over the ``free`` columns (sorted), ``ref = (Q, S, C, L)`` of the
    reference: differences for q, s', l, coefficients; ``log(C C_ref^T)`` for orientations
    (the retraction's ``C <- exp(tilde(dxi')) C``, so the gradient of ``|log|^2 / 2`` is the
    log itself)."""
    Qr, Sr, Cr, Lr = ref
    T, w = ws[W_MAT][2], ws[W_VEC][VEC_CALLER + 1]  # after an evaluation: free scratch
    last = -1
    for i in range(free.shape[0]):
        c = free[i]
        kind, j, side = tb.column[c, V_KIND], tb.column[c, V_JOINT], tb.column[c, V_SIDE]
        if kind == VAR_Q:
            u[i] = Q[c] - Qr[c]
        elif kind == VAR_S:
            k = tb.column[c, V_COMPONENT]
            u[i] = S[j, side, k] - Sr[j, side, k]
        elif kind == VAR_L:
            u[i] = L[j] - Lr[j]
        else:
            key = 2 * j + side
            if key != last:
                mmT_into(C[j, side], Cr[j, side], T)
                log_so3_into(T, w)
                last = key
            u[i] = w[tb.column[c, V_COMPONENT]]


@kernel
def _metric_jacobian(plan, vals, u, J, A):
    """The free Jacobian in the metric's coordinates into ``J`` (rows x free, rows in SI:
    ``plan.row_scale``): orientation columns in the rotation vector ``u`` from the reference,
    ``J_xi J_l(u)`` (:func:`_left_jacobian`; ``A`` 3x3 scratch)."""
    J[:, :] = 0.0
    er, ef = plan.entry_row, plan.entry_free
    for e in range(er.shape[0]):
        if ef[e] >= 0:
            J[er[e], ef[e]] += vals[e] * plan.row_scale[er[e]]
    for k in range(plan.rotations.shape[0]):
        c0 = plan.col_ptr[plan.rotations[k, 0]]
        f0 = plan.block_cols[c0 + plan.rotations[k, 1]]
        f1 = plan.block_cols[c0 + plan.rotations[k, 2]]
        f2 = plan.block_cols[c0 + plan.rotations[k, 3]]
        _left_jacobian(u[f0], u[f1], u[f2], A)
        for i in range(J.shape[0]):
            j0, j1, j2 = J[i, f0], J[i, f1], J[i, f2]
            J[i, f0] = j0 * A[0, 0] + j1 * A[1, 0] + j2 * A[2, 0]
            J[i, f1] = j0 * A[0, 1] + j1 * A[1, 1] + j2 * A[2, 1]
            J[i, f2] = j0 * A[0, 2] + j1 * A[1, 2] + j2 * A[2, 2]


@kernel
def _copy3(a, b):
    for x in range(3):
        for y in range(3):
            b[x, y] = a[x, y]


#: finite-difference step of the KKT step's Lagrangian Hessian (SI: metres, radians)
FD_STEP = 1e-7


@kernel
def kkt_step(tb, plan, Q, S, C, L, ref, buf, curvature):
    """The least-change step by Newton on the KKT system of ``min |u|_W^2 / 2`` subject to
    ``Phi = 0`` (``u`` the change from ``ref`` in the metric's coordinates, :func:`displacement`
    in ``buf[B_U]``; Phi and its entries of the state ``Q, S, C, L`` in ``buf``)::

        [W^-1 + H   J^T] [du]   [-W^-1 u]
        [J          0  ] [lam] = [-Phi   ]     (rows in SI, J in u: :func:`_metric_jacobian`)

    ``H = sum_i lam_i d2 Phi_i / du2``, the Lagrangian's curvature at the multipliers of the
    previous step (``buf[B_LAM]``), by forward differences of ``J^T lam`` (one evaluation per
    free column, step :data:`FD_STEP` in SI); without ``curvature`` ``H = 0``: the Gauss-Newton
    step of :func:`newton_step`. Solved by ``dgelsd`` (redundant rows: minimum-norm
    multipliers). Newton converges quadratically where Gauss-Newton's rate is the curvature of
    the constraint times the distance to the start (slow for large changes, orientations
    above all). The step ``dx`` (retraction coordinates: ``dxi' = J_l(u) du``) goes to
    ``buf[B_DX]``, the new multipliers to ``buf[B_LAM]``; returns the step's length in the
    metric ``|du|_W`` (the optimality residual)."""
    free, nf, m = plan.free, plan.free.shape[0], plan.n_rows
    k = nf + m
    u, u2, dx, lam, g = buf[B_U], buf[B_U2], buf[B_DX], buf[B_LAM], buf[B_G]
    M3, w3, ws = buf[B_M3], buf[B_W3], buf[B_WS]
    A = M3[2]
    J = buf[B_JF][: m * nf].reshape((m, nf))
    K, rhs = buf[B_KKT], buf[B_KRHS]
    _metric_jacobian(plan, buf[B_VALS], u, J, A)
    for c in range(k * k):
        K[c] = 0.0
    for f in range(nf):  # W^-1, J^T, J (column-major)
        K[f * k + f] = 1.0 / plan.sqrt_weights[f] ** 2
        for i in range(m):
            K[(nf + i) * k + f] = J[i, f]
            K[f * k + nf + i] = J[i, f]
    if curvature:
        for f in range(nf):  # J^T lam at the state
            s = 0.0
            for i in range(m):
                s += J[i, f] * lam[i]
            g[f] = s
        J2 = buf[B_JF2][: m * nf].reshape((m, nf))
        Phi2, vals2, none = buf[B_PHI2], buf[B_VALS2], buf[B_NONE]
        for y in range(nf):  # column y of H: d(J^T lam)/du_y
            c = free[y]
            kind, j, side = tb.column[c, V_KIND], tb.column[c, V_JOINT], tb.column[c, V_SIDE]
            h = FD_STEP * plan.sqrt_weights[y]
            comp = tb.column[c, V_COMPONENT]
            keep = 0.0
            if kind == VAR_Q:
                keep = Q[c]
                Q[c] += h
            elif kind == VAR_S:
                keep = S[j, side, comp]
                S[j, side, comp] += h
            elif kind == VAR_L:
                keep = L[j]
                L[j] += h
            else:  # C = exp(u + h e) C_ref, u its rotation vector from the reference
                _copy3(C[j, side], M3[0])
                mmT_into(C[j, side], ref[2][j, side], M3[1])
                log_so3_into(M3[1], w3)
                w3[comp] += h
                exp_so3_into(w3, M3[1])
                mm_into(M3[1], ref[2][j, side], C[j, side])
            evaluate(tb, Q, S, C, L, ws, Phi2, vals2, plan.need, none, none)
            displacement(tb, free, Q, S, C, L, ref, u2, ws)
            _metric_jacobian(plan, vals2, u2, J2, A)
            if kind == VAR_Q:
                Q[c] = keep
            elif kind == VAR_S:
                S[j, side, comp] = keep
            elif kind == VAR_L:
                L[j] = keep
            else:
                _copy3(M3[0], C[j, side])
            for f in range(nf):
                s = 0.0
                for i in range(m):
                    s += J2[i, f] * lam[i]
                K[y * k + f] += 0.5 * (s - g[f]) / h  # symmetrised: (H + H^T) / 2
                K[f * k + y] += 0.5 * (s - g[f]) / h
    Phi = buf[B_PHI]
    for f in range(nf):
        rhs[f] = -u[f] / plan.sqrt_weights[f] ** 2
    for i in range(m):
        rhs[nf + i] = -Phi[i] * plan.row_scale[i]
    if _lstsq(K, k, k, rhs, buf[B_SV], buf[B_RANK]) != 0:
        for f in range(k):
            rhs[f] = np.nan
    o2 = 0.0
    for f in range(nf):
        dx[f] = rhs[f]
        o2 += (rhs[f] / plan.sqrt_weights[f]) ** 2
    for i in range(m):
        lam[i] = rhs[nf + i]
    for r in range(plan.rotations.shape[0]):  # the retraction's dxi' = J_l(u) du
        c0 = plan.col_ptr[plan.rotations[r, 0]]
        f0 = plan.block_cols[c0 + plan.rotations[r, 1]]
        f1 = plan.block_cols[c0 + plan.rotations[r, 2]]
        f2 = plan.block_cols[c0 + plan.rotations[r, 3]]
        _left_jacobian(u[f0], u[f1], u[f2], A)
        d0, d1, d2 = dx[f0], dx[f1], dx[f2]
        dx[f0] = A[0, 0] * d0 + A[0, 1] * d1 + A[0, 2] * d2
        dx[f1] = A[1, 0] * d0 + A[1, 1] * d1 + A[1, 2] * d2
        dx[f2] = A[2, 0] * d0 + A[2, 1] * d1 + A[2, 2] * d2
    return np.sqrt(o2)


@kernel
def rigid_signs(tb, R, out):
    """Sign (+1, -1) of ``x''_a(i) . x''_b(j)`` of every rigid axis pair (``tb.rigid``) from the
    global joint frames ``R`` (the workspace's, after an evaluation), into ``out``."""
    for k in range(tb.rigid.shape[0]):
        j, a, b = tb.rigid[k, R_JOINT], tb.rigid[k, R_AXIS_I], tb.rigid[k, R_AXIS_J]
        d = R[j, 0, 0, a] * R[j, 1, 0, b] + R[j, 0, 1, a] * R[j, 1, 1, b] + R[j, 0, 2, a] * R[j, 1, 2, b]
        out[k] = 1.0 if d >= 0.0 else -1.0


@kernel
def flipped(tb, R, ref):
    """Whether some cut joint's rigid axis pair has left the side ``ref`` (from
    :func:`rigid_signs` at the start): a root of its dot-1 rows the joint cannot reach."""
    for k in range(tb.rigid.shape[0]):
        j, a, b = tb.rigid[k, R_JOINT], tb.rigid[k, R_AXIS_I], tb.rigid[k, R_AXIS_J]
        d = R[j, 0, 0, a] * R[j, 1, 0, b] + R[j, 0, 1, a] * R[j, 1, 1, b] + R[j, 0, 2, a] * R[j, 1, 2, b]
        if d * ref[k] <= 0.0:
            return True
    return False


@inlined
def _residual(tb, plan, Q, S, C, L, row_scale, buf):
    """Evaluate Phi (kept in ``buf``) and the Jacobian entries the plan needs; return the
    scaled norm of Phi."""
    Phi, vals, ws, none = buf[B_PHI], buf[B_VALS], buf[B_WS], buf[B_NONE]
    evaluate(tb, Q, S, C, L, ws, Phi, vals, plan.need, none, none)
    s = 0.0
    for i in range(Phi.shape[0]):
        r = Phi[i] * row_scale[i]
        s += r * r
    return np.sqrt(s)


@kernel
def solve(tb, plan, Q, S, C, L, row_scale, col_scale, cfg, tol, history, buf, ref, project, max_iter):
    """Newton on ``Phi(x) = 0`` from ``Q, S, C, L`` (updated in place), to ``tol``.

    Returns ``(status, iterations, ||row_scale Phi||, |dx_1|, jumped, sign_0, sign_1, opt)``:
    the first step (the implicit-function predictor; column-scaled, the longest over the plan's
    blocks), whether the later corrections took the solution further from the predictor than
    ``kappa |dx_1| + jump_atol`` (a ratio: independent of the mechanism's size) or some block's
    predictor was longer than ``trust`` (per block, an independent sub-mechanism: a large
    mechanism is not subdivided for being large), and the sign of det of the free Jacobian at
    the first and last step taken (0: not square or singular).
    ``history[k]`` receives the residual after k updates (may be shorter than ``max_iter + 1``).

    ``project``: the least-change iteration on ``min ||W^-1/2 (x - x_ref)||`` subject to
    ``Phi(x) = 0``, ``ref`` the reference state: Newton on its KKT system when the plan is
    small (``plan.second_order``, :func:`kkt_step`; its first step is Gauss-Newton's), else
    Gauss-Newton (:func:`newton_step`); converged when
    also ``opt``, the length of that step in the metric, is below ``cfg.opt_tol``: zero exactly
    at the closest assembly's KKT point, where ``W^-1 (x - x_ref)`` lies in the row space of
    the free Jacobian. Otherwise ``opt`` is 0 and ``ref`` unused.
    """
    Phi, vals, dx, disp, dx1 = buf[B_PHI], buf[B_VALS], buf[B_DX], buf[B_DISP], buf[B_DX1]
    free = plan.free
    nf = free.shape[0]
    norm, first, opt = 0.0, 1e-300, 0.0
    it, status = 0, NOT_CONVERGED
    sign0, sign1, sign = 0, 0, 0
    disp[:] = 0.0
    polishing = False
    while True:  # one evaluation per pass: one call site, where evaluate is compiled inline
        r = _residual(tb, plan, Q, S, C, L, row_scale, buf)
        if polishing:  # after the polishing step: kept if it lowered the residual, else undone
            if r < norm:
                norm = r
                for i in range(nf):
                    disp[i] += dx[i]
            else:
                for i in range(nf):
                    dx[i] = -dx[i]
                retract(tb, free, dx, Q, S, C, L, buf[B_WS])
            break
        norm = r
        if it < history.shape[0]:
            history[it] = norm
        stepped = False
        if project and nf > 0:  # the least-change step first: its length is the stopping test
            displacement(tb, free, Q, S, C, L, ref, buf[B_U], buf[B_WS])
            stepped = True
            if plan.second_order:  # Newton on the KKT system (the first step: Gauss-Newton's)
                opt = kkt_step(tb, plan, Q, S, C, L, ref, buf, it > 0)
                sign = 0
            else:
                sign = newton_step(plan, Phi, vals, buf, np.bool_(True))
                o2 = 0.0
                for i in range(nf):
                    o2 += (dx[i] / plan.sqrt_weights[i]) ** 2
                opt = np.sqrt(o2)
        if it == 0:
            first = max(norm, opt, 1e-300)
        elif not np.isfinite(norm) or norm > cfg.divergence * first:
            status = DIVERGED
            break
        if norm < tol and opt < cfg.opt_tol:
            status = CONVERGED
            if not (cfg.polish and nf > 0 and norm > POLISHED):
                break
            polishing = True  # one more step to round-off, kept if better
        elif it >= max_iter:
            break
        elif nf == 0:
            status = NO_FREE
            break
        if not stepped:
            sign = newton_step(plan, Phi, vals, buf, np.bool_(False))
        if not polishing:
            sign1 = sign
            if it == 0:
                sign0 = sign
                for i in range(nf):
                    dx1[i] = dx[i]
            for i in range(nf):
                disp[i] += dx[i]
            it += 1
        retract(tb, free, dx, Q, S, C, L, buf[B_WS])
    step1, p2, c2 = 0.0, 0.0, 0.0
    if it > 0:  # the predictor x_0 + dx_1 (per block) and how far the corrections took it
        for b in range(plan.col_ptr.shape[0] - 1):
            p = 0.0
            for y in range(plan.col_ptr[b], plan.col_ptr[b + 1]):
                f = plan.block_cols[y]
                p += (dx1[f] * col_scale[free[f]]) ** 2
                c2 += ((disp[f] - dx1[f]) * col_scale[free[f]]) ** 2
            p2 += p
            step1 = max(step1, np.sqrt(p))
    jumped = np.sqrt(c2) > cfg.kappa * np.sqrt(p2) + cfg.jump_atol or step1 > cfg.trust
    return status, it, norm, step1, jumped, sign0, sign1, opt


@kernel
def log_so3_into(R, w):
    """``w`` with ``exp(tilde(w)) = R`` (angle in [0, pi])."""
    c = min(1.0, max(-1.0, 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0)))
    th = np.arccos(c)
    v0, v1, v2 = R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]
    if th < 1e-8:
        w[0], w[1], w[2] = 0.5 * v0, 0.5 * v1, 0.5 * v2
    elif np.pi - th < 1e-6:  # near a half turn: the axis from the largest diagonal of (R + I) / 2
        k = 0
        for i in range(1, 3):
            if R[i, i] > R[k, k]:
                k = i
        ak = np.sqrt(max(0.0, 0.5 * (R[k, k] + 1.0)))
        for i in range(3):  # the axis into w, then scaled to length th
            w[i] = ak if i == k else 0.5 * (R[i, k] + R[k, i]) / (2.0 * ak)
        n = np.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
        for i in range(3):
            w[i] *= th / n
    else:
        f = th / (2.0 * np.sin(th))
        w[0], w[1], w[2] = f * v0, f * v1, f * v2


@kernel
def _copy(a, b):
    for i in range(a.shape[0]):
        b[i] = a[i]


@kernel
def copy_state(Q, S, C, L, Qd, Sd, Cd, Ld):
    """``Qd, Sd, Cd, Ld = Q, S, C, L`` (element by element: no temporary)."""
    _copy(Q, Qd)
    _copy(L, Ld)
    for j in range(S.shape[0]):
        for side in range(2):
            for a in range(3):
                Sd[j, side, a] = S[j, side, a]
                for b in range(3):
                    Cd[j, side, a, b] = C[j, side, a, b]


@njit
def follow_buffers(tb, Q, S, C, L):
    """State-shaped work arrays of :func:`follow` (start, last accepted, rotation paths, free
    masks, the least-change reference, the rigid axis pairs' signs at the start)."""
    nj = S.shape[0]
    return (Q.copy(), S.copy(), C.copy(), L.copy(), Q.copy(), S.copy(), C.copy(), L.copy(), np.zeros((nj, 2, 3)),
            np.zeros((nj, 2), np.bool_), np.zeros(Q.shape[0], np.bool_), np.zeros((nj, 2, 3), np.bool_),
            np.zeros((nj, 2), np.bool_), np.zeros(L.shape[0], np.bool_), Q.copy(), S.copy(), C.copy(), L.copy(),
            np.ones(tb.rigid.shape[0]))  # fmt: skip


@kernel
def optimality(tb, plan, Q, S, C, L, ref, buf):
    """The optimality residual at a state (the length of the least-change step from ``ref``,
    :func:`solve`); no step taken."""
    Phi, vals, ws, none = buf[B_PHI], buf[B_VALS], buf[B_WS], buf[B_NONE]
    nf = plan.free.shape[0]
    if nf == 0:
        return 0.0
    evaluate(tb, Q, S, C, L, ws, Phi, vals, plan.need, none, none)
    displacement(tb, plan.free, Q, S, C, L, ref, buf[B_U], ws)
    newton_step(plan, Phi, vals, buf, np.bool_(True))
    o2, dx = 0.0, buf[B_DX]
    for i in range(nf):
        o2 += (dx[i] / plan.sqrt_weights[i]) ** 2
    return np.sqrt(o2)


@kernel
def _sign_at(tb, plan, Q, S, C, L, buf):
    """Sign of det of the free Jacobian at a state (0: not square or singular); no step taken."""
    Phi, vals, ws, none = buf[B_PHI], buf[B_VALS], buf[B_WS], buf[B_NONE]
    if plan.free.shape[0] == 0:
        return 0
    evaluate(tb, Q, S, C, L, ws, Phi, vals, plan.need, none, none)
    return newton_step(plan, Phi, vals, buf, np.bool_(False))


@kernel
def follow(tb, plan, Q, S, C, L, Q1, S1, C1, L1, assembled, row_scale, col_scale, cfg, buf, fbuf, history,
           start_sign=UNKNOWN_SIGN):  # fmt: skip
    """Follow a change from the assembled state ``Q, S, C, L`` (design p0) to the design of
    ``Q1, S1, C1, L1`` (its entries outside the free columns) on the start's branch:
    predictor-corrector over sub-steps ``t -> t + h`` of the straight path
    (geodesic for orientations).

    A sub-step is accepted when Newton converges, its corrections stay within ``kappa`` of
    the predictor (no jump to another branch) and det of the free Jacobian keeps its sign (no
    singularity crossed unseen); otherwise it is halved, down to ``min_step``, within
    ``max_substeps``. The state ends at the last accepted point. A start that is not assembled
    (estimates; ``assembled`` 0, or -1: evaluate to know) is assembled at its own design first
    (flagged when det changed sign on the way), then the change is followed. Returns
    ``(status, iterations, fraction reached, sub-steps, ||scaled residual||, flags, entries of
    history written, det sign at the start, det sign at the last accepted step)`` (the history
    holds the assembly's residuals, then the last sub-step's, then the least-change finish's).
    ``start_sign``: the start's det sign when the caller knows it (an assembled start it solved
    from before with this plan).

    A converged trial step is also refused (flag ``FLIPPED``) when a cut joint's rigid axis pair
    (``tb.rigid``) is on the other side than at the start: a root of the joint's dot-1 rows the
    joint itself cannot reach (a slide turned by pi; :func:`flipped`). With ``cfg.least_change``
    and a free set that leaves freedom, the followed point is then moved to the assembly closest
    to the start (the original, changed start: ``argmin ||W^-1/2 (x - x_start)||``, Phi = 0) by
    the least-change iteration of :func:`solve`; when that fails (or flips) the followed point
    is kept with status ``NOT_CONVERGED`` and flag ``LEAST_CHANGE_FAILED``. The last returned
    value is the optimality residual (0 without freedom).
    """
    nj = S.shape[0]
    Q0, S0, C0, L0, Qs, Ss, Cs, Ls = fbuf[0], fbuf[1], fbuf[2], fbuf[3], fbuf[4], fbuf[5], fbuf[6], fbuf[7]
    W, turn = fbuf[8], fbuf[9]
    ref, rs = (fbuf[14], fbuf[15], fbuf[16], fbuf[17]), fbuf[18]
    copy_state(Q, S, C, L, Q0, S0, C0, L0)
    copy_state(Q, S, C, L, ref[0], ref[1], ref[2], ref[3])
    ws = buf[B_WS]
    nrigid = tb.rigid.shape[0]
    if (cfg.branch and assembled < 0) or nrigid > 0:  # is the start assembled? (no Jacobian entries needed)
        Phi, vals, none = buf[B_PHI], buf[B_VALS], buf[B_NONE]
        evaluate(tb, Q, S, C, L, ws, Phi, vals, plan.need_none, none, none)
        if nrigid > 0:
            rigid_signs(tb, ws[W_FRAME_R], rs)
        if cfg.branch and assembled < 0:
            r2 = 0.0
            for i in range(Phi.shape[0]):
                r2 += (Phi[i] * row_scale[i]) ** 2
            assembled = 1 if np.sqrt(r2) < cfg.tol else 0
    single = not cfg.branch
    flags, its0 = 0, 0
    if cfg.branch and assembled == 0:
        # not assembled (estimates): assemble at the start's own design first (the assembly the
        # estimates point at; flagged when det changed sign on the way), then follow the change
        st, it, nr, _, _, s0, s1, _ = solve(tb, plan, Q, S, C, L, row_scale, col_scale, cfg, cfg.tol, history, buf,
                                            ref, np.bool_(False), cfg.max_iter)  # fmt: skip
        flags |= FROM_ESTIMATES
        if s0 != 0 and s1 != 0 and s0 != s1:
            flags |= SIGN_FLIP
        if st == CONVERGED and nrigid > 0 and flipped(tb, ws[W_FRAME_R], rs):
            flags |= FLIPPED
            st = INFEASIBLE
        if st != CONVERGED and st != NO_FREE:
            return st, it, 0.0, 1, nr, flags, it + 1, UNKNOWN_SIGN, UNKNOWN_SIGN, 0.0
        its0 = it
        copy_state(Q, S, C, L, Q0, S0, C0, L0)
    # the change is what differs between start and target outside the free columns (the free
    # ones are the solution's: after assembling from estimates they differ from the target's)
    fq, fs, fc, fl = fbuf[10], fbuf[11], fbuf[12], fbuf[13]
    fq[:], fs[:], fc[:], fl[:] = False, False, False, False
    for i in range(plan.free.shape[0]):
        c = plan.free[i]
        kind, j, side = tb.column[c, V_KIND], tb.column[c, V_JOINT], tb.column[c, V_SIDE]
        if kind == VAR_Q:
            fq[c] = True
        elif kind == VAR_S:
            fs[j, side, tb.column[c, V_COMPONENT]] = True
        elif kind == VAR_C:
            fc[j, side] = True
        else:
            fl[j] = True
    # det sign of the free Jacobian at the assembled start: the reference of the branch test
    # (given by a batch whose variants share an assembled start)
    sign_ref = start_sign if start_sign != UNKNOWN_SIGN and its0 == 0 else _sign_at(tb, plan, Q, S, C, L, buf)
    sign_start = sign_ref
    T = ws[W_MAT][0]
    for j in range(nj):
        for side in range(2):
            turn[j, side] = False
            if fc[j, side]:
                continue
            for a in range(3):
                for b in range(3):
                    if C1[j, side, a, b] != C0[j, side, a, b]:
                        turn[j, side] = True
            if turn[j, side]:
                mmT_into(C1[j, side], C0[j, side], T)
                log_so3_into(T, W[j, side])
    w, E = ws[W_VEC][VEC_CALLER], ws[W_MAT][1]  # predictor scratch (evaluate overwrites E)
    t, h = 0.0, 1.0
    subs, its, last, hlen = 0, its0, CONVERGED, its0 + 1
    status, norm = CONVERGED, 0.0
    while t < 1.0:
        if subs >= cfg.max_substeps:
            status = STEP_LIMIT
            break
        tn = 1.0 if t + h >= 1.0 - 1e-12 else t + h
        if t > 0.0:  # keep the last accepted state (at t = 0 that is the start, Q0 S0 C0 L0)
            copy_state(Q, S, C, L, Qs, Ss, Cs, Ls)
        for k in range(Q.shape[0]):
            if Q1[k] != Q0[k] and not fq[k]:
                Q[k] = Q0[k] + tn * (Q1[k] - Q0[k])
        for j in range(L.shape[0]):  # lengths, then coupling coefficients
            if L1[j] != L0[j] and not fl[j]:
                L[j] = L0[j] + tn * (L1[j] - L0[j])
        for j in range(nj):
            for side in range(2):
                for a in range(3):
                    if S1[j, side, a] != S0[j, side, a] and not fs[j, side, a]:
                        S[j, side, a] = S0[j, side, a] + tn * (S1[j, side, a] - S0[j, side, a])
                if turn[j, side]:
                    for a in range(3):
                        w[a] = tn * W[j, side, a]
                    exp_so3_into(w, E)
                    mm_into(E, C0[j, side], C[j, side])
        hist = history[min(its0, history.shape[0]) :]  # after the assembly's residuals
        st, it, nr, _, jump, s0, s1, _ = solve(tb, plan, Q, S, C, L, row_scale, col_scale, cfg, cfg.tol, hist, buf,
                                               ref, np.bool_(False), cfg.max_iter)  # fmt: skip
        last = st
        its += it
        hlen = min(its0, history.shape[0]) + it + 1
        subs += 1
        norm = nr
        if st == NO_FREE:
            status = NO_FREE
            break
        # the sign at the last step taken (next to the solution) against the accepted state's
        flip = sign_ref != 0 and s1 != 0 and sign_ref != s1
        # a cut joint turned onto a root it cannot reach (its rigid axes reversed)
        cut_flip = st == CONVERGED and nrigid > 0 and flipped(tb, ws[W_FRAME_R], rs)
        if cut_flip:
            flags |= FLIPPED
        if single:  # plain Newton: one solve, its outcome
            status = st
            t = 1.0 if st == CONVERGED else 0.0
            break
        if st == CONVERGED and not jump and not flip and not cut_flip:
            t = tn
            if s1 != 0:
                sign_ref = s1
            if it <= 3:
                h = min(2.0 * h, 1.0)
            continue
        if (jump or cut_flip) and st == CONVERGED:
            flags |= JUMPED
        if flip:
            flags |= SIGN_FLIP
        flags |= SUBDIVIDED
        if t > 0.0:
            copy_state(Qs, Ss, Cs, Ls, Q, S, C, L)
        else:
            copy_state(Q0, S0, C0, L0, Q, S, C, L)
        h *= 0.5
        if h < cfg.min_step:
            status = INFEASIBLE
            break
    if status != CONVERGED and t == 0.0 and not flags & (JUMPED | SIGN_FLIP) and last != CONVERGED:
        status = last  # nothing of the change could be solved at all: say why (not a branch matter)
    opt = 0.0
    nf = plan.free.shape[0]
    if status == CONVERGED and nf > 0 and (not plan.square or sign_ref == 0):  # the free set leaves freedom
        if cfg.least_change:  # the closest assembly to the start, from the followed point
            copy_state(Q, S, C, L, Qs, Ss, Cs, Ls)
            h0 = min(max(hlen - 1, 0), history.shape[0])
            st, it, nr, _, _, _, _, opt = solve(tb, plan, Q, S, C, L, row_scale, col_scale, cfg, cfg.tol,
                                                history[h0:], buf, ref, np.bool_(True), cfg.max_iter)  # fmt: skip
            its += it
            hlen = h0 + it + 1
            if st == CONVERGED and not (nrigid > 0 and flipped(tb, ws[W_FRAME_R], rs)):
                norm = nr
            else:
                flags |= LEAST_CHANGE_FAILED
                status = NOT_CONVERGED
                copy_state(Qs, Ss, Cs, Ls, Q, S, C, L)
        else:  # the paper's iteration: its end point, with the optimality residual reported
            opt = optimality(tb, plan, Q, S, C, L, ref, buf)
    return status, its, t, subs, norm, flags, hlen, sign_start, sign_ref, opt


@kernel
def _store(out, k, r):
    out[k, 0], out[k, 1], out[k, 2], out[k, 3], out[k, 4], out[k, 5] = r[0], r[1], r[2], r[3], r[4], r[5]
    out[k, 6] = r[9]


@njit
def follow_one(tb, plan, nnz, Q, S, C, L, Q1, S1, C1, L1, assembled, row_scale, col_scale, cfg, history,
               start_sign):  # fmt: skip
    """:func:`follow` with its own buffers."""
    buf = buffers(tb, plan, nnz)
    return follow(tb, plan, Q, S, C, L, Q1, S1, C1, L1, assembled, row_scale, col_scale, cfg, buf,
                  follow_buffers(tb, Q, S, C, L), history, start_sign)  # fmt: skip


@njit
def _follow_range(tb, plan, nnz, Q, S, C, L, Q1, S1, C1, L1, Qo, So, Co, Lo, assembled, row_scale, col_scale, cfg,
                  out, v0, v1):  # fmt: skip
    """:func:`follow` for variants ``v0 .. v1 - 1`` with one set of buffers: variant ``v``
    starts from ``Q[v], S[v], ...`` (``[0]`` for all when the start has a leading axis of 1),
    aims at the design of ``Q1[v], ...`` and ends in ``Qo[v], ...``. A shared assembled start's
    det sign is computed once (else each variant's, by :func:`follow`)."""
    buf = buffers(tb, plan, nnz)
    fbuf = follow_buffers(tb, Q[0], S[0], C[0], L[0])
    hist = np.zeros(0)
    shared = Q.shape[0] == 1
    sign = np.int64(UNKNOWN_SIGN)  # not the literal: one signature of follow
    if shared and assembled == 1 and cfg.branch:
        sign = _sign_at(tb, plan, Q[0], S[0], C[0], L[0], buf)
    for v in range(v0, v1):
        u = 0 if shared else v
        copy_state(Q[u], S[u], C[u], L[u], Qo[v], So[v], Co[v], Lo[v])
        r = follow(tb, plan, Qo[v], So[v], Co[v], Lo[v], Q1[v], S1[v], C1[v], L1[v], assembled, row_scale, col_scale,
                   cfg, buf, fbuf, hist, sign)  # fmt: skip
        _store(out, v, r)


@njit
def follow_batch(tb, plan, nnz, Q, S, C, L, Q1, S1, C1, L1, Qo, So, Co, Lo, assembled, row_scale, col_scale, cfg,
                 out):  # fmt: skip
    """:func:`follow` for every variant of a leading batch axis (see :func:`_follow_range`);
    ``out[v]`` = (status, iterations, fraction, sub-steps, residual, flags, optimality residual)."""
    _follow_range(tb, plan, nnz, Q, S, C, L, Q1, S1, C1, L1, Qo, So, Co, Lo, assembled, row_scale, col_scale, cfg,
                  out, np.int64(0), Q1.shape[0])  # fmt: skip


@njit
def follow_sequence(tb, plan, nnz, Q, S, C, L, set_cols, values, row_scale, col_scale, cfg, Qout, Sout, Cout, Lout,
                    out):  # fmt: skip
    """Drive the q columns ``set_cols`` through the rows of ``values``, following each step
    from the last good one (a failed step leaves the state at the last good step: the next
    step restarts from there, on the same branch). ``Qout[s]``, ``Sout[s]``, ``Cout[s]``,
    ``Lout[s]`` hold the state after step ``s`` (NaN when it failed: free design variables
    move too); ``out[s]`` = (status, iterations, fraction, sub-steps, residual, flags,
    optimality residual)."""
    buf = buffers(tb, plan, nnz)
    fbuf = follow_buffers(tb, Q, S, C, L)
    hist = np.zeros(0)
    Qg, Sg, Cg, Lg = Q.copy(), S.copy(), C.copy(), L.copy()
    Q1 = Q.copy()
    sign = np.int64(UNKNOWN_SIGN)  # det sign at the last good step: the next step's reference
    for s in range(values.shape[0]):
        Q1[:] = Q
        for i in range(set_cols.shape[0]):
            Q1[set_cols[i]] = values[s, i]
        r = follow(tb, plan, Q, S, C, L, Q1, S, C, L, -1 if s == 0 else 1, row_scale, col_scale, cfg, buf, fbuf,
                   hist, sign)  # fmt: skip
        _store(out, s, r)
        if r[0] == CONVERGED:
            sign = r[8]
            copy_state(Q, S, C, L, Qout[s], Sout[s], Cout[s], Lout[s])
            copy_state(Q, S, C, L, Qg, Sg, Cg, Lg)
        else:
            Qout[s], Sout[s], Cout[s], Lout[s] = np.nan, np.nan, np.nan, np.nan
            copy_state(Qg, Sg, Cg, Lg, Q, S, C, L)


__all__ = [
    "RANK_RTOL",
    "STATUSES",
    "Settings",
    "Status",
    "follow",
    "follow_batch",
    "follow_one",
    "follow_sequence",
    "min_norm_step",
    "solve",
]
