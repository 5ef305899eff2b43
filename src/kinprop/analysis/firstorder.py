"""A suspension's first-order geometry: gains with wheel travel, front- and side-view instant
centres and swing arms, roll-centre height, anti-dive / anti-lift / anti-squat, half-track
and contact-patch changes, motion ratios and the wheel rate (docs/analysis/suspension.md has
every definition with its reference and sign).

Everything comes from one velocity analysis of the assembled state
(:mod:`kinprop.engine.motion`): the wheel's motion in bump is the one-degree-of-freedom
motion with the travel input driven (the first declared input, or the mechanism's only
degree of freedom when it declares none) and every other declared input held (a rack, a
steering input). "Wheel travel" ``z`` is the wheel centre's vertical displacement; a gain is
``(d quantity / dt) / (dz / dt)`` along that motion: exact, no differencing.

Instant centres use the wheel body's instantaneous screw axis relative to the fixed body,
written homogeneously so that an axis parallel to a view plane (an instant centre at
infinity) gives finite line directions: with the axis ``{p + l u}``, a plane through E with
unit normal n, ``H = (n.u) p + n.(E - p) u`` and weight ``s = n.u`` the intersection is
``H / s``, and the line from a point F towards it has direction ``w = H - s F`` (for ``s = 0``
the axis' own direction). Centres at infinity are reported as NaN coordinates and an infinite
swing-arm length; roll-centre height and the anti percentages stay finite (the lines
through them are parallel to the axis).
"""

from __future__ import annotations

import math

import numpy as np

from kinprop.analysis.context import OutputContext
from kinprop.analysis.motion import point_of
from kinprop.engine import Engine, State
from kinprop.engine.motion import MotionState, cross3
from kinprop.errors import AddressError
from kinprop.model import Model
from kinprop.spatial import EZ, Array

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


def travel_motion(
    engine: Engine, model: Model, travel_input: str | None = None, state: State | None = None
) -> MotionState:
    """The velocity state of the bump motion (module docstring) at the model's state (``state``:
    already packed)."""
    st = state if state is not None else engine.state_of(model)
    inputs = [a if "." in a else f"{a}.q" for a in model.mechanism.inputs]
    if travel_input is not None:
        drive = travel_input if "." in travel_input else f"{travel_input}.q"
        held = [a for a in inputs if a != drive]
    elif inputs:
        drive, held = inputs[0], inputs[1:]
    else:  # the mechanism's only degree of freedom: drive its largest coordinate
        fr_J = (
            engine.evaluate(st)[1][:, : engine.n_coordinates]
            * engine.row_scale[:, None]
            / engine.col_scale[None, : engine.n_coordinates]
        )
        _, s, Vt = np.linalg.svd(fr_J)
        null = Vt[int(np.sum(s > 1e-10 * s[0])) :]
        if null.shape[0] != 1:
            raise AddressError(
                f"the wheel's motion has {null.shape[0]} degrees of freedom: declare the travel input "
                "first in 'inputs:' (and the others, e.g. a rack, after it)"
            )
        col = int(np.argmax(np.abs(null[0])))
        drive, held = engine.column_labels[col], []
    rates = {drive: 1.0} | {a: 0.0 for a in held}
    return engine.motion(st, rates)


def _norm(v: Array) -> float:
    return math.sqrt(float(v[0]) ** 2 + float(v[1]) ** 2 + float(v[2]) ** 2)


def _contact(centre: Array, axis: Array, radius: float, v_centre: Array, da: Array) -> tuple[Array, Array]:
    """The contact point (lowest point of the wheel circle) and its rate."""
    g = -EZ + axis[2] * axis
    ng = _norm(g)
    n = g / ng
    dg = da[2] * axis + axis[2] * da
    dn = (dg - n * float(n @ dg)) / ng
    return centre + radius * n, v_centre + radius * dn


def _homogeneous(p: Array | None, u: Array, v: Array, normal: Array, E: Array) -> tuple[Array, float]:
    """``(H, s)`` of the axis' intersection with the plane through E (module docstring); a
    pure translation (``p`` None) of velocity ``v``: the centre at infinity across ``v``."""
    if p is None:
        return cross3(normal, v), 0.0
    s = float(normal @ u)
    return s * p + float(normal @ (E - p)) * u, s


def _centre(H: Array, s: float, E: Array, plane: tuple[int, int]) -> tuple[float, float, float]:
    """In-plane coordinates of the centre and its distance from E (NaN, NaN, inf at infinity)."""
    if abs(s) < PARALLEL_TOL:
        return math.nan, math.nan, math.inf
    X = H / s
    d = X - E
    return float(X[plane[0]]), float(X[plane[1]]), math.hypot(float(d[plane[0]]), float(d[plane[1]]))


def _slope(w: Array, forward: float) -> float:
    """``tan(theta)`` of a side-view line of direction ``w`` rising towards ``forward * x``
    (+1: the centre ahead, -1: behind); sign-free in ``w``; +-inf for a vertical line."""
    wx, wz = float(w[0]), float(w[2])
    if wx == 0.0:
        return math.copysign(math.inf, wz * forward) if wz != 0.0 else math.nan
    return (wz / wx) * forward


def first_order_metrics(
    ctx: OutputContext,
    engine: Engine,
    wheel: str,
    points: dict[str, tuple[int, Array]],
    radius: float | None,
    reference_contact: Array | None,
    travel_input: str | None = None,
) -> dict[str, float]:
    """Every first-order metric the wheel supports (module docstring). ``points``: ``centre``,
    ``spin``, optionally ``upper``/``lower`` (the steering axis) as ``(body, position)``;
    ``radius``: the loaded radius (None: no contact patch); ``reference_contact``: the contact
    point's reference (None: no half-track / contact-patch changes)."""
    model = ctx.model
    ms = travel_motion(engine, model, travel_input, ctx.state if ctx.engine is engine else None)
    out: dict[str, float] = {}
    names = first_order_names(model, radius is not None, "upper" in points, reference_contact is not None)
    if not ms.ok:
        return dict.fromkeys(names, math.nan)
    b = engine.body_index[wheel]
    w = ms.V[b, 3:]
    centre = points["centre"][1]
    axis = points["spin"][1] - centre
    axis = axis / _norm(axis)
    side = 1 if axis[1] >= 0 else -1
    vc = ms.point_velocity(b, centre)
    dz = float(vc[2])
    per = (lambda x: x / dz) if dz != 0.0 else (lambda x: math.nan)
    da = cross3(w, axis)
    out["camber_gain"] = per(math.degrees(-da[2] / math.sqrt(max(1e-300, 1.0 - axis[2] ** 2))))
    ay = abs(axis[1])
    out["bump_steer"] = per(math.degrees((ay * da[0] - axis[0] * side * da[1]) / (axis[0] ** 2 + axis[1] ** 2)))
    if "upper" in points:
        (bu, xu), (bl, xl) = points["upper"], points["lower"]
        k = xu - xl
        dk = ms.point_velocity(bu, xu) - ms.point_velocity(bl, xl)
        out["caster_gain"] = per(math.degrees((-dk[0] * k[2] + k[0] * dk[2]) / (k[0] ** 2 + k[2] ** 2)))
    for e in model.elements:
        bi, bj = engine.body_index[e.body_i], engine.body_index[e.body_j]
        pi = ms.r[bi] + ms.A[bi] @ np.asarray(e.s_i, dtype=float)
        pj = ms.r[bj] + ms.A[bj] @ np.asarray(e.s_j, dtype=float)
        d = pj - pi
        dl = float(d @ (ms.point_velocity(bj, pj) - ms.point_velocity(bi, pi))) / _norm(d)
        out[f"{MOTION_RATIO}:{e.name}"] = abs(per(dl))
    springs = [e for e in model.elements if e.has_spring]
    if springs:
        out["wheel_rate"] = sum(float(e.stiffness or 0.0) * out[f"{MOTION_RATIO}:{e.name}"] ** 2 for e in springs)
    if radius is None:
        return out
    E, vE = _contact(centre, axis, radius, vc, da)
    if reference_contact is not None:
        out["half_track_change"] = side * float(E[1] - reference_contact[1])
        out["contact_patch_dx"] = float(E[0] - reference_contact[0])
    out["half_track_gain"] = per(side * float(vE[1]))
    out["contact_patch_dx_gain"] = per(float(vE[0]))
    # screw axis of the wheel relative to the fixed body (the fixed body's twist is zero)
    V = ms.V[b]
    nw, nv = _norm(w), _norm(vc)
    scale = max(1.0, _norm(centre))
    if nw * scale <= TRANSLATION_RTOL * nv or nw == 0.0:
        p, u = None, np.zeros(3)
    else:
        u = w / nw
        p = cross3(w, V[:3]) / nw**2
    ex, ey = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
    Hf, sf = _homogeneous(p, u, vE, ex, E)  # front view: the plane x = x_E
    out["fvic_y"], out["fvic_z"], out["fvsa_length"] = _centre(Hf, sf, E, (1, 2))
    wf = Hf - sf * E
    out["roll_centre_height"] = -float(E[1]) * float(wf[2]) / float(wf[1]) if wf[1] != 0.0 else math.nan
    Hs, ss = _homogeneous(p, u, vE, ey, E)  # side view: the plane y = y_E
    out["svic_x"], out["svic_z"], out["svsa_length"] = _centre(Hs, ss, E, (0, 2))
    veh = model.vehicle
    if veh is not None:
        lever = veh.wheelbase / veh.cg_height * 100.0
        wE, wC = Hs - ss * E, Hs - ss * centre  # lines from the contact patch / the wheel centre
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


__all__ = ["FIRST_ORDER", "first_order_metrics", "first_order_names", "first_order_unit", "point_of", "travel_motion"]
