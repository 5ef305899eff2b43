"""The ``loads:`` section of a model file, both styles, in one place: building
:class:`~kinprop.model.loads.Loads` from the validated spec and writing it back.

Points are a body's named point (``point: wheel_centre``) or coordinates: in a frame-style
file in the body's frame, in a hardpoint-style file global at the reference configuration
(stored in the body's frame, the rule of a body's named points and of elements).

.. code-block:: yaml

    loads:
      masses:
        upright: {weight: 350, cm: wheel_centre}      # force at 1 g (units.force)
      cases:
        bump_3g:
          wheels: {upright: [0, 0, 15000]}            # ISO 8855 Fx, Fy, Fz at the contact patch
          gravity: [0, 0, -3]                         # in g
        brake_1g:
          wheels: {upright: [-5000, 0, 5000]}
          forces:
            - {body: upright, point: wheel_centre, moment: [0, 1.5e6, 0]}   # force x length
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from kinprop.errors import Problem
from kinprop.io.schema import LoadsSpec
from kinprop.model.loads import LoadCase, Loads, Mass, PointLoad
from kinprop.spatial import Array

#: ``pose(body) -> (r, A)`` of a body at the reference configuration
Pose = Callable[[str], tuple[Array, Array]]
WHEEL_POINTS = ("wheel_centre", "spin_axis", "contact_patch")


def build_loads(
    spec: LoadsSpec | None,
    points: Mapping[str, Sequence[str]],
    style: str,
    file: str | None,
    pose: Pose | None = None,
) -> tuple[Loads | None, list[Problem]]:
    """Loads of a file; ``points``: each body's named points; ``pose`` for hardpoint style."""
    if spec is None:
        return None, []
    problems: list[Problem] = []

    def body_ok(body: str, loc: str) -> bool:
        if body not in points:
            problems.append(Problem(loc, f"unknown body {body!r}; bodies are {', '.join(sorted(points))}", file))
            return False
        return True

    def point(body: str, p: str | list[float], loc: str) -> str | tuple[float, float, float]:
        if isinstance(p, str):
            if p not in points[body]:
                known = ", ".join(points[body]) or "none"
                problems.append(Problem(loc, f"body {body!r} has no named point {p!r}; its points: {known}", file))
            return p
        v = np.asarray(p, dtype=float)
        if style != "frames" and pose is not None:
            r, A = pose(body)
            v = A.T @ (v - r)
        return (float(v[0]), float(v[1]), float(v[2]))

    masses = []
    for body, m in spec.masses.items():
        loc = f"loads.masses.{body}"
        if body_ok(body, loc):
            masses.append(Mass(body, float(m.weight), point(body, m.cm, f"{loc}.cm")))
    cases = {}
    for name, c in spec.cases.items():
        loc = f"loads.cases.{name}"
        forces = []
        for k, f in enumerate(c.forces):
            floc = f"{loc}.forces[{k}]"
            if f.force is None and f.moment is None:
                problems.append(Problem(floc, "expected a 'force' or a 'moment' (or both), found neither", file))
            if body_ok(f.body, f"{floc}.body"):
                zero = [0.0, 0.0, 0.0]
                forces.append(PointLoad(f.body, point(f.body, f.point, f"{floc}.point"), tuple(f.force or zero),  # type: ignore[arg-type]
                                        tuple(f.moment or zero), f.axes))  # type: ignore[arg-type]  # fmt: skip
        for wheel in c.wheels:
            if body_ok(wheel, f"{loc}.wheels.{wheel}"):
                missing = [p for p in WHEEL_POINTS if p not in points[wheel]]
                if missing:
                    need = f"a wheel body needs the named points {', '.join(WHEEL_POINTS)}"
                    problems.append(
                        Problem(f"{loc}.wheels.{wheel}", f"{need}; {wheel!r} lacks {', '.join(missing)}", file)
                    )
        if c.gravity is not None and not spec.masses:
            problems.append(Problem(f"{loc}.gravity", "gravity needs body weights: give 'loads.masses'", file))
        wheels = {w: (float(v[0]), float(v[1]), float(v[2])) for w, v in c.wheels.items()}
        gravity = None if c.gravity is None else (float(c.gravity[0]), float(c.gravity[1]), float(c.gravity[2]))
        cases[name] = LoadCase(name, tuple(forces), wheels, gravity)
    return Loads(tuple(masses), cases), problems


def _point_data(body: str, p: Any, style: str, pose: Pose | None) -> Any:
    if isinstance(p, str):
        return p
    v = np.asarray(p, dtype=float)
    if style != "frames" and pose is not None:
        r, A = pose(body)
        v = r + A @ v
    return [float(x) + 0.0 for x in v]


def loads_to_data(loads: Loads | None, style: str, pose: Pose | None = None) -> dict[str, Any] | None:
    """The ``loads:`` section of a file of ``style`` (``pose``: current body poses, hardpoints)."""
    if loads is None:
        return None
    out: dict[str, Any] = {}
    if loads.masses:
        out["masses"] = {m.body: {"weight": m.weight, "cm": _point_data(m.body, m.cm, style, pose)}
                         for m in loads.masses}  # fmt: skip
    cases: dict[str, Any] = {}
    for name, c in loads.cases.items():
        spec: dict[str, Any] = {}
        if c.forces:
            spec["forces"] = [
                {"body": f.body, "point": _point_data(f.body, f.point, style, pose), "force": list(f.force),
                 "moment": list(f.moment), **({"axes": f.axes} if f.axes != "global" else {})}
                for f in c.forces
            ]  # fmt: skip
        if c.wheels:
            spec["wheels"] = {w: list(v) for w, v in c.wheels.items()}
        if c.gravity is not None:
            spec["gravity"] = list(c.gravity)
        cases[name] = spec
    if cases:
        out["cases"] = cases
    return out


__all__ = ["build_loads", "loads_to_data"]
