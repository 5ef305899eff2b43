"""``kinprop report``: one self-contained HTML file with a model's hardpoints and default charts."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from kinprop.cli.app import EXIT_NOT_CONVERGED, app, err, handles_user_errors, load_model_cli, out, require_plot
from kinprop.cli.checks import check_outputs, check_suffix


@app.command(name="report")
@handles_user_errors
def report_cmd(
    model: Annotated[Path, typer.Argument(help="model file (YAML or JSON)")],
    output: Annotated[Path, typer.Option("-o", "--output", help="FILE.html (self-contained, no network)")],
    title: Annotated[str | None, typer.Option("--title", help="page title (default: the file name)")] = None,
) -> None:
    """Write a self-contained HTML report: the global hardpoints and the default curves.

    The model is assembled first (free: q), as `kinprop serve` does; the hardpoint table is the
    workbench's (chassis pickups, upright points, links and steering, spring and damper, wheel)
    and the curves its default ones (the first input over its default range: camber and toe
    when the model declares a wheel), with their numbers. The file is written atomically.
    """
    check_suffix("-o", output, (".html",))
    check_outputs([model], [("-o", output)])
    require_plot(output)
    from kinprop.io.writer import atomic_write
    from kinprop.plot.report import report_html
    from kinprop.propagation import assemble

    m = load_model_cli(model)
    prop = assemble(m)
    if not prop.converged:
        err.print(f"error: {model}: cannot assemble the model: {prop.result.message}", soft_wrap=True)
        raise typer.Exit(EXIT_NOT_CONVERGED)
    atomic_write(output, report_html(prop.after, title or f"kinprop report: {model}"))
    out.print(f"wrote {output}", soft_wrap=True)
