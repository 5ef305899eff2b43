"""Revolute joint: rotation q about the common z'' axis (5 constraints when cut)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from kinprop.constraints.basic import Dot1, Spherical
from kinprop.jit import kernel
from kinprop.joints.base import JointType, angle_about_z
from kinprop.spatial import EX, EY, EZ, rot_z_into

CODE = 0


@kernel
def placement(q, A, d):
    rot_z_into(q[0], A)
    d[:] = 0.0


@kernel
def motion(q, A, d, dd, H):
    dd[:, :] = 0.0
    H[:, :] = 0.0
    H[2, 0] = 1.0


@dataclass(frozen=True)
class Revolute(JointType):
    name: str = "revolute"
    hardpoint_keys: tuple[tuple[str, ...], tuple[str, ...]] | None = (("point", "axis"), ())
    cut_fields: tuple[str, ...] = ("s_i", "s_j", "C_i", "C_j")
    description: str = "rotation about z'' (1 coordinate)"
    n_coordinates: int = 1
    angle_indices: tuple[int, ...] = (0,)
    code: ClassVar[int] = CODE
    placement_kernel = placement
    motion_kernel = motion

    def relative_values(self, R, d):
        return {"angle": angle_about_z(R)}

    def constraints(self):
        return (Spherical(), Dot1(EX, EZ), Dot1(EY, EZ))
