"""Compact summaries of a :class:`~kinprop.propagation.propagate.Propagation`: its ``repr``
in a REPL and its HTML table in a notebook, and the before/after rows the CLI's tables and
CSV are built from (values in the model's units, docs/units.md)."""

from __future__ import annotations

from collections.abc import Mapping
from html import escape
from typing import Any, Protocol

import numpy as np

from kinprop.engine import Engine
from kinprop.engine import compile as compile_engine
from kinprop.model import Model
from kinprop.propagation.units import address_unit, from_solver_units
from kinprop.solver import SolveResult
from kinprop.spatial import log_so3


class Propagation(Protocol):
    """What a summary reads of a :class:`kinprop.propagation.propagate.Propagation` (which
    imports this module for its ``repr``, so this module does not import it)."""

    before: Model
    after: Model
    result: SolveResult
    free: tuple[str, ...]
    solver_changes: Mapping[str, Any]
    engine: Engine | None

    def changed_variables(self, atol: float = 0.0) -> list[str]: ...


def variable_rows(prop: Propagation) -> list[dict[str, Any]]:
    """One row per variable: before and after values, their unit, role, max change.

    Values in the model's units (docs/units.md); ``C`` variables report the rotation angle of
    after relative to before, in the model's angle unit.
    """
    asm = prop.engine or compile_engine(prop.before.mechanism)
    layout = asm.layout
    st_before, st_after = asm.state_of(prop.before), asm.state_of(prop.after)
    changed = set(prop.changed_variables())
    set_keys = {k.split("[")[0] for k in prop.solver_changes}
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
        b = from_solver_units(model, v.key, asm.get(st_before, v.key), asm)
        a = from_solver_units(model, v.key, asm.get(st_after, v.key), asm)
        unit = address_unit(model, v.key, asm)
        change = float(np.max(np.abs(a - b))) if a.size else 0.0
        rows.append(
            {"variable": v.key, "unit": unit, "before": b.tolist(), "after": a.tolist(), "change": change, "role": role}
        )
    return rows


#: moved variables listed by a summary before it says "... and N more"
SUMMARY_ROWS = 8


#: a shown number this small against the largest of its row or column is round-off, shown as 0
ROUND_OFF = 1e-10
#: ... and so is one below this, in the model's units (1e-12 m, mm, rad or deg)
ROUND_OFF_ABS = 1e-12


def shown(value: float, scale: float = 0.0, digits: int = 6) -> str:
    """``value`` for a table or a summary: ``digits`` significant digits, round-off (below
    :data:`ROUND_OFF` times ``scale``, the largest magnitude beside it, or :data:`ROUND_OFF_ABS`)
    as ``0`` and never ``-0``; NaN as an empty string. Files keep the full values."""
    if value != value:
        return ""
    if abs(value) <= max(ROUND_OFF_ABS, ROUND_OFF * abs(scale)):
        value = 0.0
    text = f"{value:.{digits}g}"
    return "0" if text == "-0" else text


def _short(values: list[float], unit: str = "") -> str:
    """``[a, b, c]`` (one value: ``a``); a vector with mixed units (``m,m,m,,,,`` of a free
    joint) carries each component's unit, ``[0.01 m, 0, 0.4 m, 1, 0, 0, 0]``."""
    scale = max((abs(x) for x in values if x == x), default=0.0)
    units = unit.split(",") if "," in unit else [""] * len(values)
    text = ", ".join(f"{shown(x, scale)} {u}".rstrip() for x, u in zip(values, units, strict=True))
    return text if len(values) == 1 else f"[{text}]"


def unit_text(unit: str) -> str:
    """A unit for a ``unit`` column: mixed units of a vector per component (``[m, m, m, -, -, -, -]``)."""
    return f"[{', '.join(u or '-' for u in unit.split(','))}]" if "," in unit else unit


def summary_text(prop: Propagation) -> str:
    """A compact ``repr`` of a propagation for a notebook or a REPL (a few lines, not a dump):
    status, iterations, ``||Phi||``, the changes and the variables that moved most."""
    r = prop.result
    name = prop.before.mechanism.name
    rows = [row for row in variable_rows(prop) if row["role"]]
    rows.sort(key=lambda row: (row["role"] != "set", -row["change"]))
    lines = [
        f"<Propagation of {name!r}: {r.status} in {r.iterations} iterations, ||Phi|| = {r.residual:.3g};"
        f" free: {' '.join(prop.free)}>"
    ]
    for row in rows[:SUMMARY_ROWS]:
        u = row["unit"]
        before, after = (_short(row[k], u) for k in ("before", "after"))
        unit = f" {u}" if u and "," not in u else ""  # mixed units: on each component
        lines.append(f"  {row['role']:>5} {row['variable']}: {before} -> {after}{unit}")
    if len(rows) > SUMMARY_ROWS:
        lines.append(f"  ... and {len(rows) - SUMMARY_ROWS} more moved variables (prop.changed_variables())")
    return "\n".join(lines)


def summary_html(prop: Propagation) -> str:
    """``_repr_html_`` of a propagation: the status line and a before/after table of the set
    and moved variables (every one; values escaped)."""
    r = prop.result
    head = (
        f"<p><b>Propagation</b> of {escape(prop.before.mechanism.name)}: {escape(r.status)} in {r.iterations} "
        f"iterations, ||Phi|| = {r.residual:.3g}; free: {escape(' '.join(prop.free))}</p>"
    )
    cells = "".join(
        "<tr>"
        + "".join(
            f"<td>{escape(str(x))}</td>"
            for x in (row["role"], row["variable"], unit_text(row["unit"]), _short(row["before"]), _short(row["after"]))
        )
        + f"<td>{row['change']:.3g}</td></tr>"
        for row in variable_rows(prop)
        if row["role"]
    )
    header = "".join(f"<th>{h}</th>" for h in ("role", "variable", "unit", "before", "after", "max |change|"))
    return f"{head}<table><thead><tr>{header}</tr></thead><tbody>{cells}</tbody></table>"


__all__ = ["SUMMARY_ROWS", "shown", "summary_html", "summary_text", "unit_text", "variable_rows"]
