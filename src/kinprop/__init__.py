"""kinprop: kinematic design propagation in closed-loop mechanisms.

Implements Zou, Abdel-Malek & Wang (1997), "Design Propagation in Mechanical Systems:
Kinematic Analysis", ASME J. Mech. Des. 119(3).
"""

from kinprop.analysis import design_sensitivity, evaluate_outputs, mobility, output_sensitivity, sweep
from kinprop.analysis.targets import TargetPropagation, propagate_targets
from kinprop.engine import BatchSolution, Engine, Solution, State, Status, compile
from kinprop.errors import AddressError, ConvergenceError, KinpropError, ModelError, SingularityWarning
from kinprop.io import dump_model, load_model
from kinprop.model import Body, Design, Joint, Mechanism, Model
from kinprop.propagation import Propagation, assemble, propagate, propagate_continuation
from kinprop.solver import SolveResult

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
    "Mechanism",
    "Model",
    "ModelError",
    "Propagation",
    "SingularityWarning",
    "Solution",
    "SolveResult",
    "State",
    "Status",
    "TargetPropagation",
    "assemble",
    "compile",
    "design_sensitivity",
    "dump_model",
    "evaluate_outputs",
    "load_model",
    "mobility",
    "output_sensitivity",
    "propagate",
    "propagate_continuation",
    "propagate_targets",
    "sweep",
]
