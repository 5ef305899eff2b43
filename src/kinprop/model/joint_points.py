"""Named points that are a joint's point, and the steering axis from the joints.

A designer's hardpoint table names each joint once: the upper ball joint *is* the top of the
steering axis, the tie rod's outer end *is* the steering arm's point. kinprop keeps such
points as references (:attr:`kinprop.model.Body.joint_points`): a reference point is
evaluated as the joint's frame origin on one side, ``P = r + A s'``, so it follows every edit
of the joint (``--set hardpoint:UBJ=...``, a study varying ``UBJ.s_j``, a sensitivity).

* **References in a file**: a named point written as ``JOINT`` or ``JOINT.i|j`` instead of
  coordinates, or a wheel body's ``kingpin: [UPPER, LOWER]`` (points ``kingpin_upper`` and
  ``kingpin_lower``); :func:`parse_reference` reads them.
* **Coincident points**: a named point declared by coordinates that coincides, in its own
  body's frame, with a joint's point on that body (``|p - s'| <= COINCIDENT`` relative) is
  bound to that joint at load time (:func:`bind_coincident`).
* **The joint's point** without a side (:func:`joint_point_side`): the ball of a spherical
  joint on the given body; the top-mount ball (side i) of a spherical-translational strut;
  the ball (side j) of a revolute-spherical arm; for revolute, universal, cylindrical,
  translational and fixed joints the side on the given body (i otherwise). Two-ended links
  (distance, translational-distance, dot-2) need ``.i`` or ``.j``.
* **Default steering axis** of a wheel body (:func:`steering_joints`): a strut's top mount
  (an S-T joint's ball, or the chassis-side point of the joint that holds a strut body sliding
  on the wheel) and the wheel's one lower ball joint (McPherson); otherwise the wheel's two
  ball joints (double wishbone). Ball joints are spherical joints on the wheel body and the
  ball end of revolute-spherical arms; tie rods (distance, T-D) are not.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from kinprop.model.mechanism import Body, Joint, Mechanism

#: relative tolerance of "coincides" (printed hardpoints are copied digit for digit)
COINCIDENT = 1e-9
#: joint types whose two sides are two different points (a side must be named)
TWO_ENDED = ("distance", "translational-distance", "dot-2")
#: joint types without a point
NO_POINT = ("dot-1",)
#: ball joints on a wheel body (the steering axis' points)
BALLS = ("spherical", "spherical-point")
#: the strut's slide joints between a strut body and the wheel
SLIDES = ("cylindrical", "translational")
#: the strut's top mount joints between the chassis and the strut body
MOUNTS = ("universal", "spherical", "spherical-point", "revolute")


def joint_point_side(joint: Joint, body: str | None = None) -> str | None:
    """The side (``"i"``/``"j"``) of "the joint's point" for a reference without a side (module
    docstring); None when the joint has no single point (two-ended links, dot-1)."""
    name = joint.jtype.name
    if name in TWO_ENDED or name in NO_POINT:
        return None
    if name == "spherical-translational":
        return "i"
    if name == "revolute-spherical":
        return "j"
    return "j" if body is not None and joint.body_j == body and joint.body_i != body else "i"


def parse_reference(text: str, joints: Mapping[str, Joint], body: str) -> tuple[str, str] | str:
    """``(joint, side)`` of a reference ``JOINT`` or ``JOINT.i|j`` written on ``body``, or a
    message saying what is wrong."""
    joint, _, side = text.strip().partition(".")
    if joint not in joints:
        return f"unknown joint {joint!r} (a point given by name refers to a joint); joints are {sorted(joints)}"
    j = joints[joint]
    if side:
        if side not in ("i", "j"):
            return f"expected {joint}, {joint}.i or {joint}.j, found {text!r}"
        if j.jtype.name in NO_POINT:
            return f"a {j.jtype.name} joint has no point"
        return joint, side
    found = joint_point_side(j, body)
    if found is None:
        return f"a {j.jtype.name} joint has two points: write {joint}.i or {joint}.j"
    return joint, found


def joint_s(joint: Joint, side: str, design: Mapping[str, object]) -> np.ndarray:
    """The joint's ``s'`` on ``side`` (zero when the joint defines none there)."""
    field = f"s_{side}"
    if field in joint.fields:
        return np.asarray(design[f"{joint.name}.{field}"], dtype=float)
    return np.zeros(3)


def coincident_joint(mech: Mechanism, design: Mapping[str, object], body: str, p: object) -> tuple[str, str] | None:
    """The first joint point on ``body`` that the body-frame point ``p`` coincides with."""
    p = np.asarray(p, dtype=float)
    for j in mech.joints:
        if j.jtype.name in NO_POINT or j.jtype.name == "free":
            continue
        for side, b in (("i", j.body_i), ("j", j.body_j)):
            if b != body:
                continue
            s = joint_s(j, side, design)
            if np.linalg.norm(p - s) <= COINCIDENT * max(1.0, float(np.max(np.abs(p))), float(np.max(np.abs(s)))):
                return j.name, side
    return None


def bind_coincident(mech: Mechanism, design: Mapping[str, object]) -> Mechanism:
    """``mech`` with every plain named point that coincides with a joint's point on its body
    bound to that joint (declared references are kept as they are)."""
    bodies = []
    changed = False
    for b in mech.bodies:
        bound = {n for n, *_ in b.joint_points}
        extra = []
        for name, p in b.points:
            if name in bound:
                continue
            hit = coincident_joint(mech, design, b.name, p)
            if hit is not None:
                extra.append((name, hit[0], hit[1], False))
        if extra:
            changed = True
            b = Body(b.name, b.fixed, b.position, b.orientation, b.points, b.joint_points + tuple(extra))
        bodies.append(b)
    if not changed:
        return mech
    return Mechanism(tuple(bodies), mech.joints, mech.name, mech.inputs, mech.couplings, mech.edits)


def _balls(mech: Mechanism, wheel: str) -> list[tuple[str, str]]:
    out = []
    for j in mech.joints:
        name = j.jtype.name
        if name in BALLS and wheel in (j.body_i, j.body_j):
            out.append((j.name, "i" if j.body_i == wheel else "j"))
        elif name == "revolute-spherical" and j.body_j == wheel:
            out.append((j.name, "j"))
    return out


def _top_mount(mech: Mechanism, wheel: str) -> tuple[str, str] | None:
    fixed = {b.name for b in mech.bodies if b.fixed}
    for j in mech.joints:
        if j.jtype.name == "spherical-translational" and wheel in (j.body_i, j.body_j):
            return j.name, "i"
    for j in mech.joints:
        if j.jtype.name in SLIDES and wheel in (j.body_i, j.body_j):
            strut = j.body_i if j.body_j == wheel else j.body_j
            for m in mech.joints:
                if m.jtype.name in MOUNTS and {m.body_i, m.body_j} & fixed and strut in (m.body_i, m.body_j):
                    return m.name, "i" if m.body_i in fixed else "j"
    return None


def steering_joints(mech: Mechanism, wheel: str) -> tuple[tuple[str, str], tuple[str, str]] | None:
    """The two joint points the steering axis of ``wheel`` runs through by default (unordered:
    the upper one is the higher at the state evaluated), or None (e.g. a multilink)."""
    balls = _balls(mech, wheel)
    top = _top_mount(mech, wheel)
    if top is not None:
        return (top, balls[0]) if len(balls) == 1 else None
    return (balls[0], balls[1]) if len(balls) == 2 else None


__all__ = [
    "COINCIDENT",
    "bind_coincident",
    "coincident_joint",
    "joint_point_side",
    "joint_s",
    "parse_reference",
    "steering_joints",
]
