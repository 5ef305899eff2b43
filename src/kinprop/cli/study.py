"""``kinprop study`` (design of experiments of propagations) and ``kinprop tolerance``.

Exit codes: 0 every variant converged, 1 some variants failed (recorded in the output),
2 invalid input, 130 interrupted (143 after SIGTERM) (finished chunks are kept; ``--resume`` completes the study).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.table import Table

from kinprop.analysis.study import CHUNK_SIZE
from kinprop.cli.app import (
    EXIT_NOT_CONVERGED,
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
    MAX_SAMPLES,
    check_int,
    check_outputs,
    check_set_not_free,
    check_tol,
)
from kinprop.errors import AddressError
from kinprop.io.arguments import parse_assignments
from kinprop.io.commands import with_element_sets
from kinprop.propagation.element_points import is_element_address

Free = Annotated[
    list[str] | None,
    typer.Option("--free", metavar="GROUP|ADDRESS", help="groups (q s C l coef) or addresses; default q"),
]
Sets = Annotated[
    list[str] | None, typer.Option("--set", metavar="ADDRESS=VALUE", help="ADDRESS=VALUE applied to every variant")
]


def _to_internal(model, changes: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    try:
        from kinprop.engine.units import changes_to_internal
    except ImportError:  # pragma: no cover
        return changes
    return changes_to_internal(model, changes)


@app.command(name="study")
@handles_user_errors
def study_cmd(
    model: Annotated[Path, typer.Argument(help="model file (YAML or JSON)")],
    vary: Annotated[
        list[str],
        typer.Option("--vary", metavar="ADDRESS=LOW:HIGH", help="ADDRESS=LOW:HIGH, a scalar (component) address"),
    ],
    output: Annotated[Path, typer.Option("-o", "--output", help="result directory of Parquet parts (results.parquet)")],
    method: Annotated[str, typer.Option("--method", help="grid | lhs | mc")] = "lhs",
    samples: Annotated[int, typer.Option("--samples", help="variants (lhs, mc) or levels per factor (grid)")] = 100,
    seed: Annotated[int, typer.Option("--seed", help="random seed (lhs, mc)")] = 0,
    free: Free = None,
    set_: Sets = None,
    out_names: Annotated[
        list[str] | None,
        typer.Option(
            "--output-name",
            "--out",
            metavar="NAME",
            help="extra outputs (point:, metric:, camber@travel=50, slope:toe@travel=-50..50, ...)",
        ),
    ] = None,
    tol: Annotated[float, typer.Option("--tol", help="stop when ||Phi||_2 < TOL")] = 1e-10,
    max_iter: Annotated[int, typer.Option("--max-iter")] = 50,
    scheduler: Annotated[
        str | None, typer.Option("--scheduler", help="Dask scheduler address, tcp://host:8786")
    ] = None,
    resume: Annotated[bool, typer.Option("--resume", help="complete an interrupted study in OUTPUT")] = False,
    chunk_size: Annotated[
        int | None,
        typer.Option(
            "--chunk-size",
            help=f"variants per chunk (one batch solve, one Parquet part each); default "
            f"{CHUNK_SIZE}, on a cluster about four chunks per worker",
        ),
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="print a JSON summary")] = False,
    engine: Annotated[
        str, typer.Option("--engine", help="auto (compiled when possible), fast (compiled) or reference (numpy)")
    ] = "auto",
) -> None:
    """Run a design study: every variant re-assembled, inputs and results streamed to Parquet."""
    check_tol(tol)
    check_int("--max-iter", max_iter, 1, MAX_ITER)
    check_int("--samples", samples, 1, MAX_SAMPLES)
    if chunk_size is not None:
        check_int("--chunk-size", chunk_size, 1, MAX_SAMPLES)
    if method not in ("grid", "lhs", "mc"):
        raise AddressError(f"--method {method!r}: expected grid, lhs or mc")
    if engine not in ("auto", "fast", "reference"):
        raise AddressError(f"--engine {engine!r}: expected auto, fast or reference")
    check_outputs([model], [("-o", output)], directories=("-o",))
    given = parse_assignments("--set", set_)
    check_set_not_free(given, free)
    require("pandas")
    require("pyarrow")
    if scheduler is not None:
        require("distributed")
    from kinprop.analysis.study import model_unit_scale, parse_vary, run_study, sample_plan
    from kinprop.engine import compile as compile_engine
    from kinprop.propagation.hardpoints import global_plan, is_global, resolve_changes

    parsed = [parse_vary(text) for text in vary]
    seen: dict[str, str] = {}
    for f, text in zip(parsed, vary, strict=True):
        if f.address in seen:
            raise AddressError(f"--vary {text!r}: {f.address} is already varied by --vary {seen[f.address]!r}")
        seen[f.address] = text
        point = f.address.partition("[")[0] if is_element_address(f.address) else None
        if f.address in given or any(a.strip() == point for a in given):  # a whole element point set
            raise AddressError(f"--vary {text!r}: {f.address} is also given by --set")
    if method == "grid":
        sample_plan(parsed, method, samples, seed)  # refuses a huge grid up front, with its count
    m, given = with_element_sets(load_model_cli(model), given)  # element points: the model's
    sets = _to_internal(m, given)
    factors = parsed  # in the model's units, as given; stored as given (scale below)
    # global hardpoints (hardpoint:J.i[z]=LOW:HIGH, --set hardpoint:J=x,y,z): exact s' columns
    compiled = compile_engine(m)
    sets = resolve_changes(compiled, compiled.reference, sets)
    plan = addresses = None
    if any(is_global(f.address.split("[")[0]) for f in factors):
        values = sample_plan(factors, method, samples, seed)
        # element points (element:E.point_i[z]) stay factors of their own: they move no body
        el = [k for k, f in enumerate(factors) if is_element_address(f.address)]
        rest = [k for k in range(len(factors)) if k not in el]
        addresses, plan = global_plan(compiled, compiled.reference, [factors[k].address for k in rest], values[:, rest])
        addresses += [factors[k].address for k in el]
        plan = np.column_stack([plan, values[:, el]])
    try:
        totals = run_study(
            m, factors, method=method, samples=samples, seed=seed, free=tuple(free or ["q"]), sets=sets,
            outputs=out_names, tol=tol, max_iter=max_iter, chunk_size=chunk_size, output=output, resume=resume,
            scheduler=scheduler, progress=not as_json, plan=plan, addresses=addresses, engine=engine,
            scale=model_unit_scale(m, [f.address for f in factors], out_names, compiled), units="solver",
            compiled=compiled, given=None if plan is None else ([f.address for f in factors], values), collect=False,
        )  # fmt: skip
    except (KeyboardInterrupt, SystemError) as exc:
        if not is_interrupt(exc):
            raise
        err.print(f"interrupted: finished chunks are kept in {output!s}; run again with --resume")
        raise typer.Exit(interrupt_status(exc)) from None
    n_failed = totals.failed
    if as_json:
        print_json({"variants": totals.variants, "failed": n_failed, "output": str(output)})
    else:
        out.print(f"{totals.variants} variants, {n_failed} failed; wrote {output!s}/ (read with pandas.read_parquet)")
        if totals.variants:
            out.print(_summary(totals, [f.address for f in factors], out_names or []))
    if n_failed:
        raise typer.Exit(EXIT_NOT_CONVERGED)


def _summary(totals, inputs: list[str], outputs: list[str], limit: int = 12) -> Table:
    """min/mean/max of the converged variants: the factors, the requested outputs (all of
    them), iterations and residual, then up to ``limit`` other columns, each once."""
    t = Table(title="study summary (converged variants)", title_justify="left")
    for c in ("column", "min", "mean", "max"):
        t.add_column(c, justify="left" if c == "column" else "right")
    columns = list(totals.columns)
    asked = [c for o in outputs for c in columns if c == o or c.startswith(f"{o}[")]
    head = [*inputs, *asked, "iterations", "residual"]
    rest = [c for c in columns if c not in head][:limit]
    for c in dict.fromkeys(head + rest):
        row = totals.summary(c)
        if row is not None:
            t.add_row(c, *(f"{x:.6g}" for x in row))
    return t


@app.command(name="tolerance")
@handles_user_errors
def tolerance_cmd(
    model: Annotated[Path, typer.Argument(help="model file (YAML or JSON)")],
    tolerance: Annotated[
        list[str], typer.Option("--tolerance", metavar="ADDRESS=SIGMA", help="ADDRESS=SIGMA (standard deviation)")
    ],
    of: Annotated[
        list[str], typer.Option("--of", metavar="NAME", help="output: a coordinate (J32.q[1]) or point:/metric: name")
    ],
    free: Free = None,
    set_: Sets = None,
    mc: Annotated[int, typer.Option("--mc", help="also run a Monte Carlo study of N samples to compare")] = 0,
    seed: Annotated[int, typer.Option("--seed")] = 0,
    as_json: Annotated[bool, typer.Option("--json", help="print one JSON object")] = False,
) -> None:
    """Linearised output standard deviations from design-variable tolerances (sensitivity matrix)."""
    from kinprop.analysis.tolerance import monte_carlo, tolerance_analysis
    from kinprop.propagation import propagate

    check_int("--mc", mc, 0, MAX_SAMPLES)
    if mc:
        require("pandas")  # the Monte Carlo comparison runs as a design study
    given = parse_assignments("--set", set_)
    check_set_not_free(given, free)
    tols = {}
    for addr, vals in parse_assignments("--tolerance", tolerance).items():
        if vals.size != 1 or not vals[0] > 0:
            raise AddressError(f"--tolerance {addr}: expected one positive standard deviation")
        tols[addr] = float(vals[0])
    m, given = with_element_sets(load_model_cli(model), given)  # element points: the model's
    sets = _to_internal(m, given)
    freeset = tuple(free or ["q"])
    if sets:
        prop = propagate(m, sets, freeset, units="solver")
        if not prop.converged:
            err.print(f"the model does not assemble with --set: {prop.result.message}")
            raise typer.Exit(EXIT_NOT_CONVERGED)
        m = prop.after
    # sigmas as given and everything reported in the model's units (docs/units.md)
    res = tolerance_analysis(m, tols, of, free=freeset, fixed=tuple(sets))
    mc_std = monte_carlo(m, tols, res.outputs, n=mc, seed=seed, free=freeset, fixed=tuple(sets)) if mc else None
    nominal, std, cov, sigma = res.nominal, res.std, res.covariance, res.sigma
    units = list(res.output_units)
    if as_json:
        obj = {"outputs": res.outputs, "nominal": nominal.tolist(), "std": std.tolist(),
               "covariance": cov.tolist(), "inputs": res.inputs, "sigma": sigma.tolist(),
               "units": {"outputs": units, "inputs": list(res.input_units),
                         "length": m.units.get("length"), "angle": m.units.get("angle")}}  # fmt: skip
        if mc_std is not None:
            obj["mc_std"] = mc_std.tolist()
        print_json(obj)
        return
    t = Table(title=f"tolerance analysis of {model!s} (linearised)", title_justify="left")
    for c in ("output", "unit", "nominal", "std", *(["MC std", "MC / linear"] if mc_std is not None else [])):
        t.add_column(c, justify="left" if c in ("output", "unit") else "right")
    for k, name in enumerate(res.outputs):
        cells = [name, units[k], f"{nominal[k] + 0.0:.7g}", f"{std[k]:.4g}"]  # + 0.0: no "-0"
        if mc_std is not None:
            cells += [f"{mc_std[k]:.4g}", f"{mc_std[k] / res.std[k]:.3f}" if res.std[k] > 0 else "-"]
        t.add_row(*cells)
    out.print(t)
