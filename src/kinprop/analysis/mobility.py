"""Mobility and redundancy: Gruebler-Kutzbach count and the true mobility from the SVD rank.

The true (instantaneous) mobility is ``n - rank(Phi_x[:, free])`` at the model's current
configuration, where ``n`` counts the free columns: by default every relative coordinate
(group ``q``; Euler parameters as four, balanced by their normalisation rows, eq. 41), and
with ``free=("q", "l")`` the lengths too (e.g. a Stewart platform's legs).

Rank tolerance: a singular value counts when ``s_k > rtol * s_max`` (default
``RANK_RTOL = 1e-9``). At a configuration assembled to ``||Phi|| < 1e-10`` the singular
values of redundant rows are at rounding level (~1e-16 s_max in the examples) while the
independent ones are O(link length), so the gap is wide; at a configuration solved only to a
loose tolerance (the paper's 1e-3) or not assembled at all the dependent rows are not exactly
dependent, so evaluate mobility at an assembled state (``residual`` is reported).

Redundant rows are those left out of a rank-revealing (column-pivoted) QR of ``Phi_q^T``:
removing them leaves the rank unchanged. They are one removable set; any row with a
component in the left null space (``dependent``) could take the place of one of them.

The Gruebler-Kutzbach count is ``6 n_moving - sum_joints (6 - f_joint) - n_couplings`` (a
coupling between two joint coordinates is one constraint row); it ignores the
geometry, so it is -2 for a planar four-bar built from spatial revolutes and for the Bennett
linkage, whose true mobility is 1.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from kinprop.engine import Engine
from kinprop.engine import compile as compile_engine
from kinprop.model import Model
from kinprop.solver.newton import RANK_RTOL

#: a row is "dependent" when its component in the left null space exceeds this (unit vectors)
DEPENDENT_TOL = 1e-6


@dataclass(frozen=True)
class MobilityReport:
    """True mobility, Gruebler count and the redundant constraint rows, named by joint."""

    mobility: int
    gruebler: int
    n_coordinates: int
    n_constraints: int
    rank: int
    redundant: list[str]
    singular_values: list[float] = field(repr=False)
    rtol: float = RANK_RTOL
    #: ``||Phi||`` at the evaluated configuration (should be ~0: assembled)
    residual: float = 0.0
    #: rows with a component in the left null space (any of them can be the redundant one)
    dependent: list[str] = field(default_factory=list)
    free: tuple[str, ...] = ("q",)

    @property
    def redundant_joints(self) -> list[str]:
        """Cut joints (and couplings) owning redundant rows, in row order."""
        return list(dict.fromkeys(r.split(":", 1)[0] for r in self.redundant))

    @property
    def overconstrained(self) -> bool:
        """True when the true mobility exceeds the Gruebler count (redundant constraints)."""
        return self.mobility > self.gruebler


def row_names(asm: Engine) -> list[str]:
    """``JOINT:constraint`` per row of Phi, unique (``Engine.row_labels``): ``B:dot1[3]``."""
    return asm.row_labels


def joint_freedom(jtype, is_tree: bool) -> int:
    """Relative degrees of freedom a joint allows (6 minus its constraint count)."""
    if jtype.tree:
        return jtype.n_coordinates - (1 if jtype.euler is not None else 0)
    return 6 - jtype.n_constraints + jtype.n_cut_coordinates


def gruebler(model: Model, engine: Engine | None = None) -> int:
    """Spatial Gruebler-Kutzbach count ``6 (n_moving) - sum (6 - f_joint) - n_couplings``."""
    mech = model.mechanism
    asm = engine if engine is not None else compile_engine(mech)
    tree = set(asm.topology.tree_joints)
    moving = sum(1 for b in mech.bodies if not b.fixed)
    joints = sum(6 - joint_freedom(j.jtype, j.name in tree) for j in mech.joints)
    return 6 * moving - joints - len(mech.couplings)


def numerical_rank(sv: np.ndarray, rtol: float = RANK_RTOL) -> int:
    """Number of singular values above ``rtol * s_max``."""
    return int(np.sum(sv > rtol * sv[0])) if sv.size and sv[0] > 0 else 0


def mobility(model: Model, rtol: float = RANK_RTOL, free: Sequence[str] = ("q", "inputs")) -> MobilityReport:
    """True mobility at the model's configuration, Gruebler count and redundant rows.

    ``free`` selects the Jacobian columns that may move (groups or addresses, as in
    :func:`kinprop.propagation.propagate`); the default is every joint coordinate.
    """
    asm = compile_engine(model)
    Phi, J = asm.evaluate(model.design, model.coordinates)
    cols = asm.layout.columns(list(free))
    Jq = J[:, cols]
    m, n = Jq.shape
    if Jq.size:
        # U must span R^m (the left null space names dependent rows); V^T is never used, so
        # skip its n x n square when there are more columns than rows (a long chain)
        U, sv, _ = np.linalg.svd(Jq, full_matrices=m > n)
    else:
        U, sv = np.eye(m), np.zeros(0)
    rank = numerical_rank(sv, rtol)
    redundant: list[str] = []
    dependent: list[str] = []
    if m and rank < m:
        labels = row_names(asm)
        if n:
            import scipy.linalg  # here: only a model with redundant rows needs the pivoted QR

            _, _, piv = scipy.linalg.qr(Jq.T, mode="economic", pivoting=True)
            redundant = [labels[i] for i in sorted(piv[rank:])]
        else:
            redundant = list(labels)
        null = U[:, rank:]
        weight = np.sqrt(np.sum(null**2, axis=1))
        dependent = [labels[i] for i in range(m) if weight[i] > DEPENDENT_TOL]
    return MobilityReport(
        n - rank,
        gruebler(model, asm),
        n,
        m,
        rank,
        redundant,
        sv.tolist(),
        rtol,
        float(np.linalg.norm(Phi * asm.row_scale)),  # the one residual figure (SI rows, docs/units.md)
        dependent,
        tuple(free),
    )
