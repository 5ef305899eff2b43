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

import numpy as np

from kinprop.jit import njit, prange
from kinprop.kinematics.kernels import evaluate, retract, workspace

#: relative singular-value threshold for the rank (``s_k > RANK_RTOL * s_max``)
RANK_RTOL = 1e-9


class Status(StrEnum):
    """Outcome of a solve; the compiled loop returns the index of one of these."""

    CONVERGED = "converged"
    NOT_CONVERGED = "not_converged"
    DIVERGED = "diverged"
    NO_FREE = "no_free"
    #: a change that cannot be followed (continuation found no assembly along the way)
    INFEASIBLE = "infeasible"


STATUSES = tuple(Status)
CONVERGED, NOT_CONVERGED, DIVERGED, NO_FREE = 0, 1, 2, 3


@njit
def _lu_solve(M, b, x):
    """``M x = b`` by Gaussian elimination with partial pivoting (destroys M, b); False if singular."""
    n = M.shape[0]
    scale = 0.0
    for i in range(n):
        for j in range(n):
            scale = max(scale, abs(M[i, j]))
    if scale == 0.0:
        return False
    for col in range(n):
        piv, big = col, abs(M[col, col])
        for i in range(col + 1, n):
            if abs(M[i, col]) > big:
                big, piv = abs(M[i, col]), i
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


@njit
def min_norm_step(J, rhs, out):
    """``out = -pinv(J) rhs``: pivoted LU when square and well conditioned, else the SVD
    pseudo-inverse (singular values below ``eps max(m, n) s_max`` dropped, as ``lstsq``)."""
    m, n = J.shape
    if n == 0:
        return
    if m == n:
        M, b = J.copy(), rhs.copy()
        if _lu_solve(M, b, out):
            ok = True
            for i in range(n):
                out[i] = -out[i]
                ok = ok and np.isfinite(out[i])
            if ok:
                return
    if m == 0:
        out[:] = 0.0
        return
    U, s, Vt = np.linalg.svd(J, full_matrices=False)
    cut = 2.220446049250313e-16 * max(m, n) * (s[0] if s.shape[0] else 0.0)
    out[:] = 0.0
    for k in range(s.shape[0]):
        if s[k] > cut:
            c = 0.0
            for i in range(m):
                c += U[i, k] * rhs[i]
            c /= s[k]
            for i in range(n):
                out[i] -= c * Vt[k, i]


@njit
def buffers(tb, plan, nnz):
    """Work arrays of one solve: Phi, entry values, block storage, step, and the kinematics workspace."""
    return (
        np.zeros(plan.n_rows),
        np.zeros(nnz),
        np.zeros(plan.store_ptr[-1]),
        np.zeros(plan.free.shape[0]),
        workspace(tb),
    )


@njit
def newton_step(plan, Phi, vals, store, dx):
    """The minimum-norm step over the free columns (block by block) into ``dx`` (free order)."""
    store[:] = 0.0
    slot = plan.entry_slot
    for k in range(slot.shape[0]):
        if slot[k] >= 0:
            store[slot[k]] += vals[k]
    for b in range(plan.row_ptr.shape[0] - 1):
        r0, r1 = plan.row_ptr[b], plan.row_ptr[b + 1]
        c0, c1 = plan.col_ptr[b], plan.col_ptr[b + 1]
        mb, nb = r1 - r0, c1 - c0
        if nb == 0:
            continue
        J = store[plan.store_ptr[b] : plan.store_ptr[b + 1]].reshape((mb, nb))
        rhs = np.empty(mb)
        for i in range(mb):
            rhs[i] = Phi[plan.block_rows[r0 + i]]
        for e in range(plan.coupling_ptr[b], plan.coupling_ptr[b + 1]):  # solved blocks -> right side
            rhs[plan.coupling_row[e]] += vals[plan.coupling_entry[e]] * dx[plan.coupling_free[e]]
        for y in range(nb):
            w = plan.sqrt_weights[plan.block_cols[c0 + y]]
            for i in range(mb):
                J[i, y] *= w
        out = np.empty(nb)
        min_norm_step(J, rhs, out)
        for y in range(nb):
            f = plan.block_cols[c0 + y]
            dx[f] = out[y] * plan.sqrt_weights[f]


@njit
def solve(tb, plan, Q, S, C, L, tol, max_iter, divergence, history, buf):
    """Newton from the state ``Q, S, C, L`` (updated in place); returns (status, iterations, ||Phi||).

    ``history[k]`` receives ``||Phi||`` after k updates (length ``max_iter + 1``, may be shorter).
    """
    Phi, vals, store, dx, ws = buf
    free, need = plan.free, plan.need
    dummy = np.zeros(0, np.int64)
    evaluate(tb, Q, S, C, L, ws, Phi, vals, need, dummy, dummy, False)
    norm = np.sqrt(Phi @ Phi)
    if history.shape[0] > 0:
        history[0] = norm
    first = max(norm, 1e-300)
    it = 0
    status = NOT_CONVERGED
    while norm >= tol and it < max_iter:
        if free.shape[0] == 0:
            status = NO_FREE
            break
        newton_step(plan, Phi, vals, store, dx)
        retract(tb, free, dx, Q, S, C, L)
        it += 1
        evaluate(tb, Q, S, C, L, ws, Phi, vals, need, dummy, dummy, False)
        norm = np.sqrt(Phi @ Phi)
        if it < history.shape[0]:
            history[it] = norm
        if not np.isfinite(norm) or norm > divergence * first:
            status = DIVERGED
            break
    if norm < tol:
        status = CONVERGED
    return status, it, norm


@njit
def solve_one(tb, plan, nnz, Q, S, C, L, tol, max_iter, divergence, history):
    """:func:`solve` with its own buffers."""
    return solve(tb, plan, Q, S, C, L, tol, max_iter, divergence, history, buffers(tb, plan, nnz))


@njit
def solve_batch(tb, plan, nnz, Q, S, C, L, tol, max_iter, divergence, status, iterations, residual):
    """:func:`solve` on every variant of a leading batch axis (each converges on its own)."""
    buf = buffers(tb, plan, nnz)
    hist = np.zeros(0)
    for v in range(Q.shape[0]):
        st, it, nr = solve(tb, plan, Q[v], S[v], C[v], L[v], tol, max_iter, divergence, hist, buf)
        status[v], iterations[v], residual[v] = st, it, nr


@njit(parallel=True)
def solve_batch_threaded(tb, plan, nnz, Q, S, C, L, tol, max_iter, divergence, status, iterations, residual, nth):
    """:func:`solve_batch` split into ``nth`` contiguous chunks, one per thread."""
    N = Q.shape[0]
    for c in prange(nth):
        buf = buffers(tb, plan, nnz)
        hist = np.zeros(0)
        for v in range(c * N // nth, (c + 1) * N // nth):
            st, it, nr = solve(tb, plan, Q[v], S[v], C[v], L[v], tol, max_iter, divergence, hist, buf)
            status[v], iterations[v], residual[v] = st, it, nr


@njit
def solve_sequence(tb, plan, nnz, Q, S, C, L, tol, max_iter, divergence, set_cols, values, Qout, status,
                   iterations, residual):  # fmt: skip
    """For each row of ``values``, set the q columns ``set_cols`` and solve from the previous step."""
    buf = buffers(tb, plan, nnz)
    hist = np.zeros(0)
    for s in range(values.shape[0]):
        for i in range(set_cols.shape[0]):
            Q[set_cols[i]] = values[s, i]
        st, it, nr = solve(tb, plan, Q, S, C, L, tol, max_iter, divergence, hist, buf)
        Qout[s] = Q
        status[s], iterations[s], residual[s] = st, it, nr


__all__ = ["RANK_RTOL", "STATUSES", "Status", "min_norm_step", "solve", "solve_batch", "solve_one"]
