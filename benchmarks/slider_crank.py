"""Benchmark: the paper's three slider-crank propagations (Table 4), tight tolerance.

Prints the median / min / max wall time of each propagation over many repeats, by the
model-level ``kinprop.propagate`` (full Propagation record; compiling the model each call, and
with a compiled engine passed) and by the compiled engine's by-address ``engine.propagate``;
and for the ``q`` mode the same re-assembly by (a) a hand-written numpy Newton with the analytic
Jacobian of this one mechanism and (b) scipy.optimize.least_squares with finite
differences, with ratios taken in the same run.

    python benchmarks/slider_crank.py [--repeats N]
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

import kinprop as kp
from kinprop.spatial import rot_y, rot_z, tilde

MODEL = Path(__file__).resolve().parents[1] / "examples" / "slider_crank.yaml"
CHANGE = {"J12.s_j": [-2.8, 0.2, 0.1]}


def timeit(fn: Callable[[], object], repeats: int) -> tuple[float, float, float]:
    fn()  # warm-up (caches, imports)
    t = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        t.append(time.perf_counter() - t0)
    return statistics.median(t), min(t), max(t)


# --- hand-written baseline: Phi(q) for this mechanism only --------------------------------
C01 = np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0]], float)
C03 = np.array([[0, 1, 0], [0, 0, 1], [1, 0, 0]], float)
C32 = C03.copy()
A3 = C03  # the slider frame: A3 = A0 C03 A''(q4) with A'' = I
S03 = np.array([0, 3.8637, 0.0])
S12 = np.array([2.0, 0, 0])
S21 = np.array([-2.8, 0.2, 0.1])
EZ = np.array([0, 0, 1.0])


def phi(q: np.ndarray) -> np.ndarray:
    A1 = C01 @ rot_z(q[0])
    r3 = S03 + C03 @ EZ * q[3]
    A2 = A3 @ C32 @ rot_z(q[1]) @ rot_y(q[2])
    return r3 + A2 @ S21 - A1 @ S12


def jac(q: np.ndarray) -> np.ndarray:
    A1 = C01 @ rot_z(q[0])
    A2 = A3 @ C32 @ rot_z(q[1]) @ rot_y(q[2])
    s1, s2 = A1 @ S12, A2 @ S21
    h1, h2, g2 = C01 @ EZ, A3 @ C32 @ EZ, A3 @ C32 @ rot_z(q[1]) @ np.array([0, 1.0, 0])
    return np.column_stack([-tilde(h1) @ s1, tilde(h2) @ s2, tilde(g2) @ s2, C03 @ EZ])


def newton_by_hand(q0: np.ndarray, tol: float = 1e-10) -> np.ndarray:
    q = q0.copy()
    for _ in range(50):
        f = phi(q)
        if np.linalg.norm(f) < tol:
            break
        q -= np.linalg.lstsq(jac(q), f, rcond=None)[0]
    return q


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=200)
    args = ap.parse_args()
    model = kp.load_model(MODEL)
    q0 = np.array([np.pi / 4, -np.pi / 6, 0.0, 0.0])
    engine = kp.compile(model)
    rows = []
    for free in (("q",), ("s",), ("q", "s")):
        fr = " ".join(free)
        med, lo, hi = timeit(lambda f=free: kp.propagate(model, CHANGE, f), args.repeats)
        rows.append((f"kp.propagate --free {fr} (compiles)", med, lo, hi))
        med, lo, hi = timeit(lambda f=free: kp.propagate(model, CHANGE, f, engine=engine), args.repeats)
        rows.append((f"kp.propagate --free {fr} (engine=)", med, lo, hi))
        med, lo, hi = timeit(lambda f=free: engine.propagate(CHANGE, f), args.repeats)
        rows.append((f"engine.propagate --free {fr}", med, lo, hi))
        sol, ref = engine.propagate(CHANGE, free), kp.propagate(model, CHANGE, free, engine=engine)
        assert sol.converged and ref.result.converged, (sol, ref.result)
        for j, q in ref.after.coordinates.items():  # the same answer both ways
            assert np.allclose(sol.coordinates[j], q, atol=1e-12), (free, j, sol.coordinates[j], q)
    kq = kp.propagate(model, CHANGE, ("q",), engine=engine)
    ours = np.concatenate([kq.after.coordinates[j] for j in ("J01", "J32", "J03")])
    hand = newton_by_hand(q0)
    ls = least_squares(phi, q0, xtol=1e-15, ftol=1e-15, gtol=1e-15)
    assert np.linalg.norm(phi(hand)) < 1e-10 and np.linalg.norm(phi(ls.x)) < 1e-8
    # an assembly by the benchmark's own constraint equations, on the hand Newton's branch: with
    # --free q the 4 coordinates have 1 degree of freedom left, and following the change in
    # sub-steps (kinprop's default) lands a few microradians from the one-shot min-norm step
    assert np.linalg.norm(phi(ours)) < 1e-10, phi(ours)
    assert np.allclose(hand, ours, atol=1e-4), (hand, ours)
    rows.append(("baseline: numpy Newton, analytic Jacobian (q)", *timeit(lambda: newton_by_hand(q0), args.repeats)))
    rows.append(
        (
            "baseline: scipy least_squares, FD Jacobian (q)",
            *timeit(lambda: least_squares(phi, q0, xtol=1e-12, ftol=1e-12), args.repeats),
        )
    )
    print(f"slider-crank propagations, tight tolerance 1e-10, {args.repeats} repeats")
    print(f"{'case':52s} {'median ms':>10s} {'min ms':>9s} {'max ms':>9s}")
    for name, med, lo, hi in rows:
        print(f"{name:52s} {med * 1e3:10.3f} {lo * 1e3:9.3f} {hi * 1e3:9.3f}")
    by = {name: med for name, med, _, _ in rows}
    hand_t, lsq_t = rows[-2][1], rows[-1][1]
    for name in ("kp.propagate --free q (compiles)", "kp.propagate --free q (engine=)", "engine.propagate --free q"):
        print(f"ratio {name} / hand-written Newton: {by[name] / hand_t:.3g}, / scipy least_squares: "
              f"{by[name] / lsq_t:.3g}")  # fmt: skip


if __name__ == "__main__":
    main()
