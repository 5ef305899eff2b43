"""Analysis beyond one re-assembly: mobility, sensitivities, outputs, metrics, sweeps."""

from kinprop.analysis.metrics import WheelSpec, suspension_metrics
from kinprop.analysis.mobility import MobilityReport, gruebler, mobility
from kinprop.analysis.outputs import evaluate_outputs, output_names
from kinprop.analysis.points import joint_hardpoints, named_points
from kinprop.analysis.sensitivity import Sensitivity, design_sensitivity, output_sensitivity
from kinprop.analysis.sweep import Drive, SweepResult, sweep

__all__ = [
    "Drive",
    "MobilityReport",
    "Sensitivity",
    "SweepResult",
    "WheelSpec",
    "design_sensitivity",
    "evaluate_outputs",
    "gruebler",
    "joint_hardpoints",
    "mobility",
    "named_points",
    "output_names",
    "output_sensitivity",
    "suspension_metrics",
    "sweep",
]
