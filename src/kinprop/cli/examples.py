"""``kinprop examples``: the example models shipped with kinprop, and a copy to work on."""

from __future__ import annotations

import ast
import json
import re
import shutil
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from kinprop.cli.app import app, handles_user_errors, out
from kinprop.errors import AddressError
from kinprop.resources import examples_dir

#: the end of a sentence: a full stop (not inside a number or a file name) before a space
_SENTENCE_END = re.compile(r"(?<=[.!?])\s+(?=[A-Z(`\"'])")


#: a first sentence longer than this is shown up to its first colon (a whole clause)
SUMMARY_CHARS = 120


def first_sentence(text: str) -> str:
    """The first sentence of ``text`` (its lines joined), whole: never cut inside a word; a long
    one up to its first colon (``Front axle with a steering rack: ...``)."""
    flat = " ".join(text.split())
    sentence = _SENTENCE_END.split(flat, maxsplit=1)[0]
    if len(sentence) <= SUMMARY_CHARS:
        return sentence
    depth = 0
    for k, ch in enumerate(sentence):  # the first colon outside parentheses
        depth += {"(": 1, ")": -1}.get(ch, 0)
        if depth == 0 and sentence.startswith(": ", k):
            return sentence[:k]
    return sentence


def _summary(path: Path) -> str:
    """What an example is: the first sentence of a model's leading comment, of a script's
    docstring, a Markdown file's title; another tool's file says which tool and template."""
    text = path.read_text(encoding="utf-8")
    if path.suffix == ".json":
        try:
            data = json.loads(text)
        except ValueError:
            data = {}
        data = data if isinstance(data, dict) else {}
        name = f" {data['Name']!r}" if "Name" in data else ""
        return f"Project Chrono {data.get('Template', '')} suspension{name} (kinprop import)".replace("  ", " ")
    if path.suffix == ".xml":
        return "MuJoCo MJCF (kinprop import)"
    if path.suffix == ".py":
        try:
            doc = ast.get_docstring(ast.parse(text)) or ""
        except SyntaxError:
            doc = ""
        return first_sentence(doc.split("\n\n")[0])
    lines = []
    for line in text.splitlines():
        if line.startswith("#"):
            lines.append(line.lstrip("#").strip())
            if path.suffix == ".md":  # a Markdown file's title
                break
        elif line.strip() or lines:
            break
    return first_sentence(" ".join(lines))


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
