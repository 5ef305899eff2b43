"""Shared fixtures (paths to the shipped examples) and the suite's time report.

At the end of every run the terminal summary lists the seconds spent per test file and the
numba compiles of the run by entry point (compiled here, not loaded from the kernel cache);
docs/testing.md has the budget these figures are read against. Nothing here asserts a time.
"""

from __future__ import annotations

import os
import time
from collections import defaultdict
from pathlib import Path

import pytest

# command-line runs in tests compile (deterministic); tests/cli/test_first_run.py covers "auto"
os.environ.setdefault("KINPROP_JIT", "on")

import kinprop.jit  # sets the kernel cache before numba is imported

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"

#: seconds per test file (setup + call + teardown of its tests)
FILE_SECONDS: dict[str, float] = defaultdict(float)
#: top-level numba compiles of this process (loads from the kernel cache are not compiles):
#: (function, argument types, seconds)
COMPILES: list[tuple[str, str, float]] = []


def _listen_to_numba() -> None:
    """Record every top-level ``numba:compile`` event (numba sends none for a cache load)."""
    from numba.core import event

    class _Compiles(event.Listener):
        def __init__(self) -> None:
            self.started: list[float] = []

        def on_start(self, ev: event.Event) -> None:
            self.started.append(time.perf_counter())

        def on_end(self, ev: event.Event) -> None:
            t0 = self.started.pop()
            if not self.started:  # nested compiles are part of their caller's
                d = ev.data["dispatcher"]
                name = f"{d.py_func.__module__}.{d.py_func.__qualname__}"
                COMPILES.append((name, str(ev.data.get("args")), time.perf_counter() - t0))

    event.register("numba:compile", _Compiles())


if kinprop.jit.JIT:
    _listen_to_numba()


@pytest.fixture(scope="session")
def examples() -> Path:
    return EXAMPLES


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    FILE_SECONDS[report.nodeid.split("::")[0]] += report.duration


def pytest_terminal_summary(terminalreporter, exitstatus: int, config: pytest.Config) -> None:
    tr = terminalreporter
    if FILE_SECONDS:
        total = sum(FILE_SECONDS.values())
        tr.write_sep("-", f"seconds per test file (total {total:.0f} s; budget in docs/testing.md)")
        for path, sec in sorted(FILE_SECONDS.items(), key=lambda x: -x[1])[:25]:
            tr.write_line(f"{sec:8.1f}  {path}")
    if COMPILES:
        by_name: dict[str, list[float]] = defaultdict(list)
        for name, _, sec in COMPILES:
            by_name[name].append(sec)
        total = sum(sec for *_, sec in COMPILES)
        tr.write_sep("-", f"numba compiles in this process: {len(COMPILES)} ({total:.0f} s, not counting cache loads)")
        for name, secs in sorted(by_name.items(), key=lambda x: -sum(x[1])):
            tr.write_line(f"{sum(secs):8.1f}  {name} ({len(secs)} signature{'s' if len(secs) > 1 else ''})")
