"""The page's view of a session: design-variable table, coordinates, sliders, scene (JSON).

The page's own endpoint (``GET /api/state``); the CLI contracts are in :mod:`kinprop.serve.api`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from kinprop.analysis.drives import has_travel
from kinprop.analysis.metrics import metric_names
from kinprop.analysis.outputs import output_names
from kinprop.analysis.points import joint_hardpoints, named_points
from kinprop.analysis.units import unit_of
from kinprop.engine.units import METRES_PER, angle_indices, from_solver_units
from kinprop.model import Model
from kinprop.plot.scene import Scene, bounds, build_scene, scale
from kinprop.plot.style import AXIS, FADED_ALPHA, MARKERS, POINT, segment_colour
from kinprop.serve.session import Session

GROUPS = {"s_i": "s", "s_j": "s", "C_i": "C", "C_j": "C", "length": "l"}
#: slider half-range: angles [deg], lengths [fraction of the mechanism's size]
SLIDER_DEG, SLIDER_FRACTION = 45.0, 0.25
#: default half-range of a curve's drive
CURVE_DEG, CURVE_FRACTION = 10.0, 0.05
#: the wheel-travel drive's default curve: +-50 mm, in the model's length unit
TRAVEL_CURVE_M = 0.05


def _xyz(v: np.ndarray) -> list[float]:
    return [float(x) for x in np.asarray(v, dtype=float).ravel()]


def scene_json(sc: Scene) -> dict[str, Any]:
    """A :class:`~kinprop.plot.scene.Scene` as plain lists, with the plot style's colours."""
    groups: dict[tuple[str, str], dict[str, Any]] = {}
    for s in sc.segments:
        owner = s.owner if s.kind == "body" else ""
        g = groups.setdefault(
            (s.kind, owner), {"kind": s.kind, "owner": owner, "colour": segment_colour(sc, s.kind, owner), "lines": []}
        )
        g["lines"].append([_xyz(s.start), _xyz(s.end)])
    return {
        "name": sc.name,
        "unit": sc.unit,
        "segments": list(groups.values()),
        "markers": [
            {
                "joint": m.joint,
                "kind": m.kind,
                "symbol": MARKERS[m.kind][1],
                "label": MARKERS[m.kind][2],
                "at": _xyz(m.position),
            }
            for m in sc.markers
        ],
        "axes": [
            {
                "joint": a.joint,
                "label": a.label,
                "colour": AXIS[a.label],
                "origin": _xyz(a.origin),
                "direction": _xyz(a.direction),
            }
            for a in sc.axes
        ],
        "points": {k: _xyz(v) for k, v in sc.points.items()},
        "point_colour": POINT,
        "scale": scale([sc]),
    }


def _coordinate_components(model: Model) -> list[dict[str, Any]]:
    """Every joint coordinate a sweep can drive (not Euler parameters), in model units."""
    deg = model.units.get("angle") == "deg"
    size = scale([build_scene(model)])
    out = []
    for joint, q in model.coordinates.items():
        q = np.atleast_1d(np.asarray(q, dtype=float))
        jt = model.mechanism.joint(joint).jtype
        angles = set(angle_indices(model, joint))
        euler = (
            set(range(jt.euler.start, jt.euler.stop)) if jt.euler is not None and q.size == jt.n_coordinates else set()
        )
        for k in range(q.size):
            if k in euler:
                continue
            angle = k in angles
            value = math.degrees(q[k]) if angle and deg else float(q[k])
            unit = ("deg" if deg else "rad") if angle else model.units.get("length", "")
            if angle:
                half, wide = (CURVE_DEG, SLIDER_DEG) if deg else (math.radians(CURVE_DEG), math.radians(SLIDER_DEG))
            else:
                half, wide = CURVE_FRACTION * size, SLIDER_FRACTION * size
            spec = joint if q.size == 1 else f"{joint}[{k}]"
            out.append(
                {
                    "spec": spec,
                    "address": f"{joint}.q" if q.size == 1 else f"{joint}.q[{k}]",
                    "joint": joint,
                    "type": jt.name,
                    "angle": angle,
                    "unit": unit,
                    "value": value,
                    "curve": [value - half, value + half],
                    "slider": [value - wide, value + wide],
                    "slider_ok": q.size == 1 and jt.n_coordinates == 1,  # one coordinate: revolute, translational
                    "size": q.size,
                }
            )
    # single coordinates first: a sweep drives a joint's whole coordinate vector (the others
    # of a multi-coordinate joint stay as they are); a suspension's wheel travel before them
    return _travel_drive(model) + sorted(out, key=lambda c: (not c["slider_ok"], c["size"] > 1))


def _travel_drive(model: Model) -> list[dict[str, Any]]:
    """The wheel-travel drive (``travel``, kinprop.analysis.drives) of a model whose wheels have
    a ``wheel_centre_ref``: a sweep in equal length steps, +-50 mm by default."""
    if not has_travel(model):
        return []
    length = model.units.get("length", "m")
    half = TRAVEL_CURVE_M / METRES_PER.get(length, 1.0)
    return [{"spec": "travel", "address": "travel", "joint": "", "type": "wheel travel", "angle": False,
             "unit": length, "value": 0.0, "curve": [-half, half], "slider": [-half, half], "slider_ok": False,
             "size": 1}]  # fmt: skip


def default_curve_outputs(model: Model, drives: list[dict[str, Any]]) -> list[str]:
    """Camber and toe of the first wheel body; else the other single coordinates (a four-bar's
    rocker angle over its crank's), else a named point's or a hardpoint's z."""
    metrics = [m for m in metric_names(model) if m.endswith((".camber", ".toe"))]
    if metrics:
        return metrics[:2]
    others = [d["address"] for d in drives[1:] if d["size"] == 1]
    if others:
        return others[:2]
    pts = [f"point:{b.name}.{p}[z]" for b in model.mechanism.bodies if not b.fixed for p, _ in b.points]
    if pts:
        return pts[:1]
    return [f"hardpoint:{j.name}.j[z]" for j in model.mechanism.joints][:1]


def variables_json(model: Model, session: Session) -> list[dict[str, Any]]:
    """One row per design variable: address, group, body, unit, value (before, when the last
    change moved it) and, for a joint point ``s``, where it is in global coordinates."""
    length = model.units.get("length", "")
    last = session.last
    changed = set(last.changed_variables()) if last is not None else set()
    set_keys = {k.split("[")[0] for k in last.changes} if last is not None else set()
    hardpoints = joint_hardpoints(model)
    rows = []
    for key, v in model.design.items():
        joint, _, fld = key.partition(".")
        if fld == "coef":  # a coupling's coefficients: no body, the coupling's units
            role = "set" if key in set_keys else ("moved" if key in changed else "")
            rows.append({"address": key, "group": "coef", "joint": joint, "body": "", "unit": unit_of(model, key),
                         "value": _xyz(from_solver_units(model, key, v)), "before": None, "role": role,
                         "global": None})  # fmt: skip
            continue
        j = model.mechanism.joint(joint)
        group = GROUPS.get(fld, fld)
        body = j.body_i if fld.endswith("_i") else j.body_j if fld.endswith("_j") else ""
        before = None
        if last is not None and key in changed:
            before = _xyz(last.before.design[key])
        rows.append(
            {
                "address": key,
                "group": group,
                "joint": joint,
                "body": body,
                "unit": "" if group == "C" else length,
                "value": _xyz(v),
                "before": before,
                "role": "set" if key in set_keys else ("moved" if key in changed else ""),
                "global": hardpoints.get(f"{joint}.{fld[-1]}") if group == "s" else None,
            }
        )
    return rows


def state_json(session: Session, label: str) -> dict[str, Any]:
    """Everything the page draws for the session's current model."""
    model = session.model
    last = session.last
    scenes = [build_scene(model)]
    if last is not None:
        scenes.append(build_scene(last.before))
    lo, hi = bounds(scenes)
    comps = _coordinate_components(model)
    res = session.result_json
    return {
        "model": label,
        "name": model.mechanism.name,
        "units": dict(model.units),
        "variables": variables_json(model, session),
        "coordinates": {k: _xyz(v) for k, v in model.coordinates.items()},
        "hardpoints": joint_hardpoints(model),
        "points": named_points(model),
        "sliders": [c for c in comps if c["slider_ok"]],
        "drives": comps,
        "outputs": output_names(model),
        "default_outputs": default_curve_outputs(model, comps),
        "scene": scene_json(scenes[0]),
        "before_scene": scene_json(scenes[1]) if last is not None else None,
        "bounds": [_xyz(lo), _xyz(hi)],
        "faded_alpha": FADED_ALPHA,
        "changed": last.changed_variables() if last is not None else [],
        "changes": list(last.changes) if last is not None else [],
        "history": {"undo": len(session.undo_stack), "redo": len(session.redo_stack)},
        "result": None
        if res is None
        else {k: res.get(k) for k in ("status", "iterations", "residual", "message", "changed", "free")},
        "warnings": list(session.warnings),
    }
