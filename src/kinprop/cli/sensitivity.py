"""``kinprop sensitivity``: first-order derivatives of outputs with respect to design variables."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.table import Table

from kinprop.analysis.sensitivity import RESIDUAL_WARN
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
from kinprop.cli.checks import check_tol
from kinprop.cli.continuation import shown_warnings
from kinprop.io.arguments import parse_weights
from kinprop.io.commands import sensitivities, sensitivity_json
from kinprop.propagation import assemble

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
            help="outputs: J.q[k], J.s_i[k], point:BODY.NAME[x], hardpoint:J.i[x], metric:W.camber, at a drive "
            "position camber@travel=50, a slope slope:toe@travel=-50..50",
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
    with shown_warnings():
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
    if sens.methods:
        groups: dict[str, list[str]] = {}
        for name, how in zip(sens.rows, sens.methods, strict=True):
            groups.setdefault(how, []).append(str(name))
        for how, names in groups.items():
            out.print(f"method: {how}: {' '.join(names)}", soft_wrap=True)
    out.print(f"assembled: {r.message}")
