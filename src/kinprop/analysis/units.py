"""Units of output names: suspension metrics and load outputs beside addresses (docs/units.md).

The factors and the conversions of addresses (coordinates, design variables, points) are
:mod:`kinprop.engine.units`; this module only names the unit of what the analysis layer adds —
metric names (``metric:W.camber``, ``camber``; computed in degrees, reported in the model's
angle unit) and load outputs (``reaction:J.fz``) — with those factors.
"""

from __future__ import annotations

from kinprop.analysis.metrics import METRIC_ALIASES, METRICS, is_angle_valued, is_first_order, metric_unit
from kinprop.analysis.statics import is_load_output, load_output_unit
from kinprop.engine import Engine
from kinprop.engine.units import RADIANS_PER, address_scale, address_unit, degrees
from kinprop.model import Model


def is_metric(name: str) -> bool:
    """A metric name (``metric:W.camber``, ``camber``) rather than an address or a point."""
    return name.startswith("metric:") or (
        "." not in name and not name.startswith(("point:", "hardpoint:", "distance:", "body:"))
    )


def _driven(name: str) -> tuple[str, str, bool] | None:
    """``(output, condition name, is a slope)`` of an output at a drive position
    (:mod:`kinprop.analysis.drives`); the condition as a quantity: a travel is a length
    (``wheel_centre_dz``), ``roll`` and ``steer:WHEEL`` angles (``roll``), a coordinate itself."""
    if "@" not in name:
        return None
    body, _, conds = name.partition("@")
    slope = body.startswith("slope:")
    cond = conds.split("&")[0].partition("=")[0].strip()
    if cond == "travel" or cond.startswith("travel:"):
        cond = "wheel_centre_dz"
    elif cond.startswith("steer:"):
        cond = "roll"
    elif cond != "roll" and "." not in cond and cond not in ("wheel_centre_dz", "wheel_travel"):
        cond = f"{cond}.q"
    return body[len("slope:") :] if slope else body, cond, slope


def unit_of(model: Model, name: str, engine: Engine | None = None) -> str:
    """The unit, in the model's units, of an address, a column label or an output name:
    ``J01.q`` -> ``deg`` (a revolute in a degree model), ``J03.q`` -> ``m`` (a slide),
    ``J12.s_j[0]``, ``J12.length``, ``point:...``, ``hardpoint:...`` -> the length unit,
    ``J.C_i`` -> ``""`` (a rotation matrix), Euler parameters -> ``""``, ``metric:W.camber`` ->
    the angle unit; a load output (``reaction:J.fz``) -> the force unit (force x length for a moment);
    an output at a drive position (``camber@travel=50``) -> the output's; a slope
    (``slope:toe@travel=-50..50``) -> the output's per the condition's (``deg/mm``)."""
    if name == "travel" or name.startswith("travel:"):  # a drive's column (kinprop.analysis.drives)
        return model.units.get("length", "m")
    if name == "roll" or name.startswith("steer:"):
        return model.units.get("angle", "rad")
    if name.startswith("element:"):  # an element's end (kinprop.propagation.element_points)
        return model.units.get("length", "m")
    driven = _driven(name)
    if driven is not None:
        out, cond, slope = driven
        u = unit_of(model, out, engine)
        per = unit_of(model, cond, engine)
        return f"{u or '1'}/{per or '1'}" if slope else u
    if is_load_output(name):
        return load_output_unit(model, name)
    if is_metric(name):
        short = name.split(".")[-1]
        if METRIC_ALIASES.get(short, short) not in METRICS and not is_first_order(short):
            return ""  # not a quantity (step, status, iterations, ...)
        length, angle = model.units.get("length", "m"), model.units.get("angle", "rad")
        return metric_unit(short, length, angle, model.units.get("force"))
    return address_unit(model, name, engine)


def derivative_scale(model: Model, name: str, engine: Engine | None = None) -> float:
    """Factor taking a quantity named ``name`` from the units it is computed in to the model's
    units: ``180/pi`` for a joint angle or a ``C`` column (per radian of body-frame rotation)
    in a degree model, ``pi/180`` for an angle metric (computed in degrees) in a radian model,
    else 1.

    A derivative d(out)/d(in) computed in solver units becomes
    ``d_model = d_solver * derivative_scale(out) / derivative_scale(in)``. ``engine``: one
    compiled from the model's mechanism (else one is compiled per call)."""
    driven = _driven(name)
    if driven is not None:
        out, cond, slope = driven
        scale = derivative_scale(model, out, engine)
        if not slope:
            return scale
        per = 1.0 / RADIANS_PER[model.units.get("angle", "rad")] if cond == "roll" else \
            derivative_scale(model, cond, engine)  # fmt: skip
        return scale / per
    if is_metric(name):
        angle_metric = is_angle_valued(name.split(".")[-1])
        return RADIANS_PER["deg"] if (angle_metric and not degrees(model)) else 1.0
    return address_scale(model, name, engine)


__all__ = ["derivative_scale", "is_metric", "unit_of"]
