"""PNG stick figures through matplotlib's Agg canvas (no GUI backend, no global state)."""

from __future__ import annotations

import io
from collections.abc import Sequence

import numpy as np

from kinprop.plot.forces import FORCE_STYLE, ForceArrow, arrow_scale
from kinprop.plot.scene import bounds, scale
from kinprop.plot.style import (
    AXIS,
    AXIS_LABEL,
    FADED_ALPHA,
    MARKERS,
    POINT,
    SEGMENTS,
    Layer,
    segment_colour,
)

LINESTYLE = {"body": "-", "link": "-", "slide": "--", "gap": ":"}
LINEWIDTH = {"body": 2.2, "link": 2.6, "slide": 1.6, "gap": 1.4}


def render_png(
    layers: Sequence[Layer],
    title: str = "",
    view: tuple[float, float] = (20.0, -60.0),
    size: tuple[float, float] = (10.0, 7.5),
    dpi: int = 120,
    arrows: Sequence[ForceArrow] = (),
    force_unit: str = "",
) -> bytes:
    """The layers (faded ones first) as one 3D stick figure, PNG bytes; ``arrows``: forces drawn
    over the top layer (:mod:`kinprop.plot.forces`)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.ticker import MaxNLocator

    fig = Figure(figsize=size, dpi=dpi)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(projection="3d")
    scenes = [ly.scene for ly in layers]
    L = 0.12 * scale(scenes)
    handles: dict[str, Line2D] = {}
    top = layers[-1]
    for ly in sorted(layers, key=lambda x: not x.faded):
        sc = ly.scene
        alpha = FADED_ALPHA if ly.faded else 1.0
        for s in sc.segments:
            xyz = np.vstack([s.start, s.end]).T
            ax.plot(
                *xyz,
                color=segment_colour(sc, s.kind, s.owner),
                linestyle="--" if ly.faded and s.kind == "body" else LINESTYLE[s.kind],
                linewidth=LINEWIDTH[s.kind],
                alpha=alpha,
            )
            if not ly.faded:
                key = f"body {s.owner}" if s.kind == "body" else SEGMENTS[s.kind]
                colour = segment_colour(sc, s.kind, s.owner)
                handles.setdefault(key, Line2D([], [], color=colour, ls=LINESTYLE[s.kind], lw=LINEWIDTH[s.kind]))
        for m in sc.markers:
            mk, _, text = MARKERS[m.kind]
            ax.scatter(
                *m.position,
                marker=mk,
                s=46,
                c="white" if ly.faded else "#f7f7f7",
                edgecolors="black",
                linewidths=1.1,
                alpha=alpha,
                depthshade=False,
            )
            handles.setdefault(f"~{text}", Line2D([], [], ls="", marker=mk, mfc="#f7f7f7", mec="black", label=text))
        for a in sc.axes:
            ax.quiver(
                *a.origin, *(a.direction * L), color=AXIS[a.label], alpha=alpha, arrow_length_ratio=0.25, linewidth=1.5
            )
            handles.setdefault(f"~{AXIS_LABEL[a.label]}", Line2D([], [], color=AXIS[a.label], lw=1.5))
        for name, p in sc.points.items():
            ax.scatter(*p, marker="*", s=70, c=POINT, alpha=alpha, depthshade=False)
            if ly is top:
                ax.text(*p, f" {name.split('.', 1)[1]}", fontsize=7)
            handles.setdefault("~named point", Line2D([], [], ls="", marker="*", color=POINT, ms=9))
        if ly is top:
            seen: set[str] = set()
            for m in sc.markers:
                if m.joint not in seen:
                    seen.add(m.joint)
                    ax.text(*m.position, f"  {m.joint}", fontsize=7, color="#333333")
    lo, hi = bounds(scenes)
    per = arrow_scale(arrows, float(np.max(hi - lo)))
    for a in arrows:
        colour, text = FORCE_STYLE[a.kind]
        ax.quiver(*a.origin, *(a.force * per), color=colour, arrow_length_ratio=0.2, linewidth=2.0)
        ax.text(*(a.origin + a.force * per), f" {a.label}", fontsize=6, color=colour)
        handles.setdefault(f"~{text}", Line2D([], [], color=colour, lw=2.0))
    if arrows and per > 0:
        title = f"{title or top.scene.name}\nforce arrows: 1 {top.scene.unit} per {1.0 / per:.4g} {force_unit}".strip()
    states = (
        {
            ly.label: Line2D([], [], color="black", ls="--" if ly.faded else "-", alpha=FADED_ALPHA if ly.faded else 1)
            for ly in layers
        }
        if len(layers) > 1
        else {}
    )
    lines = {k: h for k, h in handles.items() if not k.startswith("~")}
    symbols = {k[1:]: h for k, h in handles.items() if k.startswith("~")}
    legend = {**states, **lines, **symbols}
    ax.legend(
        list(legend.values()), list(legend), loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8, frameon=False
    )

    lo, hi = bounds(scenes)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(tuple(hi - lo))
    for axis, span in zip((ax.xaxis, ax.yaxis, ax.zaxis), hi - lo, strict=True):
        axis.set_major_locator(MaxNLocator(nbins=max(2, round(7 * span / max(hi - lo)))))
    unit = top.scene.unit
    for setter, letter in ((ax.set_xlabel, "x"), (ax.set_ylabel, "y"), (ax.set_zlabel, "z")):
        setter(f"{letter} [{unit}]" if unit else letter)
    ax.tick_params(labelsize=7)
    ax.view_init(elev=view[0], azim=view[1])
    text = title or top.scene.name
    fig.suptitle(text, fontsize=11, y=0.985, va="top")
    fig.subplots_adjust(left=0.0, right=0.78, bottom=0.02, top=0.97 - 0.035 * (text.count("\n") + 1))
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return buf.getvalue()
