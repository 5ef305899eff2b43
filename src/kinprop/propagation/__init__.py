"""Design propagation: changes, free-variable sets, re-assembly."""

from kinprop.propagation.propagate import Propagation, apply_changes, assemble, assembly_for, propagate

__all__ = ["Propagation", "apply_changes", "assemble", "assembly_for", "propagate"]
