"""Revolute joint: rotation q about the common z'' axis (5 constraints when cut)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from kinprop.constraints.basic import Dot1, Spherical
from kinprop.joints.base import JointType
from kinprop.spatial import EX, EY, EZ, rot_z


@dataclass(frozen=True)
class Revolute(JointType):
    name: str = "revolute"
    description: str = "rotation about z'' (1 coordinate)"
    n_coordinates: int = 1
    angle_indices: tuple[int, ...] = (0,)

    def placement(self, q):
        return rot_z(q[0]), np.zeros(3)

    def motion(self, q):
        return np.zeros((3, 1)), EZ[:, None].copy()

    def constraints(self):
        return (Spherical(), Dot1(EX, EZ), Dot1(EY, EZ))
