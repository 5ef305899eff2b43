"""Cost of the loads at one pose of the shipped double wishbone (issue 21, "Speed"): the
kinetostatics (reactions, member and element forces, input effort) and the exact reduced
stiffness against one compiled position re-solve; the median of several repeats after a
warm-up.

    python benchmarks/statics_cost.py [--repeats 7]
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np

import kinprop as kp
from kinprop.analysis.statics import applied_points, input_columns
from kinprop.engine.statics import element_laws, reduced_stiffness, statics_state

ROOT = Path(__file__).resolve().parents[1]


def _time(f, n: int = 50) -> float:
    f()
    t = time.perf_counter()
    for _ in range(n):
        f()
    return (time.perf_counter() - t) / n


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args()
    model = kp.assemble(kp.load_model(ROOT / "examples" / "double_wishbone.yaml"), tol=1e-13).after
    eng = kp.compile(model)
    st = eng.state_of(model)
    r, A, _, _ = eng.poses(st)
    pf = applied_points(model, eng, np.array(r), np.array(A), model.loads.case("braking_1g"))
    cols, _ = input_columns(eng, ["LCA"])
    laws = element_laws(eng, model.elements, st)
    W = pf.wrenches(len(r))
    cases = {
        "position re-solve (compiled)": lambda: eng.propagate({"LCA.q": 0.01}, free=["q"], start=st),
        "statics_state (engine)": lambda: statics_state(eng, st, W, cols, laws),
        "kp.statics (by name)": lambda: kp.statics(model, "braking_1g", engine=eng),
        "reduced_stiffness (engine)": lambda: reduced_stiffness(eng, st, pf, cols, laws),
    }
    times = {name: statistics.median(_time(f) for _ in range(args.repeats)) for name, f in cases.items()}
    base = times["position re-solve (compiled)"]
    for name, t in times.items():
        print(f"{name:32s} {t * 1e3:8.3f} ms  {t / base:6.1f} x re-solve")


if __name__ == "__main__":
    main()
