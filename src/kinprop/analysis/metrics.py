"""Suspension metrics of a wheel body (ISO 8855 / SAE J670 vehicle axes).

Axes: x forward, y left, z up (ISO 8855). Angles are returned in degrees, lengths in the
model's length unit. The sign conventions are the same for a left and a right wheel:

* ``camber``: angle between the wheel plane and the vertical, negative when the top of the
  wheel leans inboard: ``asin(-a_z)`` with ``a`` the unit spin axis pointing outboard;
* ``toe``: angle in the ground plane between the wheel heading and x, toe-in positive (the
  front of the wheel turned towards the centreline): ``atan2(a_x, |a_y|)``;
* ``caster``: steering axis from vertical in the side view, positive with its top rearward:
  ``atan2(-k_x, k_z)``, ``k`` the unit steering axis pointing up;
* ``kpi`` (kingpin inclination): steering axis from vertical in the front view, positive
  with its top inboard: ``atan2(-side k_y, k_z)``;
* ``scrub_radius``: in the ground plane (horizontal through the contact point), from the
  steering axis' ground point G to the contact point, along the wheel's horizontal outboard
  direction; positive when the contact point is outboard of G;
* ``trail`` (mechanical caster trail): G ahead of the contact point along the wheel heading;
* ``wheel_centre_dx|dy|dz``: wheel-centre displacement from the reference configuration
  (``dz`` is the wheel travel, jounce positive).

A left wheel is one whose outboard spin axis points to +y, a right wheel to -y.

How a model declares a wheel, without any schema change: named points (``points:`` of a
body, body frame) on the wheel body (the upright/knuckle carrying the wheel):

* ``wheel_centre``: the wheel centre;
* ``spin_axis``: a point one unit (any positive distance) along the spin axis, outboard;
* ``contact_patch`` (optional): the tyre contact point at the reference configuration; only
  its distance from the spin axis (the loaded radius) is used — the contact point is the
  lowest point of that wheel circle at every configuration;
* ``kingpin_upper``, ``kingpin_lower`` (optional): two points on the steering axis.

A wheel point NAME is looked up on the wheel body, then on a fixed body as ``WHEEL.NAME``,
then on a fixed body as ``NAME`` — so a McPherson top mount, fixed on the chassis, can be a
chassis point ``kingpin_upper``. The reference wheel centre is the point ``wheel_centre_ref``
on a fixed body (same lookup), or the wheel centre of an explicit ``reference`` model. The
steering axis can also be given per call as two point specs (``hardpoint:JOINT.i|j`` or
``point:BODY.NAME``) through :class:`WheelSpec`.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from kinprop.analysis.context import OutputContext, WheelSpec, find_point
from kinprop.analysis.firstorder import (
    FIRST_ORDER,
    GAIN_METRICS,
    MOTION_RATIO,
    FirstOrderProgram,
    first_order_names,
    first_order_program,
    first_order_unit,
)
from kinprop.analysis.program import ProgramBuilder
from kinprop.engine import Engine
from kinprop.engine import compile as compile_engine
from kinprop.engine import outputs as compiled
from kinprop.errors import AddressError
from kinprop.model import Model
from kinprop.model.joint_points import steering_joints
from kinprop.spatial import Array

ANGLE_METRICS = ("camber", "toe", "caster", "kpi")
LENGTH_METRICS = ("scrub_radius", "trail", "wheel_centre_dx", "wheel_centre_dy", "wheel_centre_dz")
METRICS = ANGLE_METRICS + LENGTH_METRICS + FIRST_ORDER
#: position-level metrics (:func:`wheel_metrics`); the others are first-order (velocity analysis)
POSITION_METRICS = ANGLE_METRICS + LENGTH_METRICS
#: accepted long names
METRIC_ALIASES = {"kingpin_inclination": "kpi", "scrub": "scrub_radius", "wheel_travel": "wheel_centre_dz"}


# --- closed-form geometry (vectors in vehicle axes) -----------------------------------------
def _vec(x: Array) -> Array:
    return np.ascontiguousarray(x, dtype=float)


def camber_toe(axis: Array) -> tuple[float, float]:
    """``(camber, toe)`` in degrees from the outboard spin axis (any length)."""
    a = _vec(axis)
    return compiled.camber_toe(a[0], a[1], a[2])


def steering_angles(upper: Array, lower: Array, side: int) -> tuple[float, float]:
    """``(caster, kpi)`` in degrees of the steering axis through ``lower`` and ``upper``."""
    k = _vec(upper) - _vec(lower)
    return compiled.steering_angles(k[0], k[1], k[2], float(side))


def contact_point(centre: Array, axis: Array, radius: float) -> Array:
    """Lowest point of the wheel circle (centre, outboard axis of any length, radius)."""
    out = np.empty(3)
    compiled.contact_point(_vec(centre), _vec(axis), float(radius), out)
    return out


def ground_offsets(upper: Array, lower: Array, contact: Array, axis: Array) -> tuple[float, float]:
    """``(scrub_radius, trail)``: the steering axis' ground point G relative to the contact
    point, in the horizontal plane through the contact point (``axis``: unit outboard)."""
    return compiled.ground_offsets(_vec(upper), _vec(lower), _vec(contact), _vec(axis))


# --- wheels of a model -------------------------------------------------------------------------
def wheel_bodies(model: Model) -> list[str]:
    """Bodies carrying both ``wheel_centre`` and ``spin_axis`` named points."""
    return [b.name for b in model.mechanism.bodies if {"wheel_centre", "spin_axis"} <= {n for n, _ in b.points}]


def available_metrics(
    model: Model, wheel: str, spec: WheelSpec | None = None, has_reference: bool = False
) -> list[str]:
    """Metrics a wheel body supports with the points the model declares."""
    out = ["camber", "toe"]
    steer = (
        (spec is not None and spec.steering_axis is not None)
        or all(find_point(model, wheel, n) for n in ("kingpin_upper", "kingpin_lower"))
        or steering_joints(model.mechanism, wheel) is not None
    )
    if steer:
        out += ["caster", "kpi"]
        if "contact_patch" in dict(model.mechanism.body(wheel).points):
            out += ["scrub_radius", "trail"]
    if has_reference or find_point(model, wheel, "wheel_centre_ref", on_wheel=False):
        out += ["wheel_centre_dx", "wheel_centre_dy", "wheel_centre_dz"]
    contact = "contact_patch" in dict(model.mechanism.body(wheel).points)
    ref = has_reference or find_point(model, wheel, "contact_patch_ref", on_wheel=False) is not None
    out += first_order_names(model, contact, steer, ref)
    return out


#: what a wheel needs for each metric beyond wheel_centre and spin_axis (for messages)
METRIC_NEEDS = {
    "caster": "a steering axis: named points kingpin_upper and kingpin_lower (or a WheelSpec steering_axis)",
    "kpi": "a steering axis: named points kingpin_upper and kingpin_lower (or a WheelSpec steering_axis)",
    "scrub_radius": "a steering axis (kingpin_upper, kingpin_lower) and a contact_patch point on the wheel",
    "trail": "a steering axis (kingpin_upper, kingpin_lower) and a contact_patch point on the wheel",
    **dict.fromkeys(
        ("wheel_centre_dx", "wheel_centre_dy", "wheel_centre_dz"),
        "a reference: a fixed-body point WHEEL.wheel_centre_ref (or wheel_centre_ref with one wheel)",
    ),
}


def metric_names(model: Model, first_order: bool = False) -> list[str]:
    """``metric:WHEEL.NAME`` for every wheel body and every position-level metric it supports
    (the default outputs of sweeps and studies); ``first_order``: the first-order ones too
    (a velocity analysis per state: asked for by name)."""
    return [f"metric:{w}.{m}" for w in wheel_bodies(model) for m in available_metrics(model, w)
            if first_order or not is_first_order(m)]  # fmt: skip


def resolve_metric(model: Model, name: str) -> tuple[str, str]:
    """``metric:WHEEL.NAME`` or a bare ``NAME`` (one wheel) -> ``(wheel, metric)``."""
    wheels = wheel_bodies(model)
    if name.startswith("metric:"):
        wheel, _, metric = name[len("metric:") :].partition(".")
        if wheel not in wheels:
            raise AddressError(
                f"output {name!r}: {wheel!r} is not a wheel body (a wheel body has named points "
                f"'wheel_centre' and 'spin_axis'); wheels: {', '.join(wheels) or 'none'}"
            )
    else:
        metric = name
        if len(wheels) != 1:
            raise AddressError(
                f"output {name!r}: not a variable (JOINT.field), point or metric; a bare metric name needs "
                f"exactly one wheel body, found {len(wheels)} — write metric:WHEEL.{name}"
            )
        wheel = wheels[0]
    metric = METRIC_ALIASES.get(metric, metric)
    if metric.startswith(f"{MOTION_RATIO}:"):
        element = metric.split(":", 1)[1]
        known = [e.name for e in model.elements]
        if element not in known:
            raise AddressError(f"output {name!r}: unknown element {element!r}; elements: {', '.join(known) or 'none'}")
        return wheel, metric
    if metric not in METRICS:
        raise AddressError(f"output {name!r}: unknown metric {metric!r}; metrics: {', '.join(METRICS)}, "
                           f"{MOTION_RATIO}:ELEMENT")  # fmt: skip
    return wheel, metric


def steering_bodies(
    ctx: OutputContext, wheel: str
) -> tuple[tuple[str, Array, tuple[str, str] | None], tuple[str, Array, tuple[str, str] | None]] | None:
    """``((body, point, source), (body, point, source))`` of the steering axis' upper and lower
    points at the context's state — the declared ``kingpin_upper``/``kingpin_lower`` points, else
    the default joints of :func:`kinprop.model.joint_points.steering_joints`, the higher one upper
    (the rule :class:`kinprop.analysis.program.ProgramBuilder` compiles) — each with the body it
    moves with (a joint's point: that side's) and the joint frame it is
    (``OutputContext.point_source``)."""
    model = ctx.model
    mech = model.mechanism
    found = [find_point(model, wheel, n) for n in ("kingpin_upper", "kingpin_lower")]
    if found[0] is not None and found[1] is not None:
        out = []
        for body, name in found:  # type: ignore[misc]
            ref = mech.body(body).joint_point(name)
            if ref is not None:
                j = mech.joint(ref[0])
                out.append((j.body_i if ref[1] == "i" else j.body_j, ctx.hardpoint(*ref), ref))
            else:
                out.append((body, ctx.body_point(body, name), None))
        return out[0], out[1]
    pair = steering_joints(mech, wheel)
    if pair is None:
        return None
    ends = []
    for joint, side in pair:
        j = mech.joint(joint)
        ends.append((j.body_i if side == "i" else j.body_j, ctx.hardpoint(joint, side), (joint, side)))
    a, b = ends
    return (a, b) if a[1][2] >= b[1][2] else (b, a)


def steering_axis_mismatch(model: Model) -> list[str]:
    """Declared steering-axis points (``kingpin_upper``/``kingpin_lower`` given by coordinates)
    that do not coincide with the joint the default steering axis takes, at the model's
    coordinates: one message each, with the distance. Such points are used as declared."""
    out = []
    ctx = None  # forward kinematics only when a wheel declares its axis by coordinates
    for wheel in wheel_bodies(model):
        pair = steering_joints(model.mechanism, wheel)
        found = [find_point(model, wheel, n) for n in ("kingpin_upper", "kingpin_lower")]
        if pair is None or None in found:
            continue
        if all(model.mechanism.body(b).joint_point(k) is not None for b, k in found):  # type: ignore[misc]
            continue
        ctx = ctx or OutputContext.of(model)
        a, b = (ctx.hardpoint(*p) for p in pair)
        ordered = (pair[0], a), (pair[1], b)
        if a[2] < b[2]:
            ordered = ordered[::-1]
        names = ("kingpin_upper", "kingpin_lower")
        for name, (body, key), ((joint, side), p) in zip(names, found, ordered, strict=True):
            if model.mechanism.body(body).joint_point(key) is not None:
                continue
            d = float(np.linalg.norm(ctx.body_point(body, key) - p))
            if d > 1e-6 * max(1.0, float(np.max(np.abs(p)))):
                out.append(
                    f"bodies.{body}.points.{key}: the declared {name} is {d:.6g} from joint {joint} ({joint}.{side} "
                    f"at {np.round(p, 6).tolist()}), which the steering axis would otherwise follow; it is used as "
                    f"declared. Write '{key}: {joint}' (or delete it) to follow the joint."
                )
    return out


def is_first_order(metric: str) -> bool:
    """A metric from the velocity analysis (a gain, a centre, anti, motion ratio, wheel rate)."""
    return metric in FIRST_ORDER or metric.startswith(f"{MOTION_RATIO}:")


def _radius(model: Model, wheel: str) -> float | None:
    """The loaded radius: the ``contact_patch`` point's distance from the spin axis."""
    return _body_radius(model.mechanism.body(wheel).points)


@functools.lru_cache(maxsize=64)
def _body_radius(points: tuple[tuple[str, Any], ...]) -> float | None:
    """:func:`_radius` of a wheel body's named points (cached: the same at every state)."""
    pts = dict(points)
    if "contact_patch" not in pts:
        return None
    v = np.asarray(pts["contact_patch"], dtype=float) - np.asarray(pts["wheel_centre"], dtype=float)
    a_B = np.asarray(pts["spin_axis"], dtype=float) - np.asarray(pts["wheel_centre"], dtype=float)
    a_B /= np.linalg.norm(a_B)
    return float(np.linalg.norm(v - (v @ a_B) * a_B))


def _contact_of(ctx: OutputContext, wheel: str, radius: float) -> Array:
    centre = ctx.body_point(wheel, "wheel_centre")
    return contact_point(centre, ctx.body_point(wheel, "spin_axis") - centre, radius)


def wheel_first_order_program(
    model: Model,
    engine: Engine,
    wheel: str,
    reference: Model | None = None,
    wheels: Any = None,
) -> FirstOrderProgram:
    """The wheel's first-order program (:func:`kinprop.analysis.firstorder.first_order_program`)
    by this module's lookup rules: the loaded radius, the reference contact point (of the
    ``reference`` model, else the fixed point ``contact_patch_ref``), the travel input of its
    :class:`WheelSpec` (``wheels``)."""
    spec = wheels.get(wheel) if wheels else None
    radius = _radius(model, wheel)
    ref: Any = None
    if radius is not None:
        if reference is not None:
            ref = _contact_of(OutputContext.of(reference, engine=engine), wheel, radius)
        else:
            ref = find_point(model, wheel, "contact_patch_ref", on_wheel=False)
    travel = spec.travel_input if spec is not None else None
    return first_order_program(model, engine, wheel, radius, ref, reference=reference, wheels=wheels,
                               travel_input=travel)  # fmt: skip


def _program_of(ctx: OutputContext, wheel: str, spec: WheelSpec | None) -> tuple[FirstOrderProgram, Any]:
    engine = ctx.engine or compile_engine(ctx.model.mechanism)
    wheels = {wheel: spec} if spec is not None else ctx.wheels
    st = ctx.state if ctx.state is not None and ctx.engine is engine else engine.state_of(ctx.model)
    return wheel_first_order_program(ctx.model, engine, wheel, ctx.reference, wheels), st


def wheel_first_order(ctx: OutputContext, wheel: str, spec: WheelSpec | None = None) -> dict[str, float]:
    """Every first-order metric the wheel supports at the context's state
    (:mod:`kinprop.analysis.firstorder`; gains in degrees per length unit)."""
    program, st = _program_of(ctx, wheel, spec)
    return program.values(st)


def wheel_first_order_derivatives(
    ctx: OutputContext, wheel: str, directions: Array, spec: WheelSpec | None = None, elements: Array | None = None
) -> dict[str, Array]:
    """Exact derivatives of :func:`wheel_first_order` along each column of ``directions``
    (state directions, solver units; ``elements``: the elements' end moves,
    :meth:`kinprop.analysis.firstorder.FirstOrderProgram.derivatives`)."""
    program, st = _program_of(ctx, wheel, spec)
    return program.derivatives(st, directions, elements)


def wheel_metrics(ctx: OutputContext, wheel: str, spec: WheelSpec | None = None) -> dict[str, float]:
    """Every position-level metric the wheel supports at the context's state (angles deg,
    lengths model unit), by the compiled kernel (:mod:`kinprop.engine.outputs`)."""
    engine = ctx.engine if ctx.engine is not None else compile_engine(ctx.model.mechanism)
    wheels = {wheel: spec} if spec is not None else ctx.wheels
    b = ProgramBuilder(ctx.model, engine, ctx.reference, wheels)
    _, given = b.wheel(wheel)
    for metric in given:
        b.add_metric(metric, wheel, metric)
    program = b.build()
    values = program.evaluate(ctx.state if ctx.state is not None else engine.state_of(ctx.model))
    return dict(zip(given, (float(v) for v in values), strict=True))


def suspension_metrics(
    model: Model, wheel: str | None = None, *, reference: Model | None = None, spec: WheelSpec | None = None
) -> dict[str, float]:
    """Metrics of ``wheel`` (the only wheel body when None) at the model's current state."""
    wheels = wheel_bodies(model)
    if wheel is None:
        if len(wheels) != 1:
            raise AddressError(f"name the wheel body: the model has {len(wheels)} ({', '.join(wheels) or 'none'})")
        wheel = wheels[0]
    elif wheel not in wheels:
        raise AddressError(f"{wheel!r} is not a wheel body (needs named points 'wheel_centre' and 'spin_axis')")
    return wheel_metrics(OutputContext.of(model, reference), wheel, spec)


def metric_unit(metric: str, length_unit: str = "m", angle_unit: str = "deg", force_unit: str | None = None) -> str:
    """Unit of a metric: ``angle_unit`` for angles (computed in ``deg``), ``angle/length`` for
    gains, ``%`` for anti metrics, ``""`` for ratios, ``force/length`` for the wheel rate, the
    length unit otherwise."""
    metric = METRIC_ALIASES.get(metric, metric)
    if metric in ANGLE_METRICS:
        return angle_unit
    if is_first_order(metric):
        units = {"length": length_unit, "angle": angle_unit} | ({"force": force_unit} if force_unit else {})
        return first_order_unit(metric, units)
    return length_unit


def is_angle_valued(metric: str) -> bool:
    """Computed in degrees (an angle or a gain in degrees per length): scaled to the model's angle unit."""
    metric = METRIC_ALIASES.get(metric, metric)
    return metric in ANGLE_METRICS or metric in GAIN_METRICS


__all__ = [
    "METRICS",
    "METRIC_NEEDS",
    "POSITION_METRICS",
    "WheelSpec",
    "camber_toe",
    "contact_point",
    "ground_offsets",
    "is_angle_valued",
    "is_first_order",
    "metric_names",
    "metric_unit",
    "steering_angles",
    "steering_bodies",
    "suspension_metrics",
    "wheel_bodies",
    "wheel_first_order",
    "wheel_first_order_derivatives",
    "wheel_first_order_program",
    "wheel_metrics",
]
