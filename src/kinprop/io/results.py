"""Result records shared by the CLI's tables, JSON and CSV outputs."""

from __future__ import annotations

from typing import Any

import numpy as np

from kinprop.analysis.points import joint_hardpoints, named_points
from kinprop.analysis.units import unit_of
from kinprop.engine.units import from_solver_units
from kinprop.propagation.propagate import Propagation, summary_html, summary_text, variable_rows


def _num(v: np.ndarray) -> float | list[float]:
    v = np.asarray(v, dtype=float)
    return float(v) if v.ndim == 0 or (v.size == 1 and v.ndim == 0) else v.ravel().tolist()


def design_json(model) -> dict[str, Any]:
    """Every design variable: floats for lengths, lists for s' and C (row-major 9 numbers),
    coupling coefficients in the model's units."""
    out: dict[str, Any] = {}
    for k, v in model.design.items():
        a = from_solver_units(model, k, np.asarray(v, dtype=float))
        out[k] = float(a) if a.ndim == 0 else a.ravel().tolist()
    return out


def coordinates_json(model) -> dict[str, list[float]]:
    """Joint coordinates in the model's units (angles in ``units.angle``; docs/units.md)."""
    return {k: from_solver_units(model, f"{k}.q", v).tolist() for k, v in model.coordinates.items()}


def units_json(model) -> dict[str, Any]:
    """The ``units`` object of every JSON output: the model's length and angle units, and the
    unit of each joint coordinate component (``deg``/``rad``, the length unit, or ``""`` for
    Euler parameters)."""
    coords = {
        k: [unit_of(model, f"{k}.q[{i}]") for i in range(np.asarray(v).size)] for k, v in model.coordinates.items()
    }
    return {
        "length": model.units.get("length", "m"),
        "angle": model.units.get("angle", "rad"),
        "coordinates": coords,
        "design": "s_i, s_j, length in the length unit; C_i, C_j rotation matrices (no unit); COUPLING.coef c_k "
        "in [q_a]/[q_b]^k",
    }


def propagation_json(prop: Propagation) -> dict[str, Any]:
    """The solve, the resulting coordinates and design, and where the joints sit afterwards:
    ``hardpoints`` (``"JOINT.i"``/``"JOINT.j"`` -> global [x, y, z], see
    :func:`kinprop.analysis.points.joint_hardpoints`), ``points`` (named body points),
    ``bodies`` (global poses), ``joint_values`` (:mod:`kinprop.propagation.poses`) and ``units``."""
    r = prop.result
    return {
        "status": r.status,
        "iterations": r.iterations,
        "residual": r.residual,
        "optimality_residual": r.optimality,
        "method": r.method,
        "residual_history": list(r.residual_history),
        "coordinates": coordinates_json(prop.after),
        "design": design_json(prop.after),
        "message": r.message,
        "warnings": prop.notes,
        "fraction": r.fraction,
        "substeps": r.substeps,
        "rank": r.rank,
        "free": list(prop.free),
        "changes": {k: _num(v) for k, v in prop.changes.items()},
        "changed": prop.changed_variables(),
        "hardpoints": joint_hardpoints(prop.after),
        "points": named_points(prop.after),
        "bodies": bodies_json(prop),
        "joint_values": joint_values_json(prop),
        "units": units_json(prop.after),
    }


def bodies_json(prop: Propagation) -> dict[str, dict[str, Any]]:
    """Every body's global pose after the propagation: ``{BODY: {"R": 3x3 rows, "t": [x, y, z]}}``."""
    return {b: {"R": p["R"].tolist(), "t": p["t"].tolist()} for b, p in prop.bodies.items()}


def joint_values_json(prop: Propagation) -> dict[str, dict[str, Any]]:
    """Every joint's relative value, cut joints included, in the model's units (angles in the
    angle unit; :attr:`Propagation.joint_values`)."""
    return {j: {k: _num(v) for k, v in vals.items()} for j, vals in prop.joint_values.items()}


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


__all__ = [
    "bodies_json",
    "comparison_rows",
    "coordinates_json",
    "design_json",
    "joint_values_json",
    "point_rows",
    "propagation_json",
    "summary_html",
    "summary_text",
    "units_json",
    "variable_rows",
]
