"""Result records shared by the CLI's tables, JSON and CSV outputs."""

from __future__ import annotations

from typing import Any

import numpy as np

from kinprop.kinematics.layout import read
from kinprop.propagation.propagate import Propagation, assembly_for
from kinprop.spatial import log_so3


def _num(v: np.ndarray) -> float | list[float]:
    v = np.asarray(v, dtype=float)
    return float(v) if v.ndim == 0 or v.size == 1 and v.ndim == 0 else v.ravel().tolist()


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
    r = prop.result
    return {
        "status": r.status,
        "iterations": r.iterations,
        "residual_norm": r.residual_norm,
        "residual_history": list(r.residual_history),
        "coordinates": coordinates_json(prop.after),
        "design": design_json(prop.after),
        "message": r.message,
        "rank": r.rank,
        "free": list(prop.free),
        "changes": {k: _num(v) for k, v in prop.changes.items()},
        "changed": prop.changed_variables(),
    }


def comparison_rows(prop: Propagation) -> list[dict[str, Any]]:
    """One row per scalar of every variable: before, after, change (angles in degrees)."""
    asm = assembly_for(prop.before.mechanism)
    layout = asm.layout
    changed = set(prop.changed_variables())
    set_keys = {k.split("[")[0] for k in prop.changes}
    rows: list[dict[str, Any]] = []
    for v in layout.variables:
        role = "set" if v.key in set_keys else ("moved" if v.key in changed else "")
        if v.group == "C":
            Cb, Ca = prop.before.design[v.key], prop.after.design[v.key]
            ang = float(np.degrees(np.linalg.norm(log_so3(Ca @ Cb.T))))
            rows.append({"variable": v.key, "component": "rotation [deg]", "before": 0.0, "after": ang, "change": ang, "role": role})
            continue
        b = read(layout, prop.before.design, prop.before.coordinates, v.key)
        a = read(layout, prop.after.design, prop.after.coordinates, v.key)
        angles = set()
        if v.group == "q" and v.joint in asm.topology.tree_joints:
            angles = set(prop.before.mechanism.joint(v.joint).jtype.angle_indices)
        for k in range(v.size):
            unit = ""
            bk, ak = float(b[k]), float(a[k])
            if k in angles:
                bk, ak, unit = np.degrees(bk), np.degrees(ak), " [deg]"
            comp = f"{v.key}[{k}]" if v.size > 1 else v.key
            rows.append({"variable": v.key, "component": comp + unit, "before": bk, "after": ak, "change": ak - bk, "role": role})
    return rows
