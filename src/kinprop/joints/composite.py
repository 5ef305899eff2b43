"""The paper's composite joints (section 5): S-T, R-S and T-D; and the free tree joint."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from kinprop.constraints.basic import Distance, Dot2
from kinprop.jit import kernel
from kinprop.joints.base import JointType, distance_of, euler_of
from kinprop.spatial import EX, EY, EZ, euler_A_into, euler_E_into

ST_CODE, FREE_CODE, TD_CODE = 6, 7, 8


@kernel
def st_placement(q, A, d):
    euler_A_into(q[0:4], A)
    for x in range(3):
        d[x] = A[x, 2] * q[4]


@kernel
def st_motion(q, A, d, dd, H):
    H[:, :] = 0.0
    euler_E_into(q[0:4], 2.0, H, 0)
    # dd/dp = -tilde(d) H: the strut axis turns with the sphere (moment arm, PAPER-NOTES)
    for y in range(4):
        dd[0, y] = -(d[1] * H[2, y] - d[2] * H[1, y])
        dd[1, y] = -(d[2] * H[0, y] - d[0] * H[2, y])
        dd[2, y] = -(d[0] * H[1, y] - d[1] * H[0, y])
    for x in range(3):
        dd[x, 4] = A[x, 2]


@dataclass(frozen=True)
class SphericalTranslational(JointType):
    """S-T: spherical on body i, then translation along the rotated z'' (strut), eq. (58).

    Coordinates ``[e0, e1, e2, e3, t]``: ``A'' = E(p) G(p)^T``, ``d'' = A'' e_z t``.
    Cut form: the sphere centre stays on body j's axis (two dot-2 rows).
    """

    name: str = "spherical-translational"
    hardpoint_keys: tuple[tuple[str, ...], tuple[str, ...]] | None = (("point", "axis"), ())
    cut_fields: tuple[str, ...] = ("s_i", "s_j", "C_j")
    description: str = "Euler parameters then translation along the rotated z'' (5 coordinates)"
    n_coordinates: int = 5
    euler_start: int | None = 0
    code: ClassVar[int] = ST_CODE
    placement_kernel = st_placement
    motion_kernel = st_motion

    def relative_values(self, R, d):
        """``euler`` of the ball and ``displacement`` along the rotated z''."""
        return {"euler": euler_of(R), "displacement": float(d @ R[:, 2])}

    def constraints(self):
        return (Dot2(EX, on="j"), Dot2(EY, on="j"))


@dataclass(frozen=True)
class RevoluteSpherical(JointType):
    """R-S: a link of length l, revolute about z''_i at body i, spherical at body j (eq. 52)."""

    name: str = "revolute-spherical"
    hardpoint_keys: tuple[tuple[str, ...], tuple[str, ...]] | None = (("point_i", "axis", "point_j"), ("length",))
    cut_fields: tuple[str, ...] = ("s_i", "s_j", "C_i", "length")
    description: str = "link of length l: revolute on body i, ball on body j (cut only)"
    has_length: bool = True
    tree: bool = False

    def relative_values(self, R, d):
        return {"distance": distance_of(d)}

    def constraints(self):
        return (Dot2(EZ), Distance())


@dataclass(frozen=True)
class TranslationalDistance(JointType):
    """T-D: a rack sliding q3 along z''_i on body i, a rod of length l to body j (eqs. 53-57).

    Its own coordinate slides the point on body i: ``u = e_z q3`` in joint frame i (the
    kernel's cut offset for this code).
    """

    name: str = "translational-distance"
    hardpoint_keys: tuple[tuple[str, ...], tuple[str, ...]] | None = (("point_i", "axis", "point_j"), ("length",))
    cut_fields: tuple[str, ...] = ("s_i", "s_j", "C_i", "length")
    description: str = "rack along z''_i (1 own coordinate) and rod of length l (cut only)"
    n_cut_coordinates: int = 1
    has_length: bool = True
    tree: bool = False
    code: ClassVar[int] = TD_CODE

    def relative_values(self, R, d):
        return {"distance": distance_of(d)}

    def constraints(self):
        return (Distance(),)

    def cut_offset(self, qc):
        return EZ * qc[0], EZ[:, None].copy()


@kernel
def free_placement(q, A, d):
    """``A = E(p) G(p)^T / (p.p)``: the rotation of the normalised ``p`` (a rotation at every
    iterate, unlike the paper's ``E G^T`` of its own joints)."""
    euler_A_into(q[3:7], A)
    inv = 1.0 / (q[3] * q[3] + q[4] * q[4] + q[5] * q[5] + q[6] * q[6])
    for x in range(3):
        for y in range(3):
            A[x, y] *= inv
    d[0], d[1], d[2] = q[0], q[1], q[2]


@kernel
def free_motion(q, A, d, dd, H):
    """``H'' = 2E(p) / (p.p)``: the exact derivative of :func:`free_placement` (``E(p) p = 0``:
    a radial ``dp`` does not turn the body), so Newton converges quadratically."""
    dd[:, :] = 0.0
    H[:, :] = 0.0
    dd[0, 0], dd[1, 1], dd[2, 2] = 1.0, 1.0, 1.0
    euler_E_into(q[3:7], 2.0 / (q[3] * q[3] + q[4] * q[4] + q[5] * q[5] + q[6] * q[6]), H, 3)


@dataclass(frozen=True)
class Free(JointType):
    """Free (6-DOF) tree joint: translation ``[x, y, z]`` then Euler parameters ``[e0..e3]``.

    Lets a body be placed purely by cut constraints (e.g. a Stewart platform on distance legs).
    """

    name: str = "free"
    hardpoint_keys: tuple[tuple[str, ...], tuple[str, ...]] | None = ((), ("point",))
    description: str = "translation then Euler parameters (7 coordinates; tree only)"
    n_coordinates: int = 7
    euler_start: int | None = 3
    cut: bool = False
    code: ClassVar[int] = FREE_CODE
    placement_kernel = free_placement
    motion_kernel = free_motion

    def relative_values(self, R, d):
        return {"euler": euler_of(R), "translation_i": d.copy()}


__all__ = ["Free", "RevoluteSpherical", "SphericalTranslational", "TranslationalDistance"]
