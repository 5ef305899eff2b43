"""Analysis beyond one re-assembly: mobility, redundancy, sensitivities."""

from kinprop.analysis.mobility import MobilityReport, gruebler, mobility
from kinprop.analysis.sensitivity import Sensitivity, design_sensitivity

__all__ = ["MobilityReport", "Sensitivity", "design_sensitivity", "gruebler", "mobility"]
