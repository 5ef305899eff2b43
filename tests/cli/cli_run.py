"""Run ``kinprop`` in a fresh process under a memory limit and a timeout (issue 11)."""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
from collections.abc import Sequence
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


#: the child of :func:`run_kinprop_cases`: each case through typer's CliRunner, under an alarm;
#: ``warnings.catch_warnings`` per case, so each case shows its warnings as a fresh process would
_CASES_CHILD = r"""
import json, signal, sys, traceback, warnings
from typer.testing import CliRunner
from kinprop.cli import app

class TimedOut(BaseException):
    pass

def alarm(signum, frame):
    raise TimedOut

signal.signal(signal.SIGALRM, alarm)
cases, each = json.load(sys.stdin), int(sys.argv[1])
out = []
for argv in cases:
    with warnings.catch_warnings():
        signal.alarm(each)
        try:
            r = CliRunner().invoke(app, argv, prog_name="kinprop")
            row = [r.exit_code, r.stdout, r.stderr]
            if r.exception is not None and not isinstance(r.exception, SystemExit):
                row[2] += "".join(traceback.format_exception(r.exception))
        except TimedOut:
            row = [None, "", f"timed out after {each} s"]
        finally:
            signal.alarm(0)
    out.append(row)
sys.stdout.write(json.dumps(out))
"""


def run_kinprop_cases(
    cases: Sequence[Sequence[object]], timeout: int = 90, env: dict[str, str] | None = None
) -> list[subprocess.CompletedProcess[str]]:
    """Each of ``cases`` (argument lists) as ``kinprop ARGS``, all in ONE fresh process limited
    to :data:`MEMORY_LIMIT` (with ``env`` added to its environment), each case stopped after
    ``timeout`` seconds (exit code None): a bounded run without an interpreter, the library's
    imports and its kernels per case."""
    p = subprocess.run(
        [sys.executable, "-c", _CASES_CHILD, str(timeout)],
        input=json.dumps([[str(a) for a in args] for args in cases]),
        capture_output=True,
        text=True,
        timeout=timeout * len(cases) + 120,
        preexec_fn=_limit_memory,
        env={k: v for k, v in os.environ.items() if k != "FORCE_COLOR"} | (env or {}),
    )
    assert p.returncode == 0, p.stderr[-3000:]
    return [
        subprocess.CompletedProcess(["kinprop", *map(str, args)], code, stdout, stderr)
        for args, (code, stdout, stderr) in zip(cases, json.loads(p.stdout), strict=True)
    ]


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
