"""Universal (Hooke) joint: A'' = Rz(q0) Ry(q1) (eqs. 5.8-5.11; PAPER-NOTES on eq. 5.10).

The first axis is z''_i, the second the y axis after the q0 rotation. Cut form: spherical
plus dot-1 between z''_i and y''_j (4 constraints).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from kinprop.constraints.basic import Dot1, Spherical
from kinprop.jit import kernel
from kinprop.joints.base import JointType
from kinprop.spatial import EY, EZ

CODE = 3


@kernel
def placement(q, A, d):
    c, s = np.cos(q[0]), np.sin(q[0])
    c1, s1 = np.cos(q[1]), np.sin(q[1])
    A[0, 0], A[0, 1], A[0, 2] = c * c1, -s, c * s1
    A[1, 0], A[1, 1], A[1, 2] = s * c1, c, s * s1
    A[2, 0], A[2, 1], A[2, 2] = -s1, 0.0, c1
    d[:] = 0.0


@kernel
def motion(q, A, d, dd, H):
    dd[:, :] = 0.0
    H[:, :] = 0.0
    H[2, 0] = 1.0
    H[0, 1], H[1, 1] = -np.sin(q[0]), np.cos(q[0])  # Rz(q0) e_y


@dataclass(frozen=True)
class Universal(JointType):
    name: str = "universal"
    hardpoint_keys: tuple[tuple[str, ...], tuple[str, ...]] | None = (("point", "axis_i", "axis_j"), ())
    cut_fields: tuple[str, ...] = ("s_i", "s_j", "C_i", "C_j")
    description: str = "rotations about z''_i then the rotated y'' (2 coordinates)"
    n_coordinates: int = 2
    angle_indices: tuple[int, ...] = (0, 1)
    code: ClassVar[int] = CODE
    placement_kernel = placement
    motion_kernel = motion

    def relative_values(self, R, d):
        """``R'' = Rz(q0) Ry(q1)``: ``angle_1 = atan2(-R''_01, R''_11)``, ``angle_2 = atan2(-R''_20, R''_22)``."""
        return {"angle_1": float(np.arctan2(-R[0, 1], R[1, 1])), "angle_2": float(np.arctan2(-R[2, 0], R[2, 2]))}

    def constraints(self):
        return (Spherical(), Dot1(EZ, EY))
