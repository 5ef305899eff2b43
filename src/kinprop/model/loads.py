"""Applied loads of a model: forces and couples on body points, the contact-patch force of a
wheel, body weights under a gravity field, in named load cases (the ``loads:`` section of a
model file, :mod:`kinprop.io.loads`; analysed by :func:`kinprop.statics`).

Units: forces in the model's force unit (``units: {force: N}``), moments (couples) in force x
length (the model's length unit), points in the model's length unit. Gravity is given in
multiples of g (``[0, 0, -1]``: 1 g down in a z-up model; ``[-1, 0, -1]``: the weight plus a
1 g braking deceleration's inertia force), so it is unit-free: a body's load is its
``weight`` (the force unit, at 1 g) times that vector, at its centre of mass.

A wheel force ``[Fx, Fy, Fz]`` is the force of the road on the tyre at the contact point, in
ISO 8855 axes (x forward, y left, z up: ``Fz > 0`` is the vertical load, ``Fx < 0`` braking);
in a model declared in SAE J670 axes (y right, z down) it is converted to the model's axes.
It acts on the wheel body (the body with the ``wheel_centre`` and ``spin_axis`` points) at the
contact point (:func:`kinprop.analysis.metrics.contact_point`, the lowest point of the wheel
circle at the analysed pose).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Literal

Vec3 = tuple[float, float, float]
ZERO: Vec3 = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class PointLoad:
    """A force and a couple on ``body`` at ``point`` (a named point of the body, or
    coordinates in its frame), their components in global axes or in the body's axes."""

    body: str
    point: str | Vec3
    force: Vec3 = ZERO
    moment: Vec3 = ZERO
    axes: Literal["global", "body"] = "global"


@dataclass(frozen=True)
class Mass:
    """A body's weight (force at 1 g) at its centre of mass (named point or body-frame coordinates)."""

    body: str
    weight: float
    cm: str | Vec3


@dataclass(frozen=True)
class LoadCase:
    """One load case: point loads, wheel forces ``{wheel body: (Fx, Fy, Fz)}`` (ISO 8855) and
    a gravity vector in g (None: no weights)."""

    name: str
    forces: tuple[PointLoad, ...] = ()
    wheels: Mapping[str, Vec3] = field(default_factory=dict)
    gravity: Vec3 | None = None


@dataclass(frozen=True)
class Loads:
    """The ``loads:`` section: body masses and the named load cases."""

    masses: tuple[Mass, ...] = ()
    cases: Mapping[str, LoadCase] = field(default_factory=dict)

    def case(self, name: str) -> LoadCase:
        if name not in self.cases:
            raise KeyError(f"unknown load case {name!r}; load cases: {', '.join(self.cases) or 'none'}")
        return self.cases[name]


__all__ = ["LoadCase", "Loads", "Mass", "PointLoad", "Vec3"]
