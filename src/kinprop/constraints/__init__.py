"""Basic constraints (dot-1, dot-2, spherical, distance) with analytic partials."""

from kinprop.constraints.basic import BasicConstraint, BasicValue, Distance, Dot1, Dot2, Spherical

__all__ = ["BasicConstraint", "BasicValue", "Distance", "Dot1", "Dot2", "Spherical"]
