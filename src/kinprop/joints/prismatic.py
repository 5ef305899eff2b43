"""Translational (prismatic) joint: slide q along z'' (5 constraints when cut)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from kinprop.constraints.basic import Dot1, Dot2
from kinprop.joints.base import JointType
from kinprop.spatial import EX, EY, EZ


@dataclass(frozen=True)
class Prismatic(JointType):
    name: str = "translational"
    description: str = "translation along z'' (1 coordinate)"
    n_coordinates: int = 1

    def placement(self, q):
        return np.eye(3), EZ * q[0]

    def motion(self, q):
        return EZ[:, None].copy(), np.zeros((3, 1))

    def constraints(self):
        # axes parallel, the offset along z''_i only, no twist about the axis
        return (Dot1(EX, EZ), Dot1(EY, EZ), Dot2(EX), Dot2(EY), Dot1(EX, EY))
