"""Cylindrical joint: rotation q0 about and slide q1 along z'' (4 constraints when cut)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from kinprop.constraints.basic import Dot1, Dot2
from kinprop.joints.base import JointType
from kinprop.spatial import EX, EY, EZ, rot_z


@dataclass(frozen=True)
class Cylindrical(JointType):
    name: str = "cylindrical"
    description: str = "rotation about and translation along z'' (2 coordinates)"
    n_coordinates: int = 2
    angle_indices: tuple[int, ...] = (0,)

    def placement(self, q):
        return rot_z(q[0]), EZ * q[1]

    def motion(self, q):
        dd = np.zeros((3, 2))
        dd[:, 1] = EZ
        H = np.zeros((3, 2))
        H[:, 0] = EZ
        return dd, H

    def constraints(self):
        return (Dot1(EX, EZ), Dot1(EY, EZ), Dot2(EX), Dot2(EY))
