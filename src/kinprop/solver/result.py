"""The model-level record of one solve (what :class:`kinprop.Propagation` carries)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from kinprop.errors import ConvergenceError
from kinprop.spatial import Array


@dataclass
class SolveResult:
    converged: bool
    iterations: int
    residual: float
    residual_history: list[float]
    rank: int
    n_free: int
    n_equations: int
    singular_values: Array
    message: str
    state: Any = field(repr=False, default=None)
    #: the full Jacobian at the final state (every column, not only the free ones)
    jacobian: Array | None = field(repr=False, default=None)
    status_name: str = ""
    #: one line per thing a user should know (subdivided change, ambiguous branch)
    notes: tuple[str, ...] = ()
    #: fraction of the change followed on the start's branch (1 when converged)
    fraction: float = 1.0
    #: optimality residual (SI, weighted; 0 at the assembly closest to the start or without
    #: freedom): ``kinprop.engine.Solution.optimality``
    optimality: float = 0.0
    #: ``least-change`` or ``paper`` (``kinprop.engine.METHODS``): which result was computed
    method: str = "least-change"

    @property
    def status(self) -> str:
        return self.status_name or ("converged" if self.converged else "not_converged")

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


def rank_of(singular_values: Array, rtol: float) -> int:
    sv = singular_values
    return int(np.sum(sv > rtol * sv[0])) if sv.size and sv[0] > 0 else 0
