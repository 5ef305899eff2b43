"""Force elements (springs, dampers) between two bodies, torsion springs on joint angles, and
the vehicle parameters of a suspension model: the ``elements:`` and ``vehicle:`` sections of a model file (one place;
the file schema is :mod:`kinprop.io.schema`, the builders :mod:`kinprop.io.loader` and
:mod:`kinprop.io.hardpoints`).

An element acts along the line between a point on ``body_i`` and a point on ``body_j``,
each stored in its body's frame (``s_i``, ``s_j``, the model's length unit), exactly like a
body's named points. Its length ``|P_j - P_i|`` is what a motion ratio differentiates
(:mod:`kinprop.analysis.firstorder`). Numbers are in the model's units: ``stiffness`` force
per length, ``damping`` force per (length per second), ``free_length`` length, ``preload``
force. Kinematics never reads them; they are carried through every solve unchanged.

``Vehicle`` holds what a single corner's anti-dive / anti-lift / anti-squat needs (Milliken &
Milliken, *Race Car Vehicle Dynamics*, SAE 1995, ch. 17): wheelbase ``L``, centre-of-gravity
height ``h`` (lengths in the model unit), the front axle's share of the braking and of the
drive force, where the brakes and the drive react their torque (``outboard``: on the wheel
carrier, the force acts at the contact patch; ``inboard``: on the chassis, the force acts at
the wheel centre), and which axle the model's corner belongs to.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Literal

from kinprop.errors import Problem

ELEMENT_KINDS = ("spring", "damper", "spring_damper")
ElementKind = Literal["spring", "damper", "spring_damper"]
Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class Element:
    """A spring, damper or spring-damper between ``P_i = r_i + A_i s_i`` and ``P_j = r_j + A_j s_j``."""

    name: str
    kind: ElementKind
    body_i: str
    body_j: str
    s_i: Vec3
    s_j: Vec3
    stiffness: float | None = None
    damping: float | None = None
    free_length: float | None = None
    preload: float | None = None

    @property
    def has_spring(self) -> bool:
        return self.kind in ("spring", "spring_damper")

    @property
    def has_damper(self) -> bool:
        return self.kind in ("damper", "spring_damper")


@dataclass(frozen=True)
class TorsionSpring:
    """A torsion spring on a revolute joint's angle ``q`` (or a cylindrical joint's ``q[0]``),
    e.g. an anti-roll bar's twist at its pivot: the torque ``T = preload + k (free_angle - q)``
    turns the joint's body j about the joint axis towards increasing ``q`` (and body i the
    other way). ``stiffness`` torque per the model's angle unit, ``free_angle`` in the
    model's angle unit, ``preload`` the torque at the model's configuration (give one of the
    two; neither: ``free_angle`` is the model's angle)."""

    name: str
    joint: str
    stiffness: float
    free_angle: float | None = None
    preload: float | None = None
    kind: str = "torsion"


@dataclass(frozen=True)
class Vehicle:
    """Vehicle parameters of a suspension model (module docstring); lengths in the model unit."""

    wheelbase: float
    cg_height: float
    brake_front: float = 0.6
    drive_front: float = 0.0
    brakes: Literal["outboard", "inboard"] = "outboard"
    drive: Literal["outboard", "inboard"] = "inboard"
    axle: Literal["front", "rear"] = "front"
    #: rack travel per turn (360 deg) of the steering wheel (length unit), or None
    rack_travel_per_turn: float | None = None


def element_problems(
    name: str, kind: str, bodies: tuple[str, str], numbers: Mapping[str, float | None], known_bodies: set[str], loc: str
) -> list[Problem]:
    """Semantic problems of one element: known bodies, the numbers its kind needs."""
    out = []
    for b in bodies:
        if b not in known_bodies:
            out.append(Problem(f"{loc}.bodies", f"unknown body {b!r}; bodies are {', '.join(sorted(known_bodies))}"))
    if bodies[0] == bodies[1]:
        out.append(Problem(f"{loc}.bodies", f"an element joins two different bodies, found {bodies[0]!r} twice"))
    if kind in ("spring", "spring_damper") and numbers.get("stiffness") is None:
        out.append(Problem(f"{loc}.stiffness", f"a {kind} needs 'stiffness' (force per length, model units)"))
    if kind in ("damper", "spring_damper") and numbers.get("damping") is None:
        out.append(Problem(f"{loc}.damping", f"a {kind} needs 'damping' (force per velocity, model units)"))
    if kind == "damper":
        for key in ("stiffness", "free_length", "preload"):
            if numbers.get(key) is not None:
                out.append(Problem(f"{loc}.{key}", f"a damper takes no {key!r}; use type: spring_damper"))
    if numbers.get("free_length") is not None and numbers.get("preload") is not None:
        out.append(Problem(loc, "give either 'free_length' or 'preload', not both"))
    return out


__all__ = ["ELEMENT_KINDS", "Element", "TorsionSpring", "Vehicle", "element_problems"]
