"""P1: Stewart 6-UPS (``examples/stewart.yaml``) re-assembly after (a) ONE leg-length change of
up to +-3 mm (``L3.length``), (b) one base hardpoint moved 5 mm (``Lk.s_i``), (c) all six legs
changed by up to +-3 mm.

Methods: ``engine.propagate`` through the public by-address API (the issue's number: target
median <= 0.05 ms for (a)), ``engine.apply`` + ``engine.solve`` (the same, split), the
model-level ``kinprop.propagate`` (full Propagation record; with the engine passed, and as a
user calls it, compiling each time), a hand-written numpy Newton with the analytic Jacobian,
``scipy.optimize.least_squares`` with finite differences; and ``engine.propagate`` on the
UPS-leg model (universal + prismatic + spherical cut, same geometry) for the modelling choice.
Check: leg lengths of the solved pose by closed-form inverse kinematics.
"""

from __future__ import annotations

import sys

import numpy as np

sys.path.insert(0, __import__("os").path.dirname(__file__))
from common import (
    Row,
    compare,
    leg_lengths,
    platform_pose,
    stewart_bench,
    stewart_hand_newton,
    stewart_least_squares,
)

import kinprop as kp
from kinprop.builders import stewart

LEG = 3  # the leg changed in (a): L3


def pose(res: tuple) -> tuple[np.ndarray, np.ndarray]:
    """Platform pose ``(x, R)`` of a result: kinprop's ``(coordinates, free-joint column)`` or a pose."""
    Q, col = res
    if isinstance(col, int):
        return platform_pose(Q, col)
    return Q, col


def run(trials: int = 50, seed: int = 0, inner: int = 5) -> list[Row]:
    rng = np.random.default_rng(seed)
    sb = stewart_bench()
    a, b, model, eng, legs, fcol, st0, l0 = sb.a, sb.b, sb.model, sb.engine, sb.legs, sb.fcol, sb.st, sb.l0
    x0, R0 = sb.x0, sb.R0

    # the same platform with U-P-S legs (19 unknowns): the builder's geometry matches the file's
    ups = stewart("ups", height=float(x0[2]), base_half_angle=np.radians(10), platform_half_angle=np.radians(10))
    ueng = kp.compile(ups)
    ufcol = ueng.target("M1_F.q").start
    uR = ueng.poses(ueng.reference)[1]
    assert np.allclose(ueng.reference.S[[ueng.joint_index[f"M1_U{k}"] for k in range(1, 7)], 0], a, atol=1e-5)
    assert np.allclose(uR[ueng.body_index["M1"]], R0, atol=1e-5)  # R0: the assembled pose

    rows: list[Row] = []
    # (a) one leg changes by up to +-3 mm, through the public by-address API
    k3 = LEG - 1
    addr = f"{legs[k3]}.length"
    vals = [float(l0[k3] + rng.uniform(-3e-3, 3e-3)) for _ in range(trials)]

    def lengths_a(v):
        dl = l0.copy()
        dl[k3] = v
        return dl

    def by_address(v):
        return eng.propagate({addr: v}).state.Q, fcol

    def apply_solve(v):
        st, _, keys = eng.apply(st0, {addr: v})
        return eng.solve(st, ("q",), exclude=keys).state.Q, fcol

    def model_level(v):
        p = kp.propagate(model, {addr: v}, engine=eng)
        return p.after.coordinates["P"], 0

    def model_level_compile(v):
        p = kp.propagate(model, {addr: v})
        return p.after.coordinates["P"], 0

    def ups_a(v):  # every leg's prismatic coordinate is a q: all six are set (locked)
        return ueng.propagate({f"M1_P{k + 1}.q": x for k, x in enumerate(lengths_a(v))}).state.Q, ufcol

    def hand(v):
        x, R, _ = stewart_hand_newton(a[None], b[None], lengths_a(v)[None], x0[None], R0[None])
        return x[0], R[0]

    def lsq(v):
        return stewart_least_squares(a, b, lengths_a(v), x0, R0)

    def check(v, res):
        return np.abs(leg_lengths(a, b, *pose(res)) - lengths_a(v)).max()

    methods = {"engine.propagate (by address)": by_address, "engine.apply + engine.solve": apply_solve,
               "kp.propagate (engine=)": model_level, "kp.propagate (compiles)": model_level_compile,
               "hand numpy Newton": hand, "scipy least_squares (FD)": lsq,
               "engine.propagate, UPS legs": ups_a}  # fmt: skip
    notes = {"engine.propagate (by address)": f"{addr}; distance legs, 7x7; target <= 0.05 ms",
             "engine.propagate, UPS legs": "19x19, all six Pk.q set"}  # fmt: skip
    rows += compare("P1a one leg +-3 mm", vals, methods, check, notes=notes, inner=inner)

    # (b) one base hardpoint moves 5 mm in a random direction
    moves = []
    for _ in range(trials):
        k = int(rng.integers(6))
        u = rng.normal(size=3)
        moves.append((k, a[k] + 5e-3 * u / np.linalg.norm(u)))

    def moved(mv):
        k, ak = mv
        am = a.copy()
        am[k] = ak
        return am

    def by_address_b(mv):
        k, ak = mv
        return eng.propagate({f"{legs[k]}.s_i": ak}).state.Q, fcol

    def model_b(mv):
        k, ak = mv
        return kp.propagate(model, {f"{legs[k]}.s_i": ak}, engine=eng).after.coordinates["P"], 0

    def hand_b(mv):
        x, R, _ = stewart_hand_newton(moved(mv)[None], b[None], l0[None], x0[None], R0[None])
        return x[0], R[0]

    def lsq_b(mv):
        return stewart_least_squares(moved(mv), b, l0, x0, R0)

    def check_b(mv, res):
        return np.abs(leg_lengths(moved(mv), b, *pose(res)) - l0).max()

    methods_b = {"engine.propagate (by address)": by_address_b, "kp.propagate (engine=)": model_b,
                 "hand numpy Newton": hand_b, "scipy least_squares (FD)": lsq_b}  # fmt: skip
    rows += compare("P1b base hardpoint 5 mm", moves, methods_b, check_b, inner=inner)

    # (c) all six legs change by up to +-3 mm
    dls = [l0 + rng.uniform(-3e-3, 3e-3, 6) for _ in range(trials)]
    lidx = sb.lidx

    def by_address_c(dl):
        return eng.propagate({f"{j}.length": v for j, v in zip(legs, dl, strict=True)}).state.Q, fcol

    def solve_c(dl):
        st = st0.copy()
        st.L[lidx] = dl
        return eng.solve(st, sb.cols).state.Q, fcol

    def hand_c(dl):
        x, R, _ = stewart_hand_newton(a[None], b[None], dl[None], x0[None], R0[None])
        return x[0], R[0]

    def check_c(dl, res):
        return np.abs(leg_lengths(a, b, *pose(res)) - dl).max()

    methods_c = {"engine.propagate (by address)": by_address_c, "engine.solve (L array, columns)": solve_c,
                 "hand numpy Newton": hand_c, "scipy least_squares (FD)": lambda dl: stewart_least_squares(
                     a, b, dl, x0, R0)}  # fmt: skip
    rows += compare("P1c 6 legs +-3 mm", dls, methods_c, check_c, inner=inner)
    return rows


if __name__ == "__main__":
    from common import print_table

    print_table(run(int(sys.argv[1]) if len(sys.argv) > 1 else 50))
