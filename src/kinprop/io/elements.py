"""The ``elements:`` and ``vehicle:`` sections of a model file, both styles, in one place:
building :class:`~kinprop.model.elements.Element` / :class:`~kinprop.model.elements.Vehicle`
from the validated specs and writing them back.

Frame style: an element's ends are ``s_i``, ``s_j`` in its bodies' frames. Hardpoint style:
``point_i``, ``point_j`` global at the reference configuration, stored in the bodies' frames
(the same rule as a body's named points).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from kinprop.errors import Problem
from kinprop.io.schema import ElementSpec, VehicleSpec
from kinprop.joints import ALIASES
from kinprop.model.elements import Element, TorsionSpring, Vehicle, element_problems
from kinprop.spatial import Array

#: ``pose(body) -> (r, A)`` of a body at the reference configuration
Pose = Callable[[str], tuple[Array, Array]]


def build_elements(
    specs: Mapping[str, ElementSpec], bodies: set[str], style: str, file: str, pose: Pose | None = None
) -> tuple[tuple[Element, ...], list[Problem]]:
    """Elements of a file (``style`` ``frames`` or ``hardpoints``; ``pose`` needed for hardpoints)."""
    out, problems = [], []
    own, other = (
        (("s_i", "s_j"), ("point_i", "point_j")) if style == "frames" else (("point_i", "point_j"), ("s_i", "s_j"))
    )
    for name, e in specs.items():
        if e.type == "torsion":
            continue  # build_torsion_springs
        loc = f"elements.{name}"
        if e.bodies is None:
            problems.append(
                Problem(f"{loc}.bodies", f"a {e.type} joins two bodies: expected bodies: [BODY_I, BODY_J]", file)
            )
            continue
        for key in ("joint", "free_angle"):
            if getattr(e, key) is not None:
                problems.append(Problem(f"{loc}.{key}", f"a {e.type} takes no {key!r} (a torsion spring does)", file))
        numbers = {k: getattr(e, k) for k in ("stiffness", "damping", "free_length", "preload")}
        found = [
            Problem(p.location, p.message, file)
            for p in element_problems(name, e.type, (e.bodies[0], e.bodies[1]), numbers, bodies, loc)
        ]
        for key in other:
            if getattr(e, key) is not None:
                found.append(
                    Problem(
                        f"{loc}.{key}",
                        f"a {style}-style file gives an element's ends as {own[0]}, {own[1]}, found {key}",
                        file,
                    )
                )
        for key in own:
            if getattr(e, key) is None:
                where = "in its body's frame" if style == "frames" else "global, at the reference configuration"
                found.append(Problem(f"{loc}.{key}", f"expected the element's end {key} ({where})", file))
        problems += found
        if found:
            continue
        ends = []
        for key, body in zip(own, e.bodies, strict=True):  # type: ignore[arg-type]
            v = np.asarray(getattr(e, key), dtype=float)
            if style != "frames" and pose is not None:
                r, A = pose(body)
                v = A.T @ (v - r)
            ends.append(tuple(float(x) for x in v))
        out.append(Element(name, e.type, e.bodies[0], e.bodies[1], ends[0], ends[1], **numbers))  # type: ignore[arg-type]
    return tuple(out), problems


#: joint types whose first coordinate is an angle about the joint's z axis (a torsion spring's)
TORSION_JOINTS = ("revolute", "cylindrical")


def build_torsion_springs(
    specs: Mapping[str, ElementSpec], joint_types: Mapping[str, str], file: str
) -> tuple[tuple[TorsionSpring, ...], list[Problem]]:
    """The ``type: torsion`` elements of a file (``joint_types``: joint name -> type name)."""
    out, problems = [], []
    for name, e in specs.items():
        if e.type != "torsion":
            continue
        loc = f"elements.{name}"
        found = []
        if e.joint is None:
            found.append(
                Problem(f"{loc}.joint", "a torsion spring acts on a joint's angle: expected joint: NAME", file)
            )
        elif e.joint not in joint_types:
            found.append(
                Problem(f"{loc}.joint", f"unknown joint {e.joint!r}; joints are {', '.join(joint_types)}", file)
            )
        elif ALIASES.get(joint_types[e.joint], joint_types[e.joint]) not in TORSION_JOINTS:
            kinds = " or ".join(TORSION_JOINTS)
            found.append(Problem(f"{loc}.joint", f"a torsion spring needs a {kinds} joint (an angle about its axis), "
                                 f"found {e.joint!r} of type {joint_types[e.joint]}", file))  # fmt: skip
        if e.stiffness is None:
            found.append(
                Problem(f"{loc}.stiffness", "a torsion spring needs 'stiffness' (torque per angle unit)", file)
            )
        for key in ("bodies", "s_i", "s_j", "point_i", "point_j", "damping", "free_length"):
            if getattr(e, key) is not None:
                why = "it acts on its joint's angle"
                found.append(Problem(f"{loc}.{key}", f"a torsion spring takes no {key!r} ({why})", file))
        if e.free_angle is not None and e.preload is not None:
            found.append(Problem(loc, "give either 'free_angle' or 'preload', not both", file))
        problems += found
        if not found:
            assert e.joint is not None and e.stiffness is not None
            out.append(TorsionSpring(name, e.joint, float(e.stiffness), e.free_angle, e.preload))
    return tuple(out), problems


def build_vehicle(spec: VehicleSpec | None) -> Vehicle | None:
    return None if spec is None else Vehicle(**spec.model_dump())


def _numbers(e: Element) -> dict[str, Any]:
    keys = ("stiffness", "damping", "free_length", "preload")
    return {k: float(getattr(e, k)) for k in keys if getattr(e, k) is not None}


def elements_to_data(
    elements: tuple[Element, ...], style: str, pose: Pose | None = None, torsion: tuple[TorsionSpring, ...] = ()
) -> dict[str, Any]:
    """The ``elements:`` section of a file of ``style`` (``pose``: current body poses, hardpoints)."""
    out: dict[str, Any] = {}
    for t in torsion:
        spec_t: dict[str, Any] = {"type": "torsion", "joint": t.joint, "stiffness": float(t.stiffness)}
        spec_t.update({k: float(getattr(t, k)) for k in ("free_angle", "preload") if getattr(t, k) is not None})
        out[t.name] = spec_t
    for e in elements:
        spec: dict[str, Any] = {"type": e.kind, "bodies": [e.body_i, e.body_j]}
        for key, body, s in (("i", e.body_i, e.s_i), ("j", e.body_j, e.s_j)):
            if style == "frames" or pose is None:
                spec[f"s_{key}"] = [float(x) for x in s]
            else:
                r, A = pose(body)
                spec[f"point_{key}"] = [float(x) + 0.0 for x in r + A @ np.asarray(s, dtype=float)]
        spec.update(_numbers(e))
        out[e.name] = spec
    return out


def vehicle_to_data(vehicle: Vehicle | None) -> dict[str, Any] | None:
    if vehicle is None:
        return None
    return {k: getattr(vehicle, k) for k in VehicleSpec.model_fields if getattr(vehicle, k) is not None}


__all__ = [
    "TORSION_JOINTS",
    "build_elements",
    "build_torsion_springs",
    "build_vehicle",
    "elements_to_data",
    "vehicle_to_data",
]
