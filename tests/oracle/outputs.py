"""The position-level outputs as the library first computed them, one state at a time in numpy
(points ``r + A p'``, hardpoints, distances, variables and the wheel metrics of
docs/analysis/suspension.md), kept to check the compiled outputs (:mod:`kinprop.engine.outputs`)
against. Not part of the library."""

from __future__ import annotations

import math

import numpy as np

from kinprop.analysis.context import HARD, POINT, OutputContext, find_point
from kinprop.analysis.metrics import resolve_metric
from kinprop.analysis.outputs import AXES, _distance_ends, _parse_variable
from kinprop.model.joint_points import steering_joints
from kinprop.spatial import EZ, Array


def wheel_side(axis: Array) -> int:
    return 1 if axis[1] >= 0 else -1


def steering_points(ctx: OutputContext, wheel: str) -> tuple[Array | None, Array | None]:
    model = ctx.model
    found_upper, found_lower = (find_point(model, wheel, n) for n in ("kingpin_upper", "kingpin_lower"))
    if found_upper is not None and found_lower is not None:
        return ctx.body_point(*found_upper), ctx.body_point(*found_lower)
    pair = steering_joints(model.mechanism, wheel)
    if pair is None:
        return None, None
    a, b = (ctx.hardpoint(*p) for p in pair)
    return (a, b) if a[2] >= b[2] else (b, a)


def camber_toe(axis: Array) -> tuple[float, float]:
    a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    camber = math.degrees(math.asin(float(np.clip(-a[2], -1.0, 1.0))))
    toe = math.degrees(math.atan2(float(a[0]), abs(float(a[1]))))
    return camber, toe


def steering_angles(upper: Array, lower: Array, side: int) -> tuple[float, float]:
    k = np.asarray(upper, dtype=float) - np.asarray(lower, dtype=float)
    return math.degrees(math.atan2(-k[0], k[2])), math.degrees(math.atan2(-side * k[1], k[2]))


def contact_point(centre: Array, axis: Array, radius: float) -> Array:
    a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    down = -EZ + a[2] * a
    return np.asarray(centre, dtype=float) + radius * down / np.linalg.norm(down)


def ground_offsets(upper: Array, lower: Array, contact: Array, axis: Array) -> tuple[float, float]:
    k = np.asarray(upper, dtype=float) - np.asarray(lower, dtype=float)
    G = lower + k * (contact[2] - lower[2]) / k[2]
    a = np.asarray(axis, dtype=float)
    lateral = np.array([a[0], a[1], 0.0])
    lateral /= np.linalg.norm(lateral)
    heading = wheel_side(a) * np.cross(lateral, EZ)
    return float((contact - G) @ lateral), float((G - contact) @ heading)


def wheel_metrics(ctx: OutputContext, wheel: str) -> dict[str, float]:
    model = ctx.model
    spec = ctx.wheels.get(wheel) if ctx.wheels else None
    centre = ctx.body_point(wheel, "wheel_centre")
    axis = ctx.body_point(wheel, "spin_axis") - centre
    axis /= np.linalg.norm(axis)
    camber, toe = camber_toe(axis)
    out = {"camber": camber, "toe": toe}
    if spec is not None and spec.steering_axis is not None:
        upper, lower = (ctx.point(s) for s in spec.steering_axis)
    else:
        upper, lower = steering_points(ctx, wheel)
    if upper is not None and lower is not None:
        out["caster"], out["kpi"] = steering_angles(upper, lower, wheel_side(axis))
        if "contact_patch" in dict(model.mechanism.body(wheel).points):
            v = ctx.body_point(wheel, "contact_patch") - centre
            radius = float(np.linalg.norm(v - (v @ axis) * axis))
            out["scrub_radius"], out["trail"] = ground_offsets(upper, lower, contact_point(centre, axis, radius), axis)
    ref = None
    if ctx.reference is not None:
        ref = OutputContext.of(ctx.reference, engine=ctx.engine).body_point(wheel, "wheel_centre")
    else:
        found = find_point(model, wheel, "wheel_centre_ref", on_wheel=False)
        if found is not None:
            ref = ctx.body_point(*found)
    if ref is not None:
        out["wheel_centre_dx"], out["wheel_centre_dy"], out["wheel_centre_dz"] = (float(x) for x in centre - ref)
    return out


def scalar(ctx: OutputContext, name: str) -> float:
    """One expanded position-level output (solver units: radians, metric angles in degrees)."""
    if name.startswith("distance:"):
        a, b = _distance_ends(name)
        return float(np.linalg.norm(ctx.point(a) - ctx.point(b)))
    m = POINT.match(name)
    if name.startswith("point:") and m:
        return float(ctx.body_point(m.group("body"), m.group("name"))[AXES[m.group("c")]])
    m = HARD.match(name)
    if name.startswith("hardpoint:") and m:
        return float(ctx.hardpoint(m.group("joint"), m.group("side"))[AXES[m.group("c")]])
    if name.startswith("metric:") or "." not in name:
        wheel, metric = resolve_metric(ctx.model, name)
        return float(wheel_metrics(ctx, wheel)[metric])
    addr = _parse_variable(ctx.engine, name)
    model = ctx.model
    if addr.field == "q":
        v = np.atleast_1d(np.asarray(model.coordinates[addr.joint], dtype=float))
    else:
        v = np.atleast_1d(np.asarray(model.design[addr.key], dtype=float)).ravel()
    return float(v[addr.index or 0])
