"""Interactive HTML stick figures through plotly (one self-contained file, works offline)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from kinprop.plot.forces import FORCE_STYLE, ForceArrow, arrow_scale
from kinprop.plot.scene import Scene, bounds, scale
from kinprop.plot.style import AXIS, AXIS_LABEL, FADED_ALPHA, MARKERS, POINT, SEGMENTS, Layer, segment_colour

DASH = {"body": "solid", "link": "solid", "slide": "dash", "gap": "dot"}
WIDTH = {"body": 6, "link": 7, "slide": 4, "gap": 3}


def _polyline(pairs: list[tuple[np.ndarray, np.ndarray]]) -> tuple[list[float | None], ...]:
    """Segments as one polyline broken by ``None`` (one trace per group)."""
    xs: list[float | None] = []
    ys: list[float | None] = []
    zs: list[float | None] = []
    for a, b in pairs:
        xs += [float(a[0]), float(b[0]), None]
        ys += [float(a[1]), float(b[1]), None]
        zs += [float(a[2]), float(b[2]), None]
    return xs, ys, zs


def _layer_traces(ly: Layer, L: float, group: str, show_labels: bool) -> list[Any]:
    import plotly.graph_objects as go

    sc: Scene = ly.scene
    opacity = FADED_ALPHA if ly.faded else 1.0
    tag = f" ({ly.label})" if group else ""
    traces: list[Any] = []
    groups: dict[tuple[str, str], list[tuple[np.ndarray, np.ndarray]]] = {}
    for s in sc.segments:
        owner = s.owner if s.kind == "body" else ""
        groups.setdefault((s.kind, owner), []).append((s.start, s.end))
    for (kind, owner), pairs in groups.items():
        x, y, z = _polyline(pairs)
        name = f"body {owner}" if kind == "body" else SEGMENTS[kind]
        traces.append(
            go.Scatter3d(
                x=x,
                y=y,
                z=z,
                mode="lines",
                name=name + tag,
                legendgroup=group,
                opacity=opacity,
                line={
                    "color": segment_colour(sc, kind, owner),
                    "width": WIDTH[kind],
                    "dash": "dash" if ly.faded and kind == "body" else DASH[kind],
                },
                hoverinfo="name",
            )
        )
    by_kind: dict[str, list[Any]] = {}
    labelled: set[int] = set()  # label each joint once, at its first marker
    seen: set[str] = set()
    for k, m in enumerate(sc.markers):
        by_kind.setdefault(m.kind, []).append((k, m))
        if m.joint not in seen:
            seen.add(m.joint)
            labelled.add(k)
    for kind, kms in by_kind.items():
        _, symbol, text = MARKERS[kind]
        ms = [m for _, m in kms]
        pos = np.array([m.position for m in ms])
        traces.append(
            go.Scatter3d(
                x=pos[:, 0],
                y=pos[:, 1],
                z=pos[:, 2],
                mode="markers+text" if show_labels else "markers",
                text=[m.joint if k in labelled else "" for k, m in kms] if show_labels else None,
                textposition="top right",
                textfont={"size": 10},
                name=text + tag,
                legendgroup=group,
                opacity=opacity,
                marker={"symbol": symbol, "size": 6, "color": "white", "line": {"color": "black", "width": 2}},
                hovertext=[f"{m.joint} ({kind})" for m in ms],
                hoverinfo="text",
            )
        )
    for label in ("z''", "y''"):
        ax = [a for a in sc.axes if a.label == label]
        if not ax:
            continue
        x, y, z = _polyline([(a.origin, a.origin + a.direction * L) for a in ax])
        name = AXIS_LABEL[label] + tag
        traces.append(
            go.Scatter3d(
                x=x,
                y=y,
                z=z,
                mode="lines",
                name=name,
                legendgroup=group,
                opacity=opacity,
                line={"color": AXIS[label], "width": 4},
                hoverinfo="name",
            )
        )
        tips = np.array([a.origin + a.direction * L for a in ax])
        dirs = np.array([a.direction for a in ax])
        traces.append(
            go.Cone(
                x=tips[:, 0],
                y=tips[:, 1],
                z=tips[:, 2],
                u=dirs[:, 0],
                v=dirs[:, 1],
                w=dirs[:, 2],
                anchor="tip",
                sizemode="absolute",
                sizeref=0.25 * L,
                showscale=False,
                colorscale=[[0, AXIS[label]], [1, AXIS[label]]],
                opacity=opacity,
                name=name,
                legendgroup=group,
                showlegend=False,
                hoverinfo="skip",
            )
        )
    if sc.points:
        pos = np.array(list(sc.points.values()))
        names = [k.split(".", 1)[1] for k in sc.points]
        traces.append(
            go.Scatter3d(
                x=pos[:, 0],
                y=pos[:, 1],
                z=pos[:, 2],
                mode="markers+text" if show_labels else "markers",
                text=names if show_labels else None,
                name="named point" + tag,
                legendgroup=group,
                opacity=opacity,
                marker={"symbol": "diamond", "size": 4, "color": POINT},
                hovertext=list(sc.points),
                hoverinfo="text",
            )
        )
    return traces


def _arrow_traces(arrows: Sequence[ForceArrow], per: float, force_unit: str) -> list[Any]:
    """Force arrows (:mod:`kinprop.plot.forces`) as one shaft polyline and one set of cone heads
    per kind, hover text naming each force and its magnitude."""
    import plotly.graph_objects as go

    traces: list[Any] = []
    for kind, (colour, text) in FORCE_STYLE.items():
        mine = [a for a in arrows if a.kind == kind]
        if not mine:
            continue
        tips = [a.origin + a.force * per for a in mine]
        xs, ys, zs = _polyline([(a.origin, t) for a, t in zip(mine, tips, strict=True)])
        hover = [f"{a.label}: {float(np.linalg.norm(a.force)):.4g} {force_unit}" for a in mine]
        traces.append(go.Scatter3d(x=xs, y=ys, z=zs, mode="lines", name=text, legendgroup=f"force {kind}",
                                   line={"color": colour, "width": 5}, hoverinfo="skip"))  # fmt: skip
        d = np.array([a.force * per for a in mine])
        T = np.array(tips)
        traces.append(go.Cone(x=T[:, 0], y=T[:, 1], z=T[:, 2], u=d[:, 0], v=d[:, 1], w=d[:, 2], anchor="tip",
                              sizemode="absolute", sizeref=0.15 * float(np.max(np.linalg.norm(d, axis=1))) or 1.0,
                              colorscale=[[0, colour], [1, colour]], showscale=False, legendgroup=f"force {kind}",
                              showlegend=False, hovertext=hover, hoverinfo="text", name=text))  # fmt: skip
    return traces


def render_html(
    layers: Sequence[Layer], title: str = "", arrows: Sequence[ForceArrow] = (), force_unit: str = ""
) -> str:
    """The layers (faded ones first) as one interactive 3D figure: a self-contained HTML page
    with plotly.js inlined (no network needed to view it); ``arrows``: forces drawn over the top
    layer (:mod:`kinprop.plot.forces`: red tension, blue compression, magenta applied, grey
    reactions), scaled as in the PNG (the scale in the title)."""
    import plotly.graph_objects as go

    scenes = [ly.scene for ly in layers]
    L = 0.12 * scale(scenes)
    top = layers[-1]
    fig = go.Figure()
    compare = len(layers) > 1
    for ly in sorted(layers, key=lambda x: not x.faded):
        for tr in _layer_traces(ly, L, ly.label if compare else "", show_labels=ly is top):
            fig.add_trace(tr)
    lo, hi = bounds(scenes)
    unit = top.scene.unit
    per = arrow_scale(arrows, float(np.max(hi - lo)))
    if arrows and per > 0:
        for tr in _arrow_traces(arrows, per, force_unit):
            fig.add_trace(tr)
        title = f"{title or top.scene.name}\nforce arrows: 1 {unit} per {1.0 / per:.4g} {force_unit}".strip()
    ranges = hi - lo
    aspect = ranges / ranges.max()
    fig.update_layout(
        title={"text": (title or top.scene.name).replace("\n", "<br>")},
        scene={
            "xaxis": {"title": {"text": f"x [{unit}]" if unit else "x"}, "range": [lo[0], hi[0]]},
            "yaxis": {"title": {"text": f"y [{unit}]" if unit else "y"}, "range": [lo[1], hi[1]]},
            "zaxis": {"title": {"text": f"z [{unit}]" if unit else "z"}, "range": [lo[2], hi[2]]},
            "aspectmode": "manual",
            "aspectratio": {"x": aspect[0], "y": aspect[1], "z": aspect[2]},
        },
        legend={"groupclick": "togglegroup"},
        margin={"l": 0, "r": 0, "t": 40, "b": 0},
    )
    return fig.to_html(include_plotlyjs=True, full_html=True)
