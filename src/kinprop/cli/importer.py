"""``kinprop import``: MuJoCo MJCF and Project Chrono suspension files as kinprop model files."""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from kinprop.cli.app import app, err, fail, handles_user_errors, out, warn_scales
from kinprop.cli.convert import dump_text
from kinprop.io import model_to_data
from kinprop.io.writer import atomic_write
from kinprop.topology import build_topology


def _rounded(data: object) -> object:
    """Floats at 15 significant digits of their vector's largest component: the importers'
    unit and frame arithmetic leaves noise in the last digit (-0.04000000000000001) that the
    source file never had."""
    if isinstance(data, float):
        return float(f"{data:.15g}") + 0.0
    if isinstance(data, dict):
        return {k: _rounded(v) for k, v in data.items()}
    if isinstance(data, list):
        if data and all(isinstance(v, float) for v in data):
            scale = max(abs(v) for v in data)
            if scale > 0 and math.isfinite(scale):
                places = max(0, 14 - math.floor(math.log10(scale)))
                return [float(f"{v:.{places}f}") + 0.0 for v in data]
        return [_rounded(v) for v in data]
    return data


@app.command(name="import")
@handles_user_errors
def import_cmd(
    source: Annotated[Path, typer.Argument(help="MJCF file (.xml) or Project Chrono suspension file (.json)")],
    output: Annotated[
        Path | None, typer.Option("-o", "--output", help="model file to write (.yaml or .json; default: stdout)")
    ] = None,
    keyframe: Annotated[
        str | None, typer.Option("--keyframe", help="MJCF: start from this <key>'s qpos (default: the reference)")
    ] = None,
    tire_radius: Annotated[
        float | None,
        typer.Option(
            "--tire-radius", help="Chrono: loaded tyre radius in metres (Chrono's unit), adds the contact patch"
        ),
    ] = None,
) -> None:
    """Read another tool's mechanism file and write it as a kinprop model file.

    MJCF: bodies, joints and <equality> connect/weld loop closures (frame style, coordinates
    zero at MuJoCo's reference configuration). Chrono: DoubleWishbone, MacPhersonStrut and
    MultiLink suspensions, left side, as a hardpoint-style file with the wheel declared for the
    suspension metrics. Anything ignored is one 'note:' line on stderr.
    """
    if output is not None and output.suffix.lower() not in (".yaml", ".yml", ".json"):
        fail(f"--output {str(output)!r}: expected a .yaml or .json file (MJCF out: kinprop convert --to mjcf)")
    suffix = source.suffix.lower()
    if suffix == ".json":
        if keyframe is not None:
            fail(f"{source}: --keyframe applies to MJCF files only")
        from kinprop.imports.chrono import chrono_hardpoints
        from kinprop.io.hardpoints import model_from_hardpoints
        from kinprop.io.loader import parse_text

        try:
            text = source.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            fail(f"{source}: file: cannot read: {getattr(exc, 'strerror', None) or exc}")
        data = parse_text(text, str(source))  # syntax errors and duplicate names: located errors
        file_data, notes = chrono_hardpoints(data, str(source), tire_radius)
        model = model_from_hardpoints(file_data, str(source))  # validates what is written
    elif suffix in (".xml", ".mjcf"):
        if tire_radius is not None:
            fail(f"{source}: --tire-radius applies to Chrono suspension files only")
        from kinprop.imports.mjcf import document_to_model, read_mjcf

        doc = read_mjcf(source)
        model = document_to_model(doc, keyframe)
        file_data, notes = model_to_data(model), doc.notes
    else:
        fail(f"{source}: expected an MJCF (.xml) or Project Chrono suspension (.json) file, found {suffix or 'none'!r}")
    for note in notes:
        err.print(escape(f"note: {source}: {note}"), soft_wrap=True)
    warn_scales(model, source)
    text = dump_text(_rounded(file_data), output)
    if output is None:
        sys.stdout.write(text)
        return
    atomic_write(output, text)
    mech = model.mechanism
    cut = build_topology(mech).cut_joints
    nc = len(mech.couplings)
    couplings = f", {nc} coupling{'s' if nc > 1 else ''}: {', '.join(c.name for c in mech.couplings)}" if nc else ""
    out.print(
        escape(
            f"wrote {output}: {len(mech.bodies)} bodies, {len(mech.joints)} joints ({len(cut)} cut: {', '.join(cut)})"
            + couplings
        ),
        soft_wrap=True,
    )
