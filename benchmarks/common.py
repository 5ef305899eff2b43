"""Shared helpers for the benchmarks: interleaved timing, pairwise ratios, hand-written baselines."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np


@dataclass
class Row:
    problem: str
    method: str
    unit: str
    times: list[float]
    ratios: list[float] = field(default_factory=list)
    error: float = float("nan")
    note: str = ""

    def cells(self) -> list[str]:
        t = self.times
        ratio = f"{statistics.median(self.ratios):.3g}" if self.ratios else "-"
        return [self.problem, self.method, _fmt(statistics.median(t)), _fmt(min(t)), _fmt(max(t)), self.unit,
                ratio, f"{self.error:.1e}", self.note]  # fmt: skip


def _fmt(x: float) -> str:
    return f"{x:.4g}"


HEADER = ["problem", "method", "median", "min", "max", "unit", "time / hand baseline (pairwise)", "max error", "note"]
#: the hand-written baseline every ratio is taken against (when a problem has it)
BASELINE = "hand numpy Newton"


def compare(
    problem: str,
    trials: Sequence[object],
    methods: dict[str, Callable[[object], object]],
    check: Callable[[object, object], float],
    unit: str = "ms",
    scale: float = 1e3,
    per: float = 1.0,
    notes: dict[str, str] | None = None,
    inner: int = 1,
    ref: str | None = None,
) -> list[Row]:
    """Time every method on every trial, interleaved (method order rotates per trial).

    The method ``ref`` (default: the hand-written baseline, the method whose name starts with
    :data:`BASELINE`, else the first) is the reference for the pairwise ratios
    ``t_method / t_ref`` (same trial).
    ``per`` divides each time (e.g. steps per trial); ``check`` returns an error for a result.
    With ``inner`` > 1 each method solves the trial ``inner`` times back to back (every call
    starts from the same state) and the trial's time is the median of the calls after the first;
    the first ("cold") call, slowed by the caches the previous method left behind, is reported
    in the note of the first method.
    """
    names = list(methods)
    for name in names:  # warm-up (JIT, caches)
        methods[name](trials[0])
    times: dict[str, list[float]] = {n: [] for n in names}
    cold: dict[str, list[float]] = {n: [] for n in names}
    errors: dict[str, float] = dict.fromkeys(names, 0.0)
    for k, trial in enumerate(trials):
        order = names[k % len(names) :] + names[: k % len(names)]
        for name in order:
            dts = []
            for _ in range(inner):
                t0 = time.perf_counter()
                res = methods[name](trial)
                dts.append(time.perf_counter() - t0)
            cold[name].append(dts[0] * scale / per)
            times[name].append(statistics.median(dts[1:] if inner > 1 else dts) * scale / per)
            errors[name] = max(errors[name], float(check(trial, res)))
    if ref is None:
        ref = next((n for n in names if n.startswith(BASELINE)), names[0])
    first = times[ref]
    rows = []
    for name in names:
        ratios = [a / b for a, b in zip(times[name], first, strict=True)]
        rows.append(Row(problem, name, unit, times[name], ratios, errors[name], (notes or {}).get(name, "")))
    if inner > 1:
        c = statistics.median(cold[names[0]])
        rows[0].note = (rows[0].note + "; " if rows[0].note else "") + f"cold first call {_fmt(c)} {unit}"
    return rows


def print_table(rows: list[Row]) -> str:
    """A Markdown table of the rows (also printed)."""
    cells = [HEADER] + [r.cells() for r in rows]
    widths = [max(len(c[i]) for c in cells) for i in range(len(HEADER))]
    lines = ["| " + " | ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)) + " |" for row in cells]
    lines.insert(1, "|" + "|".join("-" * (w + 2) for w in widths) + "|")
    text = "\n".join(lines)
    print(text, flush=True)
    return text


# --- hand-written baselines --------------------------------------------------------------------


def exp_so3(w: np.ndarray) -> np.ndarray:
    """Rodrigues, batched over leading axes."""
    th = np.linalg.norm(w, axis=-1)[..., None, None]
    K = np.zeros(w.shape[:-1] + (3, 3))
    K[..., 0, 1], K[..., 0, 2], K[..., 1, 2] = -w[..., 2], w[..., 1], -w[..., 0]
    K[..., 1, 0], K[..., 2, 0], K[..., 2, 1] = w[..., 2], -w[..., 1], w[..., 0]
    ths = np.where(th < 1e-8, 1.0, th)
    a = np.where(th < 1e-8, 1.0, np.sin(ths) / ths)
    b = np.where(th < 1e-8, 0.5, (1 - np.cos(ths)) / ths**2)
    return np.eye(3) + a * K + b * (K @ K)


def stewart_hand_newton(a, b, lengths, x, R, tol=1e-10, max_iter=50):
    """Hand-written Stewart forward kinematics, batched over a leading axis N.

    a (N, 6, 3) base points, b (N, 6, 3) platform points, lengths (N, 6), pose x (N, 3),
    R (N, 3, 3). Constraints ``|x + R b_k - a_k|^2 - l_k^2``; analytic Jacobian
    ``[2 d_k, 2 (R b_k) x d_k]`` for ``dx`` and the global rotation increment ``w``
    (``R <- exp(w) R``); ``numpy.linalg.solve`` on the active variants until ``||f|| < tol``.
    """
    x, R = x.copy(), R.copy()
    N = x.shape[0]
    iters = np.zeros(N, dtype=int)
    active = np.arange(N)
    for _ in range(max_iter + 1):
        Rb = np.einsum("nij,nkj->nki", R[active], b[active])
        d = x[active, None, :] + Rb - a[active]
        f = np.einsum("nki,nki->nk", d, d) - lengths[active] ** 2
        done = np.linalg.norm(f, axis=1) < tol
        active, d, Rb, f = active[~done], d[~done], Rb[~done], f[~done]
        if active.size == 0:
            break
        J = np.empty((active.size, 6, 6))
        J[:, :, :3] = 2 * d
        J[:, :, 3:] = 2 * np.cross(Rb, d)
        step = np.linalg.solve(J, -f[..., None])[..., 0]
        x[active] += step[:, :3]
        R[active] = exp_so3(step[:, 3:]) @ R[active]
        iters[active] += 1
    return x, R, iters


def stewart_least_squares(a, b, lengths, x0, R0):
    """``scipy.optimize.least_squares`` (MINPACK LM, finite differences) on one platform."""
    from scipy.optimize import least_squares

    def fun(z):
        R = exp_so3(z[3:]) @ R0
        d = z[:3] + b @ R.T - a
        return np.einsum("ki,ki->k", d, d) - lengths**2

    sol = least_squares(fun, np.concatenate([x0, np.zeros(3)]), method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15)
    return sol.x[:3], exp_so3(sol.x[3:]) @ R0


def leg_lengths(a, b, x, R):
    """Closed-form inverse kinematics: leg lengths ``|x + R b_k - a_k|`` of a platform pose."""
    return np.linalg.norm(x[..., None, :] + np.einsum("...ij,...kj->...ki", R, b) - a, axis=-1)


EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@dataclass
class StewartBench:
    """The P1/P4 setup: ``examples/stewart.yaml`` (distance legs ``L1``..``L6`` on a free
    joint ``P``), compiled, with its hardpoints read back from the engine's reference state."""

    a: np.ndarray  # base hardpoints (base frame)
    b: np.ndarray  # platform hardpoints (platform frame)
    model: object
    engine: object  # kinprop.Engine
    legs: list[str]  # leg joint names
    lidx: list[int]  # their joints' index in the state's L / S arrays
    fcol: int  # first column of the platform's free joint in Q
    st: object  # the engine's reference State
    l0: np.ndarray  # nominal leg lengths
    x0: np.ndarray  # nominal platform position
    R0: np.ndarray  # nominal platform orientation
    keys: set[str]  # the leg-length variable keys (locked, never free)
    cols: np.ndarray  # free columns: q minus the locked legs (leg lengths are not q: all of q)


def stewart_bench(path: Path | str = EXAMPLES / "stewart.yaml", free_joint: str = "P") -> StewartBench:
    import kinprop as kp
    from kinprop.spatial import euler_to_matrix

    # the designer's start is an assembled mechanism: the file's 6-digit anchors and lengths
    # leave a residual of ~6e-7, so assemble once (every method then starts from that pose)
    model = kp.assemble(kp.load_model(path)).after
    engine = kp.compile(model)
    legs = [j.name for j in model.mechanism.joints if j.type == "distance"]
    lidx = [engine.joint_index[j] for j in legs]
    st = engine.reference
    a, b = st.S[lidx, 0].copy(), st.S[lidx, 1].copy()
    fcol = engine.target(f"{free_joint}.q").start
    q = st.Q[fcol : fcol + 7]
    keys = {f"{j}.length" for j in legs}
    cols = engine.columns(("q",), keys)
    return StewartBench(a, b, model, engine, legs, lidx, fcol, st, st.L[lidx].copy(), q[:3].copy(),
                        euler_to_matrix(q[3:]), keys, cols)  # fmt: skip


def platform_pose(Q: np.ndarray, col: int) -> tuple[np.ndarray, np.ndarray]:
    """``(x, R)`` of a free joint's coordinates (position, Euler parameters) at ``Q[..., col:col+7]``."""
    from kinprop.spatial import euler_to_matrix

    q = np.asarray(Q)[..., col : col + 7]
    return q[..., :3], euler_to_matrix(q[..., 3:])
