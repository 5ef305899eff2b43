"""Generalized-inverse Newton-Raphson solver."""

from kinprop.solver.newton import RANK_RTOL, SolveOptions, SolveResult, min_norm_step, newton

__all__ = ["RANK_RTOL", "SolveOptions", "SolveResult", "min_norm_step", "newton"]
