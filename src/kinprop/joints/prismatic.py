"""Translational (prismatic) joint: slide q along z'' (5 constraints when cut)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from kinprop.constraints.basic import Dot1, Dot2
from kinprop.jit import kernel
from kinprop.joints.base import JointType
from kinprop.spatial import EX, EY, EZ, eye_into

CODE = 1


@kernel
def placement(q, A, d):
    eye_into(A)
    d[0], d[1], d[2] = 0.0, 0.0, q[0]


@kernel
def motion(q, A, d, dd, H):
    dd[:, :] = 0.0
    H[:, :] = 0.0
    dd[2, 0] = 1.0


@dataclass(frozen=True)
class Prismatic(JointType):
    name: str = "translational"
    hardpoint_keys: tuple[tuple[str, ...], tuple[str, ...]] | None = (("point", "axis"), ())
    cut_fields: tuple[str, ...] = ("s_i", "s_j", "C_i", "C_j")
    description: str = "translation along z'' (1 coordinate)"
    n_coordinates: int = 1
    code: ClassVar[int] = CODE
    placement_kernel = placement
    motion_kernel = motion

    def relative_values(self, R, d):
        return {"displacement": float(d[2])}

    def constraints(self):
        # axes parallel, the offset along z''_i only, no twist about the axis
        return (Dot1(EX, EZ), Dot1(EY, EZ), Dot2(EX), Dot2(EY), Dot1(EX, EY))
