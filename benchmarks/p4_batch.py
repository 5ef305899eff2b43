"""P4: N = 10,000 variants of P1 (each with its own six leg changes) solved together: variants per second.

Methods: ``engine.solve_batch`` with ``threads=False`` (one numba call, serial) and
``threads=True`` (split over numba's threads; the issue's number: >= 300,000 variants/s on 2 cores),
the hand-written numpy Newton vectorised over the batch (stacked ``solve``), and
``least_squares`` per variant (timed on a subset and scaled). Check: leg lengths by inverse
kinematics for every variant.
"""

from __future__ import annotations

import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from common import (
    Row,
    compare,
    leg_lengths,
    platform_pose,
    stewart_bench,
    stewart_hand_newton,
    stewart_least_squares,
)


def run(N: int = 10_000, trials: int = 5, lsq_subset: int = 200, seed: int = 0) -> list[Row]:
    rng = np.random.default_rng(seed)
    sb = stewart_bench()
    a, b, eng, lidx, fcol, l0 = sb.a, sb.b, sb.engine, sb.lidx, sb.fcol, sb.l0
    batches = [l0 + rng.uniform(-3e-3, 3e-3, (N, 6)) for _ in range(trials)]
    base = eng.stack([sb.st] * N)
    A, B = np.broadcast_to(a, (N, 6, 3)), np.broadcast_to(b, (N, 6, 3))
    x0, R0 = np.tile(sb.x0, (N, 1)), np.tile(sb.R0, (N, 1, 1))
    keys = sorted(sb.keys)

    def fast(dl, threads=False):
        base.L[:, lidx] = dl  # solve_batch copies its input
        res = eng.solve_batch(base, ("q",), exclude=keys, threads=threads)
        return res.state.Q, None, res.converged.all()  # coordinates: the pose is read in check()

    def hand(dl):
        x, R, _ = stewart_hand_newton(A, B, dl, x0, R0)
        return x, R, True

    def lsq(dl):
        out = [stewart_least_squares(a, b, dl[k], x0[0], R0[0]) for k in range(lsq_subset)]
        return np.array([o[0] for o in out]), np.array([o[1] for o in out]), True

    def check(dl, res):
        x, R, ok = res
        if R is None:  # kinprop's coordinates -> platform pose (outside the timed call)
            x, R = platform_pose(x, fcol)
        n = x.shape[0]
        return np.abs(leg_lengths(A[:n], B[:n], x, R) - dl[:n]).max() if ok else np.inf

    methods = {"engine.solve_batch (threads=False)": fast,
               "engine.solve_batch (threads=True)": lambda dl: fast(dl, True),
               "hand numpy Newton (vectorised)": hand, "scipy least_squares (FD), per variant": lsq}  # fmt: skip
    rows = compare(f"P4 {N} Stewart variants", batches, methods, check, unit="variants/s", scale=1.0)
    for row in rows:  # seconds per batch -> variants per second
        n = lsq_subset if "least_squares" in row.method else N
        row.times = [n / t for t in row.times]
        row.ratios = [x * N / n for x in row.ratios]  # time per variant relative to the hand numpy Newton
        if n != N:
            row.note = f"timed on {n} variants"
    rows[0].note = "serial (1 thread)"
    rows[2].note = "stacked numpy.linalg.solve over the batch"
    from kinprop.jit import num_threads

    rows[1].note = f"{num_threads()} threads"
    return rows


if __name__ == "__main__":
    from common import print_table

    print_table(run())
