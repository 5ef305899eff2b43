"""Propagation to targets: the minimum-norm design change that makes outputs reach given values.

The paper's system ``Phi(x) = 0`` is extended with target rows. With ``K`` configurations
(e.g. a suspension at several wheel travels) the unknowns are one copy of the coordinates per
configuration, ``q_1 .. q_K``, and the free design columns ``p`` shared by all of them:

    hard rows    H(z) = [Phi(q_1, p); ...; Phi(q_K, p); conditions]  = 0
    target rows  T(z) = [sum_k c_k f_k(q_k, p) - value]_rows           -> 0

``conditions`` are rows that define a configuration (``wheel-centre z = 50``) and must hold
exactly; targets are met exactly when they can be, else in the least-squares sense. Each
Newton step is the weighted minimum-norm solution of the linearised system, with the hard rows
first (hierarchical least squares, ``y = W^-1/2 dz``):

    y_h = -pinv(H_y) H,    N = I - pinv(H_y) H_y,    y = y_h + N pinv(T_y N) (-T - T_y y_h)

which for a consistent system is exactly ``-pinv([H_y; T_y]) [H; T]`` — the generalized
inverse of the paper's propagation over the stacked system — and otherwise the minimum-norm
step to the least-squares compromise of the targets while the mechanism stays assembled. The
step is applied on the manifold (:meth:`Engine.retract`: additive for q, s', l; exponential map
for C) halving only a step that blows a residual up tenfold (full Newton steps otherwise).

Jacobians: ``H``'s Phi block is the engine's analytic ``Phi_x`` (Table 1). A configuration's
output rows use its ``jacobian`` when given — :mod:`kinprop.analysis.targets` gives analytic
ones for points, hardpoints, distances, coordinates, design variables and the camber, toe and
wheel-centre metrics (:mod:`kinprop.propagation.point_jacobians`: the kernel's own partials,
chained through the metric formula) — and otherwise a **central difference of the output map
only** (forward kinematics, no re-solve) along each free state column on the manifold, as
:mod:`kinprop.analysis.sensitivity` does. Either way the chain rule through the assembly is
carried by the Newton system itself (the coordinates ``q_k`` are unknowns tied to ``p`` by
Phi), so the converged design is exact; a difference only perturbs the step direction (O(h^2)).

Conflicts: at the solution, the left singular vectors of ``T_y N`` (targets restricted to the
motions that keep every configuration assembled) whose singular value is (numerically) zero
span the target combinations no free design variable can change; the targets weighted in
such a vector that carries residual are reported together as conflicting (the same reading
as :mod:`kinprop.propagation.continuation`'s ``_conflict`` for constraint rows).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from kinprop.engine import Engine, State, Status
from kinprop.errors import AddressError
from kinprop.spatial import Array, log_so3

#: relative step of the output map's central difference
FD_STEP = 1e-6
#: relative cut-off of the pseudo-inverses (hard rows, reduced target rows)
RCOND_HARD, RCOND_TARGET = 1e-10, 1e-9
#: a Newton step is halved when it makes a residual norm this many times larger
BLOWUP = 10.0
#: a left singular vector component at least this large names a target in a conflict
CONFLICT_WEIGHT = 0.1

OutputMap = Callable[[State], Array]


@dataclass(frozen=True)
class Configuration:
    """One configuration of the mechanism: ``outputs(state)`` gives every output value its rows
    use; ``held`` coordinate addresses are set (solver units) and do not move in it."""

    name: str
    outputs: OutputMap
    held: Mapping[str, Any] = field(default_factory=dict)
    #: ``(state, columns) -> d outputs / d x`` (analytic); None: central differences of ``outputs``
    jacobian: Callable[[State, Array], Array] | None = None


@dataclass(frozen=True)
class Row:
    """One scalar row ``sum(c * outputs_k[i]) = value`` over ``terms`` ``(k, i, c)``; a hard row
    (a configuration's condition) must hold exactly. ``scale`` divides the residual (a target
    stated in a unit where ``scale`` is "one unit of miss")."""

    name: str
    value: float
    terms: tuple[tuple[int, int, float], ...]
    hard: bool = False
    scale: float = 1.0


@dataclass(frozen=True)
class TargetResult:
    """Outcome of :func:`solve_targets`.

    ``status``: ``met`` (every target within ``target_tol``), ``compromise`` (converged to the
    least-squares compromise; see ``conflicts``), or a failure in the one vocabulary of
    :class:`kinprop.Status`: ``not_converged`` (the message says when a configuration could not
    be reached with the starting design).
    """

    status: str
    message: str
    iterations: int
    rows: tuple[Row, ...]
    configurations: tuple[Configuration, ...]
    before: tuple[State, ...]
    after: tuple[State, ...]
    values_before: Array
    values_after: Array
    #: ``||Phi||`` over all configurations and the conditions' residual at the end
    hard_residual: float
    #: free design variable key -> change (s', l: difference; C: body-frame rotation vector, rad)
    design_change: dict[str, Array]
    #: groups of conflicting targets: ((target name, left-singular-vector weight), ...)
    conflicts: tuple[tuple[tuple[str, float], ...], ...] = ()
    history: tuple[float, ...] = ()
    free_columns: Array = field(default_factory=lambda: np.zeros(0, np.int64))

    @property
    def converged(self) -> bool:
        return self.status in ("met", "compromise")

    @property
    def targets(self) -> list[dict[str, Any]]:
        """Per target row (not conditions): name, wanted, before, achieved, residual."""
        return [
            {
                "target": r.name,
                "value": r.value,
                "before": float(b),
                "achieved": float(a),
                "residual": float(a - r.value),
            }
            for r, b, a in zip(self.rows, self.values_before, self.values_after, strict=True)
            if not r.hard
        ]


def _row_values(rows: Sequence[Row], outs: Sequence[Array]) -> Array:
    return np.array([sum(c * outs[k][i] for k, i, c in r.terms) for r in rows])


def _step_size(engine: Engine, state: State, col: int) -> float:
    v = next(v for v in engine.layout.variables if v.start <= col < v.start + v.size)
    if v.group == "C":
        return FD_STEP
    val = float(engine.get(state, v.key).ravel()[col - v.start])
    return FD_STEP * max(1.0, abs(val))


def output_jacobian(engine: Engine, f: OutputMap, state: State, columns: Array) -> Array:
    """``d f / d x`` over layout ``columns`` by central differences of the output map on the
    manifold (:meth:`Engine.retract`); no re-assembly."""
    cols = np.asarray(columns, np.int64)
    f0 = np.asarray(f(state), float)
    G = np.zeros((f0.size, cols.size))
    for k, c in enumerate(cols):
        h = _step_size(engine, state, int(c))
        dx = np.zeros(engine.n_columns)
        dx[c] = h
        G[:, k] = (np.asarray(f(engine.retract(state, dx))) - np.asarray(f(engine.retract(state, -dx)))) / (2 * h)
    return G


def _pinv(A: Array, rcond: float) -> Array:
    return np.linalg.pinv(A, rcond=rcond) if A.size else A.T.copy()


def _design_change(engine: Engine, a: State, b: State, pcols: Array) -> dict[str, Array]:
    pset = set(pcols.tolist())
    keys = dict.fromkeys(v.key for v in engine.layout.variables if pset & set(range(v.start, v.start + v.size)))
    out: dict[str, Array] = {}
    for key in keys:
        va, vb = engine.get(a, key), engine.get(b, key)
        if engine.layout[key].group == "C":
            out[key] = np.asarray(log_so3(vb.reshape(3, 3) @ va.reshape(3, 3).T), float)
        else:
            out[key] = np.asarray(vb - va, float).ravel()
    return out


def solve_targets(
    engine: Engine,
    start: State,
    configurations: Sequence[Configuration],
    rows: Sequence[Row],
    free: Sequence[str],
    *,
    coordinates: Sequence[str] = ("q",),
    weights: Mapping[str, float] | None = None,
    tol: float = 1e-9,
    target_tol: float = 1e-6,
    max_iter: int = 60,
) -> TargetResult:
    """The minimum-(weighted-)norm change of the ``free`` design columns (groups ``s C l`` or
    design addresses; shared by every configuration) that meets the target ``rows`` with every
    configuration assembled (module docstring). ``coordinates`` selects each configuration's
    free coordinates (minus its ``held`` ones). ``tol`` bounds ``||Phi||`` and the conditions
    (relative to the engine's round-off floor), ``target_tol`` the target residuals (row units
    over ``scale``)."""
    pcols = engine.columns(free) if free else np.zeros(0, np.int64)
    qset = set(engine.columns(["q"]).tolist())
    if set(pcols.tolist()) & qset:
        raise AddressError("targets: --free names design variables (hardpoints, s, C, l); coordinates move anyway")
    states, qcols = [], []
    conditioned = {int(k) for r in rows if r.hard for k, _, _ in r.terms}
    for n, cfg in enumerate(configurations):
        st, _, keys = engine.apply(start, cfg.held)
        states.append(st)
        # the declared inputs are held, unless a condition of this configuration drives them
        # (e.g. wheel travel sets the lower arm's angle)
        sel = [*coordinates, "inputs"] if n in conditioned and "q" in coordinates else coordinates
        qcols.append(engine.columns(sel, keys))
    wfull = np.ones(engine.n_columns)
    for sel, w in (weights or {}).items():
        if not (float(w) > 0 and np.isfinite(float(w))):
            raise AddressError(f"weight for {sel!r} must be positive, found {w}")
        wfull[engine.columns([sel])] = float(w)
    hard = [r for r in rows if r.hard]
    soft = [r for r in rows if not r.hard]
    floor = max(tol, engine.roundoff_floor(start))

    def blocks(sts: list[State], with_design: bool) -> tuple[Array, Array, Array, Array, list[Array]]:
        """Residuals and Jacobians over [q_1 .. q_K, p] of the hard and target rows."""
        npc = pcols.size if with_design else 0
        offs = np.cumsum([0] + [c.size for c in qcols])
        n = int(offs[-1]) + npc
        Hr, Hj = [], []
        outs, grads = [], []
        for k, st in enumerate(sts):
            Phi, J = engine.evaluate(st)
            row = np.zeros((Phi.size, n))
            row[:, offs[k] : offs[k + 1]] = J[:, qcols[k]]
            if npc:
                row[:, offs[-1] :] = J[:, pcols]
            Hr.append(Phi)
            Hj.append(row)
            cols = np.concatenate([qcols[k], pcols[:npc]])
            outs.append(np.asarray(configurations[k].outputs(st), float))
            cfg = configurations[k]
            grads.append(
                cfg.jacobian(st, cols) if cfg.jacobian is not None else output_jacobian(engine, cfg.outputs, st, cols)
            )

        def lin(rs: list[Row]) -> tuple[Array, Array]:
            val = np.zeros(len(rs))
            jac = np.zeros((len(rs), n))
            for r_, row in enumerate(rs):
                for k, i, c in row.terms:
                    val[r_] += c * outs[k][i]
                    jac[r_, offs[k] : offs[k + 1]] += c * grads[k][i, : qcols[k].size]
                    if npc:
                        jac[r_, offs[-1] :] += c * grads[k][i, qcols[k].size :]
                val[r_] = (val[r_] - row.value) / row.scale
                jac[r_] /= row.scale
            return val, jac

        hv, hj = lin(hard)
        tv, tj = lin(soft) if with_design else (np.zeros(0), np.zeros((0, n)))
        return np.concatenate(Hr + [hv]), np.vstack(Hj + [hj]), tv, tj, outs

    def apply_step(sts: list[State], dz: Array, with_design: bool) -> list[State]:
        offs = np.cumsum([0] + [c.size for c in qcols])
        new = []
        for k, st in enumerate(sts):
            dx = np.zeros(engine.n_columns)
            dx[qcols[k]] = dz[offs[k] : offs[k + 1]]
            if with_design and pcols.size:
                dx[pcols] = dz[offs[-1] :]
            new.append(engine.retract(st, dx))
        return new

    def newton(sts: list[State], with_design: bool) -> tuple[list[State], int, bool, list[float]]:
        hist: list[float] = []
        w = np.concatenate([np.ones(sum(c.size for c in qcols))] + ([wfull[pcols]] if with_design else []))
        sw = np.sqrt(w)
        for it in range(max_iter + 1):
            h, Hj, t, Tj, _ = blocks(sts, with_design)
            merit = float(h @ h + t @ t)
            hist.append(float(np.sqrt(merit)))
            Hy, Ty = Hj * sw, Tj * sw
            Hp = _pinv(Hy, RCOND_HARD)
            yh = -Hp @ h
            if t.size:
                Nm = np.eye(sw.size) - Hp @ Hy
                TN = Ty @ Nm
                y = yh + Nm @ (_pinv(TN, RCOND_TARGET) @ (-t - Ty @ yh))
            else:
                y = yh
            dz = sw * y
            hn = float(np.linalg.norm(h))
            small = float(np.linalg.norm(dz)) <= 1e-10 * max(1.0, engine.length_scale or 1.0)
            if hn < floor and (small or (t.size == 0) or float(np.max(np.abs(t), initial=0.0)) < target_tol * 1e-3):
                return sts, it, True, hist
            if it == max_iter:
                break
            # full Newton steps (the hard rows are re-closed quadratically at the next step);
            # halve only a step that blows a residual up (a jump towards another branch)
            lam, trial = 1.0, None
            tn = float(np.linalg.norm(t))
            for _ in range(8):
                trial = apply_step(sts, lam * dz, with_design)
                h2, _, t2, _, _ = blocks_residual(trial, with_design)
                h2n, t2n = float(np.linalg.norm(h2)), float(np.linalg.norm(t2))
                if np.isfinite(h2n + t2n) and h2n <= max(BLOWUP * hn, np.sqrt(floor)) and t2n <= BLOWUP * tn + 1e-12:
                    break
                lam *= 0.5
            sts = trial  # type: ignore[assignment]
            if not np.isfinite(merit) or merit > 1e30:
                break
        return sts, max_iter, False, hist

    def blocks_residual(sts: list[State], with_design: bool) -> tuple[Array, None, Array, None, None]:
        outs = [np.asarray(configurations[k].outputs(st), float) for k, st in enumerate(sts)]
        Phi = [engine.residual(st) for st in sts]
        hv = np.array([(v - r.value) / r.scale for r, v in zip(hard, _row_values(hard, outs), strict=True)])
        tv = (
            np.array([(v - r.value) / r.scale for r, v in zip(soft, _row_values(soft, outs), strict=True)])
            if with_design
            else np.zeros(0)
        )
        return np.concatenate(Phi + [hv]), None, tv, None, None

    # 1. every configuration with the starting design (the "before" curves)
    before, it0, ok0, _ = newton(states, with_design=False)
    outs0 = [np.asarray(c.outputs(s), float) for c, s in zip(configurations, before, strict=True)]
    vb = _row_values(rows, outs0)
    if not ok0:
        return TargetResult(Status.NOT_CONVERGED.value, "not assembled: a configuration could not be reached with "
                            "the starting design (its conditions or Phi did not converge)", it0, tuple(rows),
                            tuple(configurations), tuple(before), tuple(before), vb, np.full_like(vb, np.nan),
                            float("nan"), {})  # fmt: skip
    # 2. the design change
    after, it, ok, hist = newton(list(before), with_design=True)
    outs = [np.asarray(c.outputs(s), float) for c, s in zip(configurations, after, strict=True)]
    va = _row_values(rows, outs)
    h, Hj, t, Tj, _ = blocks(after, True)
    hard_res = float(np.linalg.norm(h))
    conflicts: list[tuple[tuple[str, float], ...]] = []
    if t.size:
        sw = np.sqrt(np.concatenate([np.ones(sum(c.size for c in qcols)), wfull[pcols]]))
        Hy, Ty = Hj * sw, Tj * sw
        TN = Ty @ (np.eye(sw.size) - _pinv(Hy, RCOND_HARD) @ Hy)
        U, sv, _ = np.linalg.svd(TN)
        rank = int(np.sum(sv > RCOND_TARGET * max(sv.max(initial=0.0), 1e-300))) if sv.size else 0
        for m in range(rank, U.shape[1]):
            u = U[:, m]
            if abs(u @ t) > target_tol:
                grp = tuple((soft[i].name, float(u[i])) for i in np.argsort(-np.abs(u)) if abs(u[i]) >= CONFLICT_WEIGHT)
                conflicts.append(grp)
    worst = float(np.max(np.abs(t), initial=0.0))
    if not ok:
        status = Status.NOT_CONVERGED.value
        msg = (
            f"not converged after {it} iterations: ||Phi, conditions|| = {hard_res:.3g}, worst target miss {worst:.3g}"
        )
    elif worst <= target_tol:
        status, msg = "met", f"targets met in {it} iterations (worst miss {worst:.3g}, ||Phi|| = {hard_res:.3g})"
    else:
        status = "compromise"
        names = "; ".join(" vs ".join(n for n, _ in g) for g in conflicts) or "none identified"
        msg = (f"targets cannot all be met: least-squares compromise after {it} iterations, worst miss {worst:.3g}; "
               f"conflicting: {names}")  # fmt: skip
    return TargetResult(status, msg, it0 + it, tuple(rows), tuple(configurations), tuple(before), tuple(after), vb,
                        va, hard_res, _design_change(engine, before[0], after[0], pcols), tuple(conflicts),
                        tuple(hist), pcols)  # fmt: skip


__all__ = ["Configuration", "OutputMap", "Row", "TargetResult", "output_jacobian", "solve_targets"]
