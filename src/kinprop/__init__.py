"""kinprop: kinematic design propagation in closed-loop mechanisms.

Implements Zou, Abdel-Malek & Wang (1997), "Design Propagation in Mechanical Systems:
Kinematic Analysis", ASME J. Mech. Des. 119(3).
"""

import importlib as _importlib
from typing import TYPE_CHECKING as _TYPE_CHECKING
from typing import Any as _Any

#: public names -> the module that defines them, imported on first use (PEP 562): ``import
#: kinprop`` stays cheap, and the command line can choose how kernels run (kinprop.jit) first
_EXPORTS = {
    "design_sensitivity": "kinprop.analysis",
    "evaluate_outputs": "kinprop.analysis",
    "mobility": "kinprop.analysis",
    "motion": "kinprop.analysis.motion",
    "Motion": "kinprop.analysis.motion",
    "output_sensitivity": "kinprop.analysis",
    "sweep": "kinprop.analysis",
    "TargetPropagation": "kinprop.analysis.targets",
    "propagate_targets": "kinprop.analysis.targets",
    "BatchSolution": "kinprop.engine",
    "Engine": "kinprop.engine",
    "Solution": "kinprop.engine",
    "State": "kinprop.engine",
    "Status": "kinprop.engine",
    "compile": "kinprop.engine",
    "AddressError": "kinprop.errors",
    "ConvergenceError": "kinprop.errors",
    "KinpropError": "kinprop.errors",
    "ModelError": "kinprop.errors",
    "SingularityWarning": "kinprop.errors",
    "UnitsWarning": "kinprop.errors",
    "dump_model": "kinprop.io",
    "load_model": "kinprop.io",
    "Body": "kinprop.model",
    "Design": "kinprop.model",
    "Joint": "kinprop.model",
    "Mechanism": "kinprop.model",
    "Model": "kinprop.model",
    "LoadCase": "kinprop.model",
    "PointLoad": "kinprop.model",
    "Statics": "kinprop.analysis.statics",
    "statics": "kinprop.analysis.statics",
    "Propagation": "kinprop.propagation",
    "assemble": "kinprop.propagation",
    "propagate": "kinprop.propagation",
    "propagate_continuation": "kinprop.propagation",
}

if _TYPE_CHECKING:
    from kinprop.analysis import design_sensitivity, evaluate_outputs, mobility, output_sensitivity, sweep
    from kinprop.analysis.motion import Motion, motion
    from kinprop.analysis.statics import Statics, statics
    from kinprop.analysis.targets import TargetPropagation, propagate_targets
    from kinprop.engine import BatchSolution, Engine, Solution, State, Status, compile
    from kinprop.errors import (
        AddressError,
        ConvergenceError,
        KinpropError,
        ModelError,
        SingularityWarning,
        UnitsWarning,
    )
    from kinprop.io import dump_model, load_model
    from kinprop.model import Body, Design, Joint, LoadCase, Mechanism, Model, PointLoad
    from kinprop.propagation import Propagation, assemble, propagate, propagate_continuation


def __getattr__(name: str) -> _Any:
    if name in _EXPORTS:
        value = getattr(_importlib.import_module(_EXPORTS[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'kinprop' has no attribute {name!r}")


def __dir__() -> list[str]:
    """The public names (not the helpers this module imports), and the dunder attributes."""
    return sorted(set(_EXPORTS) | {n for n in globals() if n.startswith("__")})


__version__ = "0.1.0"

__all__ = [
    "AddressError",
    "BatchSolution",
    "Body",
    "ConvergenceError",
    "Design",
    "Engine",
    "Joint",
    "KinpropError",
    "LoadCase",
    "Mechanism",
    "Model",
    "ModelError",
    "Motion",
    "PointLoad",
    "Propagation",
    "SingularityWarning",
    "Solution",
    "State",
    "Statics",
    "Status",
    "TargetPropagation",
    "UnitsWarning",
    "assemble",
    "compile",
    "design_sensitivity",
    "dump_model",
    "evaluate_outputs",
    "load_model",
    "mobility",
    "motion",
    "output_sensitivity",
    "propagate",
    "propagate_continuation",
    "propagate_targets",
    "statics",
    "sweep",
]
