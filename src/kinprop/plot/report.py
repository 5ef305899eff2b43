"""What the workbench and the report show of a model by default, and the report itself.

* :func:`slider_joints` — the independent inputs (a slider each), :func:`coordinate_components`
  — every drivable coordinate with its default curve range, :func:`default_curve_outputs`;
* :func:`report_html` — one self-contained HTML file: the hardpoint table and the default
  charts (``kinprop report``, and the workbench's ``report.html`` download).
"""

from __future__ import annotations

import html
import math
from typing import Any

import numpy as np
import scipy.linalg

from kinprop.analysis.context import find_point
from kinprop.analysis.metrics import metric_names, wheel_bodies
from kinprop.analysis.points import hardpoint_table
from kinprop.analysis.sweep import sweep
from kinprop.engine import compile as compile_engine
from kinprop.engine.units import METRES_PER, RADIANS_PER, angle_indices, degrees
from kinprop.io.commands import sweep_inputs, sweep_json
from kinprop.model import Model
from kinprop.plot.scene import build_scene, scale


def _xyz(v: Any) -> list[float]:
    return [float(x) for x in np.asarray(v, dtype=float).ravel()]


#: slider half-range: angles [deg], lengths [fraction of the mechanism's size]
SLIDER_DEG, SLIDER_FRACTION = 45.0, 0.25
#: default half-range of a curve's drive
CURVE_DEG, CURVE_FRACTION = 10.0, 0.05


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


def coordinate_components(model: Model, sliders: tuple[str, ...] = ()) -> list[dict[str, Any]]:
    """Every joint coordinate a sweep can drive (not Euler parameters), in model units;
    ``slider_ok`` for the ``sliders`` joints (:func:`slider_joints`)."""
    deg = degrees(model)
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
            value = float(q[k]) / RADIANS_PER["deg"] if angle and deg else float(q[k])
            unit = ("deg" if deg else "rad") if angle else model.units.get("length", "")
            if angle:
                half, wide = (
                    (CURVE_DEG, SLIDER_DEG)
                    if deg
                    else (CURVE_DEG * RADIANS_PER["deg"], SLIDER_DEG * RADIANS_PER["deg"])
                )
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


#: the wheel-travel drive's default curve: +-50 mm, in the model's length unit
TRAVEL_CURVE_M = 0.05


def travel_drive(model: Model) -> list[dict[str, Any]]:
    """The designer's drives of a suspension whose wheels have a ``wheel_centre_ref``, as drive
    entries of the page (:mod:`kinprop.analysis.drives`): wheel travel (``travel``: equal
    length steps of the wheel centres' height over their reference, both wheels of an axle in
    heave), first; for an axle also body roll (``roll``, +-2 deg) and, when it declares more
    inputs than wheels (a rack), the road-wheel steer angle of its first wheel (``steer:W``,
    +-20 deg). None for other models."""
    wheels = wheel_bodies(model)
    if not wheels or not all(find_point(model, w, "wheel_centre_ref", on_wheel=False) for w in wheels):
        return []
    length = model.units.get("length", "m")
    half = TRAVEL_CURVE_M / METRES_PER.get(length, 1.0)
    out = [_drive_entry("travel", "wheel travel", length, half)]
    angle, per = ("deg", 1.0) if degrees(model) else ("rad", RADIANS_PER["deg"])
    if len(wheels) == 2:
        out.append(_drive_entry("roll", "body roll", angle, ROLL_CURVE_DEG * per))
        if len(model.mechanism.inputs) > len(wheels):
            out.append(_drive_entry(f"steer:{wheels[0]}", "road-wheel steer", angle, STEER_CURVE_DEG * per))
    return out


#: the default half-ranges of the body-roll and road-wheel steer drives, degrees
ROLL_CURVE_DEG, STEER_CURVE_DEG = 2.0, 20.0


def _drive_entry(spec: str, kind: str, unit: str, half: float) -> dict[str, Any]:
    return {"spec": spec, "address": spec, "joint": "", "type": kind, "angle": unit in ("deg", "rad"), "unit": unit,
            "value": 0.0, "curve": [-half, half], "slider": [-half, half], "slider_ok": False, "size": 1}  # fmt: skip


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


def default_curves(model: Model, steps: int = 49) -> dict[str, Any] | None:
    """The default charts' data, over the workbench's default drive: wheel travel for a
    suspension (:func:`travel_drive`), else the first input (:func:`slider_joints`), over its
    default range with :func:`default_curve_outputs`, as ``kinprop sweep --json`` prints it
    (model units); None when the model has no single-coordinate input to drive."""
    comps = travel_drive(model) + coordinate_components(model, slider_joints(model))
    if not comps or comps[0]["size"] != 1:
        return None
    d = comps[0]
    spec = f"{d['spec']}={d['curve'][0]!r}:{d['curve'][1]!r}:{steps}"
    outputs = default_curve_outputs(model, comps)
    drives, _ = sweep_inputs(model, [spec], [])
    obj = sweep_json(sweep(model, drives, outputs=outputs), None)
    obj["drive_spec"] = spec
    return obj


def _cell(x: Any) -> str:
    return (
        ""
        if x is None or (isinstance(x, float) and math.isnan(x))
        else html.escape(repr(x) if isinstance(x, float) else str(x))
    )


def report_html(model: Model, title: str) -> str:
    """One self-contained HTML page (plotly.js inline, no network): the model's global
    hardpoints (:func:`kinprop.analysis.points.hardpoint_table`) and its default charts (:func:`default_curves`), one
    panel per output, with the curves' numbers in a table below (full precision)."""
    import plotly.graph_objects as go
    from plotly.subplots import make_subplots

    unit = model.units.get("length", "")
    parts = [f"<h1>{html.escape(title)}</h1>", f"<p>{html.escape(model.mechanism.name)}; lengths in {unit}</p>"]
    parts.append('<h2>Hardpoints (global)</h2><table id="hardpoints"><tr><th>hardpoint</th><th>address</th>'
                 f"<th>body</th><th>x [{unit}]</th><th>y [{unit}]</th><th>z [{unit}]</th></tr>")  # fmt: skip
    group = None
    for r in hardpoint_table(model):
        if r["group"] != group:
            group = r["group"]
            parts.append(f'<tr class="section"><th colspan="6">{html.escape(str(group))}</th></tr>')
        cells = [r["point"], r["address"] or "", r["body"]]
        parts.append("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in cells)
                     + "".join(f"<td>{_cell(r[c])}</td>" for c in "xyz") + "</tr>")  # fmt: skip
    parts.append("</table>")
    curves = default_curves(model)
    if curves is not None:
        drive, outs, rows, units = curves["drives"][0], curves["outputs"], curves["rows"], curves["units"]
        label = {c: f"{c} [{units[c]}]" if units.get(c) else c for c in [drive, *outs]}
        fig = make_subplots(rows=1, cols=len(outs), subplot_titles=[label[o] for o in outs])
        for k, o in enumerate(outs, start=1):
            fig.add_trace(go.Scatter(x=[r[drive] for r in rows], y=[r[o] for r in rows], name=o, mode="lines+markers",
                                     marker={"size": 3}), row=1, col=k)  # fmt: skip
            fig.update_xaxes(title_text=label[drive], row=1, col=k)
        fig.update_layout(height=380, showlegend=False, margin={"l": 50, "r": 20, "t": 40, "b": 50})
        parts.append(f"<h2>Curves over {html.escape(label[drive])}</h2>")
        parts.append(f"<p>kinprop sweep --drive {html.escape(curves['drive_spec'])}: {curves['converged']} of "
                     f"{curves['steps']} points converged</p>")  # fmt: skip
        parts.append(fig.to_html(full_html=False, include_plotlyjs=True, div_id="curves"))
        cols = [drive, *outs]
        parts.append('<details><summary>the curves\' numbers</summary><table id="curve-rows"><tr>'
                     + "".join(f"<th>{html.escape(label[c])}</th>" for c in cols) + "</tr>")  # fmt: skip
        for r in rows:
            parts.append("<tr>" + "".join(f"<td>{_cell(r.get(c))}</td>" for c in cols) + "</tr>")
        parts.append("</table></details>")
    style = ("body{font:13px system-ui,sans-serif;margin:20px;color:#222}table{border-collapse:collapse}"
             "td,th{border-bottom:1px solid #ddd;padding:2px 8px;text-align:left}"
             "tr.section th{background:#eef2f6}")  # fmt: skip
    return (f'<!doctype html>\n<html lang="en"><head><meta charset="utf-8"><title>{html.escape(title)}</title>'
            f"<style>{style}</style></head><body>\n" + "\n".join(parts) + "\n</body></html>\n")  # fmt: skip
