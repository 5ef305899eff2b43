"""The state every output is evaluated from: a model with its forward kinematics."""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from kinprop.engine import Engine, Kinematics, State
from kinprop.engine import compile as compile_engine
from kinprop.errors import AddressError
from kinprop.model import Model
from kinprop.spatial import Array

POINT = re.compile(r"^point:(?P<body>[^.\s\[\]]+)\.(?P<name>[^\s\[\]]+?)(\[(?P<c>[xyz012])\])?$")
HARD = re.compile(r"^hardpoint:(?P<joint>[^\s\[\]]+)\.(?P<side>[^\s.\[\]]+)(\[(?P<c>[xyz012])\])?$")
#: a body's pose, ``body:NAME`` (every component) or ``body:NAME[x|y|z|roll|pitch|yaw]``
BODY = re.compile(r"^body:(?P<body>[^\s\[\]]+?)(\[(?P<c>[^\]]*)\])?$")
#: the components of a body pose: the body frame's origin (global, length unit), then its
#: orientation as ISO 8855 Tait-Bryan angles, z-y'-x'' (yaw, pitch, roll): ``A = Rz(yaw) Ry(pitch) Rx(roll)``
POSE = ("x", "y", "z", "roll", "pitch", "yaw")
POSE_ANGLES = ("roll", "pitch", "yaw")


@dataclass(frozen=True)
class WheelSpec:
    """Per-call metric parameters of one wheel: the steering axis as two point specs
    (``hardpoint:JOINT.i|j`` or ``point:BODY.NAME``), upper first
    (:mod:`kinprop.analysis.metrics`)."""

    steering_axis: tuple[str, str] | None = None
    #: the coordinate driven in bump for the first-order metrics (default: the first declared input)
    travel_input: str | None = None


@dataclass
class OutputContext:
    """A model with its forward kinematics, shared by every output evaluated at one state."""

    model: Model
    kin: Kinematics
    reference: Model | None = None
    wheels: Mapping[str, WheelSpec] | None = None
    #: the engine the kinematics came from and its packed state (reused for the reference
    #: configuration and the velocity analysis of first-order metrics)
    engine: Engine | None = None
    state: State | None = None

    @classmethod
    def of(
        cls,
        model: Model,
        reference: Model | None = None,
        wheels: Mapping[str, WheelSpec] | None = None,
        engine: Engine | None = None,
    ) -> OutputContext:
        """Forward kinematics of ``model`` at its current state (``engine``: compiled from its
        mechanism; None only at a public boundary, which then compiles once)."""
        eng = engine if engine is not None else compile_engine(model.mechanism)
        st = eng.state_of(model)
        return cls(model, eng.kinematics(st), reference, wheels, eng, st)

    def body_point(self, body: str, point: str) -> Array:
        """Global position of the named point ``point`` of ``body``."""
        source = locate_point(self.model, body, point)
        if source[0] == "joint":  # a joint's point: it follows the joint (kinprop.model.joint_points)
            return self.hardpoint(source[1], source[2])
        return self.kin.r[body] + self.kin.A[body] @ source[2]

    def body_pose(self, body: str) -> Array:
        """``[x, y, z, roll, pitch, yaw]`` of ``body``: its frame's global origin and the
        Tait-Bryan angles (radians) of its rotation matrix ``A = Rz(yaw) Ry(pitch) Rx(roll)``
        (the ISO 8855 yaw-pitch-roll sequence, intrinsic z-y'-x''; pitch in [-90, 90] deg, the
        others in [-180, 180])."""
        from scipy.spatial.transform import Rotation

        mech = self.model.mechanism
        if body not in mech.body_names:
            raise AddressError(f"unknown body {body!r}; bodies are {', '.join(mech.body_names)}")
        yaw, pitch, roll = Rotation.from_matrix(self.kin.A[body]).as_euler("ZYX")
        return np.concatenate([np.asarray(self.kin.r[body], dtype=float), [roll, pitch, yaw]])

    def hardpoint(self, joint: str, side: str) -> Array:
        """Global origin of ``joint``'s frame on its first (``i``) or second (``j``) body."""
        mech = self.model.mechanism
        if joint not in mech.joint_names:
            raise AddressError(f"unknown joint {joint!r}; joints are {', '.join(mech.joint_names)}")
        if side not in ("i", "j"):  # a pivot: the fixed body's point JOINT.NAME
            return self.body_point(*pivot_point(self.model, joint, side))
        f = self.kin.frames[joint]
        return f.P_i if side == "i" else f.P_j

    def point_source(self, body: str, point: str) -> tuple[str, str] | None:
        """The joint frame ``(joint, side)`` a named point is (it moves with that joint's
        ``s'``), or None for a plain body-fixed point."""
        return self.model.mechanism.body(body).joint_point(point)

    def hardpoint_source(self, joint: str, side: str) -> tuple[str, str] | None:
        """The joint frame ``hardpoint:JOINT.SIDE`` is (a pivot: its named point's, see
        :meth:`point_source`)."""
        return (joint, side) if side in ("i", "j") else self.point_source(*pivot_point(self.model, joint, side))

    def spec_source(self, spec: str) -> tuple[str, str] | None:
        """:meth:`point_source` of a ``point:BODY.NAME`` or ``hardpoint:JOINT.i|j`` spec."""
        m = POINT.match(spec)
        if m and m.group("c") is None:
            return self.point_source(m.group("body"), m.group("name"))
        m = HARD.match(spec)
        if m and m.group("c") is None:
            return self.hardpoint_source(m.group("joint"), m.group("side"))
        return None

    def point(self, spec: str) -> Array:
        """A global point from a ``point:BODY.NAME`` or ``hardpoint:JOINT.i|j`` spec."""
        m = POINT.match(spec)
        if m and m.group("c") is None:
            return self.body_point(m.group("body"), m.group("name"))
        m = HARD.match(spec)
        if m and m.group("c") is None:
            return self.hardpoint(m.group("joint"), m.group("side"))
        raise AddressError(f"{spec!r} is not a point: expected point:BODY.NAME or hardpoint:JOINT.i|j")


def locate_point(model: Model, body: str, point: str) -> tuple[str, str, Array] | tuple[str, str, str]:
    """Where the named point ``point`` of ``body`` comes from: ``("joint", JOINT, side)`` for a
    joint's point (:mod:`kinprop.model.joint_points`), else ``("body", body, p')`` (body frame).
    Raises :class:`AddressError` for an unknown body or point."""
    mech = model.mechanism
    if body not in mech.body_names:
        raise AddressError(f"unknown body {body!r}; bodies are {', '.join(mech.body_names)}")
    b = mech.body(body)
    pts = dict(b.points)
    if point not in pts:
        known = ", ".join(pts) or "none"
        raise AddressError(f"body {body!r} has no named point {point!r}; its points: {known}")
    ref = b.joint_point(point)
    if ref is not None:
        return "joint", ref[0], ref[1]
    return "body", body, np.asarray(pts[point], dtype=float)


def find_point(model: Model, wheel: str, name: str, on_wheel: bool = True) -> tuple[str, str] | None:
    """(body, point name) of a wheel point by the lookup rule of :mod:`kinprop.analysis.metrics`:
    on the wheel body (``on_wheel``), else on a fixed body as ``WHEEL.NAME``, then as ``NAME``."""
    mech = model.mechanism
    if on_wheel and name in dict(mech.body(wheel).points):
        return wheel, name
    for key in (f"{wheel}.{name}", name):
        for b in mech.bodies:
            if b.fixed and key in dict(b.points):
                return b.name, key
    return None


def pivot_point(model: Model, joint: str, name: str) -> tuple[str, str]:
    """``(fixed body, point name)`` of the pivot ``name`` of ``joint`` (``hardpoint:UCA.front``)."""
    j = model.mechanism.joint(joint)
    for body in (j.body_i, j.body_j):
        b = model.mechanism.body(body)
        if b.fixed and f"{joint}.{name}" in dict(b.points):
            return body, f"{joint}.{name}"
    raise AddressError(
        f"hardpoint:{joint}.{name}: expected {joint}.i, {joint}.j or a pivot of {joint} (none is named {name!r})"
    )
