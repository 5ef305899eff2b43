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


def test_one_solve_of_a_small_model_imports_neither_numba_nor_scipy(tmp_path) -> None:
    """``kinprop propagate`` of the slider-crank with a complete kernel cache runs its kernels
    uncompiled (kinprop.jit's rule for one solve of a small model): numba and scipy are not
    imported (``--json`` still imports ``scipy.spatial`` for rotation vectors), and the answer
    is the solver's (the numbers are compared with the compiled kernels' in
    tests/cli/test_first_run.py)."""
    from kinprop.jit import kernel_version
    from kinprop.resources import examples_dir

    folder = tmp_path / "cache" / kernel_version()
    folder.mkdir(parents=True)
    (folder / "complete").write_text("test\n")
    slider = str(examples_dir() / "slider_crank.yaml")
    env = {k: v for k, v in os.environ.items() if k not in ("KINPROP_JIT", "NUMBA_DISABLE_JIT")}
    args = ["propagate", slider, "--set", "J12.s_j=-2.8,0.2,0.1", "--free", "q"]
    p = subprocess.run(
        [sys.executable, "-X", "importtime", "-m", "kinprop", *args],
        capture_output=True,
        text=True,
        env=env | {"KINPROP_CACHE_DIR": str(tmp_path / "cache")},
        timeout=120,
    )
    assert p.returncode == 0, p.stderr[-2000:]
    modules = {line.rsplit("|", 1)[-1].strip() for line in p.stderr.splitlines() if line.startswith("import time:")}
    assert "kinprop.engine.engine" in modules
    assert not {m for m in modules if m.split(".")[0] in ("numba", "llvmlite", "scipy")}
    assert "converged in 7 iterations" in p.stdout and "44.89893" in p.stdout  # J01.q in degrees


@pytest.mark.parametrize(
    ("mode", "one_solve", "size", "warm", "expected"),
    [
        ("auto", True, 4, True, "python"),  # the slider-crank: uncompiled even with a complete cache
        ("auto", True, 20, True, "python"),
        ("auto", True, 21, True, "compiled"),  # a larger model: the cache pays for itself
        ("auto", True, 21, False, "python"),  # no complete cache: never wait for a compile
        ("auto", True, None, True, "compiled"),  # a kernel before any model: the cache's rule
        ("auto", False, 4, True, "compiled"),  # other commands: compiled when the cache is complete
        ("auto", False, 4, False, "python"),
        ("on", True, 4, False, "compiled"),  # KINPROP_JIT overrides the rule
        ("off", False, 100, True, "python"),
    ],
)
def test_the_rule_of_kinprop_jit(monkeypatch, mode, one_solve, size, warm, expected) -> None:
    """``kinprop.jit.wanted`` (docs/architecture.md, "Compilation and the cache")."""
    from kinprop import jit

    monkeypatch.setattr(jit, "MODE", mode)
    monkeypatch.setattr(jit, "one_solve", one_solve)
    monkeypatch.setattr(jit, "_model_size", size)
    monkeypatch.setattr(jit, "is_warm", lambda: warm)
    assert jit.SMALL_MODEL == 20
    assert jit.wanted() == expected
