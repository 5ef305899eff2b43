"""Result records shared by the CLI's tables, JSON and CSV outputs."""

from __future__ import annotations

from typing import Any

import numpy as np

from kinprop.analysis.points import joint_hardpoints, named_points
from kinprop.engine import compile as compile_engine
from kinprop.io.units import from_solver_units, unit_of
from kinprop.propagation.propagate import Propagation
from kinprop.spatial import log_so3


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
        "residual_norm": r.residual_norm,
        "residual_history": list(r.residual_history),
        "coordinates": coordinates_json(prop.after),
        "design": design_json(prop.after),
        "message": r.message,
        "warnings": prop.notes,
        "fraction": r.fraction,
        "rank": r.rank,
        "free": list(prop.free),
        "changes": {k: _num(from_solver_units(prop.before, k, v)) for k, v in prop.changes.items()},
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
    """Every joint's relative value, cut joints included (radians, model length unit)."""
    return {j: {k: _num(v) for k, v in vals.items()} for j, vals in prop.joint_values.items()}


def variable_rows(prop: Propagation) -> list[dict[str, Any]]:
    """One row per variable: before and after values, their unit, role, max change.

    Values in the model's units (docs/units.md); ``C`` variables report the rotation angle of
    after relative to before, in the model's angle unit.
    """
    asm = prop.engine or compile_engine(prop.before.mechanism)
    layout = asm.layout
    st_before, st_after = asm.state_of(prop.before), asm.state_of(prop.after)
    changed = set(prop.changed_variables())
    set_keys = {k.split("[")[0] for k in prop.changes}
    model = prop.before
    angle = model.units.get("angle", "rad")
    rows: list[dict[str, Any]] = []
    for v in layout.variables:
        role = "set" if v.key in set_keys else ("moved" if v.key in changed else "")
        if v.group == "C":
            Cb, Ca = prop.before.design[v.key], prop.after.design[v.key]
            ang = 0.0 if np.array_equal(Ca, Cb) else float(np.linalg.norm(log_so3(Ca @ Cb.T)))
            ang = float(np.degrees(ang)) if angle == "deg" else ang
            rows.append(
                {"variable": v.key, "unit": angle, "before": [0.0], "after": [ang], "change": ang, "role": role}
            )
            continue
        b = from_solver_units(model, v.key, asm.get(st_before, v.key))
        a = from_solver_units(model, v.key, asm.get(st_after, v.key))
        unit = unit_of(model, v.key)
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


#: moved variables listed by a summary before it says "... and N more"
SUMMARY_ROWS = 8


def _short(values: list[float]) -> str:
    text = ", ".join(f"{x:.6g}" for x in values)
    return text if len(values) == 1 else f"[{text}]"


def summary_text(prop: Propagation) -> str:
    """A compact ``repr`` of a propagation for a notebook or a REPL (a few lines, not a dump):
    status, iterations, ``||Phi||``, the changes and the variables that moved most."""
    r = prop.result
    name = prop.before.mechanism.name
    rows = [row for row in variable_rows(prop) if row["role"]]
    rows.sort(key=lambda row: (row["role"] != "set", -row["change"]))
    lines = [
        f"<Propagation of {name!r}: {r.status} in {r.iterations} iterations, ||Phi|| = {r.residual_norm:.3g};"
        f" free: {' '.join(prop.free)}>"
    ]
    for row in rows[:SUMMARY_ROWS]:
        unit = f" {row['unit']}" if row["unit"] else ""
        lines.append(f"  {row['role']:>5} {row['variable']}: {_short(row['before'])} -> {_short(row['after'])}{unit}")
    if len(rows) > SUMMARY_ROWS:
        lines.append(f"  ... and {len(rows) - SUMMARY_ROWS} more moved variables (prop.changed_variables())")
    return "\n".join(lines)


def summary_html(prop: Propagation) -> str:
    """``_repr_html_`` of a propagation: the status line and a before/after table of the set
    and moved variables (every one; values escaped)."""
    from html import escape

    r = prop.result
    head = (
        f"<p><b>Propagation</b> of {escape(prop.before.mechanism.name)}: {escape(r.status)} in {r.iterations} "
        f"iterations, ||Phi|| = {r.residual_norm:.3g}; free: {escape(' '.join(prop.free))}</p>"
    )
    cells = "".join(
        "<tr>"
        + "".join(
            f"<td>{escape(str(x))}</td>"
            for x in (row["role"], row["variable"], row["unit"], _short(row["before"]), _short(row["after"]))
        )
        + f"<td>{row['change']:.3g}</td></tr>"
        for row in variable_rows(prop)
        if row["role"]
    )
    header = "".join(f"<th>{h}</th>" for h in ("role", "variable", "unit", "before", "after", "max |change|"))
    return f"{head}<table><thead><tr>{header}</tr></thead><tbody>{cells}</tbody></table>"
