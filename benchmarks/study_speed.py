"""Where the user is (issue 22): a design study, a sweep and ``kp.propagate`` against the
compiled engine's own calls, measured in the same run and interleaved so that a shared
machine's load affects each alike. Prints ratios (and CPU times: wall times on a loaded
machine say little).

* **study**: ``run_study`` of the shipped double wishbone (LHS over ``UBJ.s_j[2]`` and
  ``TR.s_j[2]``, its default outputs: every coordinate, named point and wheel metric, Parquet
  parts written, nothing held: ``collect=False``) against ``Engine.solve_batch`` of the same
  variants (target: >= 0.3x its rate, >= 100,000 variants/s);
* **dask** (``--dask``): the same study on a ``distributed.LocalCluster`` of two single-threaded
  worker processes against the local run (target: at least as fast);
* **sweep**: a 51-point sweep of the lower arm angle with the default outputs, on the compiled
  engine (``Engine.solve_sequence`` and one compiled output call; target <= 1 ms) and as
  ``kp.sweep`` (a data frame with conditioning per step);
* **propagate**: ``kp.propagate(model, changes, engine=)`` against ``engine.propagate`` (target <= 2x).

    python benchmarks/study_speed.py [--variants 40000] [--repeats 3] [--dask]
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

import kinprop as kp
from kinprop.analysis.outputs import output_program
from kinprop.analysis.study import Factor, run_study, sample_plan
from kinprop.analysis.sweep import default_outputs, sweep

ROOT = Path(__file__).resolve().parents[1]
FACTORS = [Factor("UBJ.s_j[2]", 330.0, 340.0), Factor("TR.s_j[2]", 95.0, 105.0)]


def timed(f: Callable[[], object]) -> tuple[float, float]:
    """(wall, CPU) seconds of one call (CPU: this process, every thread)."""
    w, c = time.perf_counter(), time.process_time()
    f()
    return time.perf_counter() - w, time.process_time() - c


def interleave(cases: dict[str, Callable[[], object]], repeats: int) -> dict[str, tuple[list[float], list[float]]]:
    out: dict[str, tuple[list[float], list[float]]] = {k: ([], []) for k in cases}
    for _ in range(repeats):
        for name, f in cases.items():
            w, c = timed(f)
            out[name][0].append(w)
            out[name][1].append(c)
    return out


def study_cases(model: kp.Model, engine: kp.Engine, n: int, tmp: Path, scheduler: object = None) -> dict:
    values = sample_plan(FACTORS, "lhs", n, 0)
    st = engine.stack([engine.reference] * n)
    for k, f in enumerate(FACTORS):
        engine.set_batch(st, f.address, values[:, k])

    def batch() -> None:
        assert engine.solve_batch(st, ("q",), exclude={"UBJ.s_j", "TR.s_j"}).converged.all()

    def study(where: object = None) -> Callable[[], None]:
        def run() -> None:
            out = tmp / "study.parquet"
            shutil.rmtree(out, ignore_errors=True)
            totals = run_study(model, FACTORS, samples=n, compiled=engine, output=out, collect=False, scheduler=where)
            assert totals.variants == n and totals.failed == 0

        return run

    cases = {"Engine.solve_batch (same variants)": batch, "run_study, local": study()}
    if scheduler is not None:
        cases["run_study, LocalCluster 2 workers"] = study(scheduler)
    return cases


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--variants", type=int, default=40_000)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--dask", action="store_true", help="also run the study on a LocalCluster of 2 workers")
    args = ap.parse_args()
    print(f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f}")
    model = kp.load_model(ROOT / "examples" / "double_wishbone.yaml")
    engine = kp.compile(model)
    n = args.variants
    cluster = None
    with tempfile.TemporaryDirectory() as tmp:
        if args.dask:
            from distributed import LocalCluster

            cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                   silence_logs=40)  # fmt: skip
        try:
            cases = study_cases(model, engine, n, Path(tmp), cluster.scheduler_address if cluster else None)
            for f in cases.values():  # warm-up: compiles, and the workers' first chunks
                f()
            res = interleave(cases, args.repeats)
        finally:
            if cluster is not None:
                cluster.close()
    wall = {k: statistics.median(v[0]) for k, v in res.items()}
    cpu = {k: statistics.median(v[1]) for k, v in res.items()}
    base = "Engine.solve_batch (same variants)"
    print(f"\nstudy of {n:,} double wishbone variants (default outputs, Parquet written), median of {args.repeats}")
    print(f"{'':38s} {'variants/s':>11s} {'CPU s':>7s} {'rate / solve_batch':>19s}")
    for k in res:
        print(f"{k:38s} {n / wall[k]:11,.0f} {cpu[k]:7.2f} {wall[base] / wall[k]:19.3f}")
    if "run_study, LocalCluster 2 workers" in wall:
        print(f"LocalCluster / local rate: {wall['run_study, local'] / wall['run_study, LocalCluster 2 workers']:.3f}")

    # --- a 51-point sweep and one propagation ---------------------------------------------------
    drive = np.radians(np.linspace(-6.5, 6.5, 51))[:, None]
    program = output_program(model, default_outputs(model), engine=engine)

    def engine_sweep() -> None:
        _, seq = engine.solve_sequence(engine.reference, ["LCA.q"], drive, ("q",))
        program.evaluate(seq.state, seq.converged)

    cases2 = {
        "sweep: solve_sequence + compiled outputs": engine_sweep,
        "sweep: kp.sweep (data frame)": lambda: sweep(model, ["LCA=-6.5:6.5:50"]),
        "engine.propagate": lambda: engine.propagate({"LCA.q": 0.05}),
        "kp.propagate (engine=)": lambda: kp.propagate(model, {"LCA.q": 0.05}, engine=engine),
    }
    for f in cases2.values():
        f()
    res2 = interleave(cases2, 20 * args.repeats)
    print(f"\n{'':42s} {'median ms':>10s} {'CPU ms':>8s}")
    for k, (w, c) in res2.items():
        print(f"{k:42s} {1e3 * statistics.median(w):10.3f} {1e3 * statistics.median(c):8.3f}")
    ratio = [a / b for a, b in zip(res2["kp.propagate (engine=)"][1], res2["engine.propagate"][1], strict=True)]
    print(f"kp.propagate / engine.propagate (CPU, pairwise median): {statistics.median(ratio):.2f} (target <= 2)")


if __name__ == "__main__":
    main()
