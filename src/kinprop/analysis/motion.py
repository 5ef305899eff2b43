"""Velocities, accelerations and instantaneous screw axes of an assembled model, in the
model's units: ``kp.motion(model, rates, accelerations=None)``.

The engine does the work (:mod:`kinprop.engine.motion`: ``Phi_q qdot = 0`` and ``Phi_q
qddot = gamma`` with the driven rows); this module is the by-name view. Rates are per unit
time (whatever the time unit: the results are per the same unit), angles in the model's
angle unit (``deg/s`` in a degree model), lengths in its length unit.

Screw axis (Ball; Hunt, *Kinematic Geometry of Mechanisms*, 1978): the relative twist of a
body B with respect to a body R, ``[v_O ; w] = V_B - V_R`` at the global origin; when
``w != 0`` the axis is the line through ``w x v_O / |w|^2`` along ``u = w / |w|`` and the pitch
is ``h = w . v_O / |w|^2`` (translation along the axis per unit rotation about it); when
``w = 0`` the motion is a translation (``pitch = inf``, the axis at infinity, ``u`` the
direction of the velocity). A planar instant centre is the axis' intersection with the plane
of motion (:meth:`Motion.instant_centre`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np

from kinprop.analysis.context import HARD, POINT, OutputContext
from kinprop.engine import Engine
from kinprop.engine import compile as compile_engine
from kinprop.engine.motion import MotionState
from kinprop.engine.status import Status, message
from kinprop.engine.units import from_solver_units, radians_per_angle, to_solver_units
from kinprop.errors import AddressError
from kinprop.model import Model
from kinprop.spatial import Array

AXES = {"x": 0, "y": 1, "z": 2, "0": 0, "1": 1, "2": 2}
#: scaled residual norm above which a state is not an assembly (its rates would mean nothing)
ASSEMBLED_TOL = 1e-6
#: a relative angular velocity below this fraction of |v| / L is a pure translation
TRANSLATION_RTOL = 1e-12


@dataclass(frozen=True)
class Twist:
    """A body's angular velocity (model angle unit per time) and the velocity of its frame
    origin (length unit per time), global axes."""

    angular: Array
    linear: Array


@dataclass(frozen=True)
class ScrewAxis:
    """Instantaneous screw axis of one body relative to another (module docstring): a point
    on it (the one nearest the body's frame origin; None for a translation), its unit
    direction, the pitch (length unit per model angle unit; ``inf`` for a translation) and
    the rates of rotation about and translation along it."""

    point: Array | None
    direction: Array
    pitch: float
    angular_rate: float
    translation_rate: float

    @property
    def is_translation(self) -> bool:
        return self.point is None


def point_of(ctx: OutputContext, engine: Engine, spec: str) -> tuple[int, Array]:
    """``(body index, global position)`` of ``point:BODY.NAME`` or ``hardpoint:JOINT.i|j``."""
    m = POINT.match(spec)
    if m and m.group("c") is None:
        body = m.group("body")
        return engine.body_index[body], ctx.body_point(body, m.group("name"))
    m = HARD.match(spec)
    if m and m.group("c") is None:
        j = ctx.model.mechanism.joint(m.group("joint")) if m.group("joint") in ctx.model.mechanism.joint_names else None
        pos = ctx.hardpoint(m.group("joint"), m.group("side"))
        assert j is not None  # ctx.hardpoint raised otherwise
        return engine.body_index[j.body_i if m.group("side") == "i" else j.body_j], pos
    raise AddressError(f"{spec!r} is not a point: expected point:BODY.NAME or hardpoint:JOINT.i|j")


def screw_of(V: Array, origin: Array, angle_scale: float = 1.0) -> ScrewAxis:
    """The screw axis of a relative twist ``V = [v_O ; w]`` (point nearest ``origin``)."""
    v, w = V[:3], V[3:]
    nw, nv = float(np.linalg.norm(w)), float(np.linalg.norm(v + np.cross(w, origin)))
    scale = max(1.0, float(np.linalg.norm(origin)))
    if nw * scale <= TRANSLATION_RTOL * nv or nw == 0.0:
        u = (v / nv) if nv > 0 else np.zeros(3)
        return ScrewAxis(None, u, math.inf, 0.0, nv)
    u = w / nw
    h = float(w @ v) / nw**2
    p0 = np.cross(w, v) / nw**2  # nearest the global origin
    p = p0 + float((origin - p0) @ u) * u
    return ScrewAxis(p, u, h / angle_scale, nw * angle_scale, h * nw)


@dataclass(frozen=True)
class Motion:
    """Velocities (and accelerations) of one assembled state, by name, in the model's units."""

    model: Model
    engine: Engine
    state: MotionState
    #: coordinate rates by joint (model units per time), like ``model.coordinates``
    rates: Mapping[str, Array]
    accelerations: Mapping[str, Array] | None

    @property
    def status(self) -> Status:
        """:class:`kinprop.Status`: ``ok``, ``singular`` or ``not_assembled`` (docs/results.md)."""
        return self.state.status

    @property
    def residual(self) -> float:
        """``||Phi||`` of the pose, scaled as the solver's test (:attr:`kinprop.Solution.residual`)."""
        return self.state.residual

    @property
    def message(self) -> str:
        return self.state.message

    @property
    def ok(self) -> bool:
        return self.state.ok

    def _angle(self) -> float:
        """Model angle units per radian."""
        return 1.0 / radians_per_angle(self.model)

    def rate(self, address: str) -> Array | float:
        """Rate of a coordinate address (``J.q``, ``J.q[k]``), model units per time."""
        return self._by_address(address, self.state.qdot)

    def output_rate(self, name: str) -> float:
        """Rate of a scalar output: a coordinate (``J.q``, ``J.q[k]``), a point component
        (``point:B.N[z]``, ``hardpoint:J.i[x]``) or a distance (``distance:A,B``), model units
        per time. With one driven coordinate at unit rate this is the exact velocity ratio
        d(output)/d(input)."""
        m = POINT.match(name) or HARD.match(name)
        if m and m.group("c") is not None:
            spec = name[: name.index("[")]
            return float(self.point_velocity(spec)[AXES[m.group("c")]])
        if name.startswith("distance:"):
            a, b = (x if x.startswith(("point:", "hardpoint:")) else f"point:{x}" for x in name[9:].split(","))
            ctx = self._ctx()
            (ba, xa), (bb, xb) = point_of(ctx, self.engine, a), point_of(ctx, self.engine, b)
            d = xb - xa
            return float(d @ (self.state.point_velocity(bb, xb) - self.state.point_velocity(ba, xa))) / float(
                np.linalg.norm(d)
            )
        value = self.rate(name)
        if not isinstance(value, float):
            raise AddressError(f"{name!r} has {np.size(value)} components: name one ({name}[k])")
        return value

    def ratio(self, output: str, driven: str) -> float:
        """Exact velocity ratio ``d(output)/d(driven)`` along this motion: the output's rate over
        the driven coordinate's (model units)."""
        d = self.rate(driven if "." in driven else f"{driven}.q")
        return self.output_rate(output) / float(d)  # type: ignore[arg-type]

    def acceleration(self, address: str) -> Array | float:
        if self.state.qddot is None:
            raise ValueError("no accelerations: call kp.motion with accelerations=")
        return self._by_address(address, self.state.qddot)

    def _by_address(self, address: str, x: Array) -> Array | float:
        t = self.engine.target(address)
        if t.group != "q":
            raise AddressError(f"{address!r}: rates are of coordinates (JOINT.q, JOINT.q[k])")
        v = x[t.start : t.start + t.size]
        out = from_solver_units(self.model, f"{address.split('[')[0]}", v, self.engine)
        return float(out[t.index]) if t.index is not None else (float(out[0]) if t.size == 1 else out)

    def body_twist(self, body: str) -> Twist:
        """Angular velocity and the velocity of the frame origin of ``body``."""
        b = self._body(body)
        w = self.state.V[b, 3:]
        return Twist(w * self._angle(), self.state.point_velocity(b, self.state.r[b]))

    def body_acceleration(self, body: str) -> Twist:
        """Angular acceleration and the acceleration of the frame origin of ``body``."""
        b = self._body(body)
        if self.state.dV is None:
            raise ValueError("no accelerations: call kp.motion with accelerations=")
        return Twist(self.state.dV[b, 3:] * self._angle(), self.state.point_acceleration(b, self.state.r[b]))

    def _body(self, body: str) -> int:
        if body not in self.engine.body_index:
            raise AddressError(f"unknown body {body!r}; bodies are {', '.join(self.engine.body_index)}")
        return self.engine.body_index[body]

    def _ctx(self) -> OutputContext:
        return OutputContext.of(self.model, engine=self.engine)

    def point_velocity(self, spec: str) -> Array:
        """Velocity of a point (``point:BODY.NAME``, ``hardpoint:JOINT.i|j``) of its body."""
        b, x = point_of(self._ctx(), self.engine, spec)
        return self.state.point_velocity(b, x)

    def point_acceleration(self, spec: str) -> Array:
        b, x = point_of(self._ctx(), self.engine, spec)
        return self.state.point_acceleration(b, x)

    def screw_axis(self, body: str, relative_to: str | None = None) -> ScrewAxis:
        """Instantaneous screw axis of ``body`` relative to ``relative_to`` (default: the
        fixed frame)."""
        b = self._body(body)
        V = self.state.V[b] - (self.state.V[self._body(relative_to)] if relative_to else 0.0)
        return screw_of(V, self.state.r[b], self._angle())

    def instant_centre(
        self, body: str, relative_to: str | None = None, normal: Any = (0.0, 0.0, 1.0), through: Any = (0.0, 0.0, 0.0)
    ) -> Array | None:
        """Planar instant centre: the screw axis' intersection with the plane through
        ``through`` with ``normal`` (None when the axis is parallel to it, e.g. a translation:
        the centre is at infinity)."""
        s = self.screw_axis(body, relative_to)
        n, x0 = np.asarray(normal, dtype=float), np.asarray(through, dtype=float)
        if s.point is None or abs(float(n @ s.direction)) < 1e-12 * float(np.linalg.norm(n)):
            return None
        lam = float(n @ (x0 - s.point)) / float(n @ s.direction)
        return s.point + lam * s.direction


def motion(
    model: Model,
    rates: Mapping[str, Any],
    accelerations: Mapping[str, Any] | None = None,
    *,
    engine: Engine | None = None,
) -> Motion:
    """Velocities (and accelerations) of the assembled ``model`` driven by ``rates`` of
    coordinates (``{"O2.q": 10.0}``: 10 deg per unit time in a degree model); ``accelerations``
    of the same coordinates (missing ones 0). The status is ``singular`` (NaN rates) when the
    rates do not determine the motion or violate the constraints."""
    eng = engine or compile_engine(model)
    st = eng.state_of(model)

    def solver(values: Mapping[str, Any]) -> dict[str, Array]:
        out = {}
        for a, v in values.items():
            a = a if "." in a else f"{a}.q"  # a joint's name, as in ``inputs:``
            out[a] = to_solver_units(model, a, v, eng)
        return out

    solver_rates = solver(rates)
    solver_acc = None if accelerations is None else solver(accelerations)
    ms = eng.motion(st, solver_rates, solver_acc)
    if ms.residual > ASSEMBLED_TOL:
        msg = message(Status.NOT_ASSEMBLED, residual=ms.residual)
        nan = {f.name: np.full_like(getattr(ms, f.name), np.nan) for f in fields(ms)
               if f.name in ("qdot", "V", "qddot", "dV") and getattr(ms, f.name) is not None}  # fmt: skip
        ms = replace(ms, status=Status.NOT_ASSEMBLED, message=msg, **nan)

    def by_joint(x: Array | None) -> dict[str, Array] | None:
        if x is None:
            return None
        out = {}
        for v in eng.layout.group("q"):
            out[v.joint] = from_solver_units(model, f"{v.joint}.q", x[v.start : v.start + v.size], eng)
        return out

    return Motion(model, eng, ms, by_joint(ms.qdot) or {}, by_joint(ms.qddot))


__all__ = ["Motion", "ScrewAxis", "Twist", "motion", "point_of", "screw_of"]
