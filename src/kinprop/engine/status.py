"""The one status vocabulary's message table: what every solve, batch row, sweep step, study
variant and analysis at a pose says about its outcome (:class:`kinprop.Status`; docs/results.md).

:func:`message` gives the one-line outcome, :func:`notes` the lines a user should know besides
(sub-stepping, an ambiguous branch). ``Solution``/``BatchSolution`` read them, and so do the
records that carry a status without a solve (a study's invalid variant, motion and statics at a
pose: ``ok``, ``singular``, ``unbalanced``, ``not_assembled``)."""

from __future__ import annotations

from kinprop.solver import newton
from kinprop.solver.newton import STATUSES, Status

__all__ = ["STATUSES", "Status", "message", "notes"]


def notes(status: Status, flags: int, substeps: int) -> list[str]:
    """One line per thing a user should know about a solve (empty: nothing to say)."""
    out = []
    if status is Status.CONVERGED and flags & newton.FROM_ESTIMATES and flags & newton.SIGN_FLIP:
        out.append("ambiguous assembly: det of the free Jacobian changed sign between the estimates and the "
                   "solution, so it may be another assembly branch than the estimates suggest")  # fmt: skip
    if status is Status.CONVERGED and flags & newton.SUBDIVIDED:
        why = " (a full step left the start's branch)" if flags & (newton.JUMPED | newton.SIGN_FLIP) else ""
        if flags & newton.FLIPPED:
            why = " (a full step turned a cut joint onto a pose the joint cannot take)"
        out.append(f"the change was followed in {substeps} sub-steps to stay on the start's branch{why}")
    return out


def message(status: Status, iterations: int = 0, residual: float = 0.0, tol: float = 0.0, requested_tol: float = 0.0,
            fraction: float = 1.0, substeps: int = 1, flags: int = 0, optimality: float = 0.0,
            max_iter: int = 0, *, undetermined: int = 0, mismatch: float = 0.0,
            self_stress: int = 0) -> str:  # fmt: skip
    """The one message table of :class:`Status` (every solve, batch row, sweep step and analysis
    at a pose says its outcome with it). ``residual`` is the scaled ``||Phi||``
    (:attr:`Engine.row_scale`: metres); ``optimality`` the optimality residual (SI;
    docs/analysis/weights.md), shown when not 0; ``max_iter`` the iteration cap of one sub-step
    (0: not known). At a pose: ``undetermined`` the directions of motion the driven rates leave
    open (``singular``) or the reaction components the loads leave open (``ok``, with
    ``self_stress`` states); ``mismatch`` the part of the scaled right-hand side the linear
    system cannot meet, relative to its size (``singular``: the driven rates; ``unbalanced``:
    the loads)."""
    if status is Status.OK:
        return (f"ok: {self_stress} self-stress state(s); {undetermined} reaction component(s) are not "
                "determined by the loads" if self_stress else "ok")  # fmt: skip
    if status is Status.SINGULAR:
        if undetermined:
            return (f"singular: the driven rates leave {undetermined} direction(s) of motion undetermined "
                    "(a singular configuration, or too few driven coordinates)")  # fmt: skip
        return (f"singular: the driven rates violate the constraints (relative mismatch {mismatch:.3g}): "
                "a locked input or a singular configuration")  # fmt: skip
    if status is Status.UNBALANCED:
        return (f"unbalanced: the constraints and the inputs do not hold the loads ({mismatch:.3g} of the "
                "generalised load is not held): the mechanism can move under them (too few inputs, or a "
                "singular pose)")  # fmt: skip
    bound = (
        f"{tol:.3g} (round-off floor at this model's length scale; tol {requested_tol:g})"
        if tol > requested_tol
        else f"{tol:g}"
    )
    if status is Status.CONVERGED:
        opt = f", optimality {optimality:.3g}" if optimality else ""
        return f"converged in {iterations} iterations: ||Phi|| = {residual:.3g} < {bound}{opt}"
    if flags & newton.LEAST_CHANGE_FAILED and not flags & newton.FLIPPED:
        return (f"assembled (||Phi|| = {residual:.3g}) but the closest assembly to the start was not reached in "
                f"{iterations} iterations (optimality {optimality:.3g}); method='paper' returns the iteration's own "
                "end point")  # fmt: skip
    if status is Status.INFEASIBLE and flags & newton.FLIPPED and fraction == 0.0:
        return ("the solve converged onto a root with a cut joint turned (its axes reversed): a pose the joint "
                "itself cannot take; better estimates, or the default branch following")  # fmt: skip
    if status is Status.NO_FREE:
        return "no free variables: nothing can move to satisfy the constraints"
    if status is Status.INVALID:
        return "the values could not be applied (outside their variable's domain): not solved"
    if status is Status.NOT_ASSEMBLED:
        return f"not an assembly (||Phi|| = {residual:.3g}): assemble the model first"
    if status is Status.DIVERGED:
        return f"diverged at iteration {iterations}: ||Phi|| = {residual:.3g}"
    if status is Status.INFEASIBLE:
        return (f"the change can be followed on the start's branch only to {fraction:.6g} of its size "
                f"(no assembly beyond, or a singular configuration there); {substeps} sub-steps")  # fmt: skip
    if status is Status.STEP_LIMIT:
        return (f"sub-step cap reached ({substeps} sub-steps, at {fraction:.6g} of the change): "
                "the change is too large or too close to a singular configuration to follow")  # fmt: skip
    cap = f"each allowed --max-iter {max_iter}" if max_iter else "each allowed --max-iter iterations"
    steps = f" in all ({substeps} sub-steps of the change, {cap})" if substeps > 1 else ""
    return f"not converged after {iterations} iterations{steps}: ||Phi|| = {residual:.3g} >= {bound}"
