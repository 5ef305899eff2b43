"""Fast paths: compiled (numba) evaluation and Newton, batched over variants, sparse for large mechanisms.

The numpy implementation (:class:`kinprop.kinematics.Assembly`, :mod:`kinprop.solver`,
:mod:`kinprop.propagation`) is the reference; every path here is tested against it.
"""

from kinprop.fast.compiled import Compiled, NotCompilableError, State, compile_model, pack, unpack
from kinprop.fast.solve import BatchResult, Solver, body_poses, evaluate, propagate_fast, solve_batch

__all__ = [
    "BatchResult",
    "Compiled",
    "NotCompilableError",
    "Solver",
    "State",
    "body_poses",
    "compile_model",
    "evaluate",
    "pack",
    "propagate_fast",
    "solve_batch",
    "unpack",
]
