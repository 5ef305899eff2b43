"""First-order design sensitivities by the implicit-function theorem.

At an assembled configuration ``Phi(x) = 0``, a change ``dp`` of design variables is
absorbed by the free variables with the same (weighted) minimum-norm generalized inverse the
propagation uses: ``dx_free = -W^1/2 pinv(Phi_free W^1/2) Phi_p dp``. The matrix
``dx_free/dp`` is what a Newton propagation converges to for a small change.

Output sensitivities (:func:`output_sensitivity`) follow by the chain rule: for each design
column ``k`` the state moves along the direction ``e_k + S[:, k]`` (the design variable
itself plus the analytic free-variable response), and the output function of the state
(:mod:`kinprop.analysis.outputs`) is differenced centrally along that direction on the
manifold (``retract``: additive for q, s', l; exponential map for C). Only the output map is
differenced; coordinates and design variables are linear in the state, so for them the
difference is exact up to rounding.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from kinprop.analysis.metrics import WheelSpec
from kinprop.analysis.outputs import output_function
from kinprop.errors import AddressError
from kinprop.kinematics.layout import column_labels, read, retract
from kinprop.model import Model
from kinprop.propagation.propagate import assembly_for
from kinprop.spatial import Array

if TYPE_CHECKING:  # pandas (the 'data' extra) is imported only when a frame is built
    import pandas as pd

#: residual norm above which sensitivities are flagged as taken off the constraint manifold
RESIDUAL_WARN = 1e-6
#: relative step of the central difference of the output map
FD_STEP = 1e-6


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


def weight_vector(model: Model, weights: Mapping[str, float] | None) -> Array:
    """Per-column weights over the whole layout (1 where not given); must be positive."""
    layout = assembly_for(model.mechanism).layout
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
) -> Sensitivity:
    """``d x_free / d p`` for the design variables selected by ``wrt`` (groups or addresses)."""
    asm = assembly_for(model.mechanism)
    layout = asm.layout
    _, J = asm.evaluate(model.design, model.coordinates)
    pc = layout.columns(list(wrt))
    if pc.size == 0:
        raise AddressError(f"--wrt {' '.join(wrt)!r} selects no variable of this model")
    wrt_keys = {v.key for v in layout.variables if set(range(v.start, v.start + v.size)) & set(pc.tolist())}
    fc = layout.columns(list(free), exclude=wrt_keys)
    sw = np.sqrt(weight_vector(model, weights)[fc])
    S = -sw[:, None] * (np.linalg.pinv(J[:, fc] * sw) @ J[:, pc])
    labels = column_labels(layout)
    return Sensitivity(S, [labels[i] for i in fc], [labels[i] for i in pc], fc, pc)


def _step(model: Model, column: int) -> float:
    """Central-difference step for one design column: relative to the variable's size."""
    layout = assembly_for(model.mechanism).layout
    v = next(v for v in layout.variables if v.start <= column < v.start + v.size)
    if v.group == "C":
        return FD_STEP
    value = read(layout, model.design, model.coordinates, v.key)[column - v.start]
    return FD_STEP * max(1.0, abs(float(value)))


def output_sensitivity_matrix(
    model: Model,
    of: Sequence[str],
    wrt: Sequence[str],
    free: Sequence[str] = ("q",),
    weights: Mapping[str, float] | None = None,
    *,
    reference: Model | None = None,
    wheels: Mapping[str, WheelSpec] | None = None,
) -> tuple[Array, list[str], list[str], float]:
    """``(D, output names, design column labels, ||Phi||)`` of :func:`output_sensitivity`,
    as plain arrays and lists (no pandas)."""
    asm = assembly_for(model.mechanism)
    layout = asm.layout
    residual = float(np.linalg.norm(asm.residual(model.design, model.coordinates)))
    if residual > RESIDUAL_WARN:
        warnings.warn(
            f"sensitivities at a configuration that is not assembled: ||Phi|| = {residual:.3g}",
            RuntimeWarning,
            stacklevel=3,
        )
    sens = design_sensitivity(model, wrt, free, weights)
    f, names = output_function(model, of, reference=reference, wheels=wheels)
    D = np.zeros((len(names), sens.wrt_columns.size))
    for k, col in enumerate(sens.wrt_columns):
        direction = np.zeros(layout.n)
        direction[col] = 1.0
        direction[sens.free_columns] = sens.matrix[:, k]
        h = _step(model, int(col))
        plus = model.with_state(*retract(layout, model.design, model.coordinates, h * direction))
        minus = model.with_state(*retract(layout, model.design, model.coordinates, -h * direction))
        D[:, k] = (f(plus) - f(minus)) / (2.0 * h)
    return D, list(names), list(sens.columns), residual


def output_sensitivity(
    model: Model,
    of: Sequence[str],
    wrt: Sequence[str],
    free: Sequence[str] = ("q",),
    weights: Mapping[str, float] | None = None,
    *,
    reference: Model | None = None,
    wheels: Mapping[str, WheelSpec] | None = None,
) -> pd.DataFrame:
    """``d(output)/d(p)``: rows the (expanded) outputs ``of``, columns the design columns ``wrt``.

    The model must be assembled (``Phi = 0``); a warning is issued when ``||Phi||`` exceeds
    :data:`RESIDUAL_WARN`. ``attrs`` of the frame carry ``residual_norm``, ``free`` and
    ``weights``. Units: output unit per design-variable unit (coordinates in radians or
    length, metric angles in degrees, C columns per radian of body-frame rotation).
    """
    D, names, columns, residual = output_sensitivity_matrix(
        model, of, wrt, free, weights, reference=reference, wheels=wheels
    )
    import pandas as pd

    frame = pd.DataFrame(D, index=names, columns=columns)
    frame.attrs.update(residual_norm=residual, free=list(free), weights=dict(weights or {}))
    return frame


__all__ = ["Sensitivity", "design_sensitivity", "output_sensitivity", "output_sensitivity_matrix", "weight_vector"]
