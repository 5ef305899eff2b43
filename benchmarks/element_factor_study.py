"""A 4000-variant study of the shipped double wishbone with motion ratio, wheel rate and
camber gain as outputs, varying a design column (``UBJ.s_i[2]``: every variant re-assembled)
and an element point (``element:spring.point_j[y]``: no body moves, the engine compiled once,
each variant's element ends in the one compiled first-order batch). Median CPU time
(``time.process_time``) of a few repeats after a warm-up.

    python benchmarks/element_factor_study.py [--repeats 3]
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import kinprop as kp
from kinprop.analysis.study import Factor, run_study

ROOT = Path(__file__).resolve().parents[1]
OUTS = ["motion_ratio:spring", "wheel_rate", "camber_gain"]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--samples", type=int, default=4000)
    args = ap.parse_args()
    model = kp.assemble(kp.load_model(ROOT / "examples" / "double_wishbone.yaml")).after
    print(f"study ({args.samples} variants)                 CPU s")
    for f in (Factor("UBJ.s_i[2]", 60.0, 70.0), Factor("element:spring.point_j[y]", 530.0, 580.0)):
        run_study(model, [f], samples=50, outputs=OUTS)  # warm-up
        times = []
        for _ in range(args.repeats):
            t = time.process_time()
            run_study(model, [f], samples=args.samples, outputs=OUTS)
            times.append(time.process_time() - t)
        print(f"{f.address:<40} {statistics.median(times):6.2f}")


if __name__ == "__main__":
    main()
