"""Propagation to targets: the minimum-norm design change that makes outputs reach given values.

The paper's system ``Phi(x) = 0`` is extended with target rows. With ``K`` configurations
(e.g. a suspension at several wheel travels) the outer unknowns are the free design columns
``p``, shared by all of them, and the declared inputs ``u_k`` a configuration's conditions drive;
each configuration's other coordinates ``q_k`` are not unknowns of their own: they are the
engine's assembly at ``(u_k, p)`` (:meth:`kinprop.engine.Engine.solve`, the one compiled
branch-following Newton loop, followed from the previous iterate so every configuration stays on
its branch):

    hard rows    H(z) = conditions(q_k(u_k, p), u_k, p)          = 0
    target rows  T(z) = [sum_k c_k f_k(q_k, p) - value]_rows      -> 0

``conditions`` are rows that define a configuration (``wheel-centre z = 50``) and must hold
exactly; targets are met exactly when they can be, else in the least-squares sense. Each outer
step is the weighted minimum-norm solution of the linearised rows, with the hard rows first
(hierarchical least squares, ``y = W^-1/2 dz``):

    y_h = -pinv(H_y) H,    N = I - pinv(H_y) H_y,    y = y_h + N pinv(T_y N) (-T - T_y y_h)

the minimum-norm step to the least-squares compromise of the targets (``y`` in metres and
radians over sqrt(weight): :attr:`Engine.si_scale`), its targets' part a trust-region
(Levenberg-Marquardt) step: ``pinv(T_y N)`` damped to the radius, a step taken only when the
miss falls, the design's total change within the mechanism's size (``REACH``), so an
unreachable target ends at the least-squares best within reach. The rows' Jacobians over
``z`` eliminate the coordinates by the implicit-function theorem at each assembly,
``dq_k/dz = -Phi_q^+ Phi_z`` (the engine's analytic ``Phi_x``, Table 1), the design step is
applied on the manifold (:meth:`Engine.retract`: additive for q, s', l; exponential map for C)
and the configurations re-assembled by the engine; the conditions alone (the "before" solve)
take Newton steps halved only when an assembly fails or the residual grows tenfold.

A configuration's output rows use its ``jacobian`` when given — :mod:`kinprop.analysis.targets`
gives analytic ones for points, hardpoints, distances, coordinates, design variables and the
camber, toe, caster, KPI and wheel-centre metrics (:mod:`kinprop.propagation.point_jacobians`: the kernel's
own partials, chained through the metric formula) — and otherwise a **central difference of the
output map only** (forward kinematics, no re-solve) along each state column on the manifold, as
:mod:`kinprop.analysis.sensitivity` does. Either way every iterate is an exact assembly and the
rows are evaluated exactly, so the converged design is exact; a difference only perturbs the step
direction (O(h^2)).

Bounds (``Row.bound``: ``<=`` or ``>=``): a bound's residual is its violation only, zero while
it holds (its row then drops out of the step); a violated bound is driven onto its limit like an
equality; with bounds, a design step is halved whenever it makes the residual larger (the
violation is not smooth where a bound starts or stops holding, and full Gauss-Newton steps
can cycle there); when no halved step lowers it (the conditions holding), the iteration ends
at that compromise, and also when the residual norm stops decreasing (relative ``STALL``). A
bound is met when it holds at the end, in conflict when the compromise
leaves it violated.

Conflicts: at the solution, the left singular vectors of ``T_y N`` (targets restricted to the
motions that keep every condition) whose singular value is (numerically) zero span the target
combinations no free design variable can change; the targets weighted in such a vector that
carries residual are reported together as conflicting (the same reading as
:mod:`kinprop.propagation.continuation`'s ``_conflict`` for constraint rows).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from kinprop.engine.engine import Engine, Solution, State, Status
from kinprop.errors import AddressError
from kinprop.spatial import Array, log_so3

#: relative step of the output map's central difference
FD_STEP = 1e-6
#: relative cut-off of the pseudo-inverses (hard rows, reduced target rows)
RCOND_HARD, RCOND_TARGET = 1e-10, 1e-9
#: a Newton step is halved when it makes a residual norm this many times larger
BLOWUP = 10.0
#: relative decrease of the residual norm below which an iteration with bounds has stalled
STALL = 1e-9
#: a left singular vector component at least this large names a target in a conflict
CONFLICT_WEIGHT = 0.1
#: the trust region of the design step (SI: metres and radians over sqrt(weight)): the first
#: radius and the largest, and the largest total design change, as fractions of the
#: mechanism's size (:attr:`Engine.length_scale`, at least one metre)
RADIUS_START, RADIUS_MAX, REACH = 1.0, 1.0, 1.0
#: a step is taken when the residual falls by at least this fraction of the linear model's
#: predicted fall; the radius doubles above ``GOOD`` (when the step used it), shrinks below ``POOR``
ACCEPT, POOR, GOOD = 1e-4, 0.25, 0.75
#: a least-squares compromise is stationary when the part of the targets' miss ``r`` that the
#: linear model can remove is at most ``GTOL |r|`` (``|U^T r|``, ``U`` the range of the targets'
#: Jacobian on the conditions' null space): the full step would lower ``|r|^2`` by ``GTOL^2``
GTOL = 1e-8

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
    #: ``(state, X) -> (n_outputs, K)``: exact rates of every output along ``K`` state
    #: directions ``X`` (K, n_columns) tangent to the constraints (loads: the differentiated
    #: equilibrium, which has no partials off the constraint manifold); when given, it is used
    #: instead of ``jacobian``
    rates: Callable[[State, Array], Array] | None = None
    #: the configuration's own engine (a model with drive joints, :mod:`kinprop.analysis.drives`:
    #: the same design variables by address); None: :func:`solve_targets`' engine
    engine: Engine | None = None
    #: its starting state in that engine (None: :func:`solve_targets`' ``start``)
    start: State | None = None
    #: its free coordinates (groups, addresses; minus ``held``); None: :func:`solve_targets`'
    coordinates: tuple[str, ...] | None = None


@dataclass(frozen=True)
class ExternalDesign:
    """Free design variables outside the engine's state, e.g. element points
    (:mod:`kinprop.propagation.element_points`): they move no body, so no assembly depends on
    them, only the configurations' outputs. Outer unknowns after the design columns.

    ``configurations(e)``: the configurations with the variables at ``e`` (their outputs);
    ``partials(k, state, e)``: ``(n_outputs_k, len(e))``, the exact partial derivatives of
    configuration ``k``'s outputs with respect to ``e`` at ``state`` (no coordinate responds);
    ``weights``: as the design columns' (a larger weight lets a variable move more)."""

    names: tuple[str, ...]
    start: Array
    configurations: Callable[[Array], Sequence[Configuration]]
    partials: Callable[[int, State, Array], Array]
    weights: Array | None = None


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
    #: ``""`` an equality; ``"<="`` / ``">="`` a bound: the row's residual is its violation only
    #: (zero while ``value`` is not exceeded), so a met bound does not pull the design
    bound: str = ""

    def miss(self, v: float) -> float:
        """The row's miss at the value ``v``: ``v - value`` (a bound's violation, 0 when it holds)."""
        r = v - self.value
        return max(r, 0.0) if self.bound == "<=" else min(r, 0.0) if self.bound == ">=" else r


@dataclass(frozen=True)
class TargetResult:
    """Outcome of :func:`solve_targets`.

    ``status`` (:class:`kinprop.Status`): ``converged`` (every configuration assembled, the
    conditions held and the iteration finished: the targets are ``met``, or at their
    least-squares compromise, see ``conflicts``) or ``not_converged`` (the message says when a
    configuration could not be reached with the starting design). ``targets_status`` says
    ``met``/``compromise`` (or the status when not converged).
    """

    status: Status
    message: str
    iterations: int
    rows: tuple[Row, ...]
    configurations: tuple[Configuration, ...]
    before: tuple[State, ...]
    after: tuple[State, ...]
    values_before: Array
    values_after: Array
    #: the scaled ``||Phi||`` over all configurations (:attr:`Solution.residual`'s figure, metres)
    #: combined with the conditions' miss (row units over ``scale``) at the end
    hard_residual: float
    #: free design variable key -> change (s', l: difference; C: body-frame rotation vector, rad)
    design_change: dict[str, Array]
    #: groups of conflicting targets: ((target name, left-singular-vector weight), ...)
    conflicts: tuple[tuple[tuple[str, float], ...], ...] = ()
    history: tuple[float, ...] = ()
    free_columns: Array = field(default_factory=lambda: np.zeros(0, np.int64))
    #: every target within ``target_tol`` (converged, not a compromise)
    met: bool = False
    #: the engine's solution of each configuration at the end (``after``'s states)
    solutions: tuple[Solution, ...] = ()
    #: the hard and the target rows' Jacobians over the outer unknowns ``z = [u_1 .. u_K, p, e]``
    #: at the end (each configuration's coordinates eliminated), and the number of ``u`` columns
    row_jacobians: tuple[Array, Array, int] | None = None
    #: the :class:`ExternalDesign` variables' values at the end (None: none were free)
    external: Array | None = None
    #: each configuration's engine (``before``/``after`` are states of these)
    engines: tuple[Engine, ...] = ()

    @property
    def converged(self) -> bool:
        return self.status is Status.CONVERGED

    @property
    def targets_status(self) -> str:
        """``met``, ``compromise`` (converged to the least-squares compromise) or the status."""
        return ("met" if self.met else "compromise") if self.converged else self.status.value

    @property
    def targets(self) -> list[dict[str, Any]]:
        """Per target row (not conditions): name, wanted, before, achieved, miss (``achieved -
        wanted``, a bound's violation; row units: not ``||Phi||``, which ``residual`` names)."""
        return [
            {
                "target": r.name,
                "value": r.value,
                "before": float(b),
                "achieved": float(a),
                "miss": r.miss(float(a)),
                "bound": r.bound,
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


def _same_columns(engine: Engine, other: Engine, cols: Array) -> Array:
    """``engine``'s layout columns ``cols`` in ``other``'s layout (the same variables by key)."""
    if other is engine:
        return cols
    out = np.empty(cols.size, np.int64)
    for n, c in enumerate(cols.tolist()):
        v = next(v for v in engine.layout.variables if v.start <= c < v.start + v.size)
        out[n] = other.layout[v.key].start + c - v.start
    return out


def _response(engine: Engine, J: Array, inner: Array, zc: Array) -> Array:
    """``dq/dz = -Phi_q^+ Phi_z`` of the coordinates ``inner`` to the columns ``zc``: with
    freedom left (mobility), the least change in metres and radians, as the engine's assembly
    takes it (:meth:`Engine.weights_for`), so the linear model is the assembly's in any unit."""
    if not zc.size:
        return np.zeros((inner.size, 0))
    Js = J * engine.row_scale[:, None]
    metric = engine.weights_for(inner, None)
    if metric is None:
        return -np.linalg.lstsq(Js[:, inner], Js[:, zc], rcond=None)[0]
    d = np.sqrt(metric)
    return -d[:, None] * np.linalg.lstsq(Js[:, inner] * d, Js[:, zc], rcond=None)[0]


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


def _step(Hy: Array, h: Array, Ty: Array, t: Array, radius: float = np.inf, sv_floor: float = 0.0
          ) -> tuple[Array, float]:  # fmt: skip
    """The hierarchical minimum-norm step (module docstring): the hard rows first, the target
    rows in what they leave free, in the scaled unknowns ``y``; the targets' part damped
    (Levenberg-Marquardt) to at most ``radius`` long, without the directions whose singular
    value is below ``sv_floor`` (they change no target). Also ``|U^T r| / |r|`` of the targets'
    linear least-squares problem ``A v = r`` there (0: stationary, a compromise; 1: consistent)."""
    Hp = _pinv(Hy, RCOND_HARD)
    yh = -Hp @ h
    if not t.size:
        return yh, 0.0
    Nm = np.eye(Hy.shape[1]) - Hp @ Hy
    A, r = Ty @ Nm, -t - Ty @ yh
    U, sv, Vt = np.linalg.svd(A, full_matrices=False)
    keep = sv > max(RCOND_TARGET * sv.max(initial=0.0), sv_floor, 1e-300)
    U, sv, Vt = U[:, keep], sv[keep], Vt[keep]
    c = U.T @ r
    rn = float(np.linalg.norm(r))
    cosine = float(np.linalg.norm(c)) / rn if rn > 0 else 0.0
    return yh + Vt.T @ _damped(sv, c, radius), cosine


def _damped(sv: Array, c: Array, radius: float) -> Array:
    """The coefficients ``sv c / (sv^2 + mu)`` of the damped least-squares step along the right
    singular vectors, with the smallest ``mu >= 0`` that makes it at most ``radius`` long."""
    if not sv.size:
        return c * 0.0
    v = c / sv
    if float(np.linalg.norm(v)) <= radius:
        return v
    # |v(mu)| falls with mu, and is at most |sv c| / mu: bisection on log(mu) below that bound
    lo, hi = (np.log(float(np.linalg.norm(sv * c)) / radius) + d for d in (-70.0, 0.0))
    while hi - lo > 1e-10:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if float(np.linalg.norm(sv * c / (sv**2 + np.exp(mid)))) > radius else (lo, mid)
    return sv * c / (sv**2 + np.exp(hi))


def _within(total: Array, y: Array, reach: float) -> float:
    """The largest ``a`` in [0, 1] with ``|total + a y| <= reach``."""
    if float(np.linalg.norm(total + y)) <= reach:
        return 1.0
    a, b, c = float(y @ y), 2.0 * float(total @ y), float(total @ total) - reach**2
    if a <= 0.0 or c >= 0.0:
        return 0.0
    return max(0.0, min(1.0, (-b + np.sqrt(b * b - 4.0 * a * c)) / (2.0 * a)))


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
    external: ExternalDesign | None = None,
    tie: Array | None = None,
) -> TargetResult:
    """The minimum-(weighted-)norm change of the ``free`` design columns (groups ``s C l`` or
    design addresses; shared by every configuration) that meets the target ``rows`` with every
    configuration assembled (module docstring). ``coordinates`` selects each configuration's
    free coordinates (minus its ``held`` ones); the declared inputs a condition drives are
    unknowns of the outer iteration. ``tol`` bounds ``||Phi||`` and the conditions (relative to
    the engine's round-off floor), ``target_tol`` the target residuals (row units over
    ``scale``). Every assembly is the engine's solve (:meth:`Engine.solve`) — a configuration's
    own (:attr:`Configuration.engine`, e.g. with drive joints) when it has one; ``free``
    addresses name the same variables in every engine. ``external``: free variables outside
    the state (:class:`ExternalDesign`; then ``configurations`` are
    ``external.configurations(external.start)``). ``tie``: the design unknowns are ``y`` with
    ``d(free columns) = tie @ y`` (one column of ``tie`` per unknown, e.g. a global hardpoint
    component that writes the s' columns of both its bodies together; its unknown is a length,
    weight 1) instead of the free columns themselves."""
    e0 = np.zeros(0) if external is None else np.asarray(external.start, dtype=float).ravel()
    ne = e0.size
    built: dict[bytes, Sequence[Configuration]] = {}
    if external is not None:
        configurations = built[e0.tobytes()] = external.configurations(e0.copy())
    pcols = engine.columns(free) if free else np.zeros(0, np.int64)
    P = np.eye(pcols.size) if tie is None else np.asarray(tie, dtype=float)
    if P.shape[0] != pcols.size:
        raise ValueError(f"tie: {P.shape[0]} rows for {pcols.size} free design columns")
    # each unknown's weight and SI factor: a column's own, a tied global coordinate's 1 and metres
    alone = [np.flatnonzero(P[:, j]) for j in range(P.shape[1])]
    own = [a[0] if a.size == 1 and P[a[0], j] == 1.0 else -1 for j, a in enumerate(alone)]
    qset = set(engine.columns(["q"]).tolist())
    if set(pcols.tolist()) & qset:
        raise AddressError("targets: --free names design variables (hardpoints, s, C, l); coordinates move anyway")
    goals, inner, driven = [], [], []
    engs = [cfg.engine or engine for cfg in configurations]
    starts = [start if cfg.start is None else cfg.start for cfg in configurations]
    pc = [_same_columns(engine, eng, pcols) for eng in engs]  # the free design columns in each engine
    conditioned = {int(k) for r in rows if r.hard for k, _, _ in r.terms}
    for n, cfg in enumerate(configurations):
        eng, coords = engs[n], coordinates if cfg.coordinates is None else cfg.coordinates
        st, _, keys = eng.apply(starts[n], cfg.held)
        goals.append(st)
        inner.append(eng.columns(coords, keys))
        # the declared inputs are held, unless a condition row of this configuration drives them
        # (e.g. a point's height sets the lower arm's angle): then they are outer unknowns
        drives = n in conditioned and "q" in coords
        driven.append(np.setdiff1d(eng.columns([*coords, "inputs"], keys), inner[-1]) if drives
                      else np.zeros(0, np.int64))  # fmt: skip
    wfull = np.ones(engine.n_columns)
    for sel, w in (weights or {}).items():
        if not (float(w) > 0 and np.isfinite(float(w))):
            raise AddressError(f"weight for {sel!r} must be positive, found {w}")
        wfull[engine.columns([sel])] = float(w)
    tie_w = np.array([wfull[pcols[i]] if i >= 0 else 1.0 for i in own])
    tie_si = np.array([engine.si_scale[pcols[i]] if i >= 0 else engine.unit for i in own])
    hard = [r for r in rows if r.hard]
    soft = [r for r in rows if not r.hard]
    bounded = any(r.bound for r in soft)
    floor = max(tol, *(eng.roundoff_floor(st) for eng, st in zip(engs, starts, strict=True)))
    solve_tol = min(tol, 1e-10)
    uoffs = np.cumsum([0] + [d.size for d in driven])

    def configs(e: Array) -> Sequence[Configuration]:
        """The configurations with the external variables at ``e`` (built once per value)."""
        if external is None:
            return configurations
        key = np.asarray(e, dtype=float).tobytes()
        if key not in built:
            if len(built) > 16:
                built.clear()
            built[key] = external.configurations(np.array(e, dtype=float))
        return built[key]

    def assemble(froms: Sequence[State], targets: Sequence[State]) -> list[Solution]:
        """Every configuration re-assembled by the engine at ``targets``' design and driven
        inputs, followed from ``froms`` on their branch."""
        return [engs[k].solve(a, inner[k], target=b, tol=solve_tol) for k, (a, b) in enumerate(zip(froms, targets,
                strict=True))]  # fmt: skip

    def residuals(sts: Sequence[State], with_design: bool, e: Array) -> tuple[Array, Array, list[Array]]:
        cfgs = configs(e)
        outs = [np.asarray(cfgs[k].outputs(st), float) for k, st in enumerate(sts)]
        hv = np.array([(v - r.value) / r.scale for r, v in zip(hard, _row_values(hard, outs), strict=True)])
        tv = (np.array([r.miss(v) / r.scale for r, v in zip(soft, _row_values(soft, outs), strict=True)])
              if with_design else np.zeros(0))  # fmt: skip
        return hv, tv, outs

    def jacobians(sts: Sequence[State], with_design: bool, e: Array, t: Array | None = None) -> tuple[Array, Array]:
        """The hard and target rows' Jacobians over the outer unknowns ``z = [u_1 .. u_K, p, e]``,
        each configuration's coordinates eliminated by the implicit-function theorem:
        ``dq/dz = -Phi_q^+ Phi_z`` at its assembly (no coordinate responds to ``e``); ``t`` the
        target residuals there (a bound row with zero residual holds: its row is zero)."""
        npc = pcols.size if with_design else 0
        nx = ne if with_design else 0
        n = int(uoffs[-1]) + (P.shape[1] if with_design else 0) + nx
        cfgs = configs(e)
        reduced = []
        for k, st in enumerate(sts):
            eng = engs[k]
            zc = np.concatenate([driven[k], pc[k][:npc]])
            _, J = eng.evaluate(st)
            dq = _response(eng, J, inner[k], zc)
            cols = np.concatenate([inner[k], zc])
            cfg = cfgs[k]
            if cfg.rates is not None:  # along the tangent directions e_z + dq/dz
                X = np.zeros((zc.size, eng.n_columns))
                X[np.arange(zc.size), zc] = 1.0
                X[:, inner[k]] = dq.T
                red = np.asarray(cfg.rates(st, X), float)
            else:
                G = cfg.jacobian(st, cols) if cfg.jacobian is not None else output_jacobian(eng, cfg.outputs, st,
                                                                                            cols)  # fmt: skip
                red = G[:, : inner[k].size] @ dq + G[:, inner[k].size :]
            if npc:  # over the design unknowns: d(columns) = P dy
                nu_k = driven[k].size
                red = np.hstack([red[:, :nu_k], red[:, nu_k:] @ P])
            if nx:  # the external variables move no coordinate: their partials alone
                red = np.hstack([red, np.asarray(external.partials(k, st, e), float)])  # type: ignore[union-attr]
            reduced.append(red)

        def lin(rs: list[Row], res: Array | None = None) -> Array:
            jac = np.zeros((len(rs), n))
            for r_, row in enumerate(rs):
                if res is not None and row.bound and res[r_] == 0.0:
                    continue  # a bound that holds: no row (its violation is flat there)
                for k, i, c in row.terms:
                    nu = driven[k].size
                    jac[r_, uoffs[k] : uoffs[k + 1]] += c * reduced[k][i, :nu]
                    if npc + nx:
                        jac[r_, uoffs[-1] :] += c * reduced[k][i, nu:]
                jac[r_] /= row.scale
            return jac

        return lin(hard), lin(soft, t) if with_design else np.zeros((0, n))

    def moved(sts: Sequence[State], dz: Array, with_design: bool) -> list[State]:
        """The goal of each configuration after the outer step ``dz``: its driven inputs and
        the shared design moved (:meth:`Engine.retract`), its other coordinates as they are."""
        out = []
        for k, st in enumerate(sts):
            dx = np.zeros(engs[k].n_columns)
            dx[driven[k]] = dz[uoffs[k] : uoffs[k + 1]]
            if with_design and pcols.size:
                dx[pc[k]] = P @ dz[uoffs[-1] : uoffs[-1] + P.shape[1]]
            out.append(engs[k].retract(st, dx))
        return out

    limited = [False]  # the last design iteration ended on the design-change limit (REACH)

    def metric(with_design: bool) -> Array:
        """``dz = sw y`` over the outer unknowns: ``y`` in metres and radians over sqrt(weight),
        so that a model in mm and in m take the same steps (:attr:`Engine.si_scale`)."""
        wp, sp = tie_w, tie_si
        w = np.concatenate([np.ones(int(uoffs[-1]))] + ([wp, wext] if with_design else []))
        si = np.concatenate([engs[k].si_scale[driven[k]] for k in range(len(engs))]
                            + ([sp, np.full(ne, engine.unit)] if with_design else []))  # fmt: skip
        return np.sqrt(w) / si

    size = max(1.0, (engine.length_scale or 1.0) * engine.unit)  # the mechanism's size, metres
    # a direction along which a change of the mechanism's size moves the targets less than a
    # thousandth of their tolerance changes none (round-off, e.g. caster by a tie-rod point)
    flat = 1e-3 * target_tol / size

    def iterate(sols: list[Solution], with_design: bool, e: Array) -> tuple[list[Solution], Array, int, bool,
                                                                              list[float]]:  # fmt: skip
        """Gauss-Newton on the conditions and targets over ``z``; every configuration stays an
        engine assembly. With targets, a trust-region (Levenberg-Marquardt) step in SI units
        over sqrt(weight): taken only when the miss falls, the radius shrinking when an assembly
        fails or the linear model is poor; the design's total change at most ``REACH`` times
        the mechanism's size. Without (the conditions alone): halved when an assembly fails or
        the residual blows up tenfold."""
        hist: list[float] = []
        nu, nx = int(uoffs[-1]), ne if with_design else 0
        sw = metric(with_design)
        radius, total, reach = RADIUS_START * size, np.zeros(sw.size - nu), REACH * size
        h, t, _ = residuals([s.state for s in sols], with_design, e)
        lm = with_design and t.size > 0
        for it in range(max_iter + 1):
            hist.append(float(np.sqrt(h @ h + t @ t)))
            sts = [s.state for s in sols]
            Hj, Tj = jacobians(sts, with_design, e, t)
            if not (np.all(np.isfinite(Hj)) and np.all(np.isfinite(Tj))):
                break  # an output's derivative is not finite there: not converged
            y, cosine = _step(Hj * sw, h, Tj * sw, t, sv_floor=flat)
            dz = sw * y
            hn = float(np.linalg.norm(h))
            # a small step is done unless it still changes the targets (a miss closed by a step
            # of a rotation column, radians, is a tiny dz too)
            small = float(np.linalg.norm(dz)) <= 1e-10 * max(1.0, engine.length_scale or 1.0) and (
                not t.size or float(np.max(np.abs(Tj @ dz), initial=0.0)) < target_tol * 1e-3)  # fmt: skip
            # with bounds the compromise is approached linearly: stalled (relative 1e-9) is done
            stalled = bounded and with_design and it > 0 and hist[-2] - hist[-1] <= STALL * hist[-1]
            met = t.size > 0 and float(np.max(np.abs(t), initial=0.0)) < target_tol * 1e-3
            if hn < floor and (small or stalled or cosine <= GTOL or t.size == 0 or met):
                if met and lm:  # one more full step, kept when it lowers the miss
                    trial = assemble(sts, moved(sts, dz, with_design))
                    e2 = e + dz[dz.size - nx :] if nx else e
                    if all(s.converged for s in trial):
                        h2, t2, _ = residuals([s.state for s in trial], with_design, e2)
                        if float(h2 @ h2 + t2 @ t2) < float(h @ h + t @ t) and float(np.linalg.norm(h2)) < floor:
                            return trial, e2, it + 1, True, [*hist, float(np.sqrt(h2 @ h2 + t2 @ t2))]
                return sols, e, it, True, hist
            if it == max_iter or not np.all(np.isfinite(dz)):
                break
            merit, taken = float(h @ h + t @ t), False
            for _ in range(30 if lm else 8):
                if lm:  # the trust-region step, kept inside the design-change limit
                    y = _step(Hj * sw, h, Tj * sw, t, radius, flat)[0]
                    a = _within(total, y[nu:], reach)
                    if a <= 1e-9:  # on the limit and pulled outwards: the best within it
                        limited[0] = hn < floor
                        return sols, e, it, hn < floor, hist
                    y = a * y
                    dz = sw * y
                trial = assemble(sts, moved(sts, dz, with_design))
                e2 = e + dz[dz.size - nx :] if nx else e
                if all(s.converged for s in trial):
                    h2, t2, _ = residuals([s.state for s in trial], with_design, e2)
                    new = float(h2 @ h2 + t2 @ t2)
                    if lm and np.isfinite(new):
                        lh, lt = h + Hj @ dz, t + Tj @ dz
                        pred = merit - float(lh @ lh + lt @ lt)
                        rho = (merit - new) / pred if pred > 0 else -1.0
                        step = float(np.linalg.norm(y[nu:])) if y.size > nu else float(np.linalg.norm(y))
                        if rho > GOOD and step >= 0.99 * radius:
                            radius = min(2.0 * radius, RADIUS_MAX * size)
                        elif rho < POOR:
                            radius = max(0.5 * step, 1e-300)
                        if rho > ACCEPT:
                            taken = True
                            break
                    elif not lm:
                        # with bounds (a non-smooth residual) a step must not make it larger
                        grow = 1.0 if bounded and with_design else BLOWUP
                        if np.isfinite(new) and np.sqrt(new) <= grow * np.sqrt(merit) + np.sqrt(floor):
                            taken = True
                            break
                elif lm:
                    radius = 0.5 * float(np.linalg.norm(y[nu:] if y.size > nu else y))
                if not lm:
                    dz = 0.5 * dz
                if lm and radius <= 1e-12 * size:
                    break
            if not taken:
                if with_design and hn < floor:  # no step, however short, lowers the miss: a compromise
                    return sols, e, it, True, hist
                break
            if lm:
                total = total + y[nu:]
            sols, h, t, e = trial, h2, t2, e2
        return sols, e, max_iter, False, hist

    wext = np.ones(ne) if external is None or external.weights is None else np.asarray(external.weights, float)
    if np.any(~(wext > 0) | ~np.isfinite(wext)):
        raise AddressError(f"the external variables' weights must be positive, found {wext.tolist()}")
    # 1. every configuration with the starting design (the "before" curves)
    first = assemble(starts, goals)
    if all(s.converged for s in first):
        before_sols, _, it0, ok0, _ = iterate(first, False, e0)
    else:
        before_sols, it0, ok0 = first, 0, False
    before = [s.state for s in before_sols]
    outs0 = [np.asarray(c.outputs(s), float) for c, s in zip(configurations, before, strict=True)]
    vb = _row_values(rows, outs0)
    if not ok0:
        return TargetResult(Status.NOT_CONVERGED, "not assembled: a configuration could not be reached with "
                            "the starting design (its conditions or Phi did not converge)", it0, tuple(rows),
                            tuple(configurations), tuple(before), tuple(before), vb, np.full_like(vb, np.nan),
                            float("nan"), {}, solutions=tuple(before_sols), engines=tuple(engs))  # fmt: skip
    # 2. the design change
    after_sols, e1, it, ok, hist = iterate(list(before_sols), True, e0)
    after = [s.state for s in after_sols]
    h, t, outs = residuals(after, True, e1)
    configurations = configs(e1)
    va = _row_values(rows, outs)
    # Solution.residual's figure (scaled ||Phi||, metres) over all configurations, and the conditions'
    phi = float(np.linalg.norm(np.concatenate([e.residual(s) * e.row_scale for e, s in zip(engs, after, strict=True)])))
    hard_res = float(np.hypot(phi, np.linalg.norm(h)))
    conflicts: list[tuple[tuple[str, float], ...]] = []
    final = None
    if t.size:
        Hj, Tj = jacobians(after, True, e1, t)
    if t.size and np.all(np.isfinite(Hj)) and np.all(np.isfinite(Tj)):
        final = (Hj, Tj, int(uoffs[-1]))
        sw = metric(True)
        Hy, Ty = Hj * sw, Tj * sw
        TN = Ty @ (np.eye(sw.size) - _pinv(Hy, RCOND_HARD) @ Hy)
        U, sv, _ = np.linalg.svd(TN)
        rank = int(np.sum(sv > max(RCOND_TARGET * sv.max(initial=0.0), flat, 1e-300))) if sv.size else 0
        for m in range(rank, U.shape[1]):
            u = U[:, m]
            if abs(u @ t) > target_tol:
                grp = tuple((soft[i].name, float(u[i])) for i in np.argsort(-np.abs(u)) if abs(u[i]) >= CONFLICT_WEIGHT)
                conflicts.append(grp)
    worst = float(np.max(np.abs(t), initial=0.0))
    met = ok and worst <= target_tol
    if not ok:
        msg = (
            f"not converged after {it} iterations: ||Phi|| = {phi:.3g}, conditions' miss "
            f"{float(np.linalg.norm(h)):.3g}, worst target miss {worst:.3g}"
        )
    elif met:
        msg = f"targets met in {it} iterations (worst miss {worst:.3g}, ||Phi|| = {phi:.3g})"
    else:
        names = "; ".join(" vs ".join(n for n, _ in g) for g in conflicts) or "none identified"
        msg = (f"targets cannot all be met: least-squares compromise after {it} iterations, worst miss {worst:.3g}; "
               f"conflicting: {names}")  # fmt: skip
        if limited[0]:  # the miss still falls outwards: the best within the limit of a design change
            msg = (f"targets cannot be met within a design change of {REACH * size:.3g} m (the mechanism's size; "
                   f"metres and radians over sqrt(weight)): the best there after {it} iterations, worst miss "
                   f"{worst:.3g}")  # fmt: skip
    change = _design_change(engs[0], before[0], after[0], pc[0])
    if external is not None:
        change |= {name: np.array([e1[k] - e0[k]]) for k, name in enumerate(external.names)}
    return TargetResult(Status.CONVERGED if ok else Status.NOT_CONVERGED, msg, it0 + it, tuple(rows),
                        tuple(configurations), tuple(before), tuple(after), vb, va, hard_res, change,
                        tuple(conflicts), tuple(hist), pcols, met, tuple(after_sols), final,
                        None if external is None else np.array(e1), tuple(engs))  # fmt: skip


__all__ = ["Configuration", "ExternalDesign", "OutputMap", "Row", "TargetResult", "output_jacobian", "solve_targets"]
