"""Cold start of the command line: ``kinprop --help``, ``kinprop --version`` and one propagation
of the slider-crank, wall time (and CPU time) of the process.

    kinprop propagate examples/slider_crank.yaml --set J12.s_j=-2.8,0.2,0.1 --free q

(h) ``kinprop --help`` and (v) ``kinprop --version``, median of several runs, target <= 0.3 s
each: they import neither numba nor the library (kinprop.cli loads a command's module only
when the command runs); the one-shot runs below are ``propagate`` of a small model, which the
command line runs uncompiled whatever the cache (kinprop.jit: numba is not imported);
(a) with an EMPTY kernel cache (``KINPROP_CACHE_DIR`` set to a fresh temporary directory),
target <= 15 s: the command line runs this one-shot job uncompiled and starts the cache build
in the background (kinprop.cli.warmup); (c) how long that background build takes until the
cache is complete; (b) the same command again with the complete cache (kernels loaded from
disk), median of several runs, target <= 0.7 s, and (m) the README's McPherson propagation
(``kinprop propagate assembled.yaml --set ST.s_i=0.5,1.0,0 --free q`` after ``kinprop assemble
examples/mcpherson.yaml -o assembled.yaml``), target <= 0.7 s; (k) for reference, (b) with
``KINPROP_JIT=on`` (numba imported and the compiled kernels loaded from the complete cache);
(d) the cold run with ``KINPROP_JIT=on`` (compiling everything it needs before answering, what
the batch commands do). Each run is a new process of
the ``kinprop`` entry point next to this interpreter (the venv's), so imports are included.

Each figure is the median wall time; the CPU time (user + system) of the same runs is printed
beside it, a figure that depends less on other work on the machine. The package's bytecode is
compiled first (``compileall``), as ``pip install`` does: an editable install under
``PYTHONDONTWRITEBYTECODE`` would otherwise compile kinprop's sources in every run (~0.25 s).

    python benchmarks/cold_start.py [--warm-repeats N] [--no-cold]
"""

from __future__ import annotations

import argparse
import compileall
import importlib.util
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ARGS = ["propagate", str(ROOT / "examples" / "slider_crank.yaml"), "--set", "J12.s_j=-2.8,0.2,0.1", "--free", "q"]
#: the README's McPherson propagation (of the model ``kinprop assemble`` wrote: ``{assembled}``)
MCPHERSON = ["propagate", "{assembled}", "--set", "ST.s_i=0.5,1.0,0", "--free", "q"]
TARGETS = {"cold": 15.0, "warm": 0.7, "mcpherson": 0.7, "help": 0.3, "version": 0.3}


def kinprop_command(args: list[str] = ARGS) -> list[str]:
    exe = Path(sys.executable).parent / ("kinprop.exe" if os.name == "nt" else "kinprop")
    if not exe.exists():
        raise SystemExit(f"no kinprop entry point next to {sys.executable}: install the package (pip install -e .)")
    return [str(exe), *args]


def _children_cpu() -> float:
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def timed(cache: str, jit: str | None = None, args: list[str] = ARGS) -> tuple[float, float]:
    """(wall, CPU) seconds of one ``kinprop ARGS`` process with the kernel cache ``cache``."""
    env = {**os.environ, "KINPROP_CACHE_DIR": cache}
    env.pop("KINPROP_JIT", None)
    if jit:
        env["KINPROP_JIT"] = jit
    env.pop("KINPROP_NUMBA_CACHE_DIR", None)  # the cache must be the fresh one
    env.pop("NUMBA_CACHE_DIR", None)
    c0, t0 = _children_cpu(), time.perf_counter()
    proc = subprocess.run(kinprop_command(args), env=env, capture_output=True, text=True, check=False)
    dt, cpu = time.perf_counter() - t0, _children_cpu() - c0
    if proc.returncode != 0:
        raise SystemExit(f"exit code {proc.returncode}:\n{proc.stdout}\n{proc.stderr}")
    return dt, cpu


def run_once(cache: str, jit: str | None = None) -> float:
    return timed(cache, jit)[0]


def wait_for_build(cache: str, timeout: float = 900.0) -> float:
    """Seconds until the background build's completion marker appears in ``cache``."""
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < timeout:
        if list(Path(cache).glob("*/complete")) and not list(Path(cache).glob("*/building.lock")):
            return time.perf_counter() - t0
        time.sleep(0.5)
    raise SystemExit(f"the background kernel build did not finish in {timeout:.0f} s")


def compile_bytecode() -> None:
    """Byte-compile the kinprop package the entry point imports (what ``pip install`` does)."""
    spec = importlib.util.find_spec("kinprop")
    if spec is not None and spec.submodule_search_locations:
        for folder in spec.submodule_search_locations:
            compileall.compile_dir(folder, quiet=1)


def measure(
    warm_repeats: int = 5, compiled_cold: bool = True, cold: bool = True, cache_dir: str | None = None
) -> dict[str, float]:
    """``{"help": s, "version": s, "cold": s, "build": s, "warm": median s, "warm_min": s,
    "cold_jit": s}`` (wall; ``*_cpu``: CPU seconds of the same runs); the temporary caches are
    removed afterwards. Without ``cold``, the warm runs use ``cache_dir`` (a complete kernel
    cache) or a cache built by the warm-up first."""
    compile_bytecode()
    res: dict[str, float] = {}
    n = max(1, warm_repeats)
    with tempfile.TemporaryDirectory(prefix="kinprop_cold_") as tmp:
        cache = cache_dir if cache_dir is not None and not cold else tmp
        for key, args in (("help", ["--help"]), ("version", ["--version"])):
            runs = [timed(cache, args=args) for _ in range(n)]
            res[key], res[key + "_cpu"] = statistics.median(w for w, _ in runs), statistics.median(c for _, c in runs)
        if cold:
            res["cold"], res["cold_cpu"] = timed(cache)
            res["build"] = res["cold"] + wait_for_build(cache)
        elif cache_dir is None:
            env = {**os.environ, "KINPROP_CACHE_DIR": cache, "KINPROP_JIT": "on"}
            subprocess.run([sys.executable, "-m", "kinprop.cli.warmup"], env=env, check=True)
        warm = [timed(cache) for _ in range(n)]
        assembled = str(Path(tmp) / "assembled.yaml")
        timed(cache, args=["assemble", str(ROOT / "examples" / "mcpherson.yaml"), "-o", assembled])
        mcpherson = [timed(cache, args=[a.format(assembled=assembled) for a in MCPHERSON]) for _ in range(n)]
        compiled = [timed(cache, jit="on") for _ in range(n)]
    res["warm"], res["warm_min"] = statistics.median(w for w, _ in warm), min(w for w, _ in warm)
    res["warm_cpu"] = statistics.median(c for _, c in warm)
    res["mcpherson"], res["mcpherson_cpu"] = (
        statistics.median(w for w, _ in mcpherson),
        statistics.median(c for _, c in mcpherson),
    )
    res["warm_on"], res["warm_on_cpu"] = (
        statistics.median(w for w, _ in compiled),
        statistics.median(c for _, c in compiled),
    )
    if compiled_cold and cold:
        with tempfile.TemporaryDirectory(prefix="kinprop_cold_") as cache:
            res["cold_jit"] = run_once(cache, jit="on")
    return res


def lines(res: dict[str, float]) -> list[str]:
    cmd = "kinprop " + " ".join(ARGS).replace(str(ROOT) + os.sep, "")
    out = [
        f"kinprop --help:    {res['help']:.3f} s median ({res['help_cpu']:.3f} s CPU; target <= {TARGETS['help']:g} s)",
        f"kinprop --version: {res['version']:.3f} s median ({res['version_cpu']:.3f} s CPU; "
        f"target <= {TARGETS['version']:g} s)",
        f"cold start `{cmd}`:",
    ]
    if "cold" in res:
        out.append(f"  (a) empty kernel cache: {res['cold']:.2f} s (target <= {TARGETS['cold']:g} s)")
    out.append(
        f"  (b) warm kernel cache:  {res['warm']:.2f} s median (min {res['warm_min']:.2f} s, "
        f"{res['warm_cpu']:.2f} s CPU; target <= {TARGETS['warm']:g} s)"
    )
    out.append(
        f"  (m) README McPherson `kinprop {' '.join(MCPHERSON).format(assembled='assembled.yaml')}`: "
        f"{res['mcpherson']:.2f} s median ({res['mcpherson_cpu']:.2f} s CPU; target <= {TARGETS['mcpherson']:g} s)"
    )
    out.append(
        f"  (k) (b) compiled, KINPROP_JIT=on (numba and the cached kernels loaded): {res['warm_on']:.2f} s median "
        f"({res['warm_on_cpu']:.2f} s CPU)"
    )
    if "build" in res:
        out.append(f"  (c) background build of the complete cache: {res['build']:.1f} s after the first run started")
    if "cold_jit" in res:
        out.append(f"  (d) empty cache with KINPROP_JIT=on (compile before answering): {res['cold_jit']:.1f} s")
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--warm-repeats", type=int, default=5, help="runs of --help, --version, warm (median reported)")
    ap.add_argument("--no-cold", action="store_true", help="skip the empty-cache runs (a warm-up builds the cache)")
    ap.add_argument("--cache", help="with --no-cold: a complete kernel cache to use (KINPROP_CACHE_DIR)")
    args = ap.parse_args()
    for line in lines(measure(args.warm_repeats, cold=not args.no_cold, cache_dir=args.cache)):
        print(line, flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
