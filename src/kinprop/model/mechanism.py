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
#: readings of a hardpoint edit (:attr:`Mechanism.edits`)
EDITS = ("design", "mechanism")


@dataclass(frozen=True)
class Body:
    """A rigid body. Fixed bodies carry their global pose (``r``, ``A``)."""

    name: str
    fixed: bool = False
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    orientation: tuple[tuple[float, ...], ...] = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    #: named points in the body frame (e.g. wheel centre), for outputs
    points: tuple[tuple[str, tuple[float, float, float]], ...] = ()
    #: named points that are a joint's point: ``(name, joint, side, declared)`` with ``side``
    #: ``"i"`` or ``"j"``; such a point is evaluated as that joint's frame origin on that side
    #: (``P = r + A s'``), so it follows every edit of the joint. ``declared``: written in the
    #: file as a reference (``UBJ``, ``TR.j``, ``kingpin: [...]``) rather than found to coincide
    #: at load time. Its entry in ``points`` holds its body-frame position at load.
    joint_points: tuple[tuple[str, str, str, bool], ...] = ()

    def joint_point(self, name: str) -> tuple[str, str] | None:
        """``(joint, side)`` a named point refers to, or None for a plain body-fixed point."""
        for n, joint, side, _ in self.joint_points:
            if n == name:
                return joint, side
        return None

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
class Coupling:
    """A coupling between two single-coordinate tree joints (MuJoCo's ``<equality><joint>``):

    ``q_a - q_a0 = c0 + c1 (q_b - q_b0) + c2 (q_b - q_b0)^2 + c3 (q_b - q_b0)^3 + c4 (q_b - q_b0)^4``

    ``joint_a`` is driven by ``joint_b``; ``q_a0``, ``q_b0`` (solver units: radians for angles)
    are fixed offsets, the coefficients ``c0..c4`` are the design variable ``NAME.coef``
    (group ``coef``). One constraint row, ``NAME:coupling``.
    """

    name: str
    joint_a: str
    joint_b: str
    q_a0: float = 0.0
    q_b0: float = 0.0


@dataclass(frozen=True)
class Mechanism:
    """Bodies and joints. Validated on construction; every problem is reported at once."""

    bodies: tuple[Body, ...]
    joints: tuple[Joint, ...]
    name: str = "mechanism"
    #: driven joints (input coordinates): held unless named in a free set; ``JOINT`` (all its
    #: coordinates) or ``JOINT.q[k]``
    inputs: tuple[str, ...] = ()
    #: couplings between joint coordinates (one constraint row each)
    couplings: tuple[Coupling, ...] = ()
    #: what an edit of a global hardpoint keeps (:mod:`kinprop.propagation.hardpoints`):
    #: ``"mechanism"`` (the paper's: every length and body-frame vector not edited, so the
    #: mechanism moves) or ``"design"`` (hardpoint tools': the design position, so every other
    #: hardpoint stays and the lengths of the links ending at the edited point are re-derived)
    edits: str = "mechanism"

    _bodies: dict[str, Body] = field(init=False, repr=False, compare=False, hash=False)
    _joints: dict[str, Joint] = field(init=False, repr=False, compare=False, hash=False)

    def __post_init__(self) -> None:
        problems = validate_structure(self.bodies, self.joints, self.inputs)
        problems += validate_couplings(self.joints, self.couplings)
        if self.edits not in EDITS:
            problems.append(Problem("edits", f"expected one of {', '.join(EDITS)}, found {self.edits!r}"))
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

    @property
    def coupled_joints(self) -> frozenset[str]:
        """Joints named by a coupling: they must be tree joints (their ``q`` is a coordinate)."""
        return frozenset(n for c in self.couplings for n in (c.joint_a, c.joint_b))


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


def validate_couplings(joints: tuple[Joint, ...], couplings: tuple[Coupling, ...]) -> list[Problem]:
    """Each coupling names two different joints that can be tree joints with one coordinate
    (revolute, translational); its name is new among joints and couplings (addresses)."""
    problems: list[Problem] = []
    by_name = {j.name: j for j in joints}
    seen: set[str] = set()
    for c in couplings:
        loc = f"couplings.{c.name}"
        if c.name in by_name or c.name in seen:
            problems.append(Problem(loc, f"duplicate name {c.name!r} (joints and couplings share one address space)"))
        seen.add(c.name)
        if c.joint_a == c.joint_b:
            problems.append(Problem(f"{loc}.joints", f"couples joint {c.joint_a!r} to itself"))
        if not (np.isfinite(c.q_a0) and np.isfinite(c.q_b0)):
            problems.append(Problem(f"{loc}.q0", f"expected finite offsets, found {[c.q_a0, c.q_b0]}"))
        for k, name in enumerate((c.joint_a, c.joint_b)):
            j = by_name.get(name)
            where = f"{loc}.joints[{k}]"
            if j is None:
                problems.append(Problem(where, f"unknown joint {name!r}; joints are {sorted(by_name)}"))
                continue
            try:
                jt = joint_type(j.type)
            except KeyError:
                continue  # reported with the joint
            if not jt.tree:
                problems.append(Problem(where, f"a {jt.name} joint cannot be a tree joint, so it has no coordinate "
                                               "to couple"))  # fmt: skip
            elif jt.n_coordinates != 1:
                problems.append(Problem(where, f"a {jt.name} joint has {jt.n_coordinates} coordinates; a coupling "
                                               "takes single-coordinate joints (revolute, translational)"))  # fmt: skip
            elif j.cut is True:
                problems.append(Problem(where, f"joint {name!r} is marked 'cut: true'; a coupled joint must be a "
                                               "tree joint"))  # fmt: skip
    return problems
