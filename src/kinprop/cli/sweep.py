"""``kinprop sweep``: drive joint coordinates over a range, one re-assembly per step.

Exit codes: 0 every step converged, 1 some step failed (recorded, the sweep went on),
2 invalid input, 130 interrupted (143 after SIGTERM) (rows already computed are in the output file).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn
from rich.table import Table

from kinprop.analysis.sweep import parse_drive, plot_sweep, sweep
from kinprop.cli.app import (
    EXIT_NOT_CONVERGED,
    FreeOption,
    HoldOption,
    app,
    err,
    handles_user_errors,
    interrupt_status,
    is_interrupt,
    load_model_cli,
    out,
    print_json,
    require,
)
from kinprop.cli.checks import (
    MAX_ITER,
    check_int,
    check_outputs,
    check_set_not_free,
    check_suffix,
    check_tol,
)
from kinprop.engine.units import changes_to_internal
from kinprop.io.arguments import parse_assignments
from kinprop.io.commands import check_x, label_units, sweep_json, with_element_sets
from kinprop.propagation.propagate import hold, shown

#: show a progress bar from this many steps on
PROGRESS_FROM = 50


def _fmt(v: object, scale: float = 0.0) -> str:
    """A cell: 6 digits, round-off against the column's largest ``scale`` as 0 (never -0)."""
    return shown(v, scale) if isinstance(v, float) else str(v)


def _table(frame, columns: list[str], limit: int | None = 24) -> Table:
    """The sweep's rows; with a ``limit`` the middle rows are elided (a terminal), else all."""
    t = Table(show_lines=False, title_justify="left")
    units = frame.attrs.get("column_units", {})
    for c in columns:
        t.add_column(f"{c} [{units[c]}]" if units.get(c) else c, justify="left" if c in ("status",) else "right")
    n = len(frame)
    scale = {c: float(frame[c].abs().max()) if frame[c].dtype.kind == "f" else 0.0 for c in columns}
    if limit is None or n <= limit:
        idx = list(range(n))
    else:
        idx = list(range(limit // 2)) + [-1] + list(range(n - limit // 2, n))
    for i in idx:
        if i < 0:
            t.add_row(*["..."] * len(columns))
            continue
        row = frame.iloc[i]
        style = None if row["status"] == "converged" else "red"
        t.add_row(*[_fmt(row[c], scale[c]) for c in columns], style=style)
    return t


def _shown_columns(res, requested: list[str] | None, limit: int | None = 10) -> list[str]:
    """Step, drives, the requested outputs (all of them, first), status, iterations, then the
    default outputs and the coordinates that vary, up to ``limit`` columns (None: all)."""
    df = res.frame
    drives = [d.label for d in res.drives]
    asked = list(res.outputs) if requested else []
    head = ["step", *drives, *asked, "status", "iterations"]
    coords = [c for c in df.columns if ".q" in c and c not in head and not c.startswith(("point:", "metric:"))]
    rest = [c for c in res.outputs if c not in head] + coords
    varying = [c for c in rest if df[c].notna().any() and float(df[c].max() - df[c].min()) > 1e-12]
    return head + (varying if limit is None else varying[: max(0, limit - len(head))])


def baseline_path(output: Path) -> Path:
    """Where ``--baseline -o NAME.csv`` writes the baseline's rows: ``NAME.baseline.csv``."""
    return output.with_name(f"{output.stem}.baseline{output.suffix}")


def _plot_before_after(base, res, path: Path, x: str | None, title: str) -> None:
    """The swept outputs against ``x``: before (the design without --set) and after, or one sweep."""
    from kinprop.plot.curves import plot_curves

    x = x or res.drives[0].label
    if x not in res.frame.columns:
        raise ValueError(f"--x {x!r}: not a column of the sweep; columns: {', '.join(map(str, res.frame.columns))}")
    ys = [c for c in res.outputs if c != x and c in res.frame.columns] or [
        c for c in res.frame.columns if ".q" in c and c != x and not c.startswith(("point:", "metric:"))
    ]
    if not ys:
        raise ValueError("nothing to plot: give outputs with --out")
    from kinprop.analysis.metrics import METRICS, metric_unit

    units = dict(res.frame.attrs.get("units", {}))
    length = res.last.units.get("length", "m") if res.last is not None else "m"
    for c in [x, *ys]:
        short = c.rsplit(".", 1)[-1]
        if c not in units and short in METRICS:
            units[c] = metric_unit(short, length)
    frames = (("before", base.frame), ("after", res.frame)) if base is not None else (("sweep", res.frame),)
    ok = {k: f[f["status"] == "converged"] for k, f in frames}
    plot_curves(ok, x, ys, units=units, title=title, path=path)


@app.command(name="sweep")
@handles_user_errors
def sweep_cmd(
    model: Annotated[Path, typer.Argument(help="model file (YAML or JSON)")],
    drive: Annotated[
        list[str],
        typer.Option(
            "--drive",
            metavar="JOINT=START:STOP:STEPS",
            help="JOINT=START:STOP:STEPS (STEPS+1 values), JOINT=v1,v2,... or JOINT=@FILE.csv[:COL] (a CSV "
            "column, by name or 0-based index); model units; repeat to drive together. JOINT may also be "
            "travel (wheel travel: equal length steps), travel:WHEEL, roll (an axle's body roll) or steer:WHEEL "
            "(a road-wheel steer angle)",
        ),
    ],
    set_: Annotated[
        list[str] | None,
        typer.Option("--set", metavar="ADDRESS=VALUE", help="ADDRESS=VALUE design change applied at step 0"),
    ] = None,
    free: FreeOption = None,
    hold_: HoldOption = None,
    outputs: Annotated[
        list[str] | None,
        typer.Option(
            "--out",
            metavar="NAME",
            help="output names (point:BODY.NAME, body:BODY (its pose), distance:A,B, metric:WHEEL.camber, J.q ...); "
            "default: named points and metrics",
        ),
    ] = None,
    output: Annotated[
        Path | None, typer.Option("-o", "--output", help="results.csv or results.parquet, written as computed")
    ] = None,
    plot: Annotated[
        Path | None, typer.Option("--plot", help="plot the swept coordinates and outputs (PNG, PDF, SVG)")
    ] = None,
    continuation: Annotated[bool, typer.Option("--continuation", help="retry a failed step by continuation")] = False,
    baseline: Annotated[
        bool,
        typer.Option(
            "--baseline",
            help="also sweep the design without --set; --plot draws both, -o NAME.csv also writes NAME.baseline.csv",
        ),
    ] = False,
    x: Annotated[
        str | None, typer.Option("--x", help="abscissa of the --plot curves (an output, e.g. wheel_centre_dz)")
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="print one JSON object (summary and every row)")] = False,
    tol: Annotated[float, typer.Option("--tol", help="stop when ||Phi||_2 < TOL")] = 1e-10,
    max_iter: Annotated[int, typer.Option("--max-iter", help="maximum Newton iterations per step")] = 50,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="no table, no progress bar")] = False,
) -> None:
    """Drive joint coordinates over a range; each step is solved from the previous one."""
    check_tol(tol)
    check_int("--max-iter", max_iter, 1, MAX_ITER)
    check_suffix("-o", output, (".csv", ".parquet", ".pq"))
    check_suffix("--plot", plot, (".png", ".pdf", ".svg"))
    base_output = baseline_path(output) if baseline and output is not None else None
    check_outputs([model], [("-o", output), ("-o (baseline)", base_output), ("--plot", plot)])
    given = parse_assignments("--set", set_)
    check_set_not_free(given, free)
    if baseline and not given:
        raise ValueError("--baseline compares with the design before the --set changes: give at least one --set")
    if x is not None and plot is None:
        raise ValueError("--x sets the abscissa of the --plot figure: give --plot too")
    require("pandas")
    if output is not None and output.suffix.lower() != ".csv":
        require("pyarrow")
    if plot is not None:
        require("matplotlib")
    m = hold(load_model_cli(model), hold_ or [])  # held like declared inputs
    m, given = with_element_sets(m, given)  # element points: the model's, no body moves
    drives = [parse_drive(m, d) for d in drive]
    changes = changes_to_internal(m, given)
    if x is not None:
        check_x(m, drives, outputs, x)
    quiet = quiet or as_json
    n = max(d.values.size for d in drives)
    show = not quiet and n >= PROGRESS_FROM
    progress = Progress(
        TextColumn("sweep"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("{task.fields[failed]} failed"),
        TimeRemainingColumn(),
        console=err,
        transient=True,
        disable=not show,
    )
    failed = done = 0
    with progress:
        task = progress.add_task("sweep", total=n, failed=0)

        def on_step(k: int, total: int, row) -> None:
            nonlocal failed, done
            failed += row["status"] != "converged"
            done += 1
            progress.update(task, advance=1, failed=failed)

        try:
            res = sweep(
                m,
                drives,
                changes=changes,
                free=tuple(free or ["q"]),
                outputs=outputs,
                tol=tol,
                max_iter=max_iter,
                output=output,
                on_step=on_step,
                continuation=continuation,
                units="solver",  # changes converted above
            )
        except (KeyboardInterrupt, SystemError) as exc:
            if not is_interrupt(exc):
                raise
            where = f"; rows computed so far are in {output}" if output is not None else ""
            err.print(f"interrupted after {done} of {n} steps ({failed} failed){where}")
            raise typer.Exit(interrupt_status(exc)) from None
    base = None
    if baseline:
        base = sweep(
            m, drives, free=tuple(free or ["q"]), outputs=outputs, tol=tol, max_iter=max_iter,
            continuation=continuation, output=base_output,
        )  # fmt: skip
    df = res.frame
    label_units(res, base)
    if as_json:
        print_json(
            sweep_json(res, base, output, plot, x) | ({"baseline_file": str(base_output)} if base_output else {})
        )
    if not quiet:
        terminal = out.is_terminal  # a pipe gets every row and every varying column
        shown = _shown_columns(res, outputs, 10 if terminal else None)
        out.print(_table(df, shown, 24 if terminal else None))
    bad = df[df["status"] != "converged"]
    near = int(df["near_singular"].sum())
    say = err.print if as_json else out.print
    say(
        f"{len(df)} steps: {len(df) - len(bad)} converged, {len(bad)} failed"
        + (f", {near} near-singular" if near else "")
    )
    if len(bad):
        first = bad.iloc[0]
        label = res.drives[0].label
        why = str(first["message"])
        say(f"first failure at step {int(first['step'])} ({label} = {first[label]:g}): {why}", style="red")
    if output is not None:
        say(
            f"wrote {output}"
            + (f" (with the --set changes) and {base_output} (the baseline, without)" if base_output else "")
        )
    if plot is not None:
        if base is None and x is None:
            plot_sweep(res, plot, title=f"sweep {model.name}")
        elif base is None:  # the outputs against another output, e.g. camber and toe against travel
            _plot_before_after(None, res, plot, x, title=f"sweep {model.name}")
        else:
            _plot_before_after(base, res, plot, x, title=f"sweep {model.name}: before and after {', '.join(changes)}")
        say(f"wrote {plot}")
    if len(bad):
        raise typer.Exit(EXIT_NOT_CONVERGED)
