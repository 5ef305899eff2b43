"""Singularity measure: unit-independent conditioning of the free-variable Jacobian.

The plain singular values of ``Phi_x[:, free]`` depend on units: a distance row
``d.d - l^2`` of a model in millimetres is ~1e5 times larger than an Euler normalisation row,
so ``s_min / s_max`` would flag every configuration of such a model. The measure used here
scales first:

* rows by constraint: the rows of one basic constraint type of one joint (a spherical
  constraint's three rows, a revolute's two dot-1 rows) share a unit, so each such group is
  divided by its Frobenius norm — the group's internal geometry is kept; a group whose norm
  is below ``1e-9`` of the largest (rows that vanish identically, e.g. the out-of-plane rows
  of a planar loop closed by a spatial joint) is dropped;
* columns by their norms (angles, lengths and Euler parameters alike).

Diagonal scaling keeps the rank, so the measure still goes to zero at a singular (toggle)
configuration: ``ratio = s_r / s_1`` of the scaled matrix, ``s_r`` the smallest singular
value above the rank tolerance (exact zeros of redundant rows are structural, not a toggle).
Near a four-bar toggle it vanishes like the square root of the distance to it.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from kinprop.kinematics.tables import RowBlock
from kinprop.solver.newton import RANK_RTOL
from kinprop.spatial import Array

#: warn at a solved configuration when the scaled ``s_r / s_1`` is below this (condition > 100)
SINGULAR_RTOL = 1e-2
#: relative norm below which a row group or column counts as identically zero
ZERO_RTOL = 1e-9


#: row groups by the identity of an engine's row blocks (kept with them: the id stays theirs)
_GROUPS: dict[int, tuple[Sequence[RowBlock], np.ndarray]] = {}


def row_groups(blocks: Sequence[RowBlock]) -> np.ndarray:
    """Group index per row of Phi: one group per (joint, basic-constraint type); computed once
    per row-block sequence (an engine's ``row_blocks`` never change)."""
    hit = _GROUPS.get(id(blocks))
    if hit is not None and hit[0] is blocks:
        return hit[1]
    labels = [(b.joint, lab.split("[")[0]) for b in blocks for lab in b.labels]
    index = {k: i for i, k in enumerate(dict.fromkeys(labels))}
    groups = np.array([index[k] for k in labels], dtype=int)
    groups.setflags(write=False)
    if isinstance(blocks, tuple):
        _GROUPS[id(blocks)] = (blocks, groups)
    return groups


def scaled_jacobian(blocks: Sequence[RowBlock], J: Array) -> Array:
    """``J`` (rows of Phi, any columns) with rows scaled per constraint and columns by norm."""
    g = row_groups(blocks)
    if J.size == 0:
        return J
    norms = np.sqrt(np.bincount(g, weights=np.sum(J * J, axis=1), minlength=g.max() + 1 if g.size else 0))
    keep = norms > ZERO_RTOL * norms.max() if norms.size and norms.max() > 0 else np.zeros(norms.shape, bool)
    scale = np.where(keep, 1.0 / np.where(keep, norms, 1.0), 0.0)[g]
    Js = J * scale[:, None]
    c = np.linalg.norm(Js, axis=0)
    keepc = c > ZERO_RTOL * c.max() if c.size and c.max() > 0 else np.zeros(c.shape, bool)
    return np.where(keepc, Js / np.where(keepc, c, 1.0), 0.0)


def conditioning(blocks: Sequence[RowBlock], J: Array) -> float:
    """Unit-independent ``s_r / s_1`` of the free-variable Jacobian ``J``; NaN when it has no
    rows, no columns or rank 0 (nothing to be near-singular)."""
    Js = scaled_jacobian(blocks, J)
    if Js.size == 0:
        return float("nan")
    sv = np.linalg.svd(Js, compute_uv=False)
    if sv[0] <= 0:
        return float("nan")
    rank = int(np.sum(sv > RANK_RTOL * sv[0]))
    return float(sv[rank - 1] / sv[0])


__all__ = ["SINGULAR_RTOL", "conditioning", "row_groups", "scaled_jacobian"]
