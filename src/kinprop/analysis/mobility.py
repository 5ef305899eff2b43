"""Mobility and redundancy: Gruebler-Kutzbach count and the true mobility from the SVD rank.

The true mobility is ``n_q - rank(Phi_q)`` at the current configuration, where ``n_q``
counts every relative coordinate (Euler parameters as four, balanced by their normalisation
rows). The rank uses singular values above ``rtol * s_max`` (default 1e-9). Redundant rows
are the constraint rows left out of a rank-revealing (column-pivoted) QR of ``Phi_q^T``:
removing them leaves the rank unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from kinprop.model import Model
from kinprop.propagation.propagate import assembly_for
from kinprop.solver.newton import RANK_RTOL


@dataclass(frozen=True)
class MobilityReport:
    mobility: int
    gruebler: int
    n_coordinates: int
    n_constraints: int
    rank: int
    redundant: list[str]
    singular_values: list[float] = field(repr=False)
    rtol: float = RANK_RTOL


def joint_freedom(jtype, is_tree: bool) -> int:
    """Relative degrees of freedom a joint allows (6 minus its constraint count)."""
    if jtype.tree:
        return jtype.n_coordinates - (1 if jtype.euler is not None else 0)
    return 6 - jtype.n_constraints + jtype.n_cut_coordinates


def gruebler(model: Model) -> int:
    """Spatial Gruebler-Kutzbach count ``6 (n_moving) - sum (6 - f_joint)``."""
    mech = model.mechanism
    asm = assembly_for(mech)
    tree = set(asm.topology.tree_joints)
    moving = sum(1 for b in mech.bodies if not b.fixed)
    return 6 * moving - sum(6 - joint_freedom(j.jtype, j.name in tree) for j in mech.joints)


def mobility(model: Model, rtol: float = RANK_RTOL) -> MobilityReport:
    asm = assembly_for(model.mechanism)
    _, J = asm.evaluate(model.design, model.coordinates)
    cols = asm.layout.columns(["q"])
    Jq = J[:, cols]
    m, n = Jq.shape
    sv = np.linalg.svd(Jq, compute_uv=False) if Jq.size else np.zeros(0)
    rank = int(np.sum(sv > rtol * sv[0])) if sv.size and sv[0] > 0 else 0
    redundant: list[str] = []
    if m and rank < m:
        labels = asm.row_labels
        _, _, piv = scipy.linalg.qr(Jq.T, mode="economic", pivoting=True)
        redundant = [labels[i] for i in sorted(piv[rank:])]
    return MobilityReport(n - rank, gruebler(model), n, m, rank, redundant, sv.tolist(), rtol)
