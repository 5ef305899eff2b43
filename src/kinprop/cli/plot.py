"""``kinprop plot``: a 3D stick figure of a model, optionally over another one (before/after)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer

from kinprop.analysis.statics import statics
from kinprop.cli.app import EXIT_NOT_CONVERGED, app, err, fail, handles_user_errors, load_model_cli, out, require_plot
from kinprop.cli.checks import check_outputs, check_suffix
from kinprop.engine import compile as compile_engine
from kinprop.model import Model

#: ||Phi|| above which a drawn model is flagged as not assembled
DRAW_NOTE_TOL = 1e-6

View = Annotated[str, typer.Option("--view", help="camera ELEV,AZIM in degrees (PNG only)")]


def parse_view(text: str) -> tuple[float, float]:
    try:
        elev, azim = (float(x) for x in text.split(","))
    except ValueError:
        raise ValueError(f"--view {text!r}: expected ELEV,AZIM in degrees, e.g. 20,-60") from None
    return elev, azim


def note_if_unassembled(model: Model, path: Path | str) -> None:
    """A stderr note when a model is drawn away from an assembled configuration."""
    eng = compile_engine(model)
    res = float(np.linalg.norm(eng.residual(model.design, model.coordinates) * eng.row_scale))  # SI rows
    if res > DRAW_NOTE_TOL:
        err.print(
            f"note: {path} is drawn at its coordinates as given, not assembled (||Phi|| = {res:.3g}); "
            "run kinprop assemble first for an assembled picture",
            soft_wrap=True,
        )


@app.command(name="plot")
@handles_user_errors
def plot_cmd(
    model: Annotated[Path, typer.Argument(help="model file (YAML or JSON), drawn solid")],
    output: Annotated[Path, typer.Option("-o", "--output", help="FILE.png (matplotlib) or FILE.html (plotly)")],
    compare: Annotated[
        Path | None, typer.Option("--compare", help="another model drawn faded underneath, as 'before'")
    ] = None,
    title: Annotated[str | None, typer.Option("--title", help="figure title (default: the model's name)")] = None,
    view: View = "20,-60",
    load_case: Annotated[
        str | None,
        typer.Option(
            "--load-case",
            help="draw the forces of this load case of the model as arrows "
            "(red tension, blue compression, magenta applied, grey reactions)",
        ),
    ] = None,
) -> None:
    """Draw a 3D stick figure of a model (PNG or interactive HTML).

    Bodies are lines from each body frame to its joints, joints are markers by type, joint
    axes are arrows along z'' (both axes of a universal joint); drawn at the coordinates as given.

    With --compare OTHER, OTHER is drawn faded as 'before' and MODEL solid as 'after' (the
    paper's Figs. 5 and 6).

    With --load-case NAME, the statics of that load case at MODEL's pose (kinprop loads) drawn
    as force arrows on MODEL; the model must be assembled.
    """
    cam = parse_view(view)
    check_suffix("-o", output, (".png", ".html"))
    check_outputs([model, compare], [("-o", output)])
    require_plot(output)
    from kinprop.plot import save_plot

    m = load_model_cli(model)
    note_if_unassembled(m, model)
    before = None
    if compare is not None:
        before = load_model_cli(compare)
        note_if_unassembled(before, compare)
    arrows, force_unit = (), ""
    if load_case is not None:
        from kinprop.plot.forces import force_arrows

        cases = m.loads.cases if m.loads is not None else {}
        if load_case not in cases:
            raise ValueError(f"--load-case {load_case!r}: not a load case of {model}; load cases: "
                             f"{', '.join(cases) or 'none'}")  # fmt: skip
        s = statics(m, load_case)
        if not s.ok:
            fail(f"{model}: no forces to draw: {s.message}", EXIT_NOT_CONVERGED)
        arrows, force_unit = force_arrows(s, cases[load_case]), s.units["force"]
        title = title or f"{m.mechanism.name}: load case {load_case}"
    save_plot(
        output,
        m,
        before,
        label=f"after: {model.name}" if before is not None else model.name,
        before_label=f"before: {compare.name}" if compare is not None else "before",
        title=title,
        view=cam,
        arrows=arrows,
        force_unit=force_unit,
    )
    out.print(f"wrote {output}")
