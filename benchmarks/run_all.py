"""Run every benchmark and print one table (Markdown): ``python benchmarks/run_all.py [--quick]``.

Each problem is timed against hand-written baselines in the same run, interleaved trial by
trial; "time / first" is the median over trials of (method time / first method's time) on the
same trial (for P4, time per variant). Answers are checked independently (leg lengths by
closed-form inverse kinematics, the RSSR input-output equation): "max error" in metres.
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import numpy as np  # noqa: E402
from common import print_table  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="few trials, K up to 128, N = 2,000 (about 15 s)")
    ap.add_argument("--max-k", type=int, default=None, help="largest stack size for P2 (default 512; 128 with --quick)")
    ap.add_argument("-o", "--output", help="also write the table (Markdown) to this file")
    ap.add_argument("--only", nargs="*", default=None, help="subset of P1 P2 P3 P4 slider_crank")
    args = ap.parse_args()
    only = set(args.only or ["P1", "P2", "P3", "P4", "slider_crank"])
    t0 = time.perf_counter()
    import numba

    import kinprop

    env = f"python {platform.python_version()}, {os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f}"
    print(f"kinprop {kinprop.__version__}, numpy {np.__version__}, numba {numba.__version__}, {env}", flush=True)
    rows = []
    extra = []
    if "P1" in only:
        import p1_stewart

        rows += p1_stewart.run(trials=10 if args.quick else 50)
    if "P2" in only:
        import p2_stack

        kmax = args.max_k or (128 if args.quick else 512)
        Ks = [1 << i for i in range(kmax.bit_length()) if (1 << i) <= kmax]
        r, s = p2_stack.run(Ks, trials=3 if args.quick else 5)
        rows += r
        kk = s["K"]
        for key, label in (("fast_ms", "kinprop fast time (median)"), ("fast_min_ms", "kinprop fast time (min)"),
                           ("splu_ms", "kinprop splu time"), ("hand_ms", "hand numpy time"),
                           ("mem_MiB", "kinprop build+compile memory")):  # fmt: skip
            e128 = p2_stack.exponent(kk, s[key], 8, 128)
            eall = p2_stack.exponent(kk, s[key], 8)
            extra.append(f"P2 growth exponent in K of {label}: {e128:.3f} (K 8..128), {eall:.3f} (K 8..{max(kk)})")
        k128 = s["K"].index(128) if 128 in s["K"] else None
        if k128 is not None:
            extra.append(f"P2 K=128: kinprop fast {s['fast_ms'][k128]:.3f} ms per re-assembly")
        mem = ", ".join(f"{k}: {m:.2f}" for k, m in zip(s["K"], s["mem_MiB"], strict=True))
        extra.append(f"P2 build+compile peak memory (MiB) by K: {mem}")
    if "P3" in only:
        import p3_rssr

        rows += p3_rssr.run(trials=5 if args.quick else 20)
    if "P4" in only:
        import p4_batch

        q = args.quick
        rows += p4_batch.run(N=2000 if q else 10_000, trials=3 if q else 5, lsq_subset=50 if q else 200)
    print()
    text = print_table(rows)
    for line in extra:
        print(line)
    sc = os.path.join(HERE, "slider_crank.py")
    if "slider_crank" in only and os.path.exists(sc):
        print("\n# benchmarks/slider_crank.py", flush=True)
        subprocess.run([sys.executable, sc, *(["--repeats", "20"] if args.quick else [])], check=False)
    print(f"\ntotal {time.perf_counter() - t0:.1f} s")
    if args.output:
        with open(args.output, "w") as fh:
            fh.write(text + "\n\n" + "\n".join(extra) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
