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

from kinprop.jit import njit, prange
from kinprop.kinematics.kernels import evaluate, retract, workspace
from kinprop.kinematics.tables import V_COMPONENT, V_JOINT, V_KIND, V_SIDE, VAR_C, VAR_Q, VAR_S
from kinprop.spatial import exp_so3_into, mm_into, mmT_into

#: relative singular-value threshold for the rank (``s_k > RANK_RTOL * s_max``)
RANK_RTOL = 1e-9


class Status(StrEnum):
    """Outcome of a solve; the compiled loop returns the index of one of these."""

    CONVERGED = "converged"
    NOT_CONVERGED = "not_converged"
    DIVERGED = "diverged"
    NO_FREE = "no_free"
    #: a change that cannot be followed on the start's branch (the reached fraction is reported)
    INFEASIBLE = "infeasible"
    #: a documented cap (sub-steps of one change) was reached before the change was followed
    STEP_LIMIT = "step_limit"


STATUSES = tuple(Status)
CONVERGED, NOT_CONVERGED, DIVERGED, NO_FREE, INFEASIBLE, STEP_LIMIT = 0, 1, 2, 3, 4, 5
#: ``follow`` flags: the change was subdivided / a sub-step left the predicted branch / the
#: sign of det(Phi_free) flipped on a trial step (a singularity between two configurations) /
#: the start was not assembled (estimates: assembled at its own design before the change)
SUBDIVIDED, JUMPED, SIGN_FLIP, FROM_ESTIMATES = 1, 2, 4, 8
#: a converged residual below this (scaled, ~ metres) is at round-off already: no polishing step
POLISHED = 1e-14


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


@njit
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


@njit
def min_norm_step(J, rhs, out):
    """``out = -pinv(J) rhs``: pivoted LU when square and well conditioned, else the SVD
    pseudo-inverse (singular values below ``eps max(m, n) s_max`` dropped, as ``lstsq``).
    Returns the sign of det J when square and regular, else 0."""
    m, n = J.shape
    if n == 0:
        return 1
    if m == n:
        M, b = J.copy(), rhs.copy()
        sign = _lu_solve(M, b, out)
        if sign != 0:
            ok = True
            for i in range(n):
                out[i] = -out[i]
                ok = ok and np.isfinite(out[i])
            if ok:
                return sign
    out[:] = 0.0
    if m == 0:
        return 0
    U, s, Vt = np.linalg.svd(J, full_matrices=False)
    cut = 2.220446049250313e-16 * max(m, n) * (s[0] if s.shape[0] else 0.0)
    for k in range(s.shape[0]):
        if s[k] > cut:
            c = 0.0
            for i in range(m):
                c += U[i, k] * rhs[i]
            c /= s[k]
            for i in range(n):
                out[i] -= c * Vt[k, i]
    return 0


#: slots of :func:`buffers`
B_PHI, B_VALS, B_STORE, B_DX, B_DISP, B_WS, B_DX1 = range(7)


@njit
def buffers(tb, plan, nnz):
    """Work arrays of one solve (slots ``B_*``): Phi, entry values, block storage, step,
    displacement, the kinematics workspace, and the first step."""
    nf = plan.free.shape[0]
    return np.zeros(plan.n_rows), np.zeros(nnz), np.zeros(plan.store_ptr[-1]), np.zeros(nf), np.zeros(nf), \
        workspace(tb), np.zeros(nf)  # fmt: skip


@njit
def newton_step(plan, Phi, vals, store, dx):
    """The minimum-norm step over the free columns (block by block) into ``dx`` (free order);
    returns the sign of det of the free Jacobian (product over square blocks; 0: unknown)."""
    store[:] = 0.0
    slot = plan.entry_slot
    for k in range(slot.shape[0]):
        if slot[k] >= 0:
            store[slot[k]] += vals[k]
    sign = 1
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
        sign *= min_norm_step(J, rhs, out)
        for y in range(nb):
            f = plan.block_cols[c0 + y]
            dx[f] = out[y] * plan.sqrt_weights[f]
    return sign


@njit
def _residual(tb, plan, Q, S, C, L, row_scale, buf):
    """Evaluate Phi (kept in ``buf``) and the Jacobian entries the plan needs; return the
    scaled norm of Phi."""
    Phi, vals, ws = buf[B_PHI], buf[B_VALS], buf[B_WS]
    dummy = np.zeros(0, np.int64)
    evaluate(tb, Q, S, C, L, ws, Phi, vals, plan.need, dummy, dummy, False)
    s = 0.0
    for i in range(Phi.shape[0]):
        r = Phi[i] * row_scale[i]
        s += r * r
    return np.sqrt(s)


@njit
def solve(tb, plan, Q, S, C, L, row_scale, col_scale, cfg, tol, history, buf):
    """Newton on ``Phi(x) = 0`` from ``Q, S, C, L`` (updated in place), to ``tol``.

    Returns ``(status, iterations, ||row_scale Phi||, |dx_1|, |x - x_1|, sign_0,
    sign_1)``: the first step (the implicit-function predictor) and how far the later
    corrections took the solution from it (column-scaled), and the sign of det of the free
    Jacobian at the first and last step taken (0: not square or singular).
    ``history[k]`` receives the residual after k updates (may be shorter than ``max_iter + 1``).
    """
    Phi, vals, store, dx, disp, dx1 = buf[B_PHI], buf[B_VALS], buf[B_STORE], buf[B_DX], buf[B_DISP], buf[B_DX1]
    free = plan.free
    nf = free.shape[0]
    norm = _residual(tb, plan, Q, S, C, L, row_scale, buf)
    if history.shape[0] > 0:
        history[0] = norm
    first = max(norm, 1e-300)
    it, status = 0, NOT_CONVERGED
    step1, sign0, sign1 = 0.0, 0, 0
    disp[:] = 0.0
    while norm >= tol and it < cfg.max_iter:
        if nf == 0:
            status = NO_FREE
            break
        sign1 = newton_step(plan, Phi, vals, store, dx)
        if it == 0:
            sign0 = sign1
            for i in range(nf):
                dx1[i] = dx[i]
                step1 += (dx[i] * col_scale[free[i]]) ** 2
        for i in range(nf):
            disp[i] += dx[i]
        retract(tb, free, dx, Q, S, C, L)
        it += 1
        norm = _residual(tb, plan, Q, S, C, L, row_scale, buf)
        if it < history.shape[0]:
            history[it] = norm
        if not np.isfinite(norm) or norm > cfg.divergence * first:
            status = DIVERGED
            break
    if norm < tol:
        status = CONVERGED
        if cfg.polish and nf > 0 and norm > POLISHED:  # one more step to round-off, kept if better
            newton_step(plan, Phi, vals, store, dx)
            retract(tb, free, dx, Q, S, C, L)
            polished = _residual(tb, plan, Q, S, C, L, row_scale, buf)
            if polished < norm:
                norm = polished
                for i in range(nf):
                    disp[i] += dx[i]
            else:
                for i in range(nf):
                    dx[i] = -dx[i]
                retract(tb, free, dx, Q, S, C, L)
    corr = 0.0
    if it > 0:  # how far the corrections took the solution from the predictor x_0 + dx_1
        for i in range(nf):
            corr += ((disp[i] - dx1[i]) * col_scale[free[i]]) ** 2
    return status, it, norm, np.sqrt(step1), np.sqrt(corr), sign0, sign1


@njit
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
        a = np.empty(3)
        a[k] = np.sqrt(max(0.0, 0.5 * (R[k, k] + 1.0)))
        for i in range(3):
            if i != k:
                a[i] = 0.5 * (R[i, k] + R[k, i]) / (2.0 * a[k])
        n = np.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])
        for i in range(3):
            w[i] = th * a[i] / n
    else:
        f = th / (2.0 * np.sin(th))
        w[0], w[1], w[2] = f * v0, f * v1, f * v2


@njit
def follow_buffers(Q, S, C, L):
    """State-shaped work arrays of :func:`follow` (start, last accepted, rotation paths)."""
    nj = S.shape[0]
    return (Q.copy(), S.copy(), C.copy(), L.copy(), Q.copy(), S.copy(), C.copy(), L.copy(), np.zeros((nj, 2, 3)),
            np.zeros((nj, 2), np.bool_), np.zeros(Q.shape[0], np.bool_), np.zeros((nj, 2, 3), np.bool_),
            np.zeros((nj, 2), np.bool_), np.zeros(L.shape[0], np.bool_))  # fmt: skip


@njit
def _sign_at(tb, plan, Q, S, C, L, buf):
    """Sign of det of the free Jacobian at a state (0: not square or singular); no step taken."""
    Phi, vals, store, dx, ws = buf[B_PHI], buf[B_VALS], buf[B_STORE], buf[B_DX], buf[B_WS]
    if plan.free.shape[0] == 0:
        return 0
    dummy = np.zeros(0, np.int64)
    evaluate(tb, Q, S, C, L, ws, Phi, vals, plan.need, dummy, dummy, False)
    return newton_step(plan, Phi, vals, store, dx)


@njit
def follow(tb, plan, Q, S, C, L, Q1, S1, C1, L1, assembled, row_scale, col_scale, cfg, buf, fbuf, history):
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
    history written)`` (the history holds the assembly's residuals, then the last sub-step's).
    """
    nj = S.shape[0]
    Q0, S0, C0, L0, Qs, Ss, Cs, Ls = fbuf[0], fbuf[1], fbuf[2], fbuf[3], fbuf[4], fbuf[5], fbuf[6], fbuf[7]
    W, turn = fbuf[8], fbuf[9]
    Q0[:], S0[:], C0[:], L0[:] = Q, S, C, L
    ws = buf[B_WS]
    if cfg.branch and assembled < 0:  # is the start assembled? (no Jacobian entries needed)
        Phi, vals = buf[B_PHI], buf[B_VALS]
        dummy = np.zeros(0, np.int64)
        evaluate(tb, Q, S, C, L, ws, Phi, vals, plan.need_none, dummy, dummy, False)
        r2 = 0.0
        for i in range(Phi.shape[0]):
            r2 += (Phi[i] * row_scale[i]) ** 2
        assembled = 1 if np.sqrt(r2) < cfg.tol else 0
    single = not cfg.branch
    flags, its0 = 0, 0
    if cfg.branch and assembled == 0:
        # not assembled (estimates): assemble at the start's own design first (the assembly the
        # estimates point at; flagged when det changed sign on the way), then follow the change
        st, it, nr, p1, corr, s0, s1 = solve(tb, plan, Q, S, C, L, row_scale, col_scale, cfg, cfg.tol, history, buf)
        flags |= FROM_ESTIMATES
        if s0 != 0 and s1 != 0 and s0 != s1:
            flags |= SIGN_FLIP
        if st != CONVERGED and st != NO_FREE:
            return st, it, 0.0, 1, nr, flags, it + 1
        its0 = it
        Q0[:], S0[:], C0[:], L0[:] = Q, S, C, L
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
    sign_ref = _sign_at(tb, plan, Q, S, C, L, buf)
    T = ws[6][0]
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
    w, E = ws[7][5], ws[6][1]
    t, h = 0.0, 1.0
    subs, its, last, hlen = 0, its0, CONVERGED, its0 + 1
    status, norm = CONVERGED, 0.0
    while t < 1.0:
        if subs >= cfg.max_substeps:
            status = STEP_LIMIT
            break
        tn = 1.0 if t + h >= 1.0 - 1e-12 else t + h
        Qs[:], Ss[:], Cs[:], Ls[:] = Q, S, C, L
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
        st, it, nr, p1, corr, s0, s1 = solve(tb, plan, Q, S, C, L, row_scale, col_scale, cfg, cfg.tol, hist, buf)
        last = st
        its += it
        hlen = min(its0, history.shape[0]) + it + 1
        subs += 1
        norm = nr
        if st == NO_FREE:
            status = NO_FREE
            break
        jump = corr > cfg.kappa * p1 + cfg.jump_atol or p1 > cfg.trust
        # the sign at the last step taken (next to the solution) against the accepted state's
        flip = sign_ref != 0 and s1 != 0 and sign_ref != s1
        if single:  # plain Newton: one solve, its outcome
            status = st
            t = 1.0 if st == CONVERGED else 0.0
            break
        if st == CONVERGED and not jump and not flip:
            t = tn
            if s1 != 0:
                sign_ref = s1
            if it <= 3:
                h = min(2.0 * h, 1.0)
            continue
        if jump and st == CONVERGED:
            flags |= JUMPED
        if flip:
            flags |= SIGN_FLIP
        flags |= SUBDIVIDED
        Q[:], S[:], C[:], L[:] = Qs, Ss, Cs, Ls
        h *= 0.5
        if h < cfg.min_step:
            status = INFEASIBLE
            break
    if status != CONVERGED and t == 0.0 and not flags & (JUMPED | SIGN_FLIP) and last != CONVERGED:
        status = last  # nothing of the change could be solved at all: say why (not a branch matter)
    return status, its, t, subs, norm, flags, hlen


@njit
def _store(out, k, r):
    out[k, 0], out[k, 1], out[k, 2], out[k, 3], out[k, 4], out[k, 5] = r[0], r[1], r[2], r[3], r[4], r[5]


@njit
def follow_one(tb, plan, nnz, Q, S, C, L, Q1, S1, C1, L1, assembled, row_scale, col_scale, cfg, history):
    """:func:`follow` with its own buffers."""
    buf = buffers(tb, plan, nnz)
    return follow(tb, plan, Q, S, C, L, Q1, S1, C1, L1, assembled, row_scale, col_scale, cfg, buf,
                  follow_buffers(Q, S, C, L), history)  # fmt: skip


@njit
def follow_batch(tb, plan, nnz, Q, S, C, L, Q1, S1, C1, L1, assembled, row_scale, col_scale, cfg, out):
    """:func:`follow` for every variant of a leading batch axis; ``out[v]`` = (status,
    iterations, fraction, sub-steps, residual, flags)."""
    buf = buffers(tb, plan, nnz)
    fbuf = follow_buffers(Q[0], S[0], C[0], L[0])
    hist = np.zeros(0)
    for v in range(Q.shape[0]):
        r = follow(tb, plan, Q[v], S[v], C[v], L[v], Q1[v], S1[v], C1[v], L1[v], assembled, row_scale, col_scale,
                   cfg, buf, fbuf, hist)  # fmt: skip
        _store(out, v, r)


@njit(parallel=True)
def follow_batch_threaded(tb, plan, nnz, Q, S, C, L, Q1, S1, C1, L1, assembled, row_scale, col_scale, cfg, out, nth):
    """:func:`follow_batch` split into ``nth`` contiguous chunks, one per thread."""
    N = Q.shape[0]
    for c in prange(nth):
        buf = buffers(tb, plan, nnz)
        fbuf = follow_buffers(Q[0], S[0], C[0], L[0])
        hist = np.zeros(0)
        for v in range(c * N // nth, (c + 1) * N // nth):
            r = follow(tb, plan, Q[v], S[v], C[v], L[v], Q1[v], S1[v], C1[v], L1[v], assembled, row_scale,
                       col_scale, cfg, buf, fbuf, hist)  # fmt: skip
            _store(out, v, r)


@njit
def follow_sequence(tb, plan, nnz, Q, S, C, L, set_cols, values, row_scale, col_scale, cfg, Qout, out):
    """Drive the q columns ``set_cols`` through the rows of ``values``, following each step
    from the last good one (a failed step leaves the state at the last good step: the next
    step restarts from there, on the same branch). ``Qout[s]`` holds the coordinates after
    step ``s`` (NaN when it failed); ``out[s]`` = (status, iterations, fraction, sub-steps,
    residual, flags)."""
    buf = buffers(tb, plan, nnz)
    fbuf = follow_buffers(Q, S, C, L)
    hist = np.zeros(0)
    Qg, Sg, Cg, Lg = Q.copy(), S.copy(), C.copy(), L.copy()
    Q1 = Q.copy()
    for s in range(values.shape[0]):
        Q1[:] = Q
        for i in range(set_cols.shape[0]):
            Q1[set_cols[i]] = values[s, i]
        r = follow(tb, plan, Q, S, C, L, Q1, S, C, L, -1 if s == 0 else 1, row_scale, col_scale, cfg, buf, fbuf,
                   hist)  # fmt: skip
        _store(out, s, r)
        if r[0] == CONVERGED:
            Qout[s] = Q
            Qg[:], Sg[:], Cg[:], Lg[:] = Q, S, C, L
        else:
            Qout[s] = np.nan
            Q[:], S[:], C[:], L[:] = Qg, Sg, Cg, Lg


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
