"""Fixed (weld) joint: no relative motion (6 constraints when cut)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from kinprop.constraints.basic import Dot1, Spherical
from kinprop.joints.base import JointType
from kinprop.spatial import EX, EY, EZ

CODE = 5


@dataclass(frozen=True)
class Fixed(JointType):
    name: str = "fixed"
    hardpoint_keys: tuple[tuple[str, ...], tuple[str, ...]] | None = (("point",), ())
    cut_fields: tuple[str, ...] = ("s_i", "s_j", "C_i", "C_j")
    description: str = "rigid connection (0 coordinates)"
    code: ClassVar[int] = CODE

    def constraints(self):
        return (Spherical(), Dot1(EX, EZ), Dot1(EY, EZ), Dot1(EX, EY))
