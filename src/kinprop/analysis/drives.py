"""Outputs at a drive position and over a range, and sweeps driven by an output (issue 20).

A designer drives a suspension by wheel travel in millimetres, not by an arm angle. An output
held at a value is one more constraint row, solved with the mechanism's rows by the same
engine (:func:`kinprop.engine.targets.solve_targets`, each configuration's coordinates
the unknowns, no design variable free). The grammar is the one of ``--target``
(:mod:`kinprop.analysis.targets`) without the ``=VALUE``:

* ``OUTPUT@CONDITION[&CONDITION...]``: the output in the configuration the conditions define,
  e.g. ``camber@travel=50`` (the wheel centre 50 above its reference; the declared inputs are
  released so the suspension can travel), ``toe@travel=30&LCA.q=2``;
* ``slope:OUTPUT@COND=A..B``: ``(OUTPUT(B) - OUTPUT(A)) / (B - A)`` (bump steer
  ``slope:toe@travel=-50..50``), output unit per condition unit;
* a plain output name: at the model's state, as :func:`kinprop.analysis.outputs.evaluate_outputs`.

Units as ``--target``'s: values without a unit are in the model's units; angle metrics in the
model's angle unit.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from kinprop.analysis.outputs import evaluate_outputs
from kinprop.analysis.targets import (
    Condition,
    TargetSpec,
    _config_jacobian,
    _config_outputs,
    _kind,
    parse_target,
)
from kinprop.analysis.units import derivative_scale
from kinprop.engine import Engine
from kinprop.engine.targets import Configuration, Row, solve_targets
from kinprop.engine.units import RADIANS_PER
from kinprop.errors import AddressError, ConvergenceError
from kinprop.model import Model
from kinprop.propagation.propagate import engine_for
from kinprop.spatial import Array


def is_driven(name: str) -> bool:
    """Whether an output name carries a drive position (``@``) or is a slope (``slope:``)."""
    return "@" in name or name.startswith("slope:")


def _key(cs: Sequence[Condition]) -> tuple:
    return tuple(sorted((c.output, c.value) for c in cs))


def _to_model_units(model: Model, spec: TargetSpec, value: float, engine: Engine) -> float:
    """A configuration output (internal: metric angles deg, joint angles rad) in model units."""
    if _kind(model, spec.output) == "deg":
        return value if model.units.get("angle") == "deg" else value * RADIANS_PER["deg"]
    return value * derivative_scale(model, spec.output, engine)


def outputs_at(
    model: Model, names: Sequence[str], *, engine: Engine | None = None, tol: float = 1e-9, max_iter: int = 60
) -> dict[str, float]:
    """Values of ``names`` (module docstring) for the model's design; configurations with the
    same conditions are solved once, all together. Raises :class:`ConvergenceError` when a
    configuration cannot be reached (e.g. a travel beyond the mechanism's range)."""
    eng = engine_for(model, engine)
    plain = [n for n in names if not is_driven(n)]
    out: dict[str, float] = {}
    specs: dict[str, TargetSpec] = {}
    for n in names:
        if is_driven(n):
            if "=" in n.split("@", 1)[0]:
                raise AddressError(f"output {n!r}: expected OUTPUT@CONDITION or slope:OUTPUT@COND=A..B, no =VALUE")
            specs[n] = parse_target(model, f"{n}=0", eng)
    keys: dict[tuple, int] = {}
    conds: list[tuple[Condition, ...]] = []
    outs: list[list[str]] = []

    def config(cs: tuple[Condition, ...]) -> int:
        if _key(cs) not in keys:
            keys[_key(cs)] = len(conds)
            conds.append(cs)
            outs.append([c.output for c in cs if not c.held])
        return keys[_key(cs)]

    def slot(k: int, name: str) -> int:
        if name not in outs[k]:
            outs[k].append(name)
        return outs[k].index(name)

    wanted: dict[str, list[tuple[int, int, float]]] = {}
    for n, s in specs.items():
        if s.slope is None:
            k = config(s.conditions)
            wanted[n] = [(k, slot(k, s.output), 1.0)]
        else:
            ka, kb = config(s.slope[0]), config(s.slope[1])
            span = s.slope[2]
            wanted[n] = [(ka, slot(ka, s.output), -1.0 / span), (kb, slot(kb, s.output), 1.0 / span)]
    if conds:
        rows = [
            Row(f"{c.output}={c.value:g}", c.value, ((k, slot(k, c.output), 1.0),), hard=True)
            for k, cs in enumerate(conds)
            for c in cs
            if not c.held
        ]
        configurations = [
            Configuration(
                " & ".join(f"{c.output}={c.value:g}" for c in cs) or "base",
                _config_outputs(model, eng, outs[k]),
                {c.output: [c.value] for c in cs if c.held},
                _config_jacobian(model, eng, outs[k]),
            )
            for k, cs in enumerate(conds)
        ]
        res = solve_targets(eng, eng.state_of(model), configurations, rows, (), tol=tol, max_iter=max_iter)
        if not res.converged:
            raise ConvergenceError(f"outputs at drive positions: {res.message}")
        values = [cfg.outputs(st) for cfg, st in zip(configurations, res.after, strict=True)]
        for n, terms in wanted.items():
            v = float(sum(c * values[k][i] for k, i, c in terms))
            s = specs[n]
            out[n] = _to_model_units(model, s, v, eng) if s.slope is None else v * _slope_scale(model, s, eng)
    if plain:
        out.update(evaluate_outputs(model, plain, engine=eng))
    return {n: out[n] for n in names if n in out} | {k: v for k, v in out.items() if k not in names}


def _slope_scale(model: Model, spec: TargetSpec, engine: Engine) -> float:
    """Model units of a slope: the output's per the condition's (internal -> model)."""
    num = _to_model_units(model, spec, 1.0, engine)
    cond = spec.slope[0][0]  # type: ignore[index]
    den = 1.0 if cond.held is False else derivative_scale(model, cond.output, engine)
    return num / den


def travel_sweep(
    model: Model,
    travels: Sequence[float] | Array,
    outputs: Sequence[str],
    *,
    engine: Engine | None = None,
    tol: float = 1e-9,
) -> dict[str, Array]:
    """``outputs`` at each wheel travel of ``travels`` (the model's length unit, e.g. uniform
    steps ``np.linspace(-50, 50, 21)``): one configuration per travel, the wheel centre held
    ``travel`` above its reference by one more constraint row. Returns ``{output: values}``
    with ``"travel"`` first."""
    t = np.asarray(travels, dtype=float).ravel()
    names = [f"{o}@travel={float(v)!r}" for v in t for o in outputs]
    values = outputs_at(model, names, engine=engine, tol=tol)
    out: dict[str, Array] = {"travel": t}
    for o in outputs:
        out[o] = np.array([values[f"{o}@travel={float(v)!r}"] for v in t])
    return out


__all__ = ["is_driven", "outputs_at", "travel_sweep"]
