"""``kinprop assemble`` and ``kinprop propagate``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from kinprop.cli.app import (
    EXIT_NOT_CONVERGED,
    app,
    err,
    handles_user_errors,
    out,
    parse_assignment,
    parse_weight,
    print_json,
)
from kinprop.io import dump_model, load_model
from kinprop.io.results import propagation_json, variable_rows
from kinprop.propagation import Propagation, propagate

Tol = Annotated[float, typer.Option("--tol", help="stop when ||Phi||_2 < TOL (the paper used 1e-3)")]
MaxIter = Annotated[int, typer.Option("--max-iter", help="maximum Newton iterations")]
Output = Annotated[Path | None, typer.Option("-o", "--output", help="write the resulting model (full precision)")]
Json = Annotated[bool, typer.Option("--json", help="print one JSON object instead of tables")]


def _fmt(values: list[float]) -> str:
    text = " ".join(f"{x:.7g}" for x in values)
    return text if len(values) == 1 else f"[{text}]"


def comparison_table(prop: Propagation, title: str) -> Table:
    """Before/after of every variable, like the paper's Table 4 (set: yellow, moved: cyan)."""
    t = Table(title=title, title_justify="left")
    t.add_column("variable")
    t.add_column("unit")
    t.add_column("before", justify="right")
    t.add_column("after", justify="right")
    t.add_column("max |change|", justify="right")
    for row in variable_rows(prop):
        style = {"set": "bold yellow", "moved": "cyan"}.get(row["role"])
        t.add_row(
            row["variable"], row["unit"], _fmt(row["before"]), _fmt(row["after"]), f"{row['change']:.3g}", style=style
        )
    return t


def report(prop: Propagation, title: str, output: Path | None, as_json: bool) -> None:
    r = prop.result
    if output is not None:
        if r.converged:
            dump_model(prop.after, output)
        else:
            err.print(f"not writing {output}: the solve did not converge")
    if as_json:
        print_json(propagation_json(prop))
    else:
        out.print(comparison_table(prop, title))
        out.print(f"free: {' '.join(prop.free)}   rank {r.rank} of {r.n_equations} equations, {r.n_free} free columns")
        out.print(f"||Phi|| history: {'  '.join(f'{x:.6g}' for x in r.residual_history)}")
        out.print(("[green]" if r.converged else "[red]") + r.message)
        if output is not None and r.converged:
            out.print(f"wrote {output}")
    if not r.converged:
        raise typer.Exit(EXIT_NOT_CONVERGED)


@app.command()
@handles_user_errors
def assemble(
    model: Annotated[Path, typer.Argument(help="model file (YAML or JSON)")],
    tol: Tol = 1e-10,
    max_iter: MaxIter = 50,
    free: Annotated[list[str] | None, typer.Option("--free", help="groups (q s C l) or addresses; default q")] = None,
    output: Output = None,
    as_json: Json = False,
) -> None:
    """Solve for the joint coordinates from the model's estimates."""
    m = load_model(model)
    prop = propagate(m, {}, tuple(free or ["q"]), tol=tol, max_iter=max_iter)
    report(prop, f"assemble {model}", output, as_json)


@app.command(name="propagate")
@handles_user_errors
def propagate_cmd(
    model: Annotated[Path, typer.Argument(help="model file (YAML or JSON)")],
    set_: Annotated[list[str] | None, typer.Option("--set", help="ADDRESS=VALUE, e.g. J12.s_j=-2.8,0.2,0.1")] = None,
    free: Annotated[list[str] | None, typer.Option("--free", help="groups (q s C l) or addresses; default q")] = None,
    weight: Annotated[list[str] | None, typer.Option("--weight", help="ADDRESS_OR_GROUP=W: larger moves more")] = None,
    tol: Tol = 1e-10,
    max_iter: MaxIter = 50,
    output: Output = None,
    as_json: Json = False,
) -> None:
    """Change design variables and re-assemble, moving only the free variables."""
    m = load_model(model)
    changes = dict(parse_assignment(s) for s in (set_ or []))
    weights = dict(parse_weight(w) for w in (weight or [])) or None
    prop = propagate(m, changes, tuple(free or ["q"]), tol=tol, max_iter=max_iter, weights=weights)
    report(prop, f"propagate {model}", output, as_json)
