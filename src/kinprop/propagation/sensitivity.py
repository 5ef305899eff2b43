"""Design sensitivities of the free variables by the implicit-function theorem.

At an assembled configuration ``Phi(x) = 0``, a change ``dp`` of design variables is
absorbed by the free variables with the same (weighted) minimum-norm generalized inverse the
propagation uses: ``dx_free = -W^1/2 pinv(Phi_free W^1/2) Phi_p dp``. The matrix
``dx_free/dp`` is what a Newton propagation converges to for a small change (and the
predictor of the continuation). Output sensitivities: :mod:`kinprop.analysis.sensitivity`.

Units: by default (``units="model"``) each entry is (row unit) per (column unit) in the model's
declared units — deg per mm, mm per deg; a ``C`` column is per angle unit of body-frame rotation
(docs/units.md). ``units="solver"``: per radian, as the solver computes it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from html import escape
from typing import TYPE_CHECKING

import numpy as np

from kinprop.engine import Engine
from kinprop.engine.units import address_scale, address_unit, check_units
from kinprop.errors import AddressError
from kinprop.kinematics.layout import column_labels
from kinprop.model import Model
from kinprop.propagation.propagate import engine_for
from kinprop.spatial import Array

if TYPE_CHECKING:  # pandas (the 'data' extra) is imported only when a frame is built
    import pandas as pd


@dataclass(frozen=True)
class Sensitivity:
    """``d x_free / d p``: ``matrix[i, k]`` in ``row_units[i]`` per ``column_units[k]``."""

    matrix: Array  # (n_free, n_wrt)
    rows: list[str]  # free column labels
    columns: list[str]  # design column labels
    free_columns: Array
    wrt_columns: Array
    #: "model" (the model's declared units) or "solver" (radians)
    units: str = "solver"
    row_units: tuple[str, ...] = ()
    column_units: tuple[str, ...] = ()

    def __repr__(self) -> str:
        n, m = self.matrix.shape
        head = ", ".join(self.columns[:4]) + (", ..." if m > 4 else "")
        return f"<Sensitivity d(free)/d(design): {n} free x {m} design columns ({head}); {self.units} units>"

    def _repr_html_(self) -> str:
        cu = self.column_units or ("",) * len(self.columns)
        ru = self.row_units or ("",) * len(self.rows)
        cols = "".join(f"<th>{escape(c)} [{escape(u)}]</th>" for c, u in zip(self.columns, cu, strict=True))
        body = "".join(
            f"<tr><th>{escape(r)} [{escape(u)}]</th>" + "".join(f"<td>{x:.6g}</td>" for x in row) + "</tr>"
            for r, u, row in zip(self.rows, ru, self.matrix, strict=True)
        )
        return f"<table><thead><tr><th></th>{cols}</tr></thead><tbody>{body}</tbody></table>"

    def frame(self) -> pd.DataFrame:
        """``d x_free / d p`` as a labelled DataFrame (rows: free variables, columns: design)."""
        import pandas as pd

        return pd.DataFrame(self.matrix, index=self.rows, columns=self.columns)


def weight_vector(model: Model, weights: Mapping[str, float] | None, engine: Engine | None = None) -> Array:
    """Per-column weights of the propagation's metric over the whole layout: the user's (1
    where not given; must be positive) over the SI scale squared (``Engine.metric_weights``:
    changes in metres and radians), so a sensitivity is the derivative of the propagation."""
    eng = engine_for(model, engine)
    for sel, w in (weights or {}).items():
        if not float(w) > 0:
            raise AddressError(f"weight for {sel!r} must be positive, found {w}")
    full = eng.metric_weights({k: float(v) for k, v in (weights or {}).items()})
    return np.ones(eng.layout.n) if full is None else full


def design_sensitivity(
    model: Model,
    wrt: Sequence[str],
    free: Sequence[str] = ("q",),
    weights: Mapping[str, float] | None = None,
    *,
    engine: Engine | None = None,
    units: str = "model",
) -> Sensitivity:
    """``d x_free / d p`` for the design variables selected by ``wrt`` (groups or addresses), in
    the model's units (``units="model"``: (row unit) per (column unit)) or per radian
    (``units="solver"``)."""
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
    rows, cols = [labels[i] for i in fc], [labels[i] for i in pc]
    if not check_units(units):
        return Sensitivity(S, rows, cols, fc, pc, "solver")
    scale_r = np.array([address_scale(model, r, engine) for r in rows])
    scale_c = np.array([address_scale(model, c, engine) for c in cols])
    S = S * scale_r[:, None] / scale_c[None, :] if S.size else S
    row_units = tuple(address_unit(model, r, engine) for r in rows)
    col_units = tuple(_column_unit(model, c, engine) for c in cols)
    return Sensitivity(S, rows, cols, fc, pc, "model", row_units, col_units)


def _column_unit(model: Model, label: str, engine: Engine) -> str:
    """A design column's unit; a ``C`` column is a rotation in the angle unit."""
    if ".C_" in label:
        return model.units.get("angle", "rad")
    return address_unit(model, label, engine)


__all__ = ["Sensitivity", "design_sensitivity", "weight_vector"]
