"""The four basic constraints of section 2 (eqs. 1, 8, 15, 17), written once (compiled).

Each is evaluated on the joint-frame geometry of a cut joint:

* ``d``   = ``O''_ji - O''_ij`` (eq. 9), global;
* ``R_i``, ``R_j`` = ``A_i C_ij``, ``A_j C_ji``: joint-frame orientations, global;
* ``l``   = the joint's length.

and writes its rows' values with partials with respect to ``d``, to the virtual rotations
``w_i``, ``w_j`` of the two joint frames (global), and to ``l``. The body-level partials of
Table 1 (``Phi_r``, ``Phi_pi``, ``Phi_s'``, ``Phi_xi'``) follow by the chain rule in
:mod:`kinprop.kinematics.kernels`; ``tests/constraints`` checks them against Table 1.
The classes at the end describe a joint's cut form (kind, axes) and evaluate one constraint
from Python through the same compiled rows.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar, NamedTuple

import numpy as np

from kinprop.jit import inlined, kernel
from kinprop.spatial import EZ, Array

DOT1, DOT2, SPHERICAL, DISTANCE = 0, 1, 2, 3
#: rows per kind
ROWS = (1, 1, 3, 1)


@kernel
def _axis(R, axes, off):
    """``R @ axes[off:off+3]`` as three scalars (no allocation in the hot loop)."""
    x, y, z = axes[off], axes[off + 1], axes[off + 2]
    return (R[0, 0] * x + R[0, 1] * y + R[0, 2] * z, R[1, 0] * x + R[1, 1] * y + R[1, 2] * z,
            R[2, 0] * x + R[2, 1] * y + R[2, 2] * z)  # fmt: skip


@kernel
def _cross_row(a0, a1, a2, b0, b1, b2, out, r):
    out[r, 0], out[r, 1], out[r, 2] = a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@inlined
def basic_rows(kind, on_j, axes, d, R_i, R_j, l, r, Phi, Phi_d, Phi_wi, Phi_wj, Phi_l):
    """Rows ``r, r+1, ...`` of one basic constraint into ``Phi[r]`` and the partial rows
    (which the caller has zeroed); returns the number of rows written.

    * dot-1 (eq. 1): ``a_i . a_j``, ``a_i = R_i a''_i``, ``a_j = R_j a''_j`` (``axes = [a''_i, a''_j]``);
      ``Phi_wi = a_i x a_j``, ``Phi_wj = a_j x a_i``;
    * dot-2 (eq. 8): ``a . d`` with ``a = R a''`` on frame i (or j when ``on_j``);
      ``Phi_d = a``, ``Phi_w = a x d``;
    * spherical (eq. 15): ``d`` (3 rows), ``Phi_d = I``;
    * distance (eq. 17): ``d . d - l^2``, ``Phi_d = 2 d``, ``Phi_l = -2 l``.
    """
    if kind == DOT1:
        a0, a1, a2 = _axis(R_i, axes, 0)
        b0, b1, b2 = _axis(R_j, axes, 3)
        Phi[r] = a0 * b0 + a1 * b1 + a2 * b2
        _cross_row(a0, a1, a2, b0, b1, b2, Phi_wi, r)
        _cross_row(b0, b1, b2, a0, a1, a2, Phi_wj, r)
        return 1
    if kind == DOT2:
        a0, a1, a2 = _axis(R_j if on_j else R_i, axes, 0)
        _cross_row(a0, a1, a2, d[0], d[1], d[2], Phi_wj if on_j else Phi_wi, r)
        Phi[r] = a0 * d[0] + a1 * d[1] + a2 * d[2]
        Phi_d[r, 0], Phi_d[r, 1], Phi_d[r, 2] = a0, a1, a2
        return 1
    if kind == SPHERICAL:
        for x in range(3):
            Phi[r + x] = d[x]
            Phi_d[r + x, x] = 1.0
        return 3
    Phi[r] = d[0] * d[0] + d[1] * d[1] + d[2] * d[2] - l * l
    for x in range(3):
        Phi_d[r, x] = 2.0 * d[x]
    Phi_l[r] = -2.0 * l
    return 1


class BasicValue(NamedTuple):
    value: Array  # (m,)
    Phi_d: Array  # (m, 3)
    Phi_wi: Array  # (m, 3)
    Phi_wj: Array  # (m, 3)
    Phi_l: Array  # (m,)


@dataclass(frozen=True)
class BasicConstraint:
    rows: ClassVar[int] = 1
    kind: ClassVar[int] = -1

    def axes(self) -> tuple[Array, Array]:
        """``(a''_i, a''_j)`` for the kernel's axis table (zeros when unused)."""
        return np.zeros(3), np.zeros(3)

    @property
    def on_j(self) -> bool:
        return False

    def evaluate(self, d: Array, R_i: Array, R_j: Array, l: float) -> BasicValue:
        m = self.rows
        Phi, Pd, Wi, Wj, Pl = np.zeros(m), np.zeros((m, 3)), np.zeros((m, 3)), np.zeros((m, 3)), np.zeros(m)
        axes = np.concatenate(self.axes()).astype(float)
        basic_rows(self.kind, self.on_j, axes, np.asarray(d, float), np.asarray(R_i, float),
                   np.asarray(R_j, float), float(l), 0, Phi, Pd, Wi, Wj, Pl)  # fmt: skip
        return BasicValue(Phi, Pd, Wi, Wj, Pl)


@dataclass(frozen=True)
class Dot1(BasicConstraint):
    """Dot-1 (eq. 1): ``a_i . a_j = 0`` for body-fixed axes ``a_i = R_i a''_i``, ``a_j = R_j a''_j``."""

    kind: ClassVar[int] = DOT1
    a_i: Array = field(default_factory=lambda: EZ)
    a_j: Array = field(default_factory=lambda: EZ)

    def axes(self):
        return np.asarray(self.a_i, float), np.asarray(self.a_j, float)


@dataclass(frozen=True)
class Dot2(BasicConstraint):
    """Dot-2 (eq. 8): ``a . d_ij = 0`` with ``a`` fixed in joint frame i (or j with ``on="j"``)."""

    kind: ClassVar[int] = DOT2
    a: Array = field(default_factory=lambda: EZ)
    on: str = "i"

    def axes(self):
        return np.asarray(self.a, float), np.zeros(3)

    @property
    def on_j(self) -> bool:
        return self.on == "j"


@dataclass(frozen=True)
class Spherical(BasicConstraint):
    """Spherical (eq. 15): ``d_ij = 0``; three rows."""

    rows: ClassVar[int] = 3
    kind: ClassVar[int] = SPHERICAL


@dataclass(frozen=True)
class Distance(BasicConstraint):
    """Distance (eq. 17): ``d . d - l^2 = 0``."""

    kind: ClassVar[int] = DISTANCE
