"""Universal (Hooke) joint: A'' = Rz(q0) Ry(q1) (eqs. 5.8-5.11; PAPER-NOTES on eq. 5.10).

The first axis is z''_i, the second the y axis after the q0 rotation. Cut form: spherical
plus dot-1 between z''_i and y''_j (4 constraints).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from kinprop.constraints.basic import Dot1, Spherical
from kinprop.joints.base import JointType
from kinprop.spatial import EY, EZ, rot_y, rot_z


@dataclass(frozen=True)
class Universal(JointType):
    name: str = "universal"
    description: str = "rotations about z''_i then the rotated y'' (2 coordinates)"
    n_coordinates: int = 2
    angle_indices: tuple[int, ...] = (0, 1)

    def placement(self, q):
        return rot_z(q[0]) @ rot_y(q[1]), np.zeros(3)

    def motion(self, q):
        H = np.empty((3, 2))
        H[:, 0] = EZ
        H[:, 1] = rot_z(q[0]) @ EY
        return np.zeros((3, 2)), H

    def constraints(self):
        return (Spherical(), Dot1(EZ, EY))
