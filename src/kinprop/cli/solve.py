"""``kinprop assemble`` and ``kinprop propagate``."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from kinprop.cli.app import (
    EXIT_NOT_CONVERGED,
    FreeOption,
    HoldOption,
    WeightOption,
    app,
    err,
    handles_user_errors,
    load_model_cli,
    out,
    print_json,
    require_plot,
)
from kinprop.cli.checks import (
    MAX_ITER,
    check_int,
    check_outputs,
    check_set_not_free,
    check_suffix,
    check_tol,
    method_and_tol,
)
from kinprop.cli.continuation import run_propagation, shown_warnings
from kinprop.cli.targets import run_targets
from kinprop.engine import compile as compile_engine
from kinprop.engine.units import changes_to_internal
from kinprop.io.arguments import parse_assignments, parse_weights
from kinprop.io.commands import comparison_csv, with_element_sets
from kinprop.io.results import propagation_json, variable_rows
from kinprop.io.writer import atomic_write, dump_model_like
from kinprop.model import Model
from kinprop.propagation import Propagation, propagate
from kinprop.propagation.hardpoints import free_addresses, free_weights, is_global, resolve_changes
from kinprop.propagation.propagate import hold as hold_joints
from kinprop.propagation.propagate import shown, unit_text

Tol = Annotated[
    float | None,
    typer.Option(
        "--tol",
        help="stop when ||Phi||_2 < TOL (default 1e-10); given without --method it is the paper's stopping rule "
        "and selects --method paper (with 1e-3: the paper's tables)",
    ),
]
MaxIter = Annotated[int, typer.Option("--max-iter", help="maximum Newton iterations")]
Method = Annotated[
    str | None,
    typer.Option(
        "--method",
        help="with freedom left: least-change (the assembly closest to the start, in metres and radians, scaled "
        "by --weight; the default) or paper (the end point of the paper's generalized-inverse iteration; the "
        "default when --tol is given)",
    ),
]
Output = Annotated[Path | None, typer.Option("-o", "--output", help="write the resulting model (full precision)")]
Json = Annotated[bool, typer.Option("--json", help="print one JSON object instead of tables")]
Csv = Annotated[
    Path | None,
    typer.Option("--csv", help="write the before/after values (variables, hardpoints, named points) as CSV"),
]
Plot = Annotated[Path | None, typer.Option("--plot", help="draw before (faded) and after: FILE.png or FILE.html")]


def _fmt(values: list[float], scale: float | None = None) -> str:
    """Values at 7 digits, round-off as 0 against ``scale`` (default: their largest)."""
    if scale is None:
        scale = max((abs(x) for x in values if x == x), default=0.0)
    text = " ".join(shown(x, scale, 7) for x in values)
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
        scale = max((abs(x) for x in [*row["before"], *row["after"]] if x == x), default=0.0)
        t.add_row(row["variable"], unit_text(row["unit"]), _fmt(row["before"], scale), _fmt(row["after"], scale),
                  f"{row['change']:.3g}", style=style)  # fmt: skip
    return t


def write_csv(prop: Propagation, path: Path) -> None:
    """:func:`comparison_csv`, written atomically."""
    atomic_write(path, comparison_csv(prop))


def write_plot(prop: Propagation, path: Path) -> None:
    """Before (faded) and after of the propagation as a stick figure."""
    from kinprop.plot import save_plot

    changes = ", ".join(f"{k} = {_fmt(list(v.ravel()))}" for k, v in prop.changes.items()) or "assembled"
    title = f"{prop.before.mechanism.name}\n{changes}; free: {' '.join(prop.free)}"
    save_plot(path, prop.after, prop.before, label="after", before_label="before", title=title)


def check_report_options(
    model: Path, output: Path | None, csv: Path | None, plot: Path | None, tol: float, max_iter: int
) -> None:
    """Everything about the outputs and numbers, before the model is loaded or solved."""
    check_tol(tol)
    check_int("--max-iter", max_iter, 1, MAX_ITER)
    check_suffix("--plot", plot, (".png", ".html"))
    check_suffix("-o", output, (".yaml", ".yml", ".json"))
    check_outputs([model], [("-o", output), ("--csv", csv), ("--plot", plot)])
    if plot is not None:
        require_plot(plot)


def report(
    prop: Propagation,
    title: str,
    output: Path | None,
    as_json: bool,
    csv: Path | None = None,
    plot: Path | None = None,
    source: Path | None = None,
    quiet: bool = False,
    written_model: Model | None = None,
) -> None:
    """Print and write a propagation; ``written_model``: the model ``-o`` writes (default ``prop.after``)."""
    r = prop.result
    written = []
    for path, write in (
        (output, lambda p: dump_model_like(prop.after if written_model is None else written_model, p, source)),
        (csv, lambda p: write_csv(prop, p)),
        (plot, lambda p: write_plot(prop, p)),
    ):
        if path is None:
            continue
        if r.converged:
            write(path)
            written.append(path)
        else:
            err.print(f"not writing {path}: the solve did not converge")
    if as_json:
        print_json(propagation_json(prop))
    else:
        if not quiet:  # -q: the outcome line, notes and files only
            out.print(comparison_table(prop, title))
            out.print(
                f"free: {' '.join(prop.free)}   rank {r.rank} of {prop.engine.n_rows} equations, "
                f"{r.free.size} free columns   method {r.method}"
            )
            out.print(f"||Phi|| history: {'  '.join(f'{x:.6g}' for x in r.residual_history)}")
        out.print(r.message, style="green" if r.converged else "red")
        for note in prop.notes:
            out.print(f"note: {note}", style="yellow")
        for path in written:
            out.print(f"wrote {path}")
    if not r.converged:
        raise typer.Exit(EXIT_NOT_CONVERGED)


@app.command()
@handles_user_errors
def assemble(
    model: Annotated[Path, typer.Argument(help="model file (YAML or JSON)")],
    tol: Tol = None,
    max_iter: MaxIter = 50,
    free: FreeOption = None,
    output: Output = None,
    as_json: Json = False,
    csv: Csv = None,
    plot: Plot = None,
    method: Method = None,
) -> None:
    """Solve for the joint coordinates from the model's estimates (with freedom left: the
    assembly closest to them)."""
    method, tol = method_and_tol(method, tol)
    check_report_options(model, output, csv, plot, tol, max_iter)
    m = load_model_cli(model)
    with shown_warnings():
        prop = propagate(m, {}, tuple(free or ["q"]), tol=tol, max_iter=max_iter, method=method)
    report(prop, f"assemble {model}", output, as_json, csv, plot, source=model)


@app.command(name="propagate")
@handles_user_errors
def propagate_cmd(
    model: Annotated[Path, typer.Argument(help="model file (YAML or JSON)")],
    set_: Annotated[
        list[str] | None,
        typer.Option(
            "--set",
            metavar="ADDRESS=VALUE",
            help="ADDRESS=VALUE, e.g. J12.s_j=-2.8,0.2,0.1 or hardpoint:UBJ=x,y,z (global)",
        ),
    ] = None,
    free: FreeOption = None,
    hold: HoldOption = None,
    weight: WeightOption = None,
    tol: Tol = None,
    max_iter: MaxIter = 50,
    output: Output = None,
    as_json: Json = False,
    csv: Csv = None,
    plot: Plot = None,
    continuation: Annotated[
        bool | None,
        typer.Option("--continuation/--no-continuation", help="predictor-corrector sub-steps (default: on failure)"),
    ] = None,
    target: Annotated[
        list[str] | None,
        typer.Option("--target", help="OUTPUT[@COND]=VALUE[UNIT], e.g. metric:camber@travel=50mm=-1.5deg"),
    ] = None,
    quiet: Annotated[bool, typer.Option("-q", "--quiet", help="print only the outcome line (no table)")] = False,
    method: Method = None,
) -> None:
    """Change design variables and re-assemble, moving only the free variables; with
    --target, find the smallest change of the --free design variables meeting the targets."""
    method, tol = method_and_tol(method, tol)
    check_report_options(model, output, csv, plot, tol, max_iter)
    given = parse_assignments("--set", set_)
    check_set_not_free(given, free)
    weights = parse_weights(weight)
    if hold and target:
        raise ValueError("--hold with --target: hold joints by declaring them in the model's inputs: instead")
    m = held = load_model_cli(model)
    m = hold_joints(m, hold or [])  # held like declared inputs, for this run only
    m, given = with_element_sets(m, given)  # element points: the model's, no body moves
    changes = changes_to_internal(m, {k: v for k, v in given.items() if not is_global(k)})
    changes |= {k: v for k, v in given.items() if is_global(k)}
    if target:
        writers = [(p, fn) for p, fn in ((csv, write_csv), (plot, write_plot)) if p is not None]
        run_targets(m, model, target, tuple(free or []), changes, weights, max_iter=max_iter, output=output,
                    as_json=as_json, writers=writers)  # fmt: skip
        return
    # global hardpoints and axes: exact s'/C values at the model's assembly (propagation/hardpoints.py)
    engine = compile_engine(m)
    changes = resolve_changes(engine, engine.reference, changes)
    free = list(free_addresses(engine, free or ["q"]))
    weights = free_weights(engine, weights)
    # continuation (explicit, or the fallback when Newton fails) and singularity warnings: cli/continuation.py
    prop = run_propagation(
        m,
        changes,
        tuple(free or ["q"]),
        tol=tol,
        max_iter=max_iter,
        weights=weights,
        continuation=continuation,
        output=output,
        as_json=as_json,
        method=method,
    )
    # the written model declares the file's own inputs, not this run's --hold
    written_model = replace(prop.after, mechanism=held.mechanism) if hold else None
    report(prop, f"propagate {model}", output, as_json, csv, plot, source=model, quiet=quiet,
           written_model=written_model)  # fmt: skip
