"""The joint-type contract.

A joint connects joint frame i (on body i, placed by ``s_i``/``C_i``) to joint frame j
(on body j, placed by ``s_j``/``C_j``). A joint type knows only joint-frame math:

* tree form — relative coordinates q with the placement of frame j in frame i,
  ``A''(q)`` and ``d''(q)``, and the motion columns ``dd''/dq`` and ``H''(q)``
  (eq. 24: ``dpi'' = H'' dq``), all resolved in joint frame i;
* cut form — a tuple of basic constraints (dot-1, dot-2, spherical, distance) between the
  two joint-frame origins ``O''_ij``, ``O''_ji`` and joint-frame axes (section 2), plus
  optional own coordinates that slide ``O''_ij`` (the T-D joint's q3, eq. 53).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from kinprop.constraints.basic import BasicConstraint, Spherical
from kinprop.jit import kernel
from kinprop.spatial import Array, eye_into, matrix_to_euler


@kernel
def no_placement(q: Array, A: Array, d: Array) -> None:
    """Joints without tree coordinates: frame j coincides with frame i."""
    eye_into(A)
    d[:] = 0.0


@kernel
def no_motion(q: Array, A: Array, d: Array, dd: Array, H: Array) -> None:
    dd[:, :] = 0.0
    H[:, :] = 0.0


def angle_about_z(R: Array) -> float:
    """The rotation angle of ``R`` about z'' (``atan2(R_10, R_00)``), radians."""
    return float(np.arctan2(R[1, 0], R[0, 0]))


def euler_of(R: Array) -> Array:
    """Euler parameters ``[e0..e3]`` of ``R`` with ``e0 >= 0``."""
    p = np.asarray(matrix_to_euler(R), dtype=float)
    return -p if p[0] < 0 else p


def distance_of(d: Array) -> float:
    """``|d''|``: the distance of the two joint origins."""
    return float(np.linalg.norm(d))


@dataclass(frozen=True)
class JointType:
    """Base joint type. Subclasses override what their form needs."""

    name: str = ""
    description: str = ""
    #: number of relative coordinates in tree form (Euler parameters count 4)
    n_coordinates: int = 0
    #: number of the joint's own coordinates in cut form (T-D: 1)
    n_cut_coordinates: int = 0
    #: index of the first of four Euler parameters among the tree coordinates (eq. 41)
    euler_start: int | None = None
    #: indices of tree coordinates that are angles (reported in degrees)
    angle_indices: tuple[int, ...] = ()
    has_length: bool = False
    tree: bool = True
    cut: bool = True
    #: the keys of its hardpoint form (global points and axes; kinprop.io.hardpoints):
    #: (required, optional); None: the type has no hardpoint form
    hardpoint_keys: tuple[tuple[str, ...], tuple[str, ...]] | None = None
    #: the design fields its cut form uses (those a hardpoint file defines for it as a cut joint)
    cut_fields: tuple[str, ...] = ()

    #: the kernel's code for this type (:mod:`kinprop.joints.dispatch`)
    code: ClassVar[int] = -1
    #: compiled ``(q, A, d)``: writes ``A''(q)``, ``d''(q)`` (3x3, 3) in place
    placement_kernel: ClassVar[Callable[..., None]] = no_placement
    #: compiled ``(q, A, d, dd, H)``: writes ``dd''/dq``, ``H''`` (3 x n) given the placement
    motion_kernel: ClassVar[Callable[..., None]] = no_motion

    @property
    def euler(self) -> slice | None:
        """Slice of the tree coordinates holding Euler parameters (normalisation row)."""
        return None if self.euler_start is None else slice(self.euler_start, self.euler_start + 4)

    # --- tree form ---------------------------------------------------------------------------
    def default_coordinates(self) -> Array:
        q = np.zeros(self.n_coordinates)
        if self.euler is not None:
            q[self.euler.start] = 1.0
        return q

    def placement(self, q: Array) -> tuple[Array, Array]:
        """``(A''(q), d''(q))``: orientation and origin of frame j in frame i."""
        A, d = np.empty((3, 3)), np.empty(3)
        # a writable copy: a model's read-only coordinates would compile the kernel a second time
        type(self).placement_kernel(np.array(q, dtype=float), A, d)
        return A, d

    def motion(self, q: Array) -> tuple[Array, Array]:
        """``(dd''/dq, H'')``, each 3 x n, in frame i.

        For Euler parameters these are the paper's tangent columns ``H'' = 2E(p)`` and
        ``dd''/dp = -tilde(d'') H''`` (eq. 39; PAPER-NOTES, S-T joint).
        """
        q = np.array(q, dtype=float)  # writable, as in placement()
        A, d = self.placement(q)
        dd, H = np.zeros((3, self.n_coordinates)), np.zeros((3, self.n_coordinates))
        type(self).motion_kernel(q, A, d, dd, H)
        return dd, H

    # --- reading a joint back -------------------------------------------------------------------
    def relative_values(self, R: Array, d: Array) -> dict[str, float | Array]:
        """The joint's own named values from its relative placement ``R'' = R_i^T R_j``,
        ``d'' = R_i^T (P_j - P_i)`` (frame i), by this type's convention: a tree joint's equal
        its coordinates, a cut joint's are what they would be as a tree joint
        (:mod:`kinprop.propagation.poses`). Angles in radians. None by default."""
        return {}

    # --- cut form ----------------------------------------------------------------------------
    def constraints(self) -> tuple[BasicConstraint, ...]:
        """The basic constraints that replace this joint when it is cut."""
        raise NotImplementedError(f"joint type {self.name!r} cannot be cut")

    def cut_offset(self, qc: Array) -> tuple[Array, Array]:
        """``(u, du/dqc)``: offset of the point on body i in joint frame i (T-D slides it)."""
        return np.zeros(3), np.zeros((3, self.n_cut_coordinates))

    def default_cut_coordinates(self) -> Array:
        return np.zeros(self.n_cut_coordinates)

    @property
    def origins_coincide(self) -> bool:
        """Whether the cut form holds the two joint-frame origins together (a spherical basic
        constraint among its rows: revolute, universal, spherical, fixed, spherical-point)."""
        return self.cut and any(isinstance(c, Spherical) for c in self.constraints())

    @property
    def n_constraints(self) -> int:
        return sum(c.rows for c in self.constraints())

    @property
    def rigid_axes(self) -> tuple[tuple[int, int], ...]:
        """Axis pairs ``(a, b)`` with ``x''_a(i) . x''_b(j) = +1`` at every placement the joint
        itself can take (entries of ``A''(q)`` that are 1 for every q: a revolute's z''-z'', all
        three of a translational joint's). Its cut form's dot-1 rows also hold with such an
        axis reversed (a revolute with ``z''_j = -z''_i``, a slide turned by pi): a root the joint
        cannot reach, which the solver refuses (``kinprop.solver.newton.follow``). Found by
        evaluating the tree form at a few placements; cut-only types (defined by their
        constraints) have none."""
        return _rigid_axes(type(self), self.tree, self.n_coordinates, self.euler)


_RIGID_SAMPLES = 4


def _rigid_axes(cls: type, tree: bool, n: int, euler: slice | None) -> tuple[tuple[int, int], ...]:
    key = (cls, tree, n)
    if key not in _RIGID_CACHE:
        out: tuple[tuple[int, int], ...] = ()
        if tree:
            rng = np.random.default_rng(0)
            fixed = np.ones((3, 3), bool)
            for _ in range(_RIGID_SAMPLES):
                q = rng.uniform(-2.0, 2.0, n)
                if euler is not None:
                    q[euler] /= np.linalg.norm(q[euler])
                A, d = np.empty((3, 3)), np.empty(3)
                cls.placement_kernel(q, A, d)
                fixed &= np.abs(A - 1.0) < 1e-12
            out = tuple((int(a), int(b)) for a, b in zip(*np.nonzero(fixed), strict=True))
        _RIGID_CACHE[key] = out
    return _RIGID_CACHE[key]


_RIGID_CACHE: dict[tuple, tuple[tuple[int, int], ...]] = {}
