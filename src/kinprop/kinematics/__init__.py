"""Kinematics: variable layout, flat tables, and the compiled kernels (forward kinematics,
B/M/N transforms, assembled Phi and its Jacobian)."""

from kinprop.kinematics.layout import Variable, VariableLayout, build_layout, column_labels
from kinprop.kinematics.tables import RowBlock, Tables, build_tables, row_blocks

__all__ = [
    "RowBlock",
    "Tables",
    "Variable",
    "VariableLayout",
    "build_layout",
    "build_tables",
    "column_labels",
    "row_blocks",
]
