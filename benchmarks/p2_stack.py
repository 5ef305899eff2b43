"""P2: a stack of K Stewart modules, re-assembled after every leg changes by +-2 mm.

Two variants of the same mechanism (same leg equations, same solution):

* ``relative``: each module's platform hangs (free joint) from the one below
  (``kinprop.builders.stewart_stack``): the free Jacobian is block diagonal (plan ``blocks``);
* ``ground``: every platform hangs from the ground, the legs still join platform k-1 to
  platform k: each module's rows reach its own and the lower platform's coordinates, a block
  lower-triangular Jacobian (plan ``triangular``, block forward substitution).

Time per re-assembly (the issue's number: K=128 median <= 1.5 ms, growth exponent over K in
{16, 32, 64, 128} <= 1.0), peak memory (tracemalloc) of building, compiling and the first solve.
Methods: ``engine.solve`` on a state whose L array holds the new lengths (columns computed
once), ``engine.propagate`` by address (6K addresses per call), the hand-written numpy
Newton (the relative-pose equations, batched over modules), ``least_squares`` with finite
differences and the Jacobian's sparsity (K <= 16), and ``kp.propagate`` (K <= 4).
Check: every leg length of every module by inverse kinematics from the solved relative poses.
"""

from __future__ import annotations

import dataclasses
import os
import sys
import time
import tracemalloc

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from common import Row, compare, exp_so3, leg_lengths, stewart_hand_newton

import kinprop as kp
from kinprop.builders import STEWART, leg_addresses, stewart_hardpoints, stewart_stack
from kinprop.model import Mechanism, Model

VARIANTS = ("relative", "ground")
#: K range of the growth exponent (the issue's)
EXP_K = (16, 128)


def stack_from_ground(K: int) -> Model:
    """``stewart_stack(K)`` with every platform's free joint on the ground (``base``) instead of
    on the platform below; its coordinates become absolute (height k h). Legs unchanged."""
    rel = stewart_stack(K)
    h = STEWART["height"]
    joints = tuple(dataclasses.replace(j, body_i="base") if j.type == "free" else j for j in rel.mechanism.joints)
    coords = dict(rel.coordinates)
    for k in range(1, K + 1):
        coords[f"M{k}_F"] = np.array([0.0, 0.0, k * h, 1.0, 0.0, 0.0, 0.0])
    mech = Mechanism(rel.mechanism.bodies, joints, name=f"stewart stack K={K}, platforms on the ground")
    return Model(mech, rel.design, coords)


def build(K: int, variant: str) -> Model:
    return stewart_stack(K) if variant == "relative" else stack_from_ground(K)


def relative_poses(eng, state, K: int) -> tuple[np.ndarray, np.ndarray]:
    """Pose of platform k in the frame of the body below (base, M1, ...), from the engine's body poses."""
    r, A = eng.poses(state)[:2]
    idx = [eng.body_index[n] for n in ["base"] + [f"M{k}" for k in range(1, K + 1)]]
    r, A = r[idx], A[idx]
    At = np.swapaxes(A[:-1], -1, -2)
    return np.einsum("kij,kj->ki", At, r[1:] - r[:-1]), At @ A[1:]


def lsq_sparse(a, b, lengths, x0, R0):
    """least_squares (trf, finite differences with the block sparsity) on all modules at once."""
    from scipy.optimize import least_squares
    from scipy.sparse import block_diag

    Kn = lengths.shape[0]

    def fun(z):
        z = z.reshape(Kn, 6)
        R = exp_so3(z[:, 3:]) @ R0
        d = z[:, None, :3] + np.einsum("nij,nkj->nki", R, b) - a
        return (np.einsum("nki,nki->nk", d, d) - lengths**2).ravel()

    z0 = np.concatenate([x0, np.zeros((Kn, 3))], axis=1).ravel()
    sparsity = block_diag([np.ones((6, 6))] * Kn)
    sol = least_squares(fun, z0, jac_sparsity=sparsity, xtol=1e-15, ftol=1e-15, gtol=1e-15)
    z = sol.x.reshape(Kn, 6)
    return z[:, :3], exp_so3(z[:, 3:]) @ R0


def bench_k(K: int, variant: str, trials: int, rng: np.random.Generator) -> tuple[list[Row], dict]:
    """All methods on a stack of K modules; returns the rows and a summary entry."""
    a, b = stewart_hardpoints()
    h = STEWART["height"]
    tracemalloc.start()
    model = build(K, variant)
    eng = kp.compile(model)
    addrs = leg_addresses(model)
    keys = set(addrs)
    cols = eng.columns(("q",), keys)
    plan = eng.plan(cols)
    st0 = eng.reference
    lidx = np.array([eng.joint_index[x.split(".")[0]] for x in addrs])
    l0 = st0.L[lidx].copy()
    deltas = [l0 + rng.choice([-2e-3, 2e-3], size=l0.size) for _ in range(trials)]
    build_now, build_peak = tracemalloc.get_traced_memory()
    tracemalloc.reset_peak()

    def solve(dl):  # follow the change from the assembled stack to the new leg lengths
        st = st0.copy()
        st.L[lidx] = dl
        sol = eng.solve(st0, cols, target=st)
        assert sol.converged, sol
        return sol.state

    def by_address(dl):
        sol = eng.propagate(dict(zip(addrs, dl, strict=True)))
        assert sol.converged, sol
        return sol.state

    solve(deltas[0])
    solve_peak = tracemalloc.get_traced_memory()[1] - build_now  # above the model's own memory
    tracemalloc.stop()
    A = np.broadcast_to(a, (K, 6, 3))
    B = np.broadcast_to(b, (K, 6, 3))
    x0 = np.tile([0.0, 0.0, h], (K, 1))
    R0 = np.tile(np.eye(3), (K, 1, 1))

    def hand(dl):
        x, R, _ = stewart_hand_newton(A, B, dl.reshape(K, 6), x0, R0)
        return x, R

    def check(dl, res):
        x, R = res if isinstance(res, tuple) else relative_poses(eng, res, K)
        return np.abs(leg_lengths(A, B, x, R) - dl.reshape(K, 6)).max()

    def ref(dl):
        p = kp.propagate(model, dict(zip(addrs, dl, strict=True)), engine=eng)
        return relative_poses(eng, eng.state_of(p.after), K)

    methods = {"engine.solve (L array)": solve, "engine.propagate (by address)": by_address,
               "hand numpy Newton": hand}  # fmt: skip
    if K <= 16:
        methods["scipy least_squares (FD, sparse)"] = lambda dl: lsq_sparse(A, B, dl.reshape(K, 6), x0, R0)
    if K <= 4:
        methods["kp.propagate (engine=)"] = ref
    rows = compare(f"P2 {variant} K={K}", deltas, methods, check, inner=3)
    mib = build_peak / 2**20
    rows[0].note = (f"plan {plan.kind} ({plan.n_blocks} blocks); build+compile {mib:.2f} MiB, "
                    f"solve +{solve_peak / 2**20:.3f} MiB; " + rows[0].note)  # fmt: skip
    rows[1].note = f"{len(addrs)} addresses"
    med = {x.method: float(np.median(x.times)) for x in rows}
    entry = {"K": K, "solve_ms": med["engine.solve (L array)"], "solve_min_ms": float(np.min(rows[0].times)),
             "propagate_ms": med["engine.propagate (by address)"], "hand_ms": med["hand numpy Newton"],
             "mem_MiB": mib, "solve_mem_MiB": solve_peak / 2**20, "plan": plan.kind}  # fmt: skip
    print(f"  {variant} K={K}: plan {plan.kind}, solve {entry['solve_ms']:.3f} ms, by address "
          f"{entry['propagate_ms']:.3f} ms, {mib:.2f} MiB", file=sys.stderr, flush=True)  # fmt: skip
    return rows, entry


def run(Ks: list[int], trials: int = 5, seed: int = 0) -> tuple[list[Row], dict]:
    """Both variants for every K; the summary is ``{variant: {key: [value per K]}}``."""
    rng = np.random.default_rng(seed)
    kp.compile(stewart_stack(1)).propagate({"M1_L1.length": 0.6})  # imports and JIT outside the measurement
    rows: list[Row] = []
    summary: dict = {}
    for variant in VARIANTS:
        s: dict = {}
        for K in Ks:
            r, entry = bench_k(K, variant, trials, rng)
            rows += r
            for key, v in entry.items():
                s.setdefault(key, []).append(v)
        summary[variant] = s
    return rows, summary


def exponent(K: list[int], t: list[float], kmin: int = EXP_K[0], kmax: int = EXP_K[1]) -> float:
    """Least-squares slope of log t against log K over kmin <= K <= kmax."""
    K_, t_ = np.array(K, float), np.array(t, float)
    sel = (kmin <= K_) & (kmax >= K_)
    if sel.sum() < 2:
        sel = np.ones_like(K_, bool)
    return float(np.polyfit(np.log(K_[sel]), np.log(t_[sel]), 1)[0])


def summary_lines(summary: dict) -> list[str]:
    """The issue's P2 numbers, one line each, for both variants."""
    out = []
    for variant, s in summary.items():
        kk = s["K"]
        plans = sorted(set(s["plan"]) - {"dense"})
        line = f"P2 {variant}: plan {', '.join(plans) or 'dense'}"
        if 128 in kk:
            i = kk.index(128)
            line += (f"; K=128 engine.solve {s['solve_ms'][i]:.3f} ms median (min {s['solve_min_ms'][i]:.3f}; "
                     f"target <= 1.5), by address {s['propagate_ms'][i]:.3f} ms, "
                     f"hand numpy {s['hand_ms'][i]:.3f} ms")  # fmt: skip
        out.append(line)
        for key, label in (("solve_ms", "engine.solve time"), ("propagate_ms", "engine.propagate time"),
                           ("hand_ms", "hand numpy time"), ("mem_MiB", "build+compile memory")):  # fmt: skip
            line = (
                f"P2 {variant} growth exponent in K of {label}: {exponent(kk, s[key]):.3f} (K {EXP_K[0]}..{EXP_K[1]})"
            )
            if max(kk) > EXP_K[1]:
                line += f", {exponent(kk, s[key], EXP_K[0], 1 << 30):.3f} (K {EXP_K[0]}..{max(kk)})"
            out.append(line + (" (target <= 1.0)" if key == "solve_ms" else ""))
        mem = ", ".join(f"{k}: {m:.2f}" for k, m in zip(kk, s["mem_MiB"], strict=True))
        out.append(f"P2 {variant} build+compile peak memory (MiB) by K: {mem}")
    return out


if __name__ == "__main__":
    from common import print_table

    kmax = int(sys.argv[1]) if len(sys.argv) > 1 else 512
    t0 = time.perf_counter()
    rows, s = run([1 << i for i in range(kmax.bit_length()) if (1 << i) <= kmax])
    print_table(rows)
    for line in summary_lines(s):
        print(line)
    print(f"total {time.perf_counter() - t0:.1f} s")
