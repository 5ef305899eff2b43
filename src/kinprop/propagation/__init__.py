"""Design propagation: changes, free-variable sets, re-assembly, continuation."""

from kinprop.propagation.continuation import ContinuationResult, propagate_continuation
from kinprop.propagation.propagate import Propagation, apply_changes, assemble, engine_for, hold, propagate

__all__ = [
    "ContinuationResult",
    "Propagation",
    "apply_changes",
    "assemble",
    "engine_for",
    "hold",
    "propagate",
    "propagate_continuation",
]
