"""The four basic constraints as joints of their own (cut only, section 2)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from kinprop.constraints.basic import Distance, Dot1, Dot2, Spherical
from kinprop.joints.base import JointType, distance_of
from kinprop.spatial import EZ


@dataclass(frozen=True)
class Dot1Joint(JointType):
    name: str = "dot-1"
    hardpoint_keys: tuple[tuple[str, ...], tuple[str, ...]] | None = (("axis_i", "axis_j"), ())
    cut_fields: tuple[str, ...] = ("C_i", "C_j")
    description: str = "z''_i perpendicular to z''_j (eq. 1; cut only)"
    tree: bool = False

    def relative_values(self, R, d):
        """``angle`` between z''_i and z''_j."""
        return {"angle": float(np.arccos(np.clip(R[2, 2], -1.0, 1.0)))}

    def constraints(self):
        return (Dot1(EZ, EZ),)


@dataclass(frozen=True)
class Dot2Joint(JointType):
    name: str = "dot-2"
    hardpoint_keys: tuple[tuple[str, ...], tuple[str, ...]] | None = (("point_i", "axis", "point_j"), ())
    cut_fields: tuple[str, ...] = ("s_i", "s_j", "C_i")
    description: str = "z''_i perpendicular to d_ij (eq. 8; cut only)"
    tree: bool = False

    def constraints(self):
        return (Dot2(EZ),)


@dataclass(frozen=True)
class SphericalPoint(JointType):
    name: str = "spherical-point"
    hardpoint_keys: tuple[tuple[str, ...], tuple[str, ...]] | None = (("point",), ())
    cut_fields: tuple[str, ...] = ("s_i", "s_j")
    description: str = "the two joint origins coincide (eq. 15; cut only)"
    tree: bool = False

    def relative_values(self, R, d):
        return {"distance": distance_of(d)}

    def constraints(self):
        return (Spherical(),)


@dataclass(frozen=True)
class DistanceJoint(JointType):
    name: str = "distance"
    hardpoint_keys: tuple[tuple[str, ...], tuple[str, ...]] | None = (("point_i", "point_j"), ("length",))
    cut_fields: tuple[str, ...] = ("s_i", "s_j", "length")
    description: str = "the joint origins are l apart: S-S link, tie rod (eq. 17; cut only)"
    has_length: bool = True
    tree: bool = False

    def relative_values(self, R, d):
        return {"distance": distance_of(d)}

    def constraints(self):
        return (Distance(),)
