"""Design propagation: changes, free-variable sets, re-assembly, continuation."""

from kinprop.propagation.continuation import ContinuationResult, propagate_continuation
from kinprop.propagation.propagate import Propagation, apply_changes, assemble, engine_for, propagate

__all__ = [
    "ContinuationResult",
    "Propagation",
    "apply_changes",
    "assemble",
    "engine_for",
    "propagate",
    "propagate_continuation",
]
