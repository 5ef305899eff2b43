"""The generalized-inverse Newton-Raphson solver: plan, compiled loop, status vocabulary."""

from kinprop.solver.newton import RANK_RTOL, STATUSES, Status, min_norm_step
from kinprop.solver.plan import Plan, build_plan

__all__ = ["RANK_RTOL", "STATUSES", "Plan", "Status", "build_plan", "min_norm_step"]
