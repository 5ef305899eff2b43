"""A 51-point wheel-travel sweep of the shipped double wishbone with first-order metrics
(camber, toe, camber gain, bump steer, roll-centre height, anti-dive, motion ratio) against
the same sweep with positions only and with the position-level metrics only (issue 25,
"Speed"). Compiled engine (the velocity solve too: ``kinprop.engine.motion.velocity_solve``);
the median CPU time (``time.process_time``: the machine may be shared) of several repeats
after a warm-up, and the ratio to the positions-only sweep (the target is at most 2).

    python benchmarks/first_order_sweep.py [--repeats 7]
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import kinprop as kp
from kinprop.analysis.sweep import sweep

ROOT = Path(__file__).resolve().parents[1]
DRIVE = "LCA=-6.5:6.5:50"  # 51 points, about +-56 mm of wheel travel
CASES = {
    "positions only (wheel centre z)": ["point:upright.wheel_centre[z]"],
    "camber, toe": ["wheel_centre_dz", "camber", "toe"],
    "camber, toe + first order": ["wheel_centre_dz", "camber", "toe", "camber_gain", "bump_steer",
                                  "roll_centre_height", "anti_dive", "motion_ratio:spring"],
}  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeats", type=int, default=15)
    args = ap.parse_args()
    model = kp.assemble(kp.load_model(ROOT / "examples" / "double_wishbone.yaml")).after
    for outs in CASES.values():
        sweep(model, [DRIVE], outputs=outs, tol=1e-9)  # warm-up (compiles)
    runs: dict[str, list[float]] = {name: [] for name in CASES}
    for _ in range(args.repeats):  # interleaved, so that a shared machine's load affects every case alike
        for name, outs in CASES.items():
            t = time.process_time()
            res = sweep(model, [DRIVE], outputs=outs, tol=1e-9)
            runs[name].append(time.process_time() - t)
            assert len(res.frame) == 51
    times = {name: statistics.median(r) for name, r in runs.items()}
    base = times["positions only (wheel centre z)"]
    print(f"{'sweep (51 points)':40s} {'CPU ms':>10s} {'/ positions':>12s}")
    for name, t in times.items():
        print(f"{name:40s} {1e3 * t:10.1f} {t / base:12.2f}")


if __name__ == "__main__":
    main()
