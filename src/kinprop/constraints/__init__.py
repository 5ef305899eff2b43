"""Basic constraints (dot-1, dot-2, spherical, distance) with analytic partials."""

from kinprop.constraints.basic import (
    DISTANCE,
    DOT1,
    DOT2,
    SPHERICAL,
    BasicConstraint,
    BasicValue,
    Distance,
    Dot1,
    Dot2,
    Spherical,
    basic_rows,
)

__all__ = [
    "DISTANCE",
    "DOT1",
    "DOT2",
    "SPHERICAL",
    "BasicConstraint",
    "BasicValue",
    "Distance",
    "Dot1",
    "Dot2",
    "Spherical",
    "basic_rows",
]
