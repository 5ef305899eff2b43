"""The paper's composite joints (section 5): S-T, R-S and T-D."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from kinprop.constraints.basic import Distance, Dot2
from kinprop.joints.base import JointType
from kinprop.spatial import EX, EY, EZ, euler_E, euler_to_matrix, tilde


@dataclass(frozen=True)
class SphericalTranslational(JointType):
    """S-T: spherical on body i, then translation along the rotated z'' (strut), eq. (58).

    Coordinates ``[e0, e1, e2, e3, t]``: ``A'' = E(p) G(p)^T``, ``d'' = A'' e_z t``.
    Cut form: the sphere centre stays on body j's axis (two dot-2 rows).
    """

    name: str = "spherical-translational"
    description: str = "Euler parameters then translation along the rotated z'' (5 coordinates)"
    n_coordinates: int = 5
    euler_start: int | None = 0

    def placement(self, q):
        A = euler_to_matrix(q[0:4])
        return A, A @ EZ * q[4]

    def motion(self, q):
        A, d = self.placement(q)
        H = np.zeros((3, 5))
        H[:, :4] = 2.0 * euler_E(q[0:4])
        dd = -tilde(d) @ H  # the strut axis turns with the sphere (moment arm, PAPER-NOTES)
        dd[:, 4] = A @ EZ
        return dd, H

    def constraints(self):
        return (Dot2(EX, on="j"), Dot2(EY, on="j"))


@dataclass(frozen=True)
class RevoluteSpherical(JointType):
    """R-S: a link of length l, revolute about z''_i at body i, spherical at body j (eq. 52)."""

    name: str = "revolute-spherical"
    description: str = "link of length l: revolute on body i, ball on body j (cut only)"
    has_length: bool = True
    tree: bool = False

    def constraints(self):
        return (Dot2(EZ), Distance())


@dataclass(frozen=True)
class TranslationalDistance(JointType):
    """T-D: a rack sliding q3 along z''_i on body i, a rod of length l to body j (eqs. 53-57)."""

    name: str = "translational-distance"
    description: str = "rack along z''_i (1 own coordinate) and rod of length l (cut only)"
    n_cut_coordinates: int = 1
    has_length: bool = True
    tree: bool = False

    def constraints(self):
        return (Distance(),)

    def cut_offset(self, qc):
        return EZ * qc[0], EZ[:, None].copy()


@dataclass(frozen=True)
class Free(JointType):
    """Free (6-DOF) tree joint: translation ``[x, y, z]`` then Euler parameters ``[e0..e3]``.

    Lets a body be placed purely by cut constraints (e.g. a Stewart platform on distance legs).
    """

    name: str = "free"
    description: str = "translation then Euler parameters (7 coordinates; tree only)"
    n_coordinates: int = 7
    euler_start: int | None = 3
    cut: bool = False

    def placement(self, q):
        return euler_to_matrix(q[3:7]), np.array(q[0:3], dtype=float)

    def motion(self, q):
        dd = np.zeros((3, 7))
        dd[:, :3] = np.eye(3)
        H = np.zeros((3, 7))
        H[:, 3:] = 2.0 * euler_E(q[3:7])
        return dd, H
