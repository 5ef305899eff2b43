"""P1: Stewart 6-UPS re-assembly after (a) all six legs change by a few mm, (b) one base hardpoint moves 5 mm.

Methods: kinprop fast (compiled numba Newton), kinprop reference (``propagate``), a hand-written
numpy Newton with the analytic Jacobian, ``scipy.optimize.least_squares`` with finite
differences; and the fast path on the UPS-leg model (universal + prismatic + spherical cut) for
the modelling choice. Check: leg lengths of the solved pose by closed-form inverse kinematics.
"""

from __future__ import annotations

import sys

import numpy as np

sys.path.insert(0, __import__("os").path.dirname(__file__))
from common import Row, compare, leg_lengths, stewart_bench, stewart_hand_newton, stewart_least_squares
from kinprop.fast import Solver, compile_model, pack

from kinprop import propagate
from kinprop.builders import STEWART, stewart
from kinprop.spatial import euler_to_matrix


def pose(res: tuple) -> tuple[np.ndarray, np.ndarray]:
    """Platform pose ``(x, R)`` of a result: kinprop's ``(coordinates, free-joint column)`` or a pose."""
    Q, col = res
    if isinstance(col, int):
        return np.asarray(Q[col : col + 3]), euler_to_matrix(Q[col + 3 : col + 7])
    return Q, col


def run(trials: int = 50, seed: int = 0, inner: int = 5) -> list[Row]:
    rng = np.random.default_rng(seed)
    sb = stewart_bench()
    a, b, model, comp, legs, lcol, fcol, st0, l0 = (
        sb.a,
        sb.b,
        sb.model,
        sb.comp,
        sb.legs,
        sb.lcol,
        sb.fcol,
        sb.st,
        sb.l0,
    )
    h = STEWART["height"]
    x0, R0 = np.array([0.0, 0.0, h]), np.eye(3)

    ups = stewart("ups")
    ucomp = compile_model(ups.mechanism)
    ust0 = pack(ucomp, ups.design, ups.coordinates)
    pcols = [ucomp.assembly.layout[f"M1_P{k}.q"].start for k in range(1, 7)]
    ufcol = ucomp.assembly.layout["M1_F.q"].start
    usolver = Solver(ucomp, ("q",), exclude={f"M1_P{k}.q" for k in range(1, 7)})

    rows: list[Row] = []
    # (a) all six legs change by up to +-3 mm
    dls = [l0 + rng.uniform(-3e-3, 3e-3, 6) for _ in range(trials)]
    solver = sb.solver

    def fast(dl):
        Q, L = st0.Q[0].copy(), st0.L[0].copy()
        L[lcol] = dl
        solver.solve_one(Q, st0.S[0], st0.C[0], L)
        return Q, fcol

    def fast_ups(dl):
        Q = ust0.Q[0].copy()
        Q[pcols] = dl
        usolver.solve_one(Q, ust0.S[0], ust0.C[0], ust0.L[0])
        return Q, ufcol

    def reference(dl):
        p = propagate(model, {f"{j}.length": v for j, v in zip(legs, dl, strict=True)})
        return p.after.coordinates["M1_F"], 0

    def hand(dl):
        x, R, _ = stewart_hand_newton(a[None], b[None], dl[None], x0[None], R0[None])
        return x[0], R[0]

    def lsq(dl):
        return stewart_least_squares(a, b, dl, x0, R0)

    def check(dl, res):
        return np.abs(leg_lengths(a, b, *pose(res)) - dl).max()

    methods = {"kinprop fast": fast, "kinprop reference": reference, "hand numpy Newton": hand,
               "scipy least_squares (FD)": lsq, "kinprop fast, UPS legs": fast_ups}  # fmt: skip
    rows += compare("P1a 6 legs +-3 mm", dls, methods, check, notes={"kinprop fast": "distance legs, 7x7"}, inner=inner)

    # (b) one base hardpoint moves 5 mm in a random direction
    moves = []
    for _ in range(trials):
        k = int(rng.integers(6))
        u = rng.normal(size=3)
        moves.append((k, a[k] + 5e-3 * u / np.linalg.norm(u)))
    solvers = {k: Solver(comp, ("q",), exclude={f"M1_L{k + 1}.s_i"}) for k in range(6)}

    def fast_b(mv):
        k, ak = mv
        Q, S = st0.Q[0].copy(), st0.S[0].copy()
        S[lcol[k], 0] = ak
        solvers[k].solve_one(Q, S, st0.C[0], st0.L[0])
        return Q, fcol

    def ref_b(mv):
        k, ak = mv
        p = propagate(model, {f"M1_L{k + 1}.s_i": ak})
        return p.after.coordinates["M1_F"], 0

    def moved(mv):
        k, ak = mv
        am = a.copy()
        am[k] = ak
        return am

    def hand_b(mv):
        x, R, _ = stewart_hand_newton(moved(mv)[None], b[None], l0[None], x0[None], R0[None])
        return x[0], R[0]

    def lsq_b(mv):
        return stewart_least_squares(moved(mv), b, l0, x0, R0)

    def check_b(mv, res):
        return np.abs(leg_lengths(moved(mv), b, *pose(res)) - l0).max()

    methods_b = {"kinprop fast": fast_b, "kinprop reference": ref_b, "hand numpy Newton": hand_b,
                 "scipy least_squares (FD)": lsq_b}  # fmt: skip
    rows += compare("P1b base hardpoint 5 mm", moves, methods_b, check_b, inner=inner)
    return rows


if __name__ == "__main__":
    from common import print_table

    print_table(run(int(sys.argv[1]) if len(sys.argv) > 1 else 50))
