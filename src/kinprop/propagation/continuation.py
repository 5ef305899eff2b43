"""Continuation for large design changes: a view of the engine's branch-following solve.

A change ``p0 -> p1`` is followed along the path ``p(t)``, ``t`` in [0, 1] (linear for
coordinates, position vectors and lengths; ``C(t) = exp(t log(C1 C0^T)) C0`` for
orientations) by the one compiled predictor-corrector, :func:`kinprop.solver.newton.follow`
(``Engine.propagate``; docs/analysis/continuation.md): a sub-step is accepted when Newton
converges, stays close to the predictor and keeps the sign of det of the free Jacobian;
otherwise it is halved. When it falls below the smallest sub-step the change cannot be
assembled beyond the current ``t``: the solution holds that largest feasible fraction and
the state there, never a pose for the full change.

This module holds no loop of its own: :func:`propagate_continuation` runs one
:func:`kinprop.propagation.propagate` and reads the outcome, and :func:`diagnose` is a
function of the returned solution. At the last feasible state the free-variable Jacobian
is (nearly) rank deficient in the direction the change pushes; the left singular vector of
its smallest retained singular value weighs the constraint rows that cannot all be satisfied
(``conflict``), and the rows with the largest residual when the full change is applied to the
last feasible coordinates are listed too (``residual_rows``), each named ``JOINT:constraint``
(:func:`kinprop.analysis.mobility.row_names`).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from kinprop.engine import Engine, Solution, Status
from kinprop.errors import ConvergenceError, SingularityWarning
from kinprop.model.model import Model
from kinprop.propagation.conditioning import scaled_jacobian
from kinprop.propagation.propagate import Propagation, engine_for, propagation_of, solve_changes
from kinprop.solver import newton
from kinprop.solver.newton import RANK_RTOL
from kinprop.spatial import Array

#: rows listed by a diagnosis
TOP = 6


@dataclass(frozen=True)
class Diagnosis:
    """Why a solution stopped short of the full change (:func:`diagnose`)."""

    #: fraction of the change followed on the start's branch (1 when converged)
    fraction: float
    #: rows weighted by the left singular vector of the smallest singular value, (label, weight)
    conflict: tuple[tuple[str, float], ...] = ()
    #: rows with the largest residual with the full change at the last feasible coordinates, (label, Phi_k)
    residual_rows: tuple[tuple[str, float], ...] = ()
    #: unit-independent s_min / s_max of the free-variable Jacobian at the last feasible state
    singularity_ratio: float = float("nan")

    @property
    def joints(self) -> list[str]:
        """Joints owning the conflicting rows, most involved first."""
        return list(dict.fromkeys(r.split(":", 1)[0] for r, _ in self.conflict + self.residual_rows))


def _conflict(engine: Engine, state, free: Array, top: int) -> tuple[tuple[tuple[str, float], ...], float]:
    """Rows weighted by the left singular vector of the smallest retained singular value of the
    unit-scaled free-variable Jacobian (:func:`kinprop.propagation.conditioning.scaled_jacobian`)."""
    _, J = engine.evaluate(state)
    if free.size == 0 or J.shape[0] == 0 or not np.all(np.isfinite(J)):
        return (), float("nan")
    U, sv, _ = np.linalg.svd(scaled_jacobian(engine.row_blocks, J[:, free]))
    rank = int(np.sum(sv > RANK_RTOL * sv[0])) if sv[0] > 0 else 0
    if rank == 0:
        return (), 0.0
    u = U[:, rank - 1]
    labels = engine.row_labels
    order = [i for i in np.argsort(-np.abs(u)) if abs(u[i]) > 0.1][:top]
    return tuple((labels[i], float(u[i])) for i in order), float(sv[rank - 1] / sv[0])


def _residual_rows(engine: Engine, state, top: int) -> tuple[tuple[str, float], ...]:
    Phi = engine.residual(state)
    if not Phi.size or not np.all(np.isfinite(Phi)):
        return ()
    big = np.max(np.abs(Phi))
    labels = engine.row_labels
    order = [i for i in np.argsort(-np.abs(Phi)) if abs(Phi[i]) > 1e-3 * big and big > 0][:top]
    return tuple((labels[i], float(Phi[i])) for i in order)


def diagnose(sol: Solution, top: int = TOP) -> Diagnosis:
    """The diagnosis of a solution (a function of it alone, no further solve): the fraction
    reached, the constraint rows in conflict at the returned (last feasible) state, the rows
    that the full change leaves unsatisfied there, and the singularity measure."""
    eng = sol.engine
    conflict, ratio = _conflict(eng, sol.state, sol.free, top)
    if sol.converged or not sol.changes:
        return Diagnosis(sol.fraction, (), (), ratio)
    full = eng.apply(sol.state, sol.changes)[0]  # the full change at the last feasible coordinates
    return Diagnosis(sol.fraction, conflict, _residual_rows(eng, full, top), ratio)


@dataclass(frozen=True)
class ContinuationResult:
    """Outcome of :func:`propagate_continuation`: a view of one engine solution (``solution``,
    the solve of the full change) with its :class:`Diagnosis`; its ``status``, ``fraction`` and
    ``substeps`` are the solution's.

    ``propagation`` goes from the input model to the last feasible state: the full change when
    ``converged``, else the change scaled to ``fraction``; its ``changes`` hold the values set
    there, keyed by variable (``B.s_i``: the whole vector).
    """

    #: the engine's solution of the full change (:class:`kinprop.Solution`)
    solution: Solution
    propagation: Propagation
    diagnosis: Diagnosis

    @property
    def status(self) -> Status:
        """The engine's outcome for the full change (:class:`kinprop.Status`)."""
        return self.solution.status

    @property
    def converged(self) -> bool:
        return self.solution.converged

    @property
    def fraction(self) -> float:
        """Fraction of the change followed on the start's branch (1 when converged)."""
        return 1.0 if self.converged else self.solution.fraction

    @property
    def substeps(self) -> int:
        """Sub-steps the engine's loop took (accepted and halved)."""
        return self.solution.substeps

    @property
    def message(self) -> str:
        """The solution's message (the one table), and when it stopped short the diagnosis."""
        sol = self.solution
        if sol.converged:
            return f"the change was followed in {sol.substeps} sub-steps: {sol.message}"
        return failure_message(sol, self.diagnosis)

    @property
    def conflict(self) -> tuple[tuple[str, float], ...]:
        """Rows weighted by the left singular vector of the smallest singular value, (label, weight)."""
        return self.diagnosis.conflict

    @property
    def residual_rows(self) -> tuple[tuple[str, float], ...]:
        """Rows with the largest residual with the full change at the last feasible coordinates, (label, Phi_k)."""
        return self.diagnosis.residual_rows

    @property
    def singularity_ratio(self) -> float:
        """s_min / s_max of the free-variable Jacobian at the last feasible state."""
        return self.diagnosis.singularity_ratio

    @property
    def after(self) -> Model:
        return self.propagation.after

    @property
    def conflict_joints(self) -> list[str]:
        """Joints owning the conflicting rows, most involved first."""
        return self.diagnosis.joints

    def __repr__(self) -> str:
        """The outcome in one line, then the propagation's summary (model units)."""
        head = f"<ContinuationResult {self.status.value}: fraction {self.fraction:.6g}, {self.substeps} sub-steps>"
        return f"{head}\n{self.propagation!r}"

    def _repr_html_(self) -> str:
        return f"<p><b>ContinuationResult</b> {self.status.value}: fraction {self.fraction:.6g}</p>" + (
            self.propagation._repr_html_()
        )

    def raise_for_status(self) -> ContinuationResult:
        if not self.converged:
            raise ConvergenceError(self.message)
        return self


def failure_message(sol: Solution, d: Diagnosis) -> str:
    """One line for a solution that stopped short of its change (the message table of
    :class:`kinprop.Status` plus the diagnosis)."""
    if sol.status is Status.NO_FREE:
        return sol.message
    unassembled = sol.fraction == 0.0 and sol.flags & newton.FROM_ESTIMATES
    if unassembled and sol.status in (Status.NOT_CONVERGED, Status.DIVERGED):
        return f"the model does not assemble before the change ({sol.message}); nothing of the change can be applied"
    names = ", ".join(dict.fromkeys([r for r, _ in d.conflict] + [r for r, _ in d.residual_rows])) or "none identified"
    return (
        f"the change cannot be assembled beyond {sol.fraction:.6g} of its size ({sol.status.value}, "
        f"{sol.substeps} sub-steps); constraints in conflict: {names}; smallest/largest singular value there "
        f"{d.singularity_ratio:.3g}"
    )


def continuation_of(model: Model, sol: Solution, free: Sequence[str], top: int = TOP) -> ContinuationResult:
    """The :class:`ContinuationResult` view of an engine solution of a change to ``model``."""
    eng = sol.engine
    d = diagnose(sol, top)
    # the changes as reached, keyed by variable (the whole vector), in solver units
    keys = list(dict.fromkeys(eng.target(a).key for a in sol.changes))
    reached = {k: np.array(eng.get(sol.state, k), dtype=float) for k in keys}
    if sol.converged:
        partial = replace(sol, changes=reached)
    else:
        scaled = float(np.linalg.norm(eng.residual(sol.state) * eng.row_scale))
        assembled = sol.fraction > 0.0 or scaled < sol.tol
        partial = replace(sol, changes=reached, status=Status.CONVERGED if assembled else sol.status,
                          residual=scaled if assembled else sol.residual)  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SingularityWarning)
        prop = propagation_of(eng, model, partial, free)
    return ContinuationResult(sol, prop, d)


def propagate_continuation(
    model: Model,
    changes: Mapping[str, object],
    free: Sequence[str] = ("q",),
    *,
    tol: float = 1e-10,
    max_iter: int = 50,
    weights: Mapping[str, float] | None = None,
    top: int = TOP,
    engine: Engine | None = None,
    units: str = "model",
) -> ContinuationResult:
    """Apply a (large) design change on the start's branch and say how far it got.

    ``changes`` (any address :func:`kinprop.propagation.propagate` takes, ``hardpoint:J.i``
    included), ``free``, ``weights`` and ``units`` as there; ``max_iter`` is per sub-step. The
    model is first assembled with ``free`` if it is not already: the branch followed is the
    one of that assembly. One engine solve (:meth:`kinprop.Engine.propagate`); a failure is
    diagnosed by :func:`diagnose` of its solution.
    """
    eng = engine_for(model, engine)
    sol = solve_changes(eng, model, changes, free, tol=tol, max_iter=max_iter, weights=weights, units=units)
    return continuation_of(model, sol, free, top)


__all__ = [
    "ContinuationResult",
    "Diagnosis",
    "continuation_of",
    "diagnose",
    "failure_message",
    "propagate_continuation",
]
