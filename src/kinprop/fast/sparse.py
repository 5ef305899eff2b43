"""Sparse Newton for one large mechanism (e.g. stacked Stewart modules).

The Jacobian's structure is fixed by the topology, so it is computed once: the compiled
kernel emits the entries in a fixed order, which map to the slots of a CSC matrix over the
free columns (``np.bincount`` sums the duplicates). Two linear solvers:

* ``"blocks"`` (default when the free Jacobian splits into independent blocks, as a stack of
  Stewart modules with relative platform coordinates does): the connected components of the
  row/column graph are found once and each block gets a dense pivoted-LU / SVD solve inside
  one numba kernel. The minimum-norm step of a block-diagonal matrix is the blockwise one,
  so this is the same step as the reference.
* ``"splu"``: ``scipy.sparse.linalg.splu`` with the COLAMD column ordering computed once at
  the first factorisation and reused (``permc_spec="NATURAL"`` on the pre-permuted matrix);
  non-square systems take the minimum-norm step ``J^T (J J^T)^-1 Phi``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.sparse as sp
from numba import njit
from scipy.sparse.csgraph import connected_components
from scipy.sparse.linalg import splu

from kinprop.fast import kernels as kn
from kinprop.fast.compiled import Compiled, State
from kinprop.fast.solve import BoundSolver
from kinprop.spatial import Array


@njit(cache=True, error_model="numpy")
def _newton_blocks(tb, colinfo, m, n, free, Q, S, C, L, tol, max_iter, divergence,
                   nnz, emask, eblock, epos, bm, bn, boff, brow, bcol, rptr, cptr):  # fmt: skip
    """Newton with a block-diagonal free Jacobian: per block a dense min-norm step."""
    nb_ = bm.shape[0]
    Phi = np.zeros(m)
    vals = np.zeros(nnz)
    blocks = np.zeros(boff[nb_])
    dx = np.zeros(n)
    ws = kn._workspace(tb[7].shape[0], tb[1].shape[0])
    big = 0
    for b in range(nb_):
        big = max(big, max(bm[b], bn[b]))
    need = np.zeros(colinfo.shape[0], np.int8)
    for c in free:
        need[c - colinfo[c, 3]] = 1
    Mw = np.zeros((big, big))
    rhs = np.zeros(big)
    out = np.zeros(big)
    kn.evaluate_ws(tb, Q, S, C, L, Phi, vals, True, ws, need)
    norm = np.sqrt(Phi @ Phi)
    first = max(norm, 1e-300)
    it = 0
    status = kn.NOT_CONVERGED
    while norm >= tol and it < max_iter:
        if free.shape[0] == 0:
            status = kn.NO_FREE
            break
        blocks[:] = 0.0
        for k in range(nnz):
            if emask[k]:
                blocks[epos[k]] += vals[k]
        dx[:] = 0.0
        for b in range(nb_):
            mb, nbb = bm[b], bn[b]
            Jb = blocks[boff[b] : boff[b] + mb * nbb].reshape((mb, nbb))
            Pb = np.empty(mb)
            for i in range(mb):
                Pb[i] = Phi[brow[rptr[b] + i]]
            kn.min_norm_step(Jb, Pb, out[:nbb], Mw[:nbb, :nbb], rhs[:nbb])
            for i in range(nbb):
                dx[free[bcol[cptr[b] + i]]] = out[i]
        kn.retract(colinfo, dx, Q, S, C, L)
        it += 1
        kn.evaluate_ws(tb, Q, S, C, L, Phi, vals, True, ws, need)
        norm = np.sqrt(Phi @ Phi)
        if not np.isfinite(norm) or norm > divergence * first:
            status = kn.DIVERGED
            break
    if norm < tol:
        status = kn.CONVERGED
    return status, it, norm


class SparseSolver(BoundSolver):
    """Newton over the free columns of one large mechanism with a sparse (or block) linear solve."""

    def __init__(
        self,
        comp: Compiled,
        free: Sequence[str] | Array = ("q",),
        exclude: set[str] | frozenset[str] = frozenset(),
        tol: float = 1e-10,
        max_iter: int = 50,
        divergence: float = 1e6,
        method: str = "auto",
    ) -> None:
        super().__init__(comp, free, exclude, tol, max_iter, divergence)
        m, nf = comp.m, self.free.size
        fidx = -np.ones(comp.n, dtype=np.int64)
        fidx[self.free] = np.arange(nf)
        self.emask = fidx[comp.cols] >= 0
        self._need = np.zeros(comp.n, np.int8)
        self._need[self.free - comp.colinfo[self.free, 3]] = 1
        r, c = comp.rows[self.emask], fidx[comp.cols[self.emask]]
        keys, slot = np.unique(r * max(nf, 1) + c, return_inverse=True)
        self._slot, self._nslot = slot, keys.size
        ur, uc = keys // max(nf, 1), keys % max(nf, 1)
        self.pattern = sp.csr_matrix((np.ones(keys.size), (ur, uc)), shape=(m, nf))
        graph = sp.bmat([[None, self.pattern], [self.pattern.T, None]]).tocsr() if m and nf else None
        ncomp, labels = connected_components(graph, directed=False) if graph is not None else (1, np.zeros(m + nf, int))
        blocks_ok = ncomp > 1 and np.bincount(labels).max() <= 64
        self.method = ("blocks" if blocks_ok else "splu") if method == "auto" else method
        if self.method == "blocks":
            self._setup_blocks(labels[:m], labels[m:], ncomp, r, c)
        else:
            self._setup_splu(ur, uc)

    # --- blocks ------------------------------------------------------------------------------
    def _setup_blocks(self, rlab: Array, clab: Array, ncomp: int, r: Array, c: Array) -> None:
        brow = np.argsort(rlab, kind="stable")
        bcol = np.argsort(clab, kind="stable")
        bm = np.bincount(rlab, minlength=ncomp)
        bn = np.bincount(clab, minlength=ncomp)
        rptr = np.concatenate([[0], np.cumsum(bm)])
        cptr = np.concatenate([[0], np.cumsum(bn)])
        boff = np.concatenate([[0], np.cumsum(bm * bn)])
        rloc = np.empty_like(brow)
        rloc[brow] = np.arange(brow.size) - rptr[rlab[brow]]
        cloc = np.empty_like(bcol)
        cloc[bcol] = np.arange(bcol.size) - cptr[clab[bcol]]
        blk = rlab[r]
        epos = np.zeros(self.comp.rows.size, dtype=np.int64)
        epos[self.emask] = boff[blk] + rloc[r] * bn[blk] + cloc[c]
        self._blocks = (self.emask.astype(np.int64), rlab[self.comp.rows], epos, bm, bn, boff, brow, bcol, rptr, cptr)

    # --- splu ------------------------------------------------------------------------------
    def _setup_splu(self, ur: Array, uc: Array) -> None:
        m, nf = self.comp.m, self.free.size
        self._p = np.arange(nf)
        if m == nf and nf:
            # COLAMD ordering from the structure alone (random values), computed once; the
            # columns are relabelled so every later factorisation uses the NATURAL order
            rnd = np.random.default_rng(0).uniform(1.0, 2.0, ur.size)
            lu = splu(sp.csc_matrix((rnd, (ur, uc)), shape=(m, nf)), permc_spec="COLAMD")
            self._p = np.argsort(lu.perm_c)
        pos = np.empty(nf, dtype=np.int64)
        pos[self._p] = np.arange(nf)
        # CSC slot order of the unique entries: data position k holds unique entry order[k]
        probe = sp.csc_matrix((np.arange(1, ur.size + 1, dtype=float), (ur, pos[uc])), shape=(m, nf))
        probe.sort_indices()
        self._order = probe.data.astype(np.int64) - 1
        self._indices, self._indptr = probe.indices.copy(), probe.indptr.copy()

    def _matrix(self, vals: Array) -> sp.csc_matrix:
        """Free Jacobian with columns in the factorisation order ``self._p``."""
        data = np.bincount(self._slot, weights=vals[self.emask], minlength=self._nslot)[self._order]
        return sp.csc_matrix((data, self._indices, self._indptr), shape=(self.comp.m, self.free.size))

    def _step(self, Jp: sp.csc_matrix, Phi: Array) -> Array:
        m, nf = Jp.shape
        y = splu(Jp, permc_spec="NATURAL").solve(Phi) if m == nf else Jp.T @ splu((Jp @ Jp.T).tocsc()).solve(Phi)
        out = np.empty(nf)
        out[self._p] = y
        return -out

    # --- solve -------------------------------------------------------------------------------
    def solve_one(self, Q: Array, S: Array, C: Array, L: Array) -> tuple[int, int, float]:
        """Solve one variant in place (arrays without the batch axis); ``(status, iterations, residual)``."""
        comp = self.comp
        if self.method == "blocks":
            opts = (self.tol, self.max_iter, self.divergence)
            return _newton_blocks(
                comp.tables, comp.colinfo, comp.m, comp.n, self.free, Q, S, C, L, *opts, comp.rows.size, *self._blocks
            )
        ws = kn._workspace(comp.fixed.shape[0], comp.tint.shape[0])
        Phi = np.zeros(comp.m)
        vals = np.zeros(comp.rows.size)
        dx = np.zeros(comp.n)

        def ev() -> float:
            kn.evaluate_ws(comp.tables, Q, S, C, L, Phi, vals, True, ws, self._need)
            return float(np.linalg.norm(Phi))

        norm = ev()
        first, it, status = max(norm, 1e-300), 0, kn.NOT_CONVERGED
        while norm >= self.tol and it < self.max_iter:
            if self.free.size == 0:
                status = kn.NO_FREE
                break
            dx[:] = 0.0
            dx[self.free] = self._step(self._matrix(vals), Phi)
            kn.retract(comp.colinfo, dx, Q, S, C, L)
            it += 1
            norm = ev()
            if not np.isfinite(norm) or norm > self.divergence * first:
                status = kn.DIVERGED
                break
        if norm < self.tol:
            status = kn.CONVERGED
        return status, it, norm

    def solve(self, state: State, k: int = 0) -> tuple[State, tuple[int, int, float]]:
        """Solve variant ``k`` of ``state`` (copied); returns the solved one-variant state and the outcome."""
        st = state.take(slice(k, k + 1)).copy()
        out = self.solve_one(st.Q[0], st.S[0], st.C[0], st.L[0])
        return st, out

    def jacobian(self, state: State, k: int = 0) -> sp.csc_matrix:
        """The sparse free-column Jacobian at variant ``k`` (columns in ``free`` order)."""
        comp = self.comp
        Phi = np.zeros(comp.m)
        vals = np.zeros(comp.rows.size)
        kn.evaluate_entries(comp.tables, state.Q[k], state.S[k], state.C[k], state.L[k], Phi, vals, True)
        r, c = comp.rows[self.emask], np.searchsorted(self.free, comp.cols[self.emask])
        return sp.csc_matrix((vals[self.emask], (r, c)), shape=(comp.m, self.free.size))
