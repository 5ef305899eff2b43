"""Result records shared by the CLI's tables, JSON and CSV outputs."""

from __future__ import annotations

from typing import Any

import numpy as np

from kinprop.analysis.points import joint_hardpoints, named_points
from kinprop.engine import compile as compile_engine
from kinprop.propagation.propagate import Propagation
from kinprop.spatial import log_so3


def _num(v: np.ndarray) -> float | list[float]:
    v = np.asarray(v, dtype=float)
    return float(v) if v.ndim == 0 or (v.size == 1 and v.ndim == 0) else v.ravel().tolist()


def design_json(model) -> dict[str, Any]:
    """Every design variable: floats for lengths, lists for s' and C (row-major 9 numbers)."""
    out: dict[str, Any] = {}
    for k, v in model.design.items():
        a = np.asarray(v, dtype=float)
        out[k] = float(a) if a.ndim == 0 else a.ravel().tolist()
    return out


def coordinates_json(model) -> dict[str, list[float]]:
    """Joint coordinates in radians and model length units."""
    return {k: np.asarray(v, dtype=float).tolist() for k, v in model.coordinates.items()}


def propagation_json(prop: Propagation) -> dict[str, Any]:
    """The solve, the resulting coordinates and design, and where the joints sit afterwards:
    ``hardpoints`` (``"JOINT.i"``/``"JOINT.j"`` -> global [x, y, z], see
    :func:`kinprop.analysis.points.joint_hardpoints`), ``points`` (named body points),
    ``bodies`` (global poses) and ``joint_values`` (:mod:`kinprop.propagation.poses`)."""
    r = prop.result
    return {
        "status": r.status,
        "iterations": r.iterations,
        "residual_norm": r.residual_norm,
        "residual_history": list(r.residual_history),
        "coordinates": coordinates_json(prop.after),
        "design": design_json(prop.after),
        "message": r.message,
        "warnings": prop.notes,
        "fraction": r.fraction,
        "rank": r.rank,
        "free": list(prop.free),
        "changes": {k: _num(v) for k, v in prop.changes.items()},
        "changed": prop.changed_variables(),
        "hardpoints": joint_hardpoints(prop.after),
        "points": named_points(prop.after),
        "bodies": bodies_json(prop),
        "joint_values": joint_values_json(prop),
    }


def bodies_json(prop: Propagation) -> dict[str, dict[str, Any]]:
    """Every body's global pose after the propagation: ``{BODY: {"R": 3x3 rows, "t": [x, y, z]}}``."""
    return {b: {"R": p["R"].tolist(), "t": p["t"].tolist()} for b, p in prop.bodies.items()}


def joint_values_json(prop: Propagation) -> dict[str, dict[str, Any]]:
    """Every joint's relative value, cut joints included (radians, model length unit)."""
    return {j: {k: _num(v) for k, v in vals.items()} for j, vals in prop.joint_values.items()}


def variable_rows(prop: Propagation) -> list[dict[str, Any]]:
    """One row per variable: before and after values (angles in degrees), role, max change.

    ``C`` variables report the rotation angle [deg] of after relative to before.
    """
    asm = prop.engine or compile_engine(prop.before.mechanism)
    layout = asm.layout
    st_before, st_after = asm.state_of(prop.before), asm.state_of(prop.after)
    changed = set(prop.changed_variables())
    set_keys = {k.split("[")[0] for k in prop.changes}
    rows: list[dict[str, Any]] = []
    for v in layout.variables:
        role = "set" if v.key in set_keys else ("moved" if v.key in changed else "")
        if v.group == "C":
            Cb, Ca = prop.before.design[v.key], prop.after.design[v.key]
            ang = 0.0 if np.array_equal(Ca, Cb) else float(np.degrees(np.linalg.norm(log_so3(Ca @ Cb.T))))
            rows.append(
                {"variable": v.key, "unit": "deg", "before": [0.0], "after": [ang], "change": ang, "role": role}
            )
            continue
        b = asm.get(st_before, v.key)
        a = asm.get(st_after, v.key)
        unit = ""
        if v.group == "q" and v.joint in asm.topology.tree_joints:
            idx = list(prop.before.mechanism.joint(v.joint).jtype.angle_indices)
            if idx:
                b[idx], a[idx] = np.degrees(b[idx]), np.degrees(a[idx])
                unit = "deg" if len(idx) == v.size else "deg/len"
        change = float(np.max(np.abs(a - b))) if a.size else 0.0
        rows.append(
            {"variable": v.key, "unit": unit, "before": b.tolist(), "after": a.tolist(), "change": change, "role": role}
        )
    return rows


def comparison_rows(prop: Propagation) -> list[dict[str, Any]]:
    """Flat rows (one per scalar) of :func:`variable_rows`, for CSV export."""
    out = []
    for row in variable_rows(prop):
        n = len(row["after"])
        for k in range(n):
            comp = row["variable"] if n == 1 else f"{row['variable']}[{k}]"
            b, a = row["before"][k], row["after"][k]
            out.append(
                {"variable": comp, "unit": row["unit"], "before": b, "after": a, "change": a - b, "role": row["role"]}
            )
    return out


def point_rows(prop: Propagation) -> list[dict[str, Any]]:
    """Before/after of every joint hardpoint (``hardpoint:JOINT.i[x]``) and named point
    (``point:BODY.NAME[x]``), one row per component, in the model's length unit."""
    unit = prop.before.units.get("length", "")
    out: list[dict[str, Any]] = []
    for prefix, fn in (("hardpoint", joint_hardpoints), ("point", named_points)):
        before, after = fn(prop.before), fn(prop.after)
        for key, a in after.items():
            for k, axis in enumerate("xyz"):
                b = before[key][k]
                out.append(
                    {
                        "variable": f"{prefix}:{key}[{axis}]",
                        "unit": unit,
                        "before": b,
                        "after": a[k],
                        "change": a[k] - b,
                        "role": prefix,
                    }
                )
    return out
