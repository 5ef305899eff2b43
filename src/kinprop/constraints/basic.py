"""The four basic constraints of section 2 (eqs. 1, 8, 15, 17).

Each is evaluated on the joint-frame geometry of a cut joint:

* ``d``   = ``O''_ji - O''_ij`` (eq. 9), global;
* ``R_i``, ``R_j`` = ``A_i C_ij``, ``A_j C_ji``: joint-frame orientations, global;
* ``l``   = the joint's length.

and returns its value with partials with respect to ``d``, to the virtual rotations ``w_i``,
``w_j`` of the two joint frames (global), and to ``l``. The body-level partials of Table 1
(``Phi_r``, ``Phi_pi``, ``Phi_s'``, ``Phi_xi'``) follow by the chain rule in
:mod:`kinprop.kinematics.assembly`; ``tests/constraints`` checks them against Table 1.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar, NamedTuple

import numpy as np

from kinprop.spatial import EZ, Array, tilde


class BasicValue(NamedTuple):
    value: Array  # (m,)
    Phi_d: Array  # (m, 3)
    Phi_wi: Array  # (m, 3)
    Phi_wj: Array  # (m, 3)
    Phi_l: Array  # (m,)


@dataclass(frozen=True)
class BasicConstraint:
    rows: ClassVar[int] = 1

    def evaluate(self, d: Array, R_i: Array, R_j: Array, l: float) -> BasicValue:
        raise NotImplementedError


def _zeros(m: int) -> tuple[Array, Array, Array, Array]:
    return np.zeros((m, 3)), np.zeros((m, 3)), np.zeros((m, 3)), np.zeros(m)


@dataclass(frozen=True)
class Dot1(BasicConstraint):
    """Dot-1 (eq. 1): ``a_i . a_j = 0`` for body-fixed axes ``a_i = R_i a''_i``, ``a_j = R_j a''_j``."""

    a_i: Array = field(default_factory=lambda: EZ)
    a_j: Array = field(default_factory=lambda: EZ)

    def evaluate(self, d, R_i, R_j, l):
        a, b = R_i @ self.a_i, R_j @ self.a_j
        Phi_d, _, _, Phi_l = _zeros(1)
        return BasicValue(np.array([a @ b]), Phi_d, (-b @ tilde(a))[None], (-a @ tilde(b))[None], Phi_l)


@dataclass(frozen=True)
class Dot2(BasicConstraint):
    """Dot-2 (eq. 8): ``a . d_ij = 0`` with ``a`` fixed in joint frame i (or j with ``on="j"``)."""

    a: Array = field(default_factory=lambda: EZ)
    on: str = "i"

    def evaluate(self, d, R_i, R_j, l):
        a = (R_i if self.on == "i" else R_j) @ self.a
        _, Phi_wi, Phi_wj, Phi_l = _zeros(1)
        (Phi_wi if self.on == "i" else Phi_wj)[0] = -d @ tilde(a)
        return BasicValue(np.array([a @ d]), a[None].copy(), Phi_wi, Phi_wj, Phi_l)


@dataclass(frozen=True)
class Spherical(BasicConstraint):
    """Spherical (eq. 15): ``d_ij = 0``; three rows."""

    rows: ClassVar[int] = 3

    def evaluate(self, d, R_i, R_j, l):
        _, Phi_wi, Phi_wj, Phi_l = _zeros(3)
        return BasicValue(d.copy(), np.eye(3), Phi_wi, Phi_wj, Phi_l)


@dataclass(frozen=True)
class Distance(BasicConstraint):
    """Distance (eq. 17): ``d . d - l^2 = 0``."""

    def evaluate(self, d, R_i, R_j, l):
        _, Phi_wi, Phi_wj, _ = _zeros(1)
        return BasicValue(np.array([d @ d - l * l]), 2.0 * d[None], Phi_wi, Phi_wj, np.array([-2.0 * l]))
