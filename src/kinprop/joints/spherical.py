"""Spherical (ball) joint. Tree form: Euler parameters p with normalisation row (eqs. 39-42)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from kinprop.constraints.basic import Spherical as SphericalConstraint
from kinprop.joints.base import JointType
from kinprop.spatial import euler_E, euler_to_matrix


@dataclass(frozen=True)
class Spherical(JointType):
    name: str = "spherical"
    description: str = "three rotations as Euler parameters [e0, e1, e2, e3] (4 coordinates)"
    n_coordinates: int = 4
    euler_start: int | None = 0

    def placement(self, q):
        return euler_to_matrix(q[0:4]), np.zeros(3)

    def motion(self, q):
        return np.zeros((3, 4)), 2.0 * euler_E(q[0:4])

    def constraints(self):
        return (SphericalConstraint(),)
