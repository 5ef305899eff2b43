"""Cost of the loads at one pose of the shipped double wishbone (issue 21, "Speed"): the
kinetostatics (reactions, member and element forces, input effort), the same with their exact
design derivatives with respect to 20 hardpoint coordinates (the state response included: on
the engine, ``design_rates``, one evaluation, the input held; and by name, the free-coordinate
sensitivity then the rates) and the exact reduced stiffness, against one compiled position
re-solve; CPU time of the calling process (the machine is shared), the median of several
repeats after a warm-up. Then a 51-point
wheel-travel sweep (the lower arm over -6..6 deg) with every force of the ``bump_3g`` case as
outputs (every joint's reaction magnitude, the tie rod's tension, the springs' forces, the
input effort) against the same sweep with the positions only (the hardpoints' z).

    python benchmarks/statics_cost.py [--repeats 7]
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np

import kinprop as kp
from kinprop.analysis.statics import applied_points, input_columns, model_laws
from kinprop.engine.statics import reduced_stiffness, statics_state
from kinprop.engine.statics_rates import design_rates, statics_rates
from kinprop.propagation.sensitivity import design_sensitivity

ROOT = Path(__file__).resolve().parents[1]


def _time(f, n: int = 50) -> float:
    f()
    t = time.process_time()
    for _ in range(n):
        f()
    return (time.process_time() - t) / n


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
    laws, held = model_laws(model, eng, st)
    W = pf.wrenches(len(r))
    # 20 hardpoint coordinates: the s' of the ball joints, the tie rod's ends and the arms' pivots
    wrt = ["LBJ.s_i", "UBJ.s_i", "UBJ.s_j", "TR.s_i", "TR.s_j", "UCA.s_i", "LCA.s_i"]

    wrt_cols = design_sensitivity(model, wrt, ["q"], engine=eng, units="solver").wrt_columns[:20]

    def by_name() -> None:
        sens = design_sensitivity(model, wrt, ["q"], engine=eng, units="solver")
        X = np.zeros((20, eng.n_columns))
        X[np.arange(20), sens.wrt_columns[:20]] = 1.0
        X[:, sens.free_columns] = sens.matrix[:, :20].T
        statics_rates(eng, st, pf, X, cols, laws, held)

    cases = {
        "position re-solve (compiled)": lambda: eng.propagate({"LCA.q": 0.01}, free=["q"], start=st),
        "statics_state (engine)": lambda: statics_state(eng, st, W, cols, laws),
        "kp.statics (by name)": lambda: kp.statics(model, "braking_1g", engine=eng),
        "statics + d/d(20 hardpoints)": lambda: design_rates(eng, st, pf, wrt_cols, cols, laws, held),
        "  the same by name (sensitivity)": by_name,
        "reduced_stiffness (engine)": lambda: reduced_stiffness(eng, st, pf, cols, laws),
    }
    times = {name: statistics.median(_time(f) for _ in range(args.repeats)) for name, f in cases.items()}
    base = times["position re-solve (compiled)"]
    for name, t in times.items():
        print(f"{name:32s} {t * 1e3:8.3f} ms CPU {t / base:6.1f} x re-solve")
    joints = model.mechanism.joint_names
    positions = [f"hardpoint:{j}.j[z]" for j in joints]
    forces = [f"reaction:{j}.f@bump_3g" for j in joints] + ["force:TR@bump_3g", "force:spring", "effort:LCA@bump_3g"]
    sweeps = {
        "sweep 51 points, positions": lambda: kp.sweep(model, ["LCA=-6:6:50"], outputs=positions),
        "sweep 51 points, all forces": lambda: kp.sweep(model, ["LCA=-6:6:50"], outputs=positions + forces),
    }
    st_times = {
        name: statistics.median(_time(f, 2) for _ in range(max(1, args.repeats // 2))) for name, f in sweeps.items()
    }
    pos = st_times["sweep 51 points, positions"]
    for name, t in st_times.items():
        print(f"{name:32s} {t * 1e3:8.1f} ms CPU {t / pos:6.1f} x positions-only sweep")


if __name__ == "__main__":
    main()
