"""Cylindrical joint: rotation q0 about and slide q1 along z'' (4 constraints when cut)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from kinprop.constraints.basic import Dot1, Dot2
from kinprop.jit import kernel
from kinprop.joints.base import JointType, angle_about_z
from kinprop.spatial import EX, EY, EZ, rot_z_into

CODE = 2


@kernel
def placement(q, A, d):
    rot_z_into(q[0], A)
    d[0], d[1], d[2] = 0.0, 0.0, q[1]


@kernel
def motion(q, A, d, dd, H):
    dd[:, :] = 0.0
    H[:, :] = 0.0
    H[2, 0] = 1.0
    dd[2, 1] = 1.0


@dataclass(frozen=True)
class Cylindrical(JointType):
    name: str = "cylindrical"
    hardpoint_keys: tuple[tuple[str, ...], tuple[str, ...]] | None = (("point", "axis"), ())
    cut_fields: tuple[str, ...] = ("s_i", "s_j", "C_i", "C_j")
    description: str = "rotation about and translation along z'' (2 coordinates)"
    n_coordinates: int = 2
    angle_indices: tuple[int, ...] = (0,)
    code: ClassVar[int] = CODE
    placement_kernel = placement
    motion_kernel = motion

    def relative_values(self, R, d):
        return {"angle": angle_about_z(R), "displacement": float(d[2])}

    def constraints(self):
        return (Dot1(EX, EZ), Dot1(EY, EZ), Dot2(EX), Dot2(EY))
