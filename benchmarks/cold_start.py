"""Cold start of the command line: one propagation of the slider-crank, wall time of the process.

    kinprop propagate examples/slider_crank.yaml --set J12.s_j=-2.8,0.2,0.1 --free q

(a) with an EMPTY kernel cache (``KINPROP_CACHE_DIR`` set to a fresh temporary directory),
target <= 15 s: the command line runs this one-shot job uncompiled and starts the cache build
in the background (kinprop.cli.warmup); (c) how long that background build takes until the
cache is complete; (b) the same command again with the complete cache (kernels loaded from
disk), target <= 1.5 s; (d) for reference, the cold run with ``KINPROP_JIT=on`` (compiling
everything it needs before answering, what the batch commands do). Each run is a new process of
the ``kinprop`` entry point next to this interpreter (the venv's), so imports are included.

    python benchmarks/cold_start.py [--warm-repeats N]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ARGS = ["propagate", str(ROOT / "examples" / "slider_crank.yaml"), "--set", "J12.s_j=-2.8,0.2,0.1", "--free", "q"]
TARGETS = {"cold": 15.0, "warm": 1.5}


def kinprop_command() -> list[str]:
    exe = Path(sys.executable).parent / ("kinprop.exe" if os.name == "nt" else "kinprop")
    if not exe.exists():
        raise SystemExit(f"no kinprop entry point next to {sys.executable}: install the package (pip install -e .)")
    return [str(exe), *ARGS]


def run_once(cache: str, jit: str | None = None) -> float:
    env = {**os.environ, "KINPROP_CACHE_DIR": cache}
    env.pop("KINPROP_JIT", None)
    if jit:
        env["KINPROP_JIT"] = jit
    env.pop("KINPROP_NUMBA_CACHE_DIR", None)  # the cache must be the fresh one
    env.pop("NUMBA_CACHE_DIR", None)
    t0 = time.perf_counter()
    proc = subprocess.run(kinprop_command(), env=env, capture_output=True, text=True, check=False)
    dt = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"exit code {proc.returncode}:\n{proc.stdout}\n{proc.stderr}")
    return dt


def wait_for_build(cache: str, timeout: float = 900.0) -> float:
    """Seconds until the background build's completion marker appears in ``cache``."""
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < timeout:
        if list(Path(cache).glob("*/complete")) and not list(Path(cache).glob("*/building.lock")):
            return time.perf_counter() - t0
        time.sleep(0.5)
    raise SystemExit(f"the background kernel build did not finish in {timeout:.0f} s")


def measure(warm_repeats: int = 3, compiled_cold: bool = True) -> dict[str, float]:
    """``{"cold": s, "build": s, "warm": median s, "warm_min": s, "cold_jit": s}``; the
    temporary caches are removed afterwards."""
    with tempfile.TemporaryDirectory(prefix="kinprop_cold_") as cache:
        cold = run_once(cache)
        build = cold + wait_for_build(cache)
        warm = [run_once(cache) for _ in range(max(1, warm_repeats))]
    res = {"cold": cold, "build": build, "warm": statistics.median(warm), "warm_min": min(warm)}
    if compiled_cold:
        with tempfile.TemporaryDirectory(prefix="kinprop_cold_") as cache:
            res["cold_jit"] = run_once(cache, jit="on")
    return res


def lines(res: dict[str, float]) -> list[str]:
    cmd = "kinprop " + " ".join(ARGS).replace(str(ROOT) + os.sep, "")
    return [
        f"cold start `{cmd}`:",
        f"  (a) empty kernel cache: {res['cold']:.2f} s (target <= {TARGETS['cold']:g} s)",
        f"  (b) warm kernel cache:  {res['warm']:.2f} s median (min {res['warm_min']:.2f} s; "
        f"target <= {TARGETS['warm']:g} s)",
        f"  (c) background build of the complete cache: {res['build']:.1f} s after the first run started",
    ] + ([f"  (d) empty cache with KINPROP_JIT=on (compile before answering): {res['cold_jit']:.1f} s"]
         if "cold_jit" in res else [])  # fmt: skip


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--warm-repeats", type=int, default=3, help="warm runs (median reported)")
    args = ap.parse_args()
    for line in lines(measure(args.warm_repeats)):
        print(line, flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
