"""Axle metrics of a left and a right wheel (ISO 8855 axes; Milliken & Milliken, *Race Car
Vehicle Dynamics*, ch. 17 and 19; Dixon, *Suspension Geometry and Computation*, ch. 6).

* ``roll_centre`` — the **axle roll centre**: in the front view (the y-z plane), the line from
  each wheel's contact point through its front-view instant centre (FVIC,
  :mod:`kinprop.analysis.firstorder`); the two lines meet at the roll centre. Returned: its
  ``y``, ``z`` and its height above the ground line through the two contact points (length,
  positive above the ground). At a symmetric state it lies on ``y = 0`` at the corners' own
  ``roll_centre_height``; in heave or roll it migrates.
* ``roll_gradients`` — **roll steer** and **roll camber** (deg/deg): the wheels' toe and camber
  per degree of body roll, central over ``+-angle``. Body roll ``phi`` (positive: rolling about
  +x, the left side up) is the ``roll`` drive of :mod:`kinprop.analysis.drives` (the road plane
  rolled under the chassis about the x axis through the midpoint of the wheel-centre
  references; each wheel centre kept at its height above it), the rack held.
* ``track_change`` — **half-track change** of each wheel and the axle's **track change** (their
  sum) at a heave travel or a body roll;
* ``steering_ratio`` — the overall **steering ratio**, steering-wheel angle per mean road-wheel
  angle, from the rack's travel per steering-wheel turn (``vehicle: rack_travel_per_turn``);
* ``ackermann`` — **Ackermann percentage** at a rack travel: ``100 (delta_i - delta_o) /
  (delta_i - delta_o,ack)`` with the road-wheel steer angles ``delta = -toe`` change of the
  inner and outer wheel and ``cot(delta_o,ack) - cot(delta_i) = t / L`` (track ``t`` between
  the wheel centres, wheelbase ``L``): 100 % is true Ackermann, 0 % parallel steer.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from kinprop.analysis.context import OutputContext, WheelSpec
from kinprop.analysis.drives import model_at, outputs_at
from kinprop.analysis.metrics import _radius, contact_point
from kinprop.analysis.outputs import evaluate_outputs
from kinprop.engine.units import METRES_PER, RADIANS_PER, radians_per_angle
from kinprop.errors import AddressError
from kinprop.model import Model


def _contact(model: Model, wheel: str) -> np.ndarray:
    ctx = OutputContext.of(model)
    radius = _radius(model, wheel)
    if radius is None:
        raise AddressError(f"wheel {wheel!r}: the axle metrics need its contact_patch point")
    centre = ctx.body_point(wheel, "wheel_centre")
    return contact_point(centre, ctx.body_point(wheel, "spin_axis") - centre, radius)


def roll_centre(
    model: Model,
    left: str,
    right: str,
    travel_inputs: Mapping[str, str],
    *,
    travel: float | None = None,
    roll: float | None = None,
) -> dict[str, float]:
    """Axle roll centre (module docstring): ``{"y", "z", "height"}``; ``travel_inputs`` names
    each wheel's bump input (``{"upright_L": "LCA_L", ...}``). At the model's state, or, for
    its migration, at a heave ``travel`` of both wheels (the length unit) or a body ``roll``
    (the angle unit): the drives of :mod:`kinprop.analysis.drives`, the height then above the
    ground line through the moved contact points."""
    if travel is not None and roll is not None:
        raise AddressError("roll_centre: give a travel or a roll, not both")
    if travel is not None or roll is not None:
        model = model_at(model, f"travel={travel!r}" if travel is not None else f"roll={roll!r}")
    wheels = {w: WheelSpec(travel_input=travel_inputs[w]) for w in (left, right)}
    v = evaluate_outputs(
        model, [f"metric:{w}.{m}" for w in (left, right) for m in ("fvic_y", "fvic_z")], wheels=wheels, units="solver"
    )
    lines = []
    for w in (left, right):
        E = _contact(model, w)
        F = np.array([v[f"metric:{w}.fvic_y"], v[f"metric:{w}.fvic_z"]])
        lines.append((E[1:], F - E[1:]))
    (p, d), (q, e) = lines
    A = np.column_stack([d, -e])
    s, _ = np.linalg.solve(A, q - p)
    rc = p + s * d
    (yl, zl), (yr, zr) = lines[0][0], lines[1][0]
    ground = zl + (zr - zl) * (rc[0] - yl) / (yr - yl)
    return {"y": float(rc[0]), "z": float(rc[1]), "height": float(rc[1] - ground)}


def roll_gradients(model: Model, left: str, right: str, *, angle: float = 1.0) -> dict[str, float]:
    """Roll steer and roll camber (deg/deg) of both wheels (module docstring): keys
    ``roll_steer:WHEEL``, ``roll_camber:WHEEL``; ``angle``: the roll half-range in degrees.
    The declared inputs other than the wheels' (a rack) are held."""
    names = {
        f"{key}:{w}": f"slope:metric:{w}.{m}@roll={-angle!r}deg..{angle!r}deg"
        for w in (left, right)
        for key, m in (("roll_steer", "toe"), ("roll_camber", "camber"))
    }
    v = outputs_at(model, list(names.values()))  # angle per angle: the same in degrees and radians
    return {k: v[n] for k, n in names.items()}


def track_change(
    model: Model, left: str, right: str, *, travel: float | None = None, roll: float | None = None
) -> dict[str, float]:
    """Half-track changes of both wheels (``half_track_change:WHEEL``: the contact point's
    lateral move from its reference, outboard positive; :mod:`kinprop.analysis.firstorder`) and
    the **track change** (``track_change``, their sum: the change of the contact points'
    distance), at the model's state, at a wheel ``travel`` of both wheels (heave, the length
    unit) or at a body ``roll`` (the angle unit), drives of :mod:`kinprop.analysis.drives`."""
    if travel is not None and roll is not None:
        raise AddressError("track_change: give a travel or a roll, not both")
    at = f"@travel={travel!r}" if travel is not None else f"@roll={roll!r}" if roll is not None else ""
    names = {w: f"metric:{w}.half_track_change{at}" for w in (left, right)}
    v = outputs_at(model, list(names.values()))
    out = {f"half_track_change:{w}": v[n] for w, n in names.items()}
    return out | {"track_change": sum(out.values())}


def steering_ratio(
    model: Model, left: str, right: str, rack: str = "RACK.q", *, at: float = 0.0, step: float | None = None
) -> float:
    """Overall **steering ratio** (deg of steering wheel per deg of road-wheel steer) at rack
    travel ``at``: ``360 / c / |d delta_mean / d rack|`` with the rack's travel per
    steering-wheel turn ``c`` (``vehicle: rack_travel_per_turn``, the length unit) and the mean
    road-wheel angle ``delta_mean = (delta_left + delta_right) / 2`` (``delta = -toe`` change
    of each wheel, positive to the left), its slope central over ``at +- step`` of rack (default
    1 mm in the model's length unit)."""
    if step is None:
        step = METRES_PER["mm"] / METRES_PER[model.units.get("length", "m")]
    c = model.vehicle.rack_travel_per_turn if model.vehicle is not None else None
    if c is None:
        raise AddressError("steering_ratio needs 'vehicle: rack_travel_per_turn' (rack travel per steering-wheel turn)")
    ctx = OutputContext.of(model)
    side = {w: 1.0 if ctx.body_point(w, "wheel_centre")[1] > 0 else -1.0 for w in (left, right)}
    names = {w: f"slope:metric:{w}.toe@{rack}={at - step!r}..{at + step!r}" for w in (left, right)}
    v = outputs_at(model, list(names.values()))
    per_deg = radians_per_angle(model) / RADIANS_PER["deg"]  # toe slope -> deg per length
    mean = sum(-side[w] * v[n] * per_deg for w, n in names.items()) / 2.0
    return 360.0 / c / abs(mean)


def ackermann(model: Model, inner: str, outer: str, rack: str, travel: float, wheelbase: float) -> float:
    """Ackermann percentage (module docstring) at rack travel ``travel`` (the rack coordinate
    ``rack``, e.g. ``RACK.q``; the turn's ``inner`` and ``outer`` wheel bodies)."""
    names = [f"metric:{w}.toe@{rack}={t!r}" for t in (0.0, travel) for w in (inner, outer)]
    v = outputs_at(model, names)
    side = {w: 1.0 if OutputContext.of(model).body_point(w, "wheel_centre")[1] > 0 else -1.0 for w in (inner, outer)}

    def steer(w: str) -> float:  # road-wheel angle, positive to the left, from the toe change
        toe0, toe1 = v[f"metric:{w}.toe@{rack}={0.0!r}"], v[f"metric:{w}.toe@{rack}={travel!r}"]
        return -side[w] * (toe1 - toe0) * RADIANS_PER["deg"]  # toe is in degrees (a metric)

    d_i, d_o = abs(steer(inner)), abs(steer(outer))
    ctx = OutputContext.of(model)
    track = abs(float(ctx.body_point(inner, "wheel_centre")[1] - ctx.body_point(outer, "wheel_centre")[1]))
    d_ack = math.atan(1.0 / (1.0 / math.tan(d_i) + track / wheelbase))
    return 100.0 * (d_i - d_o) / (d_i - d_ack)


__all__ = ["ackermann", "roll_centre", "roll_gradients", "steering_ratio", "track_change"]
