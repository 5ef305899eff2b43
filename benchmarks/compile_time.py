"""CPU time of compiling every kernel entry point from an empty cache.

Runs the warm-up build (``kinprop.cli.warmup.build``: single solves, batches serial and
threaded, sequences, poses, sensitivities, on the slider-crank and the Stewart platform) in
this process with ``KINPROP_CACHE_DIR`` set to a fresh temporary directory, and prints the
process's CPU time (user + system, ``resource.getrusage``) and the CPU time of each top-level
numba compile (numba's ``numba:compile`` events; nested compiles are part of their caller's).
CPU time, not wall time: the figure depends less on other work on the machine.

    python benchmarks/compile_time.py
"""

from __future__ import annotations

import importlib
import os
import resource
import sys
import tempfile
import time
from collections import defaultdict


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def main() -> int:
    cache = tempfile.mkdtemp(prefix="kinprop-compile-")
    os.environ["KINPROP_CACHE_DIR"] = cache
    os.environ["KINPROP_JIT"] = "on"
    os.environ.pop("KINPROP_NUMBA_CACHE_DIR", None)
    t_import = _cpu()
    import kinprop.jit  # noqa: F401  (sets the cache directory before numba is imported)
    from kinprop.cli.warmup import build

    event = importlib.import_module("numba.core.event")

    per: dict[str, list[float]] = defaultdict(list)
    started: list[float] = []

    class Compiles(event.Listener):
        def on_start(self, ev) -> None:
            started.append(time.process_time())

        def on_end(self, ev) -> None:
            t0 = started.pop()
            if not started:
                d = ev.data["dispatcher"]
                per[d.py_func.__qualname__].append(time.process_time() - t0)

    event.register("numba:compile", Compiles())
    t0 = _cpu()
    build()
    total = _cpu() - t0
    print(f"kernel cache {cache}")
    print(f"imports: {t0 - t_import:.1f} s CPU")
    print(f"warm-up build from an empty cache: {total:.1f} s CPU (user + system)")
    print(f"{'entry point':28s} {'signatures':>10s} {'CPU s':>8s}")
    for name, secs in sorted(per.items(), key=lambda x: -sum(x[1])):
        print(f"{name:28s} {len(secs):10d} {sum(secs):8.1f}")
    print(f"{'all compiles':28s} {sum(len(s) for s in per.values()):10d} {sum(map(sum, per.values())):8.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
