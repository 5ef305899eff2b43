"""Generalized-inverse Newton-Raphson (eq. 5.2-5.3 and Fig. 3).

Each step is the minimum-norm correction over the free variables only,
``dx_free = -pinv(Phi_x[:, free]) Phi`` (optionally weighted), everything else frozen. The
stopping test ``||Phi||_2 < tol`` is checked after each update (PAPER-NOTES 5-6). The solver
never prints and never raises for non-convergence: it returns a :class:`SolveResult`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from kinprop.errors import ConvergenceError
from kinprop.spatial import Array

#: relative singular-value threshold for the rank (``s_k > RANK_RTOL * s_max``)
RANK_RTOL = 1e-9


@dataclass(frozen=True)
class SolveOptions:
    tol: float = 1e-10
    max_iter: int = 50
    #: stop when the residual grows beyond this factor of the initial one (divergence)
    divergence: float = 1e6
    #: round-off floor of ||Phi|| for the model's length scale; converged when
    #: ``||Phi|| < max(tol, floor)`` (0: the tolerance alone)
    floor: float = 0.0

    @property
    def target(self) -> float:
        return max(self.tol, self.floor)


@dataclass
class SolveResult:
    converged: bool
    iterations: int
    residual_norm: float
    residual_history: list[float]
    rank: int
    n_free: int
    n_equations: int
    singular_values: Array
    message: str
    state: Any = field(repr=False, default=None)
    #: the full Jacobian at the final state (every column, not only the free ones)
    jacobian: Array | None = field(repr=False, default=None)

    @property
    def status(self) -> str:
        return "converged" if self.converged else "not_converged"

    @property
    def smallest_singular_value(self) -> float:
        return float(self.singular_values[-1]) if self.singular_values.size else 0.0

    @property
    def condition_number(self) -> float:
        s = self.singular_values
        return float(s[0] / s[-1]) if s.size and s[-1] > 0 else float("inf")

    def raise_for_status(self) -> SolveResult:
        if not self.converged:
            raise ConvergenceError(self.message)
        return self


def min_norm_step(J: Array, Phi: Array, weights: Array | None = None) -> Array:
    """``-pinv(J) Phi``; with weights w, the weighted minimum-norm step
    ``argmin sum(dx^2 / w)`` subject to ``J dx = -Phi`` (larger weight = moves more)."""
    if weights is None:
        return -np.linalg.lstsq(J, Phi, rcond=None)[0]
    sw = np.sqrt(weights)
    return -sw * np.linalg.lstsq(J * sw, Phi, rcond=None)[0]


def newton(
    evaluate: Callable[[Any], tuple[Array, Array]],
    retract: Callable[[Any, Array], Any],
    state: Any,
    free: Array,
    n_columns: int,
    options: SolveOptions = SolveOptions(),
    weights: Array | None = None,
) -> SolveResult:
    """Iterate ``state <- retract(state, dx)`` with ``dx`` nonzero on the ``free`` columns."""
    Phi, J = evaluate(state)
    norm = float(np.linalg.norm(Phi))
    history = [norm]
    it = 0
    message = ""
    target = options.target
    while norm >= target and it < options.max_iter:
        if free.size == 0:
            message = "no free variables: nothing can move to satisfy the constraints"
            break
        dx = np.zeros(n_columns)
        dx[free] = min_norm_step(J[:, free], Phi, weights)
        state = retract(state, dx)
        it += 1
        Phi, J = evaluate(state)
        norm = float(np.linalg.norm(Phi))
        history.append(norm)
        if not np.isfinite(norm) or norm > options.divergence * max(history[0], 1e-300):
            message = f"diverged at iteration {it}: ||Phi|| = {norm:.3g}"
            break
    converged = bool(norm < target)
    Jf = J[:, free] if free.size else np.zeros((J.shape[0], 0))
    sv = np.linalg.svd(Jf, compute_uv=False) if Jf.size else np.zeros(0)
    rank = int(np.sum(sv > RANK_RTOL * sv[0])) if sv.size and sv[0] > 0 else 0
    bound = (
        f"{target:.3g} (round-off floor at this model's length scale; tol {options.tol:g})"
        if target > options.tol
        else f"{options.tol:g}"
    )
    if converged:
        message = f"converged in {it} iterations: ||Phi|| = {norm:.3g} < {bound}"
    elif not message:
        message = f"not converged after {it} iterations: ||Phi|| = {norm:.3g} >= {bound}"
    return SolveResult(converged, it, norm, history, rank, int(free.size), int(J.shape[0]), sv, message, state, J)
