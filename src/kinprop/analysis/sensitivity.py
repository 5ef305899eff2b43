"""First-order design sensitivities by the implicit-function theorem.

At an assembled configuration ``Phi(x) = 0``, a change ``dp`` of design variables is
absorbed by the free variables with the same (weighted) minimum-norm generalized inverse the
propagation uses: ``dx_free = -W^1/2 pinv(Phi_free W^1/2) Phi_p dp``. The matrix
``dx_free/dp`` is what a Newton propagation converges to for a small change.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from kinprop.kinematics.layout import column_labels
from kinprop.model import Model
from kinprop.propagation.propagate import assembly_for
from kinprop.spatial import Array


@dataclass(frozen=True)
class Sensitivity:
    matrix: Array  # (n_free, n_wrt)
    rows: list[str]  # free column labels
    columns: list[str]  # design column labels
    free_columns: Array
    wrt_columns: Array


def design_sensitivity(
    model: Model,
    wrt: Sequence[str],
    free: Sequence[str] = ("q",),
    weights: Mapping[str, float] | None = None,
) -> Sensitivity:
    """``d x_free / d p`` for the design variables selected by ``wrt`` (groups or addresses)."""
    asm = assembly_for(model.mechanism)
    layout = asm.layout
    _, J = asm.evaluate(model.design, model.coordinates)
    pc = layout.columns(list(wrt))
    wrt_keys = {v.key for v in layout.variables if set(range(v.start, v.start + v.size)) & set(pc.tolist())}
    fc = layout.columns(list(free), exclude=wrt_keys)
    sw = np.ones(fc.size)
    if weights:
        wfull = np.ones(layout.n)
        for sel, w in weights.items():
            wfull[layout.columns([sel])] = w
        sw = np.sqrt(wfull[fc])
    S = -sw[:, None] * (np.linalg.pinv(J[:, fc] * sw) @ J[:, pc])
    labels = column_labels(layout)
    return Sensitivity(S, [labels[i] for i in fc], [labels[i] for i in pc], fc, pc)
