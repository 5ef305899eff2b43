"""The linear-solve plan of a free set: how the Newton step ``J_f dx = -Phi`` is split.

Chosen by structure, once per free set, from the Jacobian's sparsity pattern:

* the bipartite row/column graph's connected components are independent blocks (a stack of
  modules in relative coordinates); the minimum-norm step of a block-diagonal matrix is the
  blockwise one, so each block is solved on its own;
* a large square component with a perfect structural matching is put in block-triangular form
  (Dulmage-Mendelsohn: strongly connected components of the matched column graph, in
  topological order), solved by block forward substitution — the unique solution, so the
  same step (a chain of modules each hanging from the ground: O(K));
* anything else (redundant rows, more free variables than rows, small systems) is one dense
  block with the minimum-norm (optionally weighted) step. A single small mechanism is one
  dense block: the dense path is simply the one-block plan.
"""

from __future__ import annotations

from graphlib import TopologicalSorter
from typing import NamedTuple

import numpy as np

from kinprop.spatial import Array
from kinprop.topology.graph import connected_components

#: square components up to this size are solved dense (exact min-norm even when singular)
DENSE_MAX = 24
#: a free set that leaves freedom with at most this many free columns plus rows takes the
#: least change by Newton on its KKT system (dense, second order; larger: Gauss-Newton)
KKT_MAX = 96


class Plan(NamedTuple):
    """Arrays the compiled Newton loop reads (``kinprop.solver.newton``)."""

    n_rows: int  # rows of Phi (every row, whether a free variable reaches it or not)
    free: Array  # (nf,) sorted layout columns that may move
    sqrt_weights: Array  # (nf,) sqrt of the weighted min-norm weights (ones: plain pinv)
    need: Array  # (n,) int8: 1 on every column of a variable that has a free column
    need_none: Array  # (n,) int8 zeros: evaluate the residual only
    entry_slot: Array  # (nnz,) slot of an entry in its diagonal block's storage, or -1
    block_rows: Array  # rows of Phi, block by block; block b holds row_ptr[b]:row_ptr[b+1]
    row_ptr: Array
    block_cols: Array  # free indices, block by block
    col_ptr: Array
    store_ptr: Array  # block b's dense matrix (row-major) at store_ptr[b]:store_ptr[b+1]
    coupling_entry: Array  # off-diagonal entries (block-triangular), grouped by the row's block
    coupling_row: Array  # their local row within the block
    coupling_free: Array  # their free index (solved in an earlier block)
    coupling_ptr: Array
    #: every block square: a regular free Jacobian leaves no freedom (the Newton step is unique)
    square: bool
    #: per row of Phi: its scale to SI (``Engine.row_scale``), applied to a pseudo-inverse block's
    #: rows, so that its least-squares fit and rank do not depend on the model's length unit
    row_scale: Array
    #: (k, 4): ``[block, y0, y1, y2]``, the local columns (components 0, 1, 2) of each
    #: orientation whose three columns are free in one block: the least-change step takes them
    #: in the rotation vector from the reference (``kinprop.solver.newton.newton_step``)
    rotations: Array
    #: per Jacobian entry: its row and its free index (-1: not free), for the dense KKT system
    entry_row: Array
    entry_free: Array
    #: the least change by Newton on the dense KKT system (freedom left, at most KKT_MAX
    #: free columns plus rows; ``kinprop.solver.newton.kkt_step``)
    second_order: bool

    @property
    def n_blocks(self) -> int:
        return int(self.row_ptr.size - 1)

    @property
    def kind(self) -> str:
        """``dense``, ``blocks`` (block diagonal) or ``triangular`` (with coupling)."""
        if self.coupling_entry.size:
            return "triangular"
        return "blocks" if self.n_blocks > 1 else "dense"


def _order_square(rows: Array, cols: Array, r_loc: Array, c_loc: Array) -> list[tuple[Array, Array]] | None:
    """Block-triangular diagonal blocks (rows, cols) of a square component, dependencies first;
    None when it has no perfect structural matching. (scipy, imported here: only components
    larger than :data:`DENSE_MAX` come here, none of a one-shot job's small models.)"""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components as strong_components
    from scipy.sparse.csgraph import maximum_bipartite_matching

    n = cols.size
    pat = sp.csr_matrix((np.ones(r_loc.size), (r_loc, c_loc)), shape=(n, n))
    match = maximum_bipartite_matching(pat, perm_type="column")  # row -> column
    if np.any(match < 0):
        return None
    # row r, matched to column match[r], also reads column c: c's block is solved first
    dep = c_loc != match[r_loc]
    src, dst = c_loc[dep], match[r_loc[dep]]
    g = sp.csr_matrix((np.ones(src.size), (src, dst)), shape=(n, n))
    n_blocks, label = strong_components(g, directed=True, connection="strong")
    order = TopologicalSorter({b: () for b in range(n_blocks)})
    for a, b in np.unique(np.stack([label[src], label[dst]], axis=1), axis=0).tolist():
        if a != b:
            order.add(b, a)
    by_block = np.argsort(label, kind="stable")
    start = np.concatenate([[0], np.cumsum(np.bincount(label, minlength=n_blocks))])
    row_of = np.empty(n, dtype=np.int64)
    row_of[match] = np.arange(n)
    out = []
    for b in order.static_order():
        members = by_block[start[b] : start[b + 1]]
        out.append((rows[row_of[members]], cols[members]))
    return out


def build_plan(
    m: int,
    n: int,
    rows: Array,
    cols: Array,
    free: Array,
    column_variable: Array,
    weights: Array | None = None,
    row_scale: Array | None = None,
    rotations: Array | None = None,
) -> Plan:
    """The plan for ``free`` columns (sorted) of an ``m x n`` Jacobian with entries at
    ``rows``/``cols``; ``column_variable`` maps a column to its variable's first column;
    ``weights`` (per free column) of the step's metric, ``row_scale`` (per row) of its fit;
    ``rotations``: the first column of each orientation variable (three columns, the
    components of its rotation vector)."""
    free = np.ascontiguousarray(free, dtype=np.int64)
    nf = free.size
    fidx = -np.ones(n, dtype=np.int64)
    fidx[free] = np.arange(nf)
    need = np.zeros(n, dtype=np.int8)
    if nf:
        need[np.isin(column_variable, column_variable[free])] = 1
    on = fidx[cols] >= 0
    er, ef = rows[on], fidx[cols[on]]
    blocks: list[tuple[Array, Array]] = []
    if m and nf:
        ncomp, labels = connected_components(m + nf, er, m + ef)  # rows, then the free columns
        rlab, clab = labels[:m], labels[m:]
        for comp in range(ncomp):
            rws, cls = np.flatnonzero(rlab == comp), np.flatnonzero(clab == comp)
            if cls.size == 0:
                blocks.append((rws, cls))  # rows no free variable reaches (residual stays)
                continue
            tri = None
            if rws.size == cls.size > DENSE_MAX:
                sel = np.isin(er, rws)
                r_loc = np.searchsorted(rws, er[sel])
                c_loc = np.searchsorted(cls, ef[sel])
                tri = _order_square(rws, cls, r_loc, c_loc)
            blocks.extend(tri if tri is not None else [(rws, cls)])
    block_of_row = -np.ones(m, dtype=np.int64)
    local_row = np.zeros(m, dtype=np.int64)
    block_of_col = -np.ones(max(nf, 1), dtype=np.int64)
    local_col = np.zeros(max(nf, 1), dtype=np.int64)
    sizes = []
    for b, (rws, cls) in enumerate(blocks):
        block_of_row[rws], local_row[rws] = b, np.arange(rws.size)
        block_of_col[cls], local_col[cls] = b, np.arange(cls.size)
        sizes.append(rws.size * cls.size)
    store_ptr = np.concatenate([[0], np.cumsum(sizes, dtype=np.int64)]).astype(np.int64)
    slot = -np.ones(rows.size, dtype=np.int64)
    k_on = np.flatnonzero(on)
    if k_on.size:
        rb, cb = block_of_row[er], block_of_col[ef]
        diag = rb == cb
        ncols_b = np.array([c.size for _, c in blocks], dtype=np.int64)
        slot[k_on[diag]] = store_ptr[rb[diag]] + local_row[er[diag]] * ncols_b[rb[diag]] + local_col[ef[diag]]
        off = np.flatnonzero(~diag)
        order = np.argsort(rb[off], kind="stable")
        off = off[order]
        c_entry, c_row, c_free = k_on[off], local_row[er[off]], ef[off]
        c_ptr = np.searchsorted(rb[off], np.arange(len(blocks) + 1)).astype(np.int64)
    else:
        c_entry = c_row = c_free = np.zeros(0, dtype=np.int64)
        c_ptr = np.zeros(len(blocks) + 1, dtype=np.int64)

    def cat(parts: list[Array]) -> Array:
        return np.concatenate(parts).astype(np.int64) if parts else np.zeros(0, dtype=np.int64)

    def ptr(parts: list[Array]) -> Array:
        return np.concatenate([[0], np.cumsum([p.size for p in parts])]).astype(np.int64)

    rot = []
    for c0 in () if rotations is None else rotations:
        f = fidx[c0 : c0 + 3]
        if f.size == 3 and np.all(f >= 0) and np.all(block_of_col[f] == block_of_col[f[0]]):
            rot.append([block_of_col[f[0]], *local_col[f]])
    sw = np.ones(nf) if weights is None else np.sqrt(np.asarray(weights, dtype=float))
    rows_b, cols_b = [r for r, _ in blocks], [c for _, c in blocks]
    square = bool(all(r.size == c.size for r, c in blocks if c.size))
    return Plan(m, free, sw, need, np.zeros(n, dtype=np.int8), slot, cat(rows_b), ptr(rows_b), cat(cols_b), ptr(cols_b),
                store_ptr,
                c_entry.astype(np.int64), c_row.astype(np.int64), c_free.astype(np.int64), c_ptr,
                square, np.ones(m) if row_scale is None else np.ascontiguousarray(row_scale, dtype=float),
                np.array(rot, dtype=np.int64).reshape(-1, 4), np.ascontiguousarray(rows, dtype=np.int64),
                fidx[cols].astype(np.int64), bool(nf and not square and nf + m <= KKT_MAX))  # fmt: skip
