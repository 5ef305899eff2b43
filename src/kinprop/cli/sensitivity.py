"""``kinprop sensitivity``: first-order derivatives of outputs with respect to design variables."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Annotated, Any, NamedTuple

import numpy as np
import typer
from rich.table import Table

from kinprop.analysis.sensitivity import RESIDUAL_WARN, design_sensitivity, output_sensitivity_matrix
from kinprop.cli.app import (
    EXIT_NOT_CONVERGED,
    FreeOption,
    WeightOption,
    app,
    err,
    fail,
    handles_user_errors,
    load_model_cli,
    out,
    print_json,
)
from kinprop.cli.checks import check_tol, parse_weights
from kinprop.cli.continuation import shown_warnings
from kinprop.engine import compile as compile_engine
from kinprop.io.units import derivative_scale, unit_of
from kinprop.model import Model
from kinprop.propagation import assemble
from kinprop.propagation.hardpoints import free_weights, global_columns, is_global
from kinprop.solver import SolveResult

Json = Annotated[bool, typer.Option("--json", help="print one JSON object instead of a table")]


def sensitivity_table(matrix: np.ndarray, rows: list[str], columns: list[str], title: str) -> Table:
    """A labelled matrix: one row per output, one column per design variable."""
    t = Table(title=title, title_justify="left")
    t.add_column("d(output) / d(design)", style="bold")
    for c in columns:
        t.add_column(str(c), justify="right")
    for name, row in zip(rows, np.asarray(matrix), strict=True):
        scale = max(1.0, float(np.max(np.abs(row)))) if row.size else 1.0
        cells = [f"{x:.6g}" if abs(x) > 1e-9 * scale else "0" for x in row]
        t.add_row(str(name), *cells)
    return t


def _per(model, name: str, engine=None) -> str:
    """The unit of a design column: a C column is per angle of body-frame rotation."""
    if ".C_" in name:
        return model.units.get("angle", "rad")
    return unit_of(model, name, engine)


class Sensitivities(NamedTuple):
    """d(rows)/d(columns) in the model's units, with the unit of every row and column."""

    matrix: np.ndarray
    rows: list[str]
    columns: list[str]
    units_of: list[str]
    units_wrt: list[str]


def _solver_matrix(
    assembled: Model, wrt: Sequence[str], of: Sequence[str] | None, free: Sequence[str], weights: Any
) -> tuple[np.ndarray, list[str], list[str]]:
    if of:
        with shown_warnings():
            matrix, rows, columns, _ = output_sensitivity_matrix(assembled, of, wrt, free, weights, units="solver")
        return np.asarray(matrix), list(rows), list(columns)
    sens = design_sensitivity(assembled, wrt, free, weights, units="solver")
    return np.asarray(sens.matrix), list(sens.rows), list(sens.columns)


def sensitivities(
    assembled: Model,
    wrt: Sequence[str],
    of: Sequence[str] | None,
    free: Sequence[str],
    weights: Mapping[str, float] | None,
) -> Sensitivities:
    """d(outputs)/d(wrt) at an assembled model (without ``of``: of the free variables), in the
    model's units (docs/units.md); ``hardpoint:J[.i|.j][c]`` columns are per global length unit
    (:func:`kinprop.propagation.hardpoints.global_columns`)."""
    engine = compile_engine(assembled)
    design, combos = global_columns(engine, engine.reference, wrt)
    matrix, rows, columns = _solver_matrix(assembled, design, of, free, free_weights(engine, weights))
    if combos:
        index = {c: k for k, c in enumerate(columns)}
        plain = {engine.column_labels[int(c)] for c in engine.columns([w for w in wrt if not is_global(w)])}
        keep = [c for c in columns if c in plain]
        extra = list(combos)
        cols = [matrix[:, index[c]] for c in keep] + [
            sum(coef * matrix[:, index[c]] for c, coef in combos[label].items()) for label in extra
        ]
        matrix, columns = np.column_stack(cols) if cols else np.zeros((len(rows), 0)), keep + extra
    # in the model's units: d(out)/d(in) * scale(out) / scale(in)
    so = np.array([derivative_scale(assembled, str(name), engine) for name in rows])
    si = np.array([derivative_scale(assembled, str(name), engine) for name in columns])
    matrix = matrix * so[:, None] / si[None, :]
    units_of = [unit_of(assembled, str(name), engine) for name in rows]
    units_wrt = [_per(assembled, str(name), engine) for name in columns]
    return Sensitivities(matrix, rows, columns, units_of, units_wrt)


def sensitivity_json(
    model: str, sens: Sensitivities, free: Sequence[str], weights: Mapping[str, float] | None, assembly: SolveResult
) -> dict[str, Any]:
    """What ``kinprop sensitivity --json`` prints (``assembly``: the assembly solved first)."""
    r = assembly
    return {
        "model": model,
        "of": [str(i) for i in sens.rows],
        "wrt": [str(c) for c in sens.columns],
        "matrix": np.asarray(sens.matrix).tolist(),
        "units": {"of": sens.units_of, "wrt": sens.units_wrt, "matrix": "unit of the row per unit of the column"},
        "free": list(free),
        "weights": dict(weights) if weights else {},
        "assembly": {
            "initial_residual": r.residual_history[0],
            "residual": r.residual_norm,
            "iterations": r.iterations,
        },
    }


@app.command(name="sensitivity")
@handles_user_errors
def sensitivity_cmd(
    model: Annotated[Path, typer.Argument(help="model file (YAML or JSON)")],
    wrt: Annotated[
        list[str],
        typer.Option(
            "--wrt",
            metavar="ADDRESS",
            help="design variables: addresses (RS.s_i[2]), groups, hardpoint:J.i[x] (per global length unit)",
        ),
    ],
    of: Annotated[
        list[str] | None,
        typer.Option(
            "--of",
            metavar="NAME",
            help="outputs: J.q[k], J.s_i[k], point:BODY.NAME[x], hardpoint:J.i[x], metric:W.camber",
        ),
    ] = None,
    free: FreeOption = None,
    weight: WeightOption = None,
    tol: Annotated[float, typer.Option("--tol", help="assembly tolerance on ||Phi||_2")] = 1e-10,
    as_json: Json = False,
) -> None:
    """Derivatives of outputs (default: the free variables) with respect to design variables.

    The model is assembled first (free: q), then the implicit-function theorem gives the free
    variables' response with the same weighted minimum-norm inverse as `propagate`.
    """
    check_tol(tol)
    weights = parse_weights(weight)
    m = load_model_cli(model)
    free_set = tuple(free or ["q"])
    with shown_warnings():  # a near-singular assembly is one "warning:" line on stderr
        prop = assemble(m, tol=tol)
    r = prop.result
    initial = r.residual_history[0]
    if not r.converged:
        fail(f"{model}: cannot assemble the model before differentiating: {r.message}", EXIT_NOT_CONVERGED)
    if initial > RESIDUAL_WARN:
        err.print(
            f"note: {model} was not assembled (||Phi|| = {initial:.3g}); assembled first: {r.message}",
            soft_wrap=True,
        )
    assembled = prop.after
    sens = sensitivities(assembled, wrt, of, free_set, weights)
    if as_json:
        print_json(sensitivity_json(str(model), sens, free_set, weights, r))
        return
    title = f"sensitivity {model}"
    labelled_rows = [f"{r} [{u}]" if u else str(r) for r, u in zip(sens.rows, sens.units_of, strict=True)]
    labelled_cols = [f"{c} [{u}]" if u else str(c) for c, u in zip(sens.columns, sens.units_wrt, strict=True)]
    out.print(sensitivity_table(sens.matrix, labelled_rows, labelled_cols, title))
    weights_text = "; weights " + " ".join(f"{k}={v:g}" for k, v in weights.items()) if weights else ""
    out.print(f"free: {' '.join(free_set)}{weights_text}")
    angle = assembled.units.get("angle", "rad")
    out.print(
        f"units: [row unit] per [column unit], the model's units ({assembled.units.get('length')}, {angle}); "
        f"C columns per {angle} of body-frame rotation"
    )
    out.print(f"assembled: {r.message}")
