"""First-order design sensitivities by the implicit-function theorem.

At an assembled configuration ``Phi(x) = 0``, a change ``dp`` of design variables is
absorbed by the free variables with the same (weighted) minimum-norm generalized inverse the
propagation uses: ``dx_free = -W^1/2 pinv(Phi_free W^1/2) Phi_p dp``. The matrix
``dx_free/dp`` is what a Newton propagation converges to for a small change.

Output sensitivities (:func:`output_sensitivity`) follow by the chain rule: for each design
column ``k`` the state moves along the direction ``e_k + S[:, k]`` (the design variable
itself plus the analytic free-variable response). The first-order metrics (gains, instant
centres, roll-centre height, anti-dive/squat, motion ratios, wheel rate) are differentiated
exactly along it (:func:`kinprop.analysis.outputs.first_order_derivatives`: the velocity
state's analytic derivatives, :func:`kinprop.engine.motion.motion_derivatives`), and so are
the load outputs (``reaction:``, ``force:``, ``effort:``: the differentiated equilibrium,
:mod:`kinprop.engine.statics_rates`, the direct method). Every other
output function of the state (:mod:`kinprop.analysis.outputs`) is differenced centrally
along that direction on the manifold (``retract``: additive for q, s', l; exponential map for
C); coordinates and design variables are linear in the state, so for them the difference is
exact up to rounding. :func:`derivative_method` names the method of each output.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from kinprop.analysis.metrics import WheelSpec
from kinprop.analysis.outputs import first_order_derivatives, first_order_of, output_function
from kinprop.analysis.statics import is_load_output, load_derivatives
from kinprop.analysis.units import derivative_scale
from kinprop.engine import Engine, State
from kinprop.engine.units import check_units
from kinprop.model import Model
from kinprop.propagation.element_points import (
    apply_element_changes,
    element_directions,
    element_labels,
    element_point,
    is_element_address,
)
from kinprop.propagation.hardpoints import free_addresses, free_weights, global_columns, is_global
from kinprop.propagation.propagate import engine_for
from kinprop.propagation.sensitivity import Sensitivity, design_sensitivity, weight_vector
from kinprop.spatial import Array

if TYPE_CHECKING:  # pandas (the 'data' extra) is imported only when a frame is built
    import pandas as pd


@dataclass(frozen=True)
class OnBase:
    """Outputs of a base ``model`` (its ``engine``) evaluated at the states of a model with drive
    joints (:mod:`kinprop.analysis.drives`): ``view`` maps those states to ``engine``'s,
    ``columns[c]`` is the augmented column of base column ``c``. The first-order metrics then
    move the suspension by its own inputs, not with a drive held."""

    model: Model
    engine: Engine
    view: Callable[[State], State]
    columns: Array


#: residual norm above which sensitivities are flagged as taken off the constraint manifold
RESIDUAL_WARN = 1e-6
#: relative step of the central difference of the output map
FD_STEP = 1e-6
#: :func:`derivative_method` values
EXACT, CENTRAL = "exact (analytic velocity derivatives)", "central difference of the output map along the exact tangent"
#: a load output's method: the differentiated equilibrium (:mod:`kinprop.engine.statics_rates`)
DIRECT = "exact (the differentiated equilibrium, direct method)"


def derivative_method(model: Model, name: str) -> str:
    """How :func:`output_sensitivity` differentiates the expanded output ``name``: exactly for
    the first-order metrics and the load outputs, by a central difference of the output map for
    the rest."""
    if is_load_output(name):
        return DIRECT
    return EXACT if first_order_of(model, name) is not None else CENTRAL


def _step(engine: Engine, model: Model, column: int) -> float:
    """Central-difference step for one design column: relative to the variable's size."""
    v = next(v for v in engine.layout.variables if v.start <= column < v.start + v.size)
    if v.group == "C":
        return FD_STEP
    value = engine.get(engine.state_of(model), v.key)[column - v.start]
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
    engine: Engine | None = None,
    units: str = "model",
    base: OnBase | None = None,
) -> tuple[Array, list[str], list[str], float]:
    """``(D, output names, design column labels, ||Phi||)`` of :func:`output_sensitivity`,
    as plain arrays and lists (no pandas). ``wrt``, ``free`` and ``weights`` take every address
    a propagation takes: ``hardpoint:J.i`` / ``hardpoint:J.i[z]`` columns are per global length
    unit (:func:`kinprop.propagation.hardpoints.global_columns`). ``base``: the outputs are the
    base model's of a model with drive joints (:class:`OnBase`; the tangent is ``model``'s)."""
    model_units = check_units(units)
    engine = engine_for(model, engine)
    state = engine.state_of(model)
    residual = float(np.linalg.norm(engine.residual(state) * engine.row_scale))  # SI rows (docs/units.md)
    if residual > RESIDUAL_WARN:
        warnings.warn(
            f"sensitivities at a configuration that is not assembled: ||Phi|| = {residual:.3g}",
            RuntimeWarning,
            stacklevel=3,
        )
    asked = list(wrt)
    wrt = [w for w in asked if not is_element_address(w)]
    element_wrt = [w for w in asked if is_element_address(w)]
    on = base.model if base is not None else model
    _, names = output_function(on, of, reference=reference, wheels=wheels, engine=base.engine if base else engine)
    D, columns = np.zeros((len(names), 0)), []
    if wrt:
        D, columns = _design_rows(model, engine, state, names, wrt, free, weights, reference, wheels, base)
    if element_wrt:  # no body moves: at the base model's state (with drive joints: its view)
        at = (model, engine, state) if base is None else (on, base.engine, base.view(state))
        labels, E = _element_sensitivity(*at, names, element_wrt, reference, wheels)
        D, columns = _in_asked_order(model, asked, np.column_stack([D, E]), columns + labels)
    if model_units and D.size:
        so = np.array([derivative_scale(model, n, engine) for n in names])
        si = np.array([derivative_scale(model, c, engine) for c in columns])
        D = D * so[:, None] / si[None, :]
    return D, list(names), columns, residual


def _design_rows(
    model: Model,
    engine: Engine,
    state: State,
    names: list[str],
    wrt: Sequence[str],
    free: Sequence[str],
    weights: Mapping[str, float] | None,
    reference: Model | None,
    wheels: Mapping[str, WheelSpec] | None,
    base: OnBase | None = None,
) -> tuple[Array, list[str]]:
    """``(D, columns)`` with respect to the design addresses ``wrt`` (solver units, layout
    order): the implicit-function tangent, exact rows where there are, central differences of
    the output map along it for the rest (module docstring); with ``base``, of the base model's
    outputs along the tangent's base columns."""
    # global hardpoints: wrt their s' columns, then each global component combines them (exact)
    design, combos = global_columns(engine, state, wrt)
    free, weights = free_addresses(engine, free), free_weights(engine, weights)
    sens = design_sensitivity(model, design, free, weights, engine=engine, units="solver")
    directions = np.zeros((engine.n_columns, sens.wrt_columns.size))
    directions[sens.wrt_columns, np.arange(sens.wrt_columns.size)] = 1.0
    directions[sens.free_columns] = sens.matrix
    on, on_engine, along = model, engine, directions
    if base is not None:  # the outputs of the base model, along the tangent's base columns
        on, on_engine, along = base.model, base.engine, directions[base.columns]
    exact = first_order_derivatives(on, names, along, reference=reference, wheels=wheels, engine=on_engine)
    D = np.zeros((len(names), sens.wrt_columns.size))
    for i, row in exact.items():
        D[i] = row
    loads = [i for i, n in enumerate(names) if is_load_output(n)]
    if loads:  # exact: the differentiated equilibrium (direct method)
        D[loads] = load_derivatives(on, [names[i] for i in loads], along.T, engine=on_engine, reference=reference)
    rest = [i for i in range(len(names)) if i not in exact and i not in loads]
    if rest:
        f, _ = output_function(on, [names[i] for i in rest], reference=reference, wheels=wheels, engine=on_engine)

        def at(st: State) -> Model:
            return engine.model_of(st, model) if base is None else on_engine.model_of(base.view(st), on)

        for k, col in enumerate(sens.wrt_columns):
            h = _step(engine, model, int(col))
            plus, minus = (at(engine.retract(state, sg * h * directions[:, k])) for sg in (1.0, -1.0))
            D[rest, k] = (f(plus) - f(minus)) / (2.0 * h)
    columns = list(sens.columns)
    if combos:
        index = {c: k for k, c in enumerate(columns)}
        plain = [w for w in wrt if not is_global(w.split("[")[0])]
        keep = (
            [c for c in columns if c in {engine.column_labels[int(i)] for i in engine.columns(plain)}] if plain else []
        )
        cols = [D[:, index[c]] for c in keep] + [
            sum(coef * D[:, index[c]] for c, coef in combos[label].items()) for label in combos
        ]
        D, columns = (np.column_stack(cols) if cols else np.zeros((len(names), 0))), keep + list(combos)
    return _as_asked(engine, wrt, D, columns)


def _element_sensitivity(
    model: Model,
    engine: Engine,
    state: State,
    names: list[str],
    wrt: Sequence[str],
    reference: Model | None,
    wheels: Mapping[str, WheelSpec] | None,
) -> tuple[list[str], Array]:
    """``(labels, D)``: derivatives of the outputs ``names`` with respect to element points
    (:mod:`kinprop.propagation.element_points`, per global length unit): no body moves, so the
    first-order metrics (motion ratios, wheel rate) are exact along the elements' end moves
    alone (:func:`kinprop.analysis.outputs.first_order_derivatives` with ``elements``); every
    other output (a load's element force) by a central difference of the output map of the
    model with the element point moved; the kinematic outputs do not depend on them (0)."""
    labels, moves = element_directions(model, engine, state, wrt)
    k = len(labels)
    none = np.zeros((engine.n_columns, k))
    exact = first_order_derivatives(model, names, none, reference=reference, wheels=wheels, engine=engine,
                                    elements=moves)  # fmt: skip
    D = np.zeros((len(names), k))
    for i, row in exact.items():
        D[i] = row
    loads = [i for i, n in enumerate(names) if is_load_output(n)]
    if loads:
        f, _ = output_function(model, [names[i] for i in loads], reference=reference, wheels=wheels, engine=engine)
        h = FD_STEP * max(1.0, engine.length_scale or 1.0)
        for c, lab in enumerate(labels):
            p = element_point(model, engine, state, lab)
            plus, _ = apply_element_changes(model, engine, state, {lab: p + h})
            minus, _ = apply_element_changes(model, engine, state, {lab: p - h})
            D[loads, c] = (f(plus) - f(minus)) / (2.0 * h)
    return labels, D


def _in_asked_order(model: Model, asked: Sequence[str], D: Array, columns: list[str]) -> tuple[Array, list[str]]:
    """Element-point columns placed where ``asked`` names them among the others."""
    rank: dict[str, int] = {}
    for k, w in enumerate(asked):
        base = w.split("[")[0]
        mine = element_labels(model, w) if is_element_address(w) else [
            c for c in columns if c == w or c.startswith(f"{base}[") or c.startswith(f"{base}.")]  # fmt: skip
        for c in mine:
            rank.setdefault(c, k)
    order = sorted(range(len(columns)), key=lambda i: (rank.get(columns[i], len(asked)), i))
    return D[:, order], [columns[i] for i in order]


def _as_asked(engine: Engine, wrt: Sequence[str], D: Array, columns: list[str]) -> tuple[Array, list[str]]:
    """``D``'s columns in the order ``wrt`` asks for them (the solve gives layout order); the
    components of one address stay in their own order."""
    rank: dict[str, int] = {}
    for k, w in enumerate(wrt):
        base = w.split("[")[0]
        if is_global(base):  # hardpoint:J.i, hardpoint:J.i[z]: its own component labels
            mine = [c for c in columns if c == w or (c.startswith(f"{w}[") and "[" not in w)]
        else:
            mine = [engine.column_labels[int(i)] for i in engine.columns([w])]
        for c in mine:
            rank.setdefault(c, k)
    order = sorted(range(len(columns)), key=lambda i: (rank.get(columns[i], len(wrt)), i))
    return D[:, order], [columns[i] for i in order]


def output_sensitivity(
    model: Model,
    of: Sequence[str],
    wrt: Sequence[str],
    free: Sequence[str] = ("q",),
    weights: Mapping[str, float] | None = None,
    *,
    reference: Model | None = None,
    wheels: Mapping[str, WheelSpec] | None = None,
    engine: Engine | None = None,
    units: str = "model",
) -> pd.DataFrame:
    """``d(output)/d(p)``: rows the (expanded) outputs ``of``, columns the design columns ``wrt``.

    The model must be assembled (``Phi = 0``); a warning is issued when ``||Phi||`` exceeds
    :data:`RESIDUAL_WARN`. ``attrs`` of the frame carry ``residual``, ``free`` and ``weights``,
    ``units`` and ``method`` (per output, :func:`derivative_method`). Units: output unit per
    design-variable unit, in the model's declared units (``units="model"``: deg per mm, mm per
    deg, metric angles in the angle unit, C columns per angle unit of body-frame rotation;
    docs/units.md); ``units="solver"``: as computed (coordinates per radian, metric angles in
    degrees, C columns per radian).
    """
    D, names, columns, residual = output_sensitivity_matrix(
        model, of, wrt, free, weights, reference=reference, wheels=wheels, engine=engine, units=units
    )
    import pandas as pd

    frame = pd.DataFrame(D, index=names, columns=columns)
    frame.attrs.update(residual=residual, free=list(free), weights=dict(weights or {}), units=units)
    frame.attrs["method"] = {n: derivative_method(model, n) for n in names}
    return frame


__all__ = [
    "CENTRAL",
    "DIRECT",
    "EXACT",
    "Sensitivity",
    "derivative_method",
    "design_sensitivity",
    "output_sensitivity",
    "output_sensitivity_matrix",
    "weight_vector",
]
