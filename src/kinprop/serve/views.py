"""The page's view of a session: design-variable table, coordinates, sliders, scene (JSON).

The page's own endpoint (``GET /api/state``); the CLI contracts are in :mod:`kinprop.serve.api`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import scipy.linalg

from kinprop.analysis.metrics import metric_names, wheel_bodies
from kinprop.analysis.outputs import output_names
from kinprop.analysis.points import joint_hardpoints, named_points, snapshot
from kinprop.analysis.units import unit_of
from kinprop.engine import compile as compile_engine
from kinprop.engine.units import angle_indices, from_solver_units
from kinprop.errors import AddressError
from kinprop.model import Model
from kinprop.propagation.hardpoints import parse_global, pivots
from kinprop.plot.scene import Scene, bounds, build_scene, scale
from kinprop.plot.style import AXIS, FADED_ALPHA, MARKERS, POINT, segment_colour
from kinprop.serve.session import Session

GROUPS = {"s_i": "s", "s_j": "s", "C_i": "C", "C_j": "C", "length": "l"}
#: slider half-range: angles [deg], lengths [fraction of the mechanism's size]
SLIDER_DEG, SLIDER_FRACTION = 45.0, 0.25
#: default half-range of a curve's drive
CURVE_DEG, CURVE_FRACTION = 10.0, 0.05


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


#: a coordinate counts as independent when its row of the Jacobian's null-space basis is this large
INDEPENDENT_TOL = 1e-8


def slider_joints(model: Model) -> tuple[str, ...]:
    """The joints the page offers a slider for: the declared inputs (``inputs:``) with one
    coordinate; without declared inputs, as many single-coordinate joints as the mechanism has
    degrees of freedom, chosen so that each can be set independently (a column-pivoted QR of the
    rows of a null-space basis of ``Phi_q``): a dependent coordinate (a double wishbone's upper
    arm angle, fixed by the lower one) is never offered."""
    mech = model.mechanism
    single = [j.name for j in mech.joints if j.name in model.coordinates and j.jtype.n_coordinates == 1]
    if mech.inputs:
        return tuple(j for j in mech.inputs if j in single)
    if not single:
        return ()
    asm = compile_engine(model)
    _, J = asm.evaluate(model.design, model.coordinates)
    cols = asm.layout.columns(["q", "inputs"])
    null = scipy.linalg.null_space(J[:, cols]) if J.shape[0] else np.eye(len(cols))
    if null.shape[1] == 0:
        return ()
    row = {c: k for k, c in enumerate(cols)}
    cand = [j for j in single if asm.layout[f"{j}.q"].start in row]
    rows = null[[row[asm.layout[f"{j}.q"].start] for j in cand]]
    _, R, piv = scipy.linalg.qr(rows.T, mode="economic", pivoting=True)
    d = np.abs(np.diag(R))
    chosen = {cand[p] for p, r in zip(piv, d, strict=False) if r > INDEPENDENT_TOL}
    return tuple(j for j in single if j in chosen)


def _coordinate_components(model: Model, sliders: tuple[str, ...] = ()) -> list[dict[str, Any]]:
    """Every joint coordinate a sweep can drive (not Euler parameters), in model units;
    ``slider_ok`` for the ``sliders`` joints (:func:`slider_joints`)."""
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
                    "slider_ok": q.size == 1 and joint in sliders,
                    "size": q.size,
                }
            )
    # inputs first, then single coordinates: a sweep drives a joint's whole coordinate vector
    # (the others of a multi-coordinate joint stay as they are)
    return sorted(out, key=lambda c: (not c["slider_ok"], c["size"] > 1))


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


#: the design table's hardpoint sections, in the order a suspension designer reads them
SECTIONS = ("chassis pickups", "upright points", "links and steering", "spring and damper", "wheel")


def hardpoint_rows(model: Model) -> list[dict[str, Any]]:
    """The global hardpoints, by section (:data:`SECTIONS`): each joint's ``hardpoint:``
    addresses that an edit accepts (a revolute's two chassis pivots, a ball joint, a link's
    two ends), in the model's length unit, then the force elements' ends and the moving bodies'
    named points (read-only: ``address`` None). An edit of a row is ``kinprop propagate --set
    ADDRESS=x,y,z`` with the file's reading of hardpoint edits (``edits:``)."""
    mech = model.mechanism
    asm = compile_engine(model)
    snap = snapshot(model, asm)
    fixed = {b.name for b in mech.bodies if b.fixed}
    hp = joint_hardpoints(model)
    rows: list[dict[str, Any]] = []

    def valid(address: str) -> bool:
        try:
            parse_global(asm, address)
        except AddressError:
            return False
        return True

    for j in mech.joints:
        piv = pivots(asm, j.name)
        if piv is not None:
            for name, p in piv[1].items():
                rows.append({"section": SECTIONS[0], "label": f"{j.name} {name} pivot", "address": f"hardpoint:{j.name}.{name}",
                             "body": (j.body_i, j.body_j)[piv[0]], "value": _xyz(p)})  # fmt: skip
            continue
        on_fixed = [b in fixed for b in (j.body_i, j.body_j)]
        if j.jtype.name == "distance" or not valid(f"hardpoint:{j.name}"):
            for k, side in enumerate("ij"):
                address = f"hardpoint:{j.name}.{side}"
                if not valid(address):
                    continue
                body = (j.body_i, j.body_j)[k]
                section = SECTIONS[0] if on_fixed[k] else SECTIONS[2]
                end = "inner" if on_fixed[k] else "outer" if any(on_fixed) else ("i", "j")[k]
                rows.append({"section": section, "label": f"{j.name} {end} ({body})", "address": address,
                             "body": body, "value": hp[f"{j.name}.{side}"]})  # fmt: skip
            continue
        section = SECTIONS[0] if any(on_fixed) else SECTIONS[1]
        rows.append({"section": section, "label": f"{j.name} ({j.jtype.name})", "address": f"hardpoint:{j.name}",
                     "body": f"{j.body_i}/{j.body_j}", "value": hp[f"{j.name}.i"]})  # fmt: skip
    for e in model.elements:
        for k, (body, p) in enumerate(((e.body_i, e.s_i), (e.body_j, e.s_j))):
            g = snap.r[body] + snap.A[body] @ np.asarray(p, dtype=float)
            rows.append({"section": SECTIONS[3], "label": f"{e.name} {('i', 'j')[k]} ({body})", "address": None,
                         "body": body, "value": _xyz(g)})  # fmt: skip
    points = named_points(model)
    for b in mech.bodies:
        if b.fixed:
            continue
        for name, _ in b.points:
            if b.joint_point(name) is None:
                rows.append({"section": SECTIONS[4], "label": f"{b.name}.{name}", "address": None, "body": b.name,
                             "value": points[f"{b.name}.{name}"]})  # fmt: skip
    order = {s: k for k, s in enumerate(SECTIONS)}
    return sorted(rows, key=lambda r: order[r["section"]])  # stable: joint order inside a section


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
    comps = _coordinate_components(model, sliders)
    res = session.result_json
    return {
        "model": label,
        "name": model.mechanism.name,
        "units": dict(model.units),
        "variables": variables_json(model, session),
        "hardpoint_style": hardpoint_style,
        "hardpoint_rows": hardpoint_rows(model),
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
