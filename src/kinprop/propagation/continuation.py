"""Continuation for large design changes: predictor-corrector over controlled sub-steps.

A change ``p0 -> p1`` is followed along the path ``p(t)``, ``t`` in [0, 1] (linear for
coordinates, position vectors and lengths; ``C(t) = exp(t log(C1 C0^T)) C0`` for
orientations). Each sub-step ``t -> t + h``:

* predictor: the implicit-function derivative ``dx_free/dp = -pinv(Phi_free) Phi_p``
  (:func:`kinprop.analysis.sensitivity.design_sensitivity`, the same minimum-norm inverse as
  the propagation) times ``dp = p(t + h) - p(t)``: ``x_pred = x(t) (+) dx``;
* corrector: Newton (:func:`kinprop.propagation.propagate`) from ``x_pred`` with ``p(t + h)``
  set, moving the free variables only.

The sub-step is accepted when the corrector converges and stays close to the predictor:
``|x_corr - x_pred| <= kappa |x_pred - x(t)| + jump_atol`` (the predictor error is O(h^2),
so a corrector that moves farther than ``kappa`` times the predictor step has jumped to
another solution branch). Otherwise ``h`` is halved; after an easy step (few iterations, a
corrector well inside the bound) it is doubled. When ``h`` falls below ``min_step`` the
change cannot be assembled beyond the current ``t``: the result reports that largest feasible
fraction and the constraints in conflict there, never a pose for the full change.

Diagnosis of a failure: at the last feasible state the free-variable Jacobian is (nearly)
rank deficient in the direction the change pushes; the left singular vector of its smallest
retained singular value weighs the constraint rows that cannot all be satisfied (``conflict``),
and the rows with the largest residual at the failed attempt are listed too
(``residual_rows``), each named ``JOINT:constraint`` (:func:`kinprop.analysis.mobility.row_names`).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from kinprop.engine import Engine
from kinprop.errors import ConvergenceError, SingularityWarning
from kinprop.model.design import parse_address
from kinprop.model.model import Model
from kinprop.propagation.conditioning import scaled_jacobian
from kinprop.propagation.propagate import Propagation, apply_changes, engine_for, propagate
from kinprop.propagation.sensitivity import design_sensitivity
from kinprop.propagation.units import changes_to_internal, check_units
from kinprop.solver.newton import RANK_RTOL
from kinprop.spatial import Array, exp_so3, log_so3

#: accept a sub-step when |corrector| <= KAPPA |predictor| + jump_atol
KAPPA = 0.5


@dataclass(frozen=True)
class ContinuationStep:
    """One attempted sub-step ``t -> t + h``."""

    fraction: float  # target t + h
    step: float  # h
    accepted: bool
    iterations: int
    residual_norm: float
    predictor_norm: float
    corrector_norm: float
    reason: str = ""


@dataclass(frozen=True)
class ContinuationResult:
    """Outcome of :func:`propagate_continuation`.

    ``propagation`` goes from the input model to the last feasible state: the full change when
    ``converged``, else the change scaled to ``fraction``; its ``changes`` hold the values set
    there, keyed by variable (``B.s_i``: the whole vector).
    """

    converged: bool
    fraction: float
    propagation: Propagation
    steps: tuple[ContinuationStep, ...]
    message: str
    #: rows weighted by the left singular vector of the smallest singular value, (label, weight)
    conflict: tuple[tuple[str, float], ...] = ()
    #: rows with the largest residual at the failed attempt, (label, Phi_k)
    residual_rows: tuple[tuple[str, float], ...] = ()
    #: s_min / s_max of the free-variable Jacobian at the last feasible state
    singularity_ratio: float = field(default=float("nan"))

    @property
    def status(self) -> str:
        return "converged" if self.converged else "infeasible"

    @property
    def after(self) -> Model:
        return self.propagation.after

    @property
    def n_solves(self) -> int:
        return len(self.steps)

    @property
    def conflict_joints(self) -> list[str]:
        """Joints owning the conflicting rows, most involved first."""
        return list(dict.fromkeys(r.split(":", 1)[0] for r, _ in self.conflict + self.residual_rows))

    def __repr__(self) -> str:
        """The outcome in one line, then the propagation's summary (model units)."""
        n_ok = sum(s.accepted for s in self.steps)
        head = (f"<ContinuationResult {self.status}: fraction {self.fraction:.6g}, {n_ok} accepted of "
                f"{len(self.steps)} sub-steps>")  # fmt: skip
        return f"{head}\n{self.propagation!r}"

    def _repr_html_(self) -> str:
        return f"<p><b>ContinuationResult</b> {self.status}: fraction {self.fraction:.6g}</p>" + (
            self.propagation._repr_html_()
        )

    def raise_for_status(self) -> ContinuationResult:
        if not self.converged:
            raise ConvergenceError(self.message)
        return self


@dataclass(frozen=True)
class _Path:
    """Start and target value of each changed variable (full arrays), keyed by layout key."""

    start: dict[str, Array]
    target: dict[str, Array]
    groups: dict[str, str]

    def at(self, t: float) -> dict[str, Array]:
        out = {}
        for k, s in self.start.items():
            e = self.target[k]
            if self.groups[k] == "C":
                out[k] = exp_so3(t * log_so3(e @ s.T)) @ s
            else:
                out[k] = s + t * (e - s)
        return out


def _build_path(engine: Engine, model: Model, changes: Mapping[str, object]) -> _Path:
    """Straight path from the model's values of the changed variables to their targets."""
    target_model, _, keys = apply_changes(model, changes, engine)  # validates (AddressError)
    layout = engine.layout

    def value(m: Model, key: str) -> Array:
        var = layout[key]
        return np.array(m.coordinates[var.joint] if var.group == "q" else m.design[key], dtype=float)

    keys_in_order = [k for k in dict.fromkeys(parse_address(t).key for t in changes) if k in keys]
    start = {k: value(model, k) for k in keys_in_order}
    target = {k: value(target_model, k) for k in keys_in_order}
    return _Path(start, target, {k: layout[k].group for k in keys_in_order})


def _delta(group: str, a: Array, b: Array) -> Array:
    """Layout-column increment from value ``a`` to ``b`` (``xi'`` for orientations)."""
    if group == "C":
        return log_so3(b @ a.T)
    return np.atleast_1d(b - a).ravel()


def _distance(layout, free_keys: list[str], m1: Model, m2: Model) -> float:
    """Euclidean distance between two states over the free variables (rotation angle for C)."""
    total = 0.0
    for key in free_keys:
        v = layout[key]
        if v.group == "q":
            d = np.asarray(m2.coordinates[v.joint]) - np.asarray(m1.coordinates[v.joint])
        elif v.group == "C":
            d = log_so3(m2.design[key] @ m1.design[key].T)
        else:
            d = np.asarray(m2.design[key]) - np.asarray(m1.design[key])
        total += float(np.sum(np.square(d)))
    return float(np.sqrt(total))


def _quiet_propagate(model: Model, changes, free, **kw) -> Propagation:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SingularityWarning)
        return propagate(model, changes, free, units="solver", **kw)


def _conflict(
    engine: Engine, model: Model, free: Sequence[str], exclude: set[str], top: int
) -> tuple[tuple[tuple[str, float], ...], float]:
    """Rows weighted by the left singular vector of the smallest retained singular value of the
    unit-scaled free-variable Jacobian (:func:`kinprop.propagation.conditioning.scaled_jacobian`)."""
    _, J = engine.evaluate(engine.state_of(model))
    cols = engine.columns(free, exclude)
    if cols.size == 0 or J.shape[0] == 0 or not np.all(np.isfinite(J)):
        return (), float("nan")
    U, sv, _ = np.linalg.svd(scaled_jacobian(engine.row_blocks, J[:, cols]))
    rank = int(np.sum(sv > RANK_RTOL * sv[0])) if sv[0] > 0 else 0
    if rank == 0:
        return (), 0.0
    u = U[:, rank - 1]
    labels = engine.row_labels
    order = [i for i in np.argsort(-np.abs(u)) if abs(u[i]) > 0.1][:top]
    return tuple((labels[i], float(u[i])) for i in order), float(sv[rank - 1] / sv[0])


def _residual_rows(engine: Engine, model: Model, top: int) -> tuple[tuple[str, float], ...]:
    Phi = engine.residual(engine.state_of(model))
    if not Phi.size or not np.all(np.isfinite(Phi)):
        return ()
    big = np.max(np.abs(Phi))
    labels = engine.row_labels
    order = [i for i in np.argsort(-np.abs(Phi)) if abs(Phi[i]) > 1e-3 * big and big > 0][:top]
    return tuple((labels[i], float(Phi[i])) for i in order)


def propagate_continuation(
    model: Model,
    changes: Mapping[str, object],
    free: Sequence[str] = ("q",),
    *,
    tol: float = 1e-10,
    max_iter: int = 20,
    weights: Mapping[str, float] | None = None,
    initial_step: float = 0.25,
    min_step: float = 1e-5,
    max_steps: int = 500,
    kappa: float = KAPPA,
    jump_atol: float = 1e-6,
    easy_iterations: int = 3,
    top: int = 6,
    engine: Engine | None = None,
    units: str = "model",
) -> ContinuationResult:
    """Apply a (large) design change by predictor-corrector continuation on one branch.

    ``changes``, ``free`` and ``units`` as in :func:`kinprop.propagation.propagate`; ``max_iter`` is
    per corrector. The model is first assembled with ``free`` if it is not already
    (``||Phi|| >= tol``): the branch followed is the one of that assembly. Sub-steps are
    fractions of the change, between ``min_step`` and 1; ``max_steps`` bounds the attempts.
    """
    engine = engine_for(model, engine)
    if check_units(units):
        changes = changes_to_internal(model, changes, engine)
    path = _build_path(engine, model, changes)
    layout = engine.layout
    keys = list(path.start)
    exclude = set(keys)
    free_cols = layout.columns(list(free), exclude=exclude)
    free_keys = [v.key for v in layout.variables if np.any((free_cols >= v.start) & (free_cols < v.start + v.size))]
    kw = {"tol": tol, "max_iter": max_iter, "weights": weights, "engine": engine}
    steps: list[ContinuationStep] = []

    # t = 0: start from an assembled state (the branch to follow)
    start_prop = _quiet_propagate(model, path.at(0.0), free, **kw)
    if not start_prop.converged:
        conflict, ratio = _conflict(engine, start_prop.after, free, exclude, top)
        msg = (
            f"the model does not assemble before the change ({start_prop.result.message}); "
            "nothing of the change can be applied"
        )
        steps.append(
            ContinuationStep(
                0.0, 0.0, False, start_prop.result.iterations, start_prop.result.residual_norm, 0.0, 0.0, "start"
            )
        )
        return ContinuationResult(
            False, 0.0, start_prop, tuple(steps), msg, conflict, _residual_rows(engine, start_prop.after, top), ratio
        )
    if not keys:  # nothing to change: the assembly is the answer
        msg = f"no change to follow: {start_prop.result.message}"
        return ContinuationResult(True, 1.0, start_prop, tuple(steps), msg, (), (), start_prop.singularity_ratio)
    current, last = start_prop.after, start_prop
    t, h = 0.0, min(max(initial_step, min_step), 1.0)
    just_failed = False
    failed_state: Model | None = None
    while t < 1.0 and len(steps) < max_steps:
        h = min(h, 1.0 - t)
        t_new = 1.0 if 1.0 - (t + h) < 1e-12 else t + h
        p_old, p_new = path.at(t), path.at(t_new)
        # predictor: dx_free = S dp (implicit-function theorem, min-norm inverse)
        dx = np.zeros(layout.n)
        for k in keys:
            v = layout[k]
            dx[v.columns] = _delta(v.group, p_old[k], p_new[k])
        sens = design_sensitivity(current, keys, free, weights, engine=engine, units="solver")
        dx[sens.free_columns] = sens.matrix @ dx[sens.wrt_columns]
        pred_norm = float(np.linalg.norm(dx[sens.free_columns]))
        if np.all(np.isfinite(dx)):
            predicted = engine.model_of(engine.retract(engine.state_of(current), dx), current)
        else:
            predicted = current
        corr = _quiet_propagate(predicted, p_new, free, **kw)
        corr_norm = _distance(layout, free_keys, predicted, corr.after) if corr.converged else float("nan")
        r = corr.result
        reason = ""
        if not r.converged:
            reason = "corrector did not converge"
        elif corr_norm > kappa * pred_norm + jump_atol:
            reason = f"branch jump suspected: corrector {corr_norm:.3g} > {kappa:g} x predictor {pred_norm:.3g}"
        accepted = not reason
        steps.append(ContinuationStep(t_new, h, accepted, r.iterations, r.residual_norm, pred_norm, corr_norm, reason))
        if accepted:
            current, last, t = corr.after, corr, t_new
            easy = r.iterations <= easy_iterations and corr_norm <= 0.25 * kappa * pred_norm + jump_atol
            if easy and not just_failed:
                h = min(2.0 * h, 1.0)
            just_failed = False
            failed_state = None
            continue
        if not r.converged:
            failed_state = corr.after
        just_failed = True
        h *= 0.5
        if h < min_step:
            break

    if t >= 1.0:
        prop = Propagation(model, current, last.result, path.at(1.0), tuple(free), last.singularity_ratio, engine)
        n_ok = sum(s.accepted for s in steps)
        msg = f"continuation reached the full change in {n_ok} sub-steps ({len(steps)} attempts): {last.result.message}"
        return ContinuationResult(True, 1.0, prop, tuple(steps), msg, (), (), last.singularity_ratio)

    conflict, ratio = _conflict(engine, current, free, exclude, top)
    residual = _residual_rows(engine, failed_state, top) if failed_state is not None else ()
    prop = Propagation(model, current, last.result, path.at(t), tuple(free), last.singularity_ratio, engine)
    names = ", ".join(dict.fromkeys([r for r, _ in conflict] + [r for r, _ in residual])) or "none identified"
    why = "step limit reached" if len(steps) >= max_steps else f"sub-step below {min_step:g}"
    msg = (
        f"the change cannot be assembled beyond {t:.6g} of its size ({why}); "
        f"constraints in conflict: {names}; smallest/largest singular value there {ratio:.3g}"
    )
    return ContinuationResult(False, t, prop, tuple(steps), msg, conflict, residual, ratio)


__all__ = ["ContinuationResult", "ContinuationStep", "propagate_continuation"]
