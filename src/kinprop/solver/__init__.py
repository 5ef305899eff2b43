"""The generalized-inverse Newton-Raphson solver: plan, compiled loop, result records."""

from kinprop.solver.newton import RANK_RTOL, STATUSES, Status, min_norm_step
from kinprop.solver.plan import Plan, build_plan
from kinprop.solver.result import SolveResult, rank_of

__all__ = ["RANK_RTOL", "STATUSES", "Plan", "SolveResult", "Status", "build_plan", "min_norm_step", "rank_of"]
