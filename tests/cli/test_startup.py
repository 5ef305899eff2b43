"""Start-up of the command line (issue 24, item 6): ``kinprop --help`` and ``--version`` import
neither numba nor the library, and the list ``kinprop --help`` prints without loading the
commands is the commands' own. The times are measured by benchmarks/cold_start.py, not here."""

from __future__ import annotations

import inspect
import os
import subprocess
import sys

import pytest
import typer

from kinprop.cli import COMMANDS, app, load_commands


def _imported(*args: str) -> tuple[subprocess.CompletedProcess[str], set[str]]:
    """Run ``python -m kinprop ARGS`` with ``-X importtime``: the process and the modules it imported."""
    env = {k: v for k, v in os.environ.items() if k not in ("KINPROP_JIT", "NUMBA_DISABLE_JIT")}
    p = subprocess.run(
        [sys.executable, "-X", "importtime", "-m", "kinprop", *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=60,
    )
    modules = {line.rsplit("|", 1)[-1].strip() for line in p.stderr.splitlines() if line.startswith("import time:")}
    return p, modules


@pytest.mark.parametrize("args", [["--help"], ["--version"], [], ["propagate", "--help"]])
def test_answers_without_the_library_or_numba(args) -> None:
    p, modules = _imported(*args)
    assert p.returncode == (2 if not args else 0), p.stderr[-2000:]
    assert "kinprop.cli.app" in modules  # the measurement sees kinprop's own imports
    heavy = {"numba", "numpy", "kinprop.engine", "kinprop.jit", "kinprop.io", "scipy", "networkx"}
    if args[:1] == ["propagate"]:  # a command's own help loads its module (and so the library), never compiles
        assert "kinprop.cli.checks" in modules and "background" not in p.stderr
        assert "--set ADDRESS=VALUE" in p.stdout
        return
    assert not heavy & modules, sorted(heavy & modules)
    assert not any(m.startswith("kinprop.cli.") and m != "kinprop.cli.app" for m in modules), sorted(modules)
    if args == ["--version"]:
        assert p.stdout.startswith("kinprop ")
    else:
        shown = p.stdout or p.stderr  # ``kinprop`` alone prints the help on stderr (exit 2)
        listed = [line.split()[0] for line in shown.split("Commands:")[1].splitlines() if line.strip()]
        assert listed == list(COMMANDS)


def test_the_command_table_is_the_commands_own() -> None:
    """:data:`kinprop.cli.COMMANDS` names each registered command, its module and its help line
    (a new command, or a changed first line of a command's docstring, goes into that table)."""
    load_commands()
    registered = {}
    for info in app.registered_commands:
        name = info.name or typer.main.get_command_name(info.callback.__name__)
        registered[name] = info
    assert set(registered) == set(COMMANDS), "add every command to kinprop.cli.app.COMMANDS"
    for name, (module, text) in COMMANDS.items():
        info = registered[name]
        assert info.callback.__module__ == module, name
        first = inspect.getdoc(info.callback).split("\n\n")[0]
        assert " ".join(first.split()) == text, name
