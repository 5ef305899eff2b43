"""Spherical (ball) joint. Tree form: Euler parameters p with normalisation row (eqs. 39-42)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from kinprop.constraints.basic import Spherical as SphericalConstraint
from kinprop.jit import kernel
from kinprop.joints.base import JointType, euler_of
from kinprop.spatial import euler_A_into, euler_E_into

CODE = 4


@kernel
def placement(q, A, d):
    euler_A_into(q[0:4], A)
    d[:] = 0.0


@kernel
def motion(q, A, d, dd, H):
    dd[:, :] = 0.0
    euler_E_into(q[0:4], 2.0, H, 0)  # H'' = 2E(p) (eq. 39)


@dataclass(frozen=True)
class Spherical(JointType):
    name: str = "spherical"
    hardpoint_keys: tuple[tuple[str, ...], tuple[str, ...]] | None = (("point",), ())
    cut_fields: tuple[str, ...] = ("s_i", "s_j")
    description: str = "three rotations as Euler parameters [e0, e1, e2, e3] (4 coordinates)"
    n_coordinates: int = 4
    euler_start: int | None = 0
    code: ClassVar[int] = CODE
    placement_kernel = placement
    motion_kernel = motion

    def relative_values(self, R, d):
        return {"euler": euler_of(R)}

    def constraints(self):
        return (SphericalConstraint(),)
