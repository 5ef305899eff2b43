"""Design sensitivities of the free variables by the implicit-function theorem.

At an assembled configuration ``Phi(x) = 0``, a change ``dp`` of design variables is
absorbed by the free variables with the same (weighted) minimum-norm generalized inverse the
propagation uses: ``dx_free = -W^1/2 pinv(Phi_free W^1/2) Phi_p dp``. The matrix
``dx_free/dp`` is what a Newton propagation converges to for a small change (and the
predictor of the continuation). Output sensitivities: :mod:`kinprop.analysis.sensitivity`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from kinprop.engine import Engine
from kinprop.errors import AddressError
from kinprop.kinematics.layout import column_labels
from kinprop.model import Model
from kinprop.propagation.propagate import engine_for
from kinprop.spatial import Array

if TYPE_CHECKING:  # pandas (the 'data' extra) is imported only when a frame is built
    import pandas as pd


@dataclass(frozen=True)
class Sensitivity:
    matrix: Array  # (n_free, n_wrt)
    rows: list[str]  # free column labels
    columns: list[str]  # design column labels
    free_columns: Array
    wrt_columns: Array

    def frame(self) -> pd.DataFrame:
        """``d x_free / d p`` as a labelled DataFrame (rows: free variables, columns: design)."""
        import pandas as pd

        return pd.DataFrame(self.matrix, index=self.rows, columns=self.columns)


def weight_vector(model: Model, weights: Mapping[str, float] | None, engine: Engine | None = None) -> Array:
    """Per-column weights over the whole layout (1 where not given); must be positive."""
    layout = engine_for(model, engine).layout
    wfull = np.ones(layout.n)
    for sel, w in (weights or {}).items():
        if not float(w) > 0:
            raise AddressError(f"weight for {sel!r} must be positive, found {w}")
        wfull[layout.columns([sel])] = float(w)
    return wfull


def design_sensitivity(
    model: Model,
    wrt: Sequence[str],
    free: Sequence[str] = ("q",),
    weights: Mapping[str, float] | None = None,
    *,
    engine: Engine | None = None,
) -> Sensitivity:
    """``d x_free / d p`` for the design variables selected by ``wrt`` (groups or addresses)."""
    engine = engine_for(model, engine)
    layout = engine.layout
    _, J = engine.evaluate(engine.state_of(model))
    pc = layout.columns(list(wrt))
    if pc.size == 0:
        raise AddressError(f"--wrt {' '.join(wrt)!r} selects no variable of this model")
    wrt_keys = {v.key for v in layout.variables if set(range(v.start, v.start + v.size)) & set(pc.tolist())}
    fc = layout.columns(list(free), exclude=wrt_keys)
    sw = np.sqrt(weight_vector(model, weights, engine)[fc])
    S = -sw[:, None] * (np.linalg.pinv(J[:, fc] * sw) @ J[:, pc])
    labels = column_labels(layout)
    return Sensitivity(S, [labels[i] for i in fc], [labels[i] for i in pc], fc, pc)


__all__ = ["Sensitivity", "design_sensitivity", "weight_vector"]
