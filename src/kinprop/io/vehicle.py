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

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from kinprop.analysis.context import WheelSpec
from kinprop.analysis.drives import travel_input
from kinprop.analysis.metrics import wheel_bodies
from kinprop.analysis.outputs import evaluate_outputs
from kinprop.errors import ModelError, Problem
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

    def build(spec: VehicleFile, file: str) -> Any:
        return spec

    spec: VehicleFile = build_or_report(data, VehicleFile, build, file)
    vehicle = Vehicle(**spec.vehicle.model_dump())
    axles = {}
    for axle in ("front", "rear"):
        where = path.parent / getattr(spec, axle)
        if not where.is_file():
            raise ModelError([Problem(axle, f"no axle model file {str(where)!r}", file)])
        axles[axle] = _axle(load_model(where), vehicle, spec.units.length, axle, file)
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


__all__ = ["VehicleModel", "anti_geometry", "load_vehicle"]
