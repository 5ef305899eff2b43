"""Run ``kinprop`` in a fresh process under a memory limit and a timeout (issue 11)."""

from __future__ import annotations

import os
import resource
import subprocess
import sys
from pathlib import Path

#: address-space limit of a child process: runaway memory fails fast instead of swapping
MEMORY_LIMIT = 4_000_000_000


def _limit_memory() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))


def kinprop_cmd(*args: object) -> list[str]:
    return [sys.executable, "-c", "from kinprop.cli import main; main()", *map(str, args)]


def run_kinprop(
    *args: object, timeout: float = 120, env: dict[str, str] | None = None, cwd: str | Path | None = None
) -> subprocess.CompletedProcess[str]:
    """``python -m kinprop ARGS`` with :data:`MEMORY_LIMIT` and ``timeout`` (raises on timeout)."""
    full_env = {**os.environ, **(env or {})}
    full_env.pop("FORCE_COLOR", None)
    return subprocess.run(
        kinprop_cmd(*args),
        capture_output=True,
        text=True,
        timeout=timeout,
        preexec_fn=_limit_memory,
        env=full_env,
        cwd=cwd,
    )


def invoke_kinprop(*args: object) -> subprocess.CompletedProcess[str]:
    """``kinprop ARGS`` in this process (typer's CliRunner: the kernels already compiled, no
    new interpreter), as a CompletedProcess; for checks of what a command prints and its exit
    code. A process of its own (:func:`run_kinprop`) when the process is the point: memory
    limits, signals, pipes, the entry point."""
    from typer.testing import CliRunner

    from kinprop.cli import app

    r = CliRunner().invoke(app, [str(a) for a in args], prog_name="kinprop")
    if r.exception is not None and not isinstance(r.exception, SystemExit):
        raise r.exception
    return subprocess.CompletedProcess(["kinprop", *map(str, args)], r.exit_code, r.stdout, r.stderr)


def one_error_line(p: subprocess.CompletedProcess[str]) -> str:
    """The single ``error: ...`` line of an invalid-input run (exit 2, nothing else on stderr)."""
    assert p.returncode == 2, (p.returncode, p.stdout[-2000:], p.stderr[-2000:])
    assert "Traceback" not in p.stderr, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), p.stderr
    return lines[0]
