"""The page's view of a session: design-variable table, coordinates, sliders, scene (JSON).

The page's own endpoint (``GET /api/state``); the CLI contracts are in :mod:`kinprop.serve.api`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from kinprop.analysis.context import find_point
from kinprop.analysis.metrics import wheel_bodies
from kinprop.analysis.outputs import output_names
from kinprop.analysis.points import hardpoint_table, joint_hardpoints, named_points
from kinprop.analysis.units import unit_of
from kinprop.engine.units import METRES_PER, from_solver_units
from kinprop.model import Model
from kinprop.plot.report import coordinate_components, default_curve_outputs
from kinprop.plot.scene import Scene, bounds, build_scene, scale
from kinprop.plot.style import AXIS, FADED_ALPHA, MARKERS, POINT, segment_colour
from kinprop.serve.session import Session

GROUPS = {"s_i": "s", "s_j": "s", "C_i": "C", "C_j": "C", "length": "l"}


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


def wheels_json(model: Model) -> dict[str, Any]:
    """What the views draw of each wheel body (one with ``wheel_centre`` and ``spin_axis``
    points): its centre, unit spin axis and loaded radius (the ``contact_patch`` point's distance
    from the spin axis, None without one), global, model units; and the ground plane's height,
    the lowest contact patch's z (ISO 8855: z up), or None without a contact patch."""
    points = named_points(model)
    wheels, ground = [], None
    for w in wheel_bodies(model):
        c = np.asarray(points[f"{w}.wheel_centre"])
        a = np.asarray(points[f"{w}.spin_axis"]) - c
        a = a / np.linalg.norm(a)
        radius = None
        if f"{w}.contact_patch" in points:
            p = np.asarray(points[f"{w}.contact_patch"])
            v = p - c
            radius = float(np.linalg.norm(v - (v @ a) * a))
            ground = float(p[2]) if ground is None else min(ground, float(p[2]))
        wheels.append({"body": w, "centre": _xyz(c), "axis": _xyz(a), "radius": radius})
    return {"wheels": wheels, "ground": ground}


def _value_text(v: Any) -> str:
    if isinstance(v, list | tuple):
        return "[" + ", ".join(f"{float(x):.7g}" for x in v) + "]"
    return f"{float(v):.7g}" if isinstance(v, float | int) else str(v)


def status_text(changes: dict[str, Any], result: dict[str, Any]) -> str:
    """The status line of an applied change: what was set (model units, as asked), the solve,
    what moved; without changes, the loaded model's assembly."""
    what = ", ".join(f"{a} = {_value_text(v)}" for a, v in changes.items()) or "loaded"
    residual = result.get("residual")
    parts = [
        f"{what}: {result.get('status')}",
        f"{result.get('iterations')} iterations",
        "||Phi|| = " + ("nan" if residual is None or residual != residual else f"{residual:.3e}"),
    ]
    if result.get("changed"):
        parts.append("moved: " + " ".join(result["changed"]))
    return "  ·  ".join(parts)


#: the wheel-travel drive's default curve: +-50 mm, in the model's length unit
TRAVEL_CURVE_M = 0.05


def travel_drive(model: Model) -> list[dict[str, Any]]:
    """The wheel-travel drive (``travel``, :mod:`kinprop.analysis.drives`: equal length steps of
    the wheel centres' height over their ``wheel_centre_ref``, both wheels of an axle in heave)
    of a suspension whose wheels have that reference, as a drive entry of the page; else none."""
    wheels = wheel_bodies(model)
    if not wheels or not all(find_point(model, w, "wheel_centre_ref", on_wheel=False) for w in wheels):
        return []
    length = model.units.get("length", "m")
    half = TRAVEL_CURVE_M / METRES_PER.get(length, 1.0)
    return [{"spec": "travel", "address": "travel", "joint": "", "type": "wheel travel", "angle": False,
             "unit": length, "value": 0.0, "curve": [-half, half], "slider": [-half, half], "slider_ok": False,
             "size": 1}]  # fmt: skip


def state_json(
    session: Session, label: str, sliders: tuple[str, ...] = (), hardpoint_style: bool = False
) -> dict[str, Any]:
    """Everything the page draws for the session's current model."""
    model = session.model
    last = session.last
    scenes = [build_scene(model)]
    if last is not None:
        scenes.append(build_scene(last.before))
    lo, hi = bounds(scenes)
    comps = travel_drive(model) + coordinate_components(model, sliders)  # a suspension's default: wheel travel
    res = session.result_json
    return {
        "model": label,
        "name": model.mechanism.name,
        "units": dict(model.units),
        "variables": variables_json(model, session),
        "hardpoint_style": hardpoint_style,
        "hardpoint_rows": hardpoint_table(model),
        "status_line": session.status_line(),
        "coordinates": {k: _xyz(v) for k, v in model.coordinates.items()},
        "hardpoints": joint_hardpoints(model),
        "points": named_points(model),
        "sliders": [c for c in comps if c["slider_ok"]],
        "drives": comps,
        "outputs": output_names(model),
        "default_outputs": default_curve_outputs(model, comps),
        "scene": scene_json(scenes[0]),
        **wheels_json(model),
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
