"""A suspension's first-order geometry: gains with wheel travel, front- and side-view instant
centres and swing arms, roll-centre height, anti-dive / anti-lift / anti-squat, half-track
and contact-patch changes, motion ratios and the wheel rate (docs/analysis/suspension.md has
every definition with its reference and sign).

Everything comes from one velocity analysis of the assembled state
(:mod:`kinprop.engine.motion`): the wheel's motion in bump is the one-degree-of-freedom
motion with the travel input driven (the first declared input, or the mechanism's only
degree of freedom when it declares none) and every other declared input held (a rack, a
steering input; a translational-distance joint's own rack coordinate too). "Wheel travel"
``z`` is the wheel centre's vertical displacement; a gain is
``(d quantity / dt) / (dz / dt)`` along that motion: exact, no differencing.

Instant centres use the wheel body's instantaneous screw axis relative to the fixed body,
written homogeneously so that an axis parallel to a view plane (an instant centre at
infinity) gives finite line directions: with the axis ``{p + l u}``, a plane through E with
unit normal n, ``H = (n.u) p + n.(E - p) u`` and weight ``s = n.u`` the intersection is
``H / s``, and the line from a point F towards it has direction ``w = H - s F`` (for ``s = 0``
the axis' own direction). Centres at infinity are reported as NaN coordinates and an infinite
swing-arm length; roll-centre height and the anti percentages stay finite (the lines
through them are parallel to the axis).

Design derivatives (:func:`first_order_derivatives`) are exact too: the velocity state's
derivatives along a state direction come from :func:`kinprop.engine.motion.motion_derivatives`
(analytic second-order terms), the points move with their bodies (and with their own ``s'``
when they are joint frames), and the formulas below, analytic in all of these, are
differentiated in forward mode by a complex step (dual numbers; no subtractive difference).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from kinprop.analysis.context import OutputContext
from kinprop.analysis.motion import point_of
from kinprop.engine import Engine, State
from kinprop.engine.motion import MotionState, cross3, motion_derivatives
from kinprop.errors import AddressError
from kinprop.kinematics.tables import J_NQ, J_QCOL, K_JOINT
from kinprop.model import Model
from kinprop.spatial import Array

#: |n.u| below this: the screw axis is parallel to the view plane (the centre at infinity)
PARALLEL_TOL = 1e-12
#: relative |w| below which the wheel's relative motion is a pure translation
TRANSLATION_RTOL = 1e-12

GAIN_METRICS = ("camber_gain", "bump_steer", "caster_gain")
CENTRE_METRICS = ("fvic_y", "fvic_z", "fvsa_length", "svic_x", "svic_z", "svsa_length", "roll_centre_height")
ANTI_METRICS = ("anti_dive", "anti_lift", "anti_squat")
GROUND_METRICS = ("half_track_change", "contact_patch_dx", "half_track_gain", "contact_patch_dx_gain")
#: motion ratios are ``motion_ratio:ELEMENT``
MOTION_RATIO = "motion_ratio"
FIRST_ORDER = GAIN_METRICS + CENTRE_METRICS + ANTI_METRICS + GROUND_METRICS + ("wheel_rate",)


def travel_rates(engine: Engine, model: Model, travel_input: str | None, state: State) -> dict[str, float]:
    """The driven rates of the bump motion (module docstring): the travel input at unit rate,
    every other declared input held, and a cut joint's own coordinate (a translational-distance
    joint's rack, which ``inputs:`` cannot name) held when the motion would otherwise have
    more than one degree of freedom."""
    inputs = [a if "." in a else f"{a}.q" for a in model.mechanism.inputs]
    nq = engine.n_coordinates
    tb = engine.tables
    cut = tb.cut[:, K_JOINT]
    racks = tb.joint[cut[tb.joint[cut, J_NQ] > 0], J_QCOL].tolist()

    def null(cols: list[int]) -> Array:
        J = engine.evaluate(state)[1][:, :nq] * engine.row_scale[:, None] / engine.col_scale[None, :nq]
        E = np.zeros((len(cols), nq))
        E[np.arange(len(cols)), cols] = 1.0
        M = np.vstack([J, E])
        _, s, Vt = np.linalg.svd(M)
        return Vt[int(np.sum(s > 1e-10 * s[0])) :]

    if travel_input is not None or inputs:
        drive = (travel_input if "." in travel_input else f"{travel_input}.q") if travel_input else inputs[0]
        held = [a for a in inputs if a != drive]
        if racks:
            driven = [int(c) for c in engine.columns([drive, *held])]
            if null(driven).shape[0] > 0:  # underdetermined: hold the racks too
                held += [engine.column_labels[c] for c in racks if c not in driven]
    else:  # the mechanism's only degree of freedom (racks held): drive its largest coordinate
        free = null(racks)
        if free.shape[0] != 1:
            raise AddressError(
                f"the wheel's motion has {free.shape[0]} degrees of freedom: declare the travel input "
                "first in 'inputs:' (and the others, e.g. a rack, after it)"
            )
        col = int(np.argmax(np.abs(free[0])))
        drive, held = engine.column_labels[col], [engine.column_labels[c] for c in racks]
    return {drive: 1.0} | {a: 0.0 for a in held}


def travel_motion(
    engine: Engine, model: Model, travel_input: str | None = None, state: State | None = None
) -> MotionState:
    """The velocity state of the bump motion (module docstring) at the model's state (``state``:
    already packed)."""
    st = state if state is not None else engine.state_of(model)
    return engine.motion(st, travel_rates(engine, model, travel_input, st))


#: complex step of the exact derivatives (:func:`first_order_derivatives`): the metric
#: formulas are analytic in their inputs, so ``Im f(x + i h dx) / h`` is ``f'(x) dx`` with a
#: truncation error of order h^2 (1e-60 relative), far below round-off: forward-mode dual numbers
COMPLEX_STEP = 1e-30


class _Vec:
    """A 3-vector of Python scalars, real or complex (the metric formulas' arithmetic: ten times
    cheaper than numpy's on single vectors, and analytic, for the complex step)."""

    __slots__ = ("x", "y", "z")

    def __init__(self, x: Any, y: Any, z: Any) -> None:
        self.x, self.y, self.z = x, y, z

    @classmethod
    def of(cls, a: Array) -> _Vec:
        return cls(*a.tolist())

    def __getitem__(self, i: int) -> Any:
        return self.x if i == 0 else self.y if i == 1 else self.z

    def __add__(self, o: _Vec) -> _Vec:
        return _Vec(self.x + o.x, self.y + o.y, self.z + o.z)

    def __sub__(self, o: _Vec) -> _Vec:
        return _Vec(self.x - o.x, self.y - o.y, self.z - o.z)

    def __mul__(self, k: Any) -> _Vec:
        return _Vec(self.x * k, self.y * k, self.z * k)

    __rmul__ = __mul__

    def __truediv__(self, k: Any) -> _Vec:
        return _Vec(self.x / k, self.y / k, self.z / k)

    def __matmul__(self, o: _Vec) -> Any:
        return self.x * o.x + self.y * o.y + self.z * o.z

    def cross(self, o: _Vec) -> _Vec:
        return _Vec(self.y * o.z - self.z * o.y, self.z * o.x - self.x * o.z, self.x * o.y - self.y * o.x)

    def norm(self) -> Any:
        return (self.x * self.x + self.y * self.y + self.z * self.z) ** 0.5


def _abs(x: Any) -> Any:
    return -x if x.real < 0 else x


_EX, _EY, _EZ = _Vec(1.0, 0.0, 0.0), _Vec(0.0, 1.0, 0.0), _Vec(0.0, 0.0, 1.0)


def _contact(centre: _Vec, axis: _Vec, radius: float, v_centre: _Vec, da: _Vec) -> tuple[_Vec, _Vec]:
    """The contact point (lowest point of the wheel circle) and its rate."""
    g = axis * axis.z - _EZ
    ng = g.norm()
    n = g / ng
    dg = axis * da.z + da * axis.z
    dn = (dg - n * (n @ dg)) / ng
    return centre + n * radius, v_centre + dn * radius


def _homogeneous(p: _Vec | None, u: _Vec, v: _Vec, normal: _Vec, E: _Vec) -> tuple[_Vec, Any]:
    """``(H, s)`` of the axis' intersection with the plane through E (module docstring); a
    pure translation (``p`` None) of velocity ``v``: the centre at infinity across ``v``."""
    if p is None:
        return normal.cross(v), 0.0
    s = normal @ u
    return p * s + u * (normal @ (E - p)), s


def _centre(H: _Vec, s: Any, E: _Vec, plane: tuple[int, int]) -> tuple[Any, Any, Any]:
    """In-plane coordinates of the centre and its distance from E (NaN, NaN, inf at infinity)."""
    if abs(s) < PARALLEL_TOL:
        return math.nan, math.nan, math.inf
    X = H / s
    d = X - E
    return X[plane[0]], X[plane[1]], (d[plane[0]] ** 2 + d[plane[1]] ** 2) ** 0.5


def _slope(w: _Vec, forward: float) -> Any:
    """``tan(theta)`` of a side-view line of direction ``w`` rising towards ``forward * x``
    (+1: the centre ahead, -1: behind); sign-free in ``w``; +-inf for a vertical line."""
    wx, wz = w.x, w.z
    if wx == 0.0:
        return math.copysign(math.inf, wz.real * forward) if wz != 0.0 else math.nan
    return (wz / wx) * forward


@dataclass(frozen=True)
class _Inputs:
    """What the metrics are computed from (real, or complex along one direction): the wheel's
    body index, the named points ``(body, position)``, every body's twist, pose and the
    reference contact point."""

    wheel: int
    points: dict[str, tuple[int, Array]]
    V: Array
    r: Array
    A: Array
    reference_contact: Array | None
    #: per element: name, body indices, body-frame end points
    elements: tuple[tuple[str, int, int, Array, Array], ...]


def _metrics(model: Model, inp: _Inputs, radius: float | None) -> dict[str, Any]:
    """The metric formulas (module docstring), analytic in every input (complex-step safe)."""
    out: dict[str, Any] = {}
    b, Vall = inp.wheel, inp.V
    points = {k: (body, _Vec.of(x)) for k, (body, x) in inp.points.items()}
    twist: dict[int, tuple[_Vec, _Vec]] = {}

    def vel(body: int, x: _Vec) -> _Vec:
        if body not in twist:
            twist[body] = (_Vec.of(Vall[body, :3]), _Vec.of(Vall[body, 3:]))
        v, w = twist[body]
        return v + w.cross(x)

    centre = points["centre"][1]
    axis = points["spin"][1] - centre
    axis = axis / axis.norm()
    side = 1 if axis.y.real >= 0 else -1
    vc = vel(b, centre)
    w = twist[b][1]
    dz = vc.z
    per = (lambda x: x / dz) if dz != 0.0 else (lambda x: math.nan)
    deg = 180.0 / math.pi
    da = w.cross(axis)
    out["camber_gain"] = per(deg * (-da.z / (1.0 - axis.z**2) ** 0.5))
    ay = axis.y * side
    out["bump_steer"] = per(deg * ((ay * da.x - axis.x * side * da.y) / (axis.x**2 + axis.y**2)))
    if "upper" in points:
        (bu, xu), (bl, xl) = points["upper"], points["lower"]
        k = xu - xl
        dk = vel(bu, xu) - vel(bl, xl)
        out["caster_gain"] = per(deg * ((-dk.x * k.z + k.x * dk.z) / (k.x**2 + k.z**2)))
    for n, bi, bj, s_i, s_j in inp.elements:
        pi = _Vec.of(inp.r[bi] + inp.A[bi] @ s_i)
        pj = _Vec.of(inp.r[bj] + inp.A[bj] @ s_j)
        d = pj - pi
        dl = (d @ (vel(bj, pj) - vel(bi, pi))) / d.norm()
        out[f"{MOTION_RATIO}:{n}"] = _abs(per(dl))
    springs = [e for e in model.elements if e.has_spring]
    if springs:
        out["wheel_rate"] = sum(float(e.stiffness or 0.0) * out[f"{MOTION_RATIO}:{e.name}"] ** 2 for e in springs)
    if radius is None:
        return out
    E, vE = _contact(centre, axis, radius, vc, da)
    if inp.reference_contact is not None:
        ref = _Vec.of(np.asarray(inp.reference_contact))
        out["half_track_change"] = side * (E.y - ref.y)
        out["contact_patch_dx"] = E.x - ref.x
    out["half_track_gain"] = per(side * vE.y)
    out["contact_patch_dx_gain"] = per(vE.x)
    # screw axis of the wheel relative to the fixed body (the fixed body's twist is zero)
    v_O = twist[b][0]
    nw, nv = w.norm(), vc.norm()
    scale = max(1.0, abs(centre.norm()))
    p: _Vec | None
    if abs(nw) * scale <= TRANSLATION_RTOL * abs(nv) or nw == 0.0:
        p, u = None, _Vec(0.0, 0.0, 0.0)
    else:
        u = w / nw
        p = w.cross(v_O) / nw**2
    Hf, sf = _homogeneous(p, u, vE, _EX, E)  # front view: the plane x = x_E
    out["fvic_y"], out["fvic_z"], out["fvsa_length"] = _centre(Hf, sf, E, (1, 2))
    wf = Hf - E * sf
    out["roll_centre_height"] = -E.y * wf.z / wf.y if wf.y != 0.0 else math.nan
    Hs, ss = _homogeneous(p, u, vE, _EY, E)  # side view: the plane y = y_E
    out["svic_x"], out["svic_z"], out["svsa_length"] = _centre(Hs, ss, E, (0, 2))
    veh = model.vehicle
    if veh is not None:
        lever = veh.wheelbase / veh.cg_height * 100.0
        wE, wC = Hs - E * ss, Hs - centre * ss  # lines from the contact patch / the wheel centre
        front = veh.axle == "front"
        brake_line = wE if veh.brakes == "outboard" else wC
        drive_line = wE if veh.drive == "outboard" else wC
        toward = -1.0 if front else 1.0  # the centre behind a front wheel, ahead of a rear wheel
        if front:
            out["anti_dive"] = veh.brake_front * _slope(brake_line, toward) * lever
            out["anti_lift"] = veh.drive_front * _slope(drive_line, toward) * lever
        else:
            out["anti_lift"] = (1.0 - veh.brake_front) * _slope(brake_line, toward) * lever
            out["anti_squat"] = (1.0 - veh.drive_front) * _slope(drive_line, toward) * lever
    return out


#: a point of the analysis: ``(body index, global position)``, optionally with the joint frame
#: ``(joint, side)`` it is (its ``s'`` a design variable: the point moves with it)
PointRef = tuple[int, Array] | tuple[int, Array, tuple[str, str] | None]


def _inputs(
    model: Model, engine: Engine, wheel: str, points: dict[str, PointRef], ms: MotionState, ref: Array | None
) -> _Inputs:
    elements = tuple(
        (
            e.name,
            engine.body_index[e.body_i],
            engine.body_index[e.body_j],
            np.asarray(e.s_i, float),
            np.asarray(e.s_j, float),
        )
        for e in model.elements
    )
    pts = {k: (int(v[0]), v[1]) for k, v in points.items()}
    return _Inputs(engine.body_index[wheel], pts, ms.V, ms.r, ms.A, ref, elements)


def _reference(reference_contact: Array | PointRef | None) -> tuple[Array | None, PointRef | None]:
    """``(position, point)``: a reference given as a point of a body moves with it."""
    if reference_contact is None or not isinstance(reference_contact, tuple):
        return reference_contact, None
    return reference_contact[1], reference_contact


def first_order_metrics(
    ctx: OutputContext,
    engine: Engine,
    wheel: str,
    points: dict[str, PointRef],
    radius: float | None,
    reference_contact: Array | PointRef | None,
    travel_input: str | None = None,
) -> dict[str, float]:
    """Every first-order metric the wheel supports (module docstring). ``points``: ``centre``,
    ``spin``, optionally ``upper``/``lower`` (the steering axis); ``radius``: the loaded radius
    (None: no contact patch); ``reference_contact``: the contact point's reference, a position
    or a body's point (None: no half-track / contact-patch changes)."""
    model = ctx.model
    ms = travel_motion(engine, model, travel_input, ctx.state if ctx.engine is engine else None)
    ref, _ = _reference(reference_contact)
    if not ms.ok:
        names = first_order_names(model, radius is not None, "upper" in points, ref is not None)
        return dict.fromkeys(names, math.nan)
    return _metrics(model, _inputs(model, engine, wheel, points, ms, ref), radius)


def first_order_derivatives(
    ctx: OutputContext,
    engine: Engine,
    wheel: str,
    points: dict[str, PointRef],
    radius: float | None,
    reference_contact: Array | PointRef | None,
    directions: Array,
    travel_input: str | None = None,
) -> dict[str, Array]:
    """Exact derivatives of :func:`first_order_metrics` along each column ``dx`` of
    ``directions`` (``(n_columns, k)``, solver units; the state moves along ``retract(x, eps
    dx)``, the wheel's travel rate held): the velocity state's derivatives from
    :func:`kinprop.engine.motion.motion_derivatives` (analytic), the points' from the bodies'
    pose changes (and their own ``s'`` when they are joint frames), and the metric formulas
    differentiated in forward mode by a complex step (:data:`COMPLEX_STEP`). NaN where a
    metric is undefined or infinite."""
    model = ctx.model
    st = ctx.state if ctx.engine is engine and ctx.state is not None else engine.state_of(model)
    md = motion_derivatives(engine, st, travel_rates(engine, model, travel_input, st), directions)
    ms, X = md.motion, np.asarray(directions, dtype=float).reshape(engine.n_columns, -1)
    ref, ref_point = _reference(reference_contact)
    base = _metrics(model, _inputs(model, engine, wheel, points, ms, ref), radius) if ms.ok else {}
    names = list(base) or first_order_names(model, radius is not None, "upper" in points, ref is not None)
    out = {n: np.full(X.shape[1], np.nan) for n in names}
    if not ms.ok:
        return out
    h = COMPLEX_STEP

    def moved(p: PointRef, i: int) -> Array:
        body, x = int(p[0]), np.asarray(p[1], dtype=float)
        P = md.pose[i, body]
        dx = P[:3] + cross3(P[3:], x)
        source = p[2] if len(p) > 2 else None  # type: ignore[misc]
        if source is not None:
            key = f"{source[0]}.s_{source[1]}"
            if key in engine.layout:
                dx = dx + ms.A[body] @ X[engine.columns([key]), i]
        return x + 1j * h * dx

    for i in range(X.shape[1]):
        P = md.pose[i]
        pts = {k: (int(v[0]), moved(v, i)) for k, v in points.items()}
        r = ms.r + 1j * h * (P[:, :3] + np.cross(P[:, 3:], ms.r))
        A = ms.A + 1j * h * np.cross(P[:, 3:, None], ms.A, axis=1)
        rc = ref if ref_point is None else moved(ref_point, i)
        inp = _inputs(model, engine, wheel, pts, ms, rc)
        inp = _Inputs(inp.wheel, inp.points, ms.V + 1j * h * md.V[i], r, A, rc, inp.elements)
        values = _metrics(model, inp, radius)
        for n, v in values.items():
            if n in out:
                out[n][i] = np.imag(v) / h if np.isfinite(np.real(v)) else math.nan
    return out


def first_order_names(model: Model, contact: bool, steer: bool, reference: bool) -> list[str]:
    """First-order metrics a wheel supports: the gains always, caster gain with a steering axis,
    the ground and centre metrics with a contact patch (changes with a reference), the anti
    metrics of the vehicle's axle, the elements' motion ratios and the springs' wheel rate."""
    out = ["camber_gain", "bump_steer"] + (["caster_gain"] if steer else [])
    if contact:
        out += (["half_track_change", "contact_patch_dx"] if reference else []) + [
            "half_track_gain",
            "contact_patch_dx_gain",
        ]
        out += list(CENTRE_METRICS)
        if model.vehicle is not None:
            out += ["anti_dive", "anti_lift"] if model.vehicle.axle == "front" else ["anti_lift", "anti_squat"]
    out += [f"{MOTION_RATIO}:{e.name}" for e in model.elements]
    if any(e.has_spring for e in model.elements):
        out.append("wheel_rate")
    return out


def first_order_unit(metric: str, units: dict[str, str] | None = None) -> str:
    """Unit of a first-order metric in the model's units."""
    u = units or {}
    length, angle = u.get("length", "m"), u.get("angle", "rad")
    if metric in GAIN_METRICS:
        return f"{angle}/{length}"
    if metric in ANTI_METRICS:
        return "%"
    if metric == "wheel_rate":
        return f"{u.get('force', 'force')}/{length}"
    if metric in ("half_track_gain", "contact_patch_dx_gain") or metric.startswith(f"{MOTION_RATIO}:"):
        return ""
    return length


__all__ = [
    "COMPLEX_STEP",
    "FIRST_ORDER",
    "PointRef",
    "first_order_derivatives",
    "first_order_metrics",
    "first_order_names",
    "first_order_unit",
    "point_of",
    "travel_motion",
    "travel_rates",
]
