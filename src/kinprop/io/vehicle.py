"""A vehicle: a front and a rear axle model and the parameters the anti geometry needs.

A vehicle file (YAML or JSON)::

    kinprop: 1
    name: generic vehicle
    units: {length: mm}
    vehicle: {wheelbase: 2800, cg_height: 500, brake_front: 0.65, drive_front: 0.0,
              rack_travel_per_turn: 50}
    front: mcpherson_axle.yaml        # axle model files, relative to this file
    rear: multilink_rear_axle.yaml

:func:`load_vehicle` reads both axles and gives each the vehicle's parameters in its own length
unit (an axle in metres and a vehicle file in millimetres agree), with ``axle: front`` or
``rear``: every anti metric (:mod:`kinprop.analysis.firstorder`: anti-dive, anti-lift,
anti-squat, Milliken & Milliken ch. 17) of either axle then uses the vehicle's wheelbase, CG
height and brake and drive split. :func:`anti_geometry` gives the usual four numbers.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from kinprop.analysis.axle import roll_centre, roll_gradients, steering_ratio
from kinprop.analysis.context import OutputContext, WheelSpec
from kinprop.analysis.drives import travel_input
from kinprop.analysis.metrics import wheel_bodies
from kinprop.analysis.outputs import evaluate_outputs
from kinprop.errors import AddressError, ModelError, Problem
from kinprop.io.files import load_model
from kinprop.io.loader import build_or_report, parse_document, read_text
from kinprop.io.schema import VehicleFile
from kinprop.model import Model
from kinprop.model.elements import Vehicle

#: metres per length unit
_METRES = {"m": 1.0, "mm": 1e-3}


@dataclass(frozen=True)
class VehicleModel:
    """A vehicle: its name, parameters (the file's units) and the two axles (each with the
    vehicle's parameters in its own units)."""

    name: str
    vehicle: Vehicle
    units: dict[str, str]
    front: Model
    rear: Model


def _axle(model: Model, vehicle: Vehicle, unit: str, axle: str, file: str) -> Model:
    length = model.units.get("length", "m")
    if length not in _METRES:
        raise ModelError([Problem(axle, f"the {axle} axle's length unit {length!r} is not m or mm", file)])
    k = _METRES[unit] / _METRES[length]
    rack = vehicle.rack_travel_per_turn
    scaled = replace(vehicle, wheelbase=vehicle.wheelbase * k, cg_height=vehicle.cg_height * k, axle=axle,
                     rack_travel_per_turn=None if rack is None else rack * k)  # fmt: skip
    return replace(model, vehicle=scaled)


def load_vehicle(path: str | Path) -> VehicleModel:
    """Read a vehicle file (module docstring) and its two axle files; every problem is a
    :class:`ModelError` naming the file and the key."""
    path = Path(path)
    file = str(path)
    data, dups = parse_document(read_text(path), file)
    if dups:
        raise ModelError(dups)
    if not isinstance(data, dict):
        found = type(data).__name__
        raise ModelError([Problem("vehicle", f"expected a mapping at the top level, found {found}", file)])

    if not {"front", "rear"} & data.keys() and {"bodies", "joints"} & data.keys():
        why = "expected a vehicle file (vehicle:, front:, rear: axle files); this is a model file (bodies, joints)"
        raise ModelError([Problem("front", f"{why}: name it from a vehicle file's front: or rear:", file)])

    def build(spec: VehicleFile, file: str) -> Any:
        return spec

    spec: VehicleFile = build_or_report(data, VehicleFile, build, file)
    vehicle = Vehicle(**spec.vehicle.model_dump())
    axles = {}
    where = {a: Path(os.path.normpath(path.parent / getattr(spec, a))) for a in ("front", "rear")}
    missing = [Problem(a, f"no axle model file {str(p)!r}", file) for a, p in where.items() if not p.is_file()]
    if missing:
        raise ModelError(missing)
    for axle, p in where.items():
        axles[axle] = _axle(load_model(p), vehicle, spec.units.length, axle, file)
    return VehicleModel(spec.name, vehicle, spec.units.model_dump(exclude_none=True), axles["front"], axles["rear"])


def anti_geometry(vehicle: VehicleModel) -> dict[str, float]:
    """Anti-dive and anti-lift of the front axle, anti-lift (braking) and anti-squat of the rear
    (%, first-order metrics of each axle's first wheel, its own travel input driving it)."""
    out: dict[str, float] = {}
    for axle, names in (("front", ("anti_dive", "anti_lift")), ("rear", ("anti_lift", "anti_squat"))):
        model: Model = getattr(vehicle, axle)
        wheel = wheel_bodies(model)[0]
        spec = {wheel: WheelSpec(travel_input=travel_input(model, wheel))}
        v = evaluate_outputs(model, [f"metric:{wheel}.{n}" for n in names], wheels=spec, units="solver")
        out |= {f"{axle}.{n}": v[f"metric:{wheel}.{n}"] for n in names}
    return out


def _sides(model: Model) -> tuple[str, str]:
    """The axle's (left, right) wheel bodies (the left one at y > 0, ISO 8855)."""
    wheels = wheel_bodies(model)
    if len(wheels) != 2:
        raise AddressError(f"an axle has two wheel bodies; this one has {len(wheels)}: {', '.join(wheels) or 'none'}")
    y = {w: float(OutputContext.of(model).body_point(w, "wheel_centre")[1]) for w in wheels}
    left, right = sorted(wheels, key=lambda w: -y[w])
    return left, right


def vehicle_summary(vehicle: VehicleModel) -> dict[str, Any]:
    """What a designer reads off a vehicle (``kinprop vehicle``): its parameters (the file's
    units) and per axle the wheels, the track (between the wheel centres), the anti percentages
    (:func:`anti_geometry`), the axle roll-centre height
    (:func:`kinprop.analysis.axle.roll_centre`), roll steer and roll camber of each wheel
    (deg/deg, :func:`kinprop.analysis.axle.roll_gradients`) and, for an axle with a rack and a
    ``rack_travel_per_turn``, the steering ratio; lengths in the vehicle file's unit."""
    unit = vehicle.units.get("length", "m")
    v = vehicle.vehicle
    out: dict[str, Any] = {
        "name": vehicle.name,
        "units": {"length": unit},
        "wheelbase": v.wheelbase,
        "cg_height": v.cg_height,
        "brake_front": v.brake_front,
        "drive_front": v.drive_front,
        "brakes": v.brakes,
        "drive": v.drive,
        "rack_travel_per_turn": v.rack_travel_per_turn,
    }
    anti = anti_geometry(vehicle)
    for axle in ("front", "rear"):
        model: Model = getattr(vehicle, axle)
        k = _METRES[model.units.get("length", "m")] / _METRES[unit]  # axle unit -> the vehicle's
        left, right = _sides(model)
        ctx = OutputContext.of(model)
        track = abs(float(ctx.body_point(left, "wheel_centre")[1] - ctx.body_point(right, "wheel_centre")[1]))
        inputs = {w: travel_input(model, w) for w in (left, right)}
        rc = roll_centre(model, left, right, inputs)
        roll = roll_gradients(model, left, right)
        a: dict[str, Any] = {"source": model.source, "wheels": {"left": left, "right": right}, "track": track * k}
        a |= {n.split(".", 1)[1]: x for n, x in anti.items() if n.startswith(f"{axle}.")}
        a["roll_centre_height"] = rc["height"] * k
        a["roll_steer"] = {w: roll[f"roll_steer:{w}"] for w in (left, right)}
        a["roll_camber"] = {w: roll[f"roll_camber:{w}"] for w in (left, right)}
        rack = "RACK.q" if "RACK" in model.mechanism.joint_names else None
        steer = rack is not None and model.vehicle is not None and model.vehicle.rack_travel_per_turn is not None
        a["steering_ratio"] = steering_ratio(model, left, right, rack) if steer else None  # type: ignore[arg-type]
        out[axle] = a
    return out


__all__ = ["VehicleModel", "anti_geometry", "load_vehicle", "vehicle_summary"]
