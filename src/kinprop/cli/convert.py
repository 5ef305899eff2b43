"""``kinprop convert``: frame-style and hardpoint-style model files, both ways."""

from __future__ import annotations

import json
import sys
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any

import typer

from kinprop.cli.app import app, err, handles_user_errors, load_model_cli, out
from kinprop.cli.checks import check_outputs, check_suffix
from kinprop.io import model_to_data
from kinprop.io.hardpoints import joint_mismatch, model_to_hardpoints
from kinprop.io.writer import atomic_write, yaml_text

#: a cut joint whose two sides are farther apart than this is reported as not assembled
MISMATCH_TOL = 1e-9


class Style(StrEnum):
    hardpoints = "hardpoints"
    frames = "frames"
    mjcf = "mjcf"


class BodyFrames(StrEnum):
    global_ = "global"
    joint = "joint"


def dump_text(data: dict[str, Any], path: Path | None) -> str:
    """JSON for ``*.json``, else YAML (leaf lists inline), floats at full precision."""
    if path is not None and path.suffix == ".json":
        return json.dumps(data, indent=2) + "\n"
    return yaml_text(data, width=120)


@app.command()
@handles_user_errors
def convert(
    model: Annotated[Path, typer.Argument(help="model file (YAML or JSON), either style")],
    to: Annotated[Style, typer.Option("--to", help="style to write")],
    output: Annotated[Path | None, typer.Option("-o", "--output", help="file to write (default: stdout)")] = None,
    body_frames: Annotated[
        BodyFrames, typer.Option("--body-frames", help="hardpoints: body-frame rule written into the file")
    ] = BodyFrames.global_,
) -> None:
    """Convert a model between frame style (s', C, q) and hardpoint style (global points and axes),
    or write it as a kinematic MuJoCo MJCF file (--to mjcf; at the model's coordinates).

    To hardpoints, the joints' global points and axes are evaluated at the model's current
    coordinates (run ``kinprop assemble -o`` first if the model is not assembled). To frames,
    body frames, s', C and zero coordinates are derived from the hardpoints.
    """
    check_suffix("-o", output, (".xml", ".mjcf") if to is Style.mjcf else (".yaml", ".yml", ".json"))
    check_outputs([model], [("-o", output)])
    m = load_model_cli(model)
    if to is Style.mjcf:
        from kinprop.imports.mjcf_export import model_to_mjcf

        text, warnings = model_to_mjcf(m)
        for w in warnings:
            err.print(f"warning: {model}: {w}", soft_wrap=True, markup=False)
        if output is None:
            sys.stdout.write(text)
            return
        atomic_write(output, text)
        out.print(f"wrote {output} (kinematic MJCF)")
        return
    if to is Style.hardpoints:
        gaps = {k: v for k, v in joint_mismatch(m).items() if v > MISMATCH_TOL}
        for joint, gap in gaps.items():
            err.print(
                f"warning: {model}: joints.{joint}: not assembled (its rows miss by {gap:.3g}, model units); "
                "the hardpoints keep body i's side (run kinprop assemble first)",
                soft_wrap=True,
            )
        data = model_to_hardpoints(m, body_frames.value)
    else:
        data = model_to_data(m)
    text = dump_text(data, output)
    if output is None:
        sys.stdout.write(text)
        return
    atomic_write(output, text)
    out.print(f"wrote {output} ({to.value} style)")
