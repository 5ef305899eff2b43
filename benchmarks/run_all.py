"""Run every benchmark and print one table (Markdown): ``python benchmarks/run_all.py [--quick]``.

Each problem is timed against hand-written baselines in the same run, interleaved trial by
trial; "time / hand baseline" is the median over trials of (method time / the hand-written numpy
Newton's time) on the same trial (for P4, time per variant). Answers are checked independently (leg lengths by
closed-form inverse kinematics, the RSSR input-output equation): "max error" in metres.
Everything kinprop runs goes through the compiled engine (``kinprop.compile``) and its
by-address API, or the model-level ``kinprop.propagate``. ``benchmarks/study_speed.py`` (a
design study, a Dask run, a sweep and ``kp.propagate`` against the engine's own calls) runs
after the table; ``benchmarks/cold_start.py`` (the
command line's first run with an empty kernel cache, then warm) runs last; ``--quick`` skips it
unless named in ``--only``.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import numpy as np  # noqa: E402
from common import print_table  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="few trials, K up to 128, no cold start")
    ap.add_argument("--max-k", type=int, default=None, help="largest stack size for P2 (default 512; 128 with --quick)")
    ap.add_argument("-o", "--output", help="also write the table (Markdown) to this file")
    ap.add_argument("--only", nargs="*", default=None, help="subset of P1 P2 P3 P4 slider_crank study cold_start")
    args = ap.parse_args()
    default = ["P1", "P2", "P3", "P4", "slider_crank", "study"] + ([] if args.quick else ["cold_start"])
    only = set(args.only or default)
    t0 = time.perf_counter()
    import numba

    import kinprop

    env = f"python {platform.python_version()}, {os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f}"
    print(f"kinprop {kinprop.__version__}, numpy {np.__version__}, numba {numba.__version__}, {env}", flush=True)
    rows = []
    extra = []
    if "P1" in only:
        import p1_stewart

        r = p1_stewart.run(trials=10 if args.quick else 50)
        rows += r
        for x in r:
            if x.method in ("engine.propagate (by address)", "kp.propagate (engine=)"):
                target = " (target <= 0.05 ms)" if x.problem.startswith("P1a") and "engine." in x.method else ""
                extra.append(f"{x.problem}: {x.method} {statistics.median(x.times):.4f} ms median{target}, "
                             f"{statistics.median(x.ratios):.3g} x the hand numpy Newton")  # fmt: skip
    if "P2" in only:
        import p2_stack

        kmax = args.max_k or (128 if args.quick else 512)
        Ks = [1 << i for i in range(kmax.bit_length()) if (1 << i) <= kmax]
        r, s = p2_stack.run(Ks, trials=3 if args.quick else 5)
        rows += r
        extra += p2_stack.summary_lines(s)
    if "P3" in only:
        import p3_rssr

        r = p3_rssr.run(trials=5 if args.quick else 20)
        rows += r
        extra.append(f"P3 engine.solve_sequence: {statistics.median(r[0].times) * 1e3:.2f} us per 1-degree step, "
                     f"{statistics.median(r[0].ratios):.3g} x the hand numpy Newton")  # fmt: skip
    if "P4" in only:
        import p4_batch

        q = args.quick
        r = p4_batch.run(N=10_000, trials=3 if q else 5, lsq_subset=50 if q else 200)
        rows += r
        rate = {x.method: statistics.median(x.times) for x in r}
        extra.append(
            "P4 "
            + ", ".join(f"{m}: {v:,.0f} variants/s" for m, v in rate.items() if "engine" in m or "hand" in m)
            + " (target >= 300,000/s with threads)"
        )
    print()
    text = print_table(rows)
    for line in extra:
        print(line)
    sc = os.path.join(HERE, "slider_crank.py")
    if "slider_crank" in only and os.path.exists(sc):
        print("\n# benchmarks/slider_crank.py", flush=True)
        subprocess.run([sys.executable, sc, *(["--repeats", "20"] if args.quick else [])], check=False)
    if "study" in only:  # issue 22: study vs raw batch, Dask vs local, sweep, kp.propagate vs engine
        print("\n# benchmarks/study_speed.py", flush=True)
        quick = ["--variants", "10000", "--repeats", "2"] if args.quick else ["--dask"]
        subprocess.run([sys.executable, os.path.join(HERE, "study_speed.py"), *quick], check=False)
    if "cold_start" in only:
        import cold_start

        print("\n# benchmarks/cold_start.py", flush=True)
        cs = cold_start.lines(cold_start.measure())
        print("\n".join(cs), flush=True)
        extra += cs
    print(f"\ntotal {time.perf_counter() - t0:.1f} s")
    if args.output:
        with open(args.output, "w") as fh:
            fh.write(text + "\n\n" + "\n".join(extra) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
