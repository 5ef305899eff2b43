"""Kinematics: forward kinematics, B/M/N transforms, assembled Phi and Jacobians."""

from kinprop.kinematics.assembly import Assembly, RowBlock, build_assembly
from kinprop.kinematics.forward import JointFrames, Kinematics, forward_kinematics
from kinprop.kinematics.layout import Variable, VariableLayout, build_layout

__all__ = [
    "Assembly",
    "JointFrames",
    "Kinematics",
    "RowBlock",
    "Variable",
    "VariableLayout",
    "build_assembly",
    "build_layout",
    "forward_kinematics",
]
