"""``kinprop examples``: the example models shipped with kinprop, and a copy to work on."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from kinprop.cli.app import app, handles_user_errors, out
from kinprop.errors import AddressError
from kinprop.resources import examples_dir


def _summary(path: Path) -> str:
    """The first comment line of an example file (another tool's file: which tool)."""
    if path.suffix in (".json", ".xml"):
        return f"{'Project Chrono suspension' if path.suffix == '.json' else 'MuJoCo MJCF'} (kinprop import)"
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.startswith("#"):
            return line.lstrip("# ").strip()
        if line.strip():
            break
    return ""


#: the files ``kinprop examples`` lists and copies (setup.py ships the same)
EXAMPLE_SUFFIXES = (".yaml", ".yml", ".json", ".xml", ".py", ".md")


@app.command(name="examples")
@handles_user_errors
def examples_cmd(
    copy: Annotated[
        Path | None, typer.Option("--copy", help="copy the example files into this (existing or new) directory")
    ] = None,
) -> None:
    """List the example models (the paper's mechanisms and more), or copy them to a directory.

    The README's commands use ``examples/...``: after a plain ``pip install kinprop``, run
    ``kinprop examples --copy examples`` first.
    """
    src = examples_dir()
    # the models and scripts, and other tools' files in examples/chrono and examples/mjcf
    files = sorted(
        p for p in src.rglob("*") if p.is_file() and p.suffix in EXAMPLE_SUFFIXES and "__pycache__" not in p.parts
    )
    if copy is None:
        t = Table(title=f"example models in {src}", title_justify="left")
        t.add_column("file")
        t.add_column("what")
        for p in files:
            t.add_row(p.relative_to(src).as_posix(), _summary(p))
        out.print(t)
        return
    if copy.exists() and not copy.is_dir():
        raise AddressError(f"--copy {str(copy)!r}: exists and is not a directory")
    clash = [p.relative_to(src).as_posix() for p in files if (copy / p.relative_to(src)).exists()]
    if clash:
        raise AddressError(f"--copy {str(copy)!r}: would overwrite {', '.join(clash)}; choose an empty directory")
    copy.mkdir(parents=True, exist_ok=True)
    for p in files:
        dest = copy / p.relative_to(src)
        dest.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(p, dest)
    out.print(f"copied {len(files)} example files to {copy}")
