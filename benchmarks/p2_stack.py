"""P2: a stack of K Stewart modules (each platform is the next module's base).

Time per re-assembly after every leg changes by +-2 mm, peak memory (tracemalloc) of building,
compiling and solving, and the fitted growth exponent of time in K. Methods: kinprop fast
(numba Newton over the block-diagonal free Jacobian), kinprop sparse (scipy ``splu`` with the
column ordering reused), the hand-written numpy Newton (the same relative-pose equations,
batched over modules), ``least_squares`` with finite differences and the Jacobian's sparsity
(K <= 16 only: its cost grows fast), and the reference ``propagate`` (K <= 4).
Check: every leg length of every module by inverse kinematics from the solved relative poses.
"""

from __future__ import annotations

import os
import sys
import time
import tracemalloc

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from common import Row, compare, exp_so3, leg_lengths, stewart_hand_newton
from kinprop.fast import compile_model, pack
from kinprop.fast.sparse import SparseSolver

from kinprop import propagate
from kinprop.builders import STEWART, leg_addresses, stewart_hardpoints, stewart_stack
from kinprop.spatial import euler_to_matrix


def poses(Q: np.ndarray, cols: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    idx = cols[:, None] + np.arange(7)
    q = Q[idx]
    return q[:, :3], euler_to_matrix(q[:, 3:])


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


def bench_k(K: int, trials: int, rng: np.random.Generator) -> tuple[list[Row], dict]:
    """All methods on a stack of K modules; returns the rows and a summary entry."""
    a, b = stewart_hardpoints()
    h = STEWART["height"]
    tracemalloc.start()
    model = stewart_stack(K)
    comp = compile_model(model.mechanism)
    addrs = leg_addresses(model)
    st0 = pack(comp, model.design, model.coordinates)
    excl = set(addrs)
    blocks = SparseSolver(comp, ("q",), exclude=excl, method="blocks")
    build_now, build_peak = tracemalloc.get_traced_memory()
    tracemalloc.reset_peak()
    lidx = np.array([comp.joint_index[x.split(".")[0]] for x in addrs])
    fcols = np.array([comp.assembly.layout[f"M{k}_F.q"].start for k in range(1, K + 1)])
    l0 = st0.L[0, lidx].copy()
    deltas = [l0 + rng.choice([-2e-3, 2e-3], size=l0.size) for _ in range(trials)]

    def fast(dl, solver=blocks):
        Q, L = st0.Q[0].copy(), st0.L[0].copy()
        L[lidx] = dl
        solver.solve_one(Q, st0.S[0], st0.C[0], L)
        return Q

    fast(deltas[0])
    solve_peak = tracemalloc.get_traced_memory()[1] - build_now  # above the model's own memory
    tracemalloc.stop()
    splu = SparseSolver(comp, ("q",), exclude=excl, method="splu")
    A = np.broadcast_to(a, (K, 6, 3))
    B = np.broadcast_to(b, (K, 6, 3))
    x0 = np.tile([0.0, 0.0, h], (K, 1))
    R0 = np.tile(np.eye(3), (K, 1, 1))

    def hand(dl):
        x, R, _ = stewart_hand_newton(A, B, dl.reshape(K, 6), x0, R0)
        return x, R

    def check(dl, res):
        x, R = poses(res, fcols) if isinstance(res, np.ndarray) else res
        return np.abs(leg_lengths(A, B, x, R) - dl.reshape(K, 6)).max()

    def ref(dl):
        p = propagate(model, dict(zip(addrs, dl, strict=True)))
        q = np.concatenate([p.after.coordinates[f"M{k}_F"] for k in range(1, K + 1)])
        return poses(q, np.arange(K) * 7)

    methods = {"kinprop fast (blocks)": fast, "kinprop sparse (splu)": lambda dl: fast(dl, splu),
               "hand numpy Newton": hand}  # fmt: skip
    if K <= 16:
        methods["scipy least_squares (FD, sparse)"] = lambda dl: lsq_sparse(A, B, dl.reshape(K, 6), x0, R0)
    if K <= 4:
        methods["kinprop reference"] = ref
    rows = compare(f"P2 stack K={K}", deltas, methods, check, inner=3)
    mib = build_peak / 2**20
    rows[0].note = f"build+compile {mib:.2f} MiB, solve +{solve_peak / 2**20:.3f} MiB; " + rows[0].note
    med = {x.method: float(np.median(x.times)) for x in rows}
    entry = {"K": K, "fast_ms": med["kinprop fast (blocks)"], "fast_min_ms": float(np.min(rows[0].times)),
             "splu_ms": med["kinprop sparse (splu)"], "hand_ms": med["hand numpy Newton"], "mem_MiB": mib,
             "solve_mem_MiB": solve_peak / 2**20}  # fmt: skip
    print(f"  K={K}: fast {entry['fast_ms']:.3f} ms, {mib:.2f} MiB", file=sys.stderr, flush=True)
    return rows, entry


def run(Ks: list[int], trials: int = 5, seed: int = 0) -> tuple[list[Row], dict]:
    rng = np.random.default_rng(seed)
    SparseSolver(compile_model(stewart_stack(1).mechanism), method="blocks")  # imports and JIT outside the measurement
    rows: list[Row] = []
    summary: dict = {
        "K": [],
        "fast_ms": [],
        "fast_min_ms": [],
        "splu_ms": [],
        "hand_ms": [],
        "mem_MiB": [],
        "solve_mem_MiB": [],
    }
    for K in Ks:
        r, entry = bench_k(K, trials, rng)
        rows += r
        for key, v in entry.items():
            summary[key].append(v)
    return rows, summary


def exponent(K: list[int], t: list[float], kmin: int = 8, kmax: int = 1 << 30) -> float:
    """Least-squares slope of log t against log K over kmin <= K <= kmax."""
    K_, t_ = np.array(K, float), np.array(t, float)
    sel = (kmin <= K_) & (kmax >= K_)
    if sel.sum() < 2:
        sel = np.ones_like(K_, bool)
    return float(np.polyfit(np.log(K_[sel]), np.log(t_[sel]), 1)[0])


if __name__ == "__main__":
    from common import print_table

    t0 = time.perf_counter()
    rows, s = run([1, 2, 4, 8, 16, 32, 64, 128, 256, 512])
    print_table(rows)
    for key in ("fast_ms", "splu_ms", "hand_ms", "mem_MiB"):
        print(key, "exponent (K >= 8):", round(exponent(s["K"], s[key]), 3))
    print(f"total {time.perf_counter() - t0:.1f} s")
