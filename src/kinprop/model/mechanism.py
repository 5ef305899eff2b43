"""Mechanism: names, joint types and connectivity (frozen; section 2, Fig. 1)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from kinprop.errors import ModelError, Problem
from kinprop.joints import JointType, joint_type
from kinprop.spatial import Array

#: design fields a joint may carry: position vectors (body frame), orientations, length
VECTOR_FIELDS = ("s_i", "s_j")
ROTATION_FIELDS = ("C_i", "C_j")
DESIGN_FIELDS = ("s_i", "s_j", "C_i", "C_j", "length")


@dataclass(frozen=True)
class Body:
    """A rigid body. Fixed bodies carry their global pose (``r``, ``A``)."""

    name: str
    fixed: bool = False
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    orientation: tuple[tuple[float, ...], ...] = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    #: named points in the body frame (e.g. wheel centre), for outputs
    points: tuple[tuple[str, tuple[float, float, float]], ...] = ()

    @property
    def r(self) -> Array:
        return np.array(self.position, dtype=float)

    @property
    def A(self) -> Array:
        return np.array(self.orientation, dtype=float)


@dataclass(frozen=True)
class Joint:
    """A joint between ``body_i`` and ``body_j`` with a joint frame on each (Fig. 1).

    ``fields`` names the design variables this joint's model defines (``s_i``, ``C_j``,
    ``length``, ...); a field not listed keeps its default (zero vector, identity) and is not
    a design variable. ``cut``: True forces the joint to be cut, False keeps it in the tree,
    None lets the topology decide.
    """

    name: str
    type: str
    body_i: str
    body_j: str
    fields: frozenset[str] = field(default_factory=frozenset)
    cut: bool | None = None

    @property
    def jtype(self) -> JointType:
        return joint_type(self.type)


@dataclass(frozen=True)
class Mechanism:
    """Bodies and joints. Validated on construction; every problem is reported at once."""

    bodies: tuple[Body, ...]
    joints: tuple[Joint, ...]
    name: str = "mechanism"
    #: driven joints (input coordinates): held unless named in a free set; ``JOINT`` (all its
    #: coordinates) or ``JOINT.q[k]``
    inputs: tuple[str, ...] = ()

    _bodies: dict[str, Body] = field(init=False, repr=False, compare=False, hash=False)
    _joints: dict[str, Joint] = field(init=False, repr=False, compare=False, hash=False)

    def __post_init__(self) -> None:
        problems = validate_structure(self.bodies, self.joints, self.inputs)
        if problems:
            raise ModelError(problems)
        object.__setattr__(self, "_bodies", {b.name: b for b in self.bodies})
        object.__setattr__(self, "_joints", {j.name: j for j in self.joints})

    def body(self, name: str) -> Body:
        return self._bodies[name]

    def joint(self, name: str) -> Joint:
        return self._joints[name]

    @property
    def body_names(self) -> list[str]:
        return [b.name for b in self.bodies]

    @property
    def joint_names(self) -> list[str]:
        return [j.name for j in self.joints]


def validate_structure(
    bodies: tuple[Body, ...], joints: tuple[Joint, ...], inputs: tuple[str, ...] = ()
) -> list[Problem]:
    """Names, types and connectivity problems (the topology checks reachability)."""
    problems: list[Problem] = []
    jnames = {j.name for j in joints}
    for k, name in enumerate(inputs):
        joint = name.split(".q")[0] if ".q" in name else name
        if joint not in jnames:
            problems.append(Problem(f"inputs[{k}]", f"unknown joint {name!r}; joints are {sorted(jnames)}"))
    seen: set[str] = set()
    for k, b in enumerate(bodies):
        if b.name in seen:
            problems.append(Problem(f"bodies[{k}]", f"duplicate body name {b.name!r}"))
        seen.add(b.name)
    if bodies and not any(b.fixed for b in bodies):
        problems.append(Problem("bodies", "no fixed body: mark at least one body 'fixed: true'"))
    names = {b.name for b in bodies}
    jseen: set[str] = set()
    for j in joints:
        loc = f"joints.{j.name}"
        if j.name in jseen:
            problems.append(Problem(loc, f"duplicate joint name {j.name!r}"))
        jseen.add(j.name)
        try:
            jt = joint_type(j.type)
        except KeyError as exc:
            problems.append(Problem(f"{loc}.type", str(exc.args[0])))
            jt = None
        for side in ("body_i", "body_j"):
            bname = getattr(j, side)
            if bname not in names:
                problems.append(Problem(f"{loc}.{side}", f"unknown body {bname!r}; bodies are {sorted(names)}"))
        if j.body_i == j.body_j:
            problems.append(Problem(loc, f"joint connects body {j.body_i!r} to itself"))
        unknown = set(j.fields) - set(DESIGN_FIELDS)
        if unknown:
            problems.append(Problem(loc, f"unknown design fields {sorted(unknown)}; expected {DESIGN_FIELDS}"))
        if jt is not None:
            if "length" in j.fields and not jt.has_length:
                problems.append(Problem(f"{loc}.length", f"joint type {jt.name!r} has no length"))
            if jt.has_length and "length" not in j.fields:
                problems.append(Problem(f"{loc}.length", f"joint type {jt.name!r} needs a length"))
            if j.cut is True and not jt.cut:
                problems.append(Problem(f"{loc}.cut", f"joint type {jt.name!r} cannot be cut"))
            if j.cut is False and not jt.tree:
                problems.append(Problem(f"{loc}.cut", f"joint type {jt.name!r} can only be a cut joint"))
    return problems
