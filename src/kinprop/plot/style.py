"""Colours, markers and line styles shared by the PNG (matplotlib) and HTML (plotly) plots."""

from __future__ import annotations

from dataclasses import dataclass

from kinprop.plot.scene import Scene

#: body colours (matplotlib's tab10 without grey), by the body's index in the mechanism
BODY_COLOURS = (
    "#1f77b4",
    "#ff7f0e",
    "#2ca02c",
    "#d62728",
    "#9467bd",
    "#8c564b",
    "#e377c2",
    "#bcbd22",
    "#17becf",
)
LINK = "#222222"
SLIDE = "#555555"
GAP = "#e41a1c"
AXIS = {"z''": "#b2182b", "y''": "#2166ac"}
AXIS_LABEL = {"z''": "joint axis z''", "y''": "universal 2nd axis y''"}
POINT = "#000000"

#: joint-marker kind -> (matplotlib marker, plotly symbol, legend text)
MARKERS = {
    "revolute": ("s", "square", "revolute"),
    "spherical": ("o", "circle", "spherical (ball)"),
    "universal": ("D", "diamond", "universal"),
    "translational": ("^", "cross", "translational (slide)"),
    "cylindrical": ("v", "square-open", "cylindrical"),
    "fixed": ("X", "x", "fixed"),
    "other": ("P", "diamond-open", "other constraint"),
}

#: segment kind -> legend text
SEGMENTS = {
    "link": "link (S-S, R-S, T-D rod)",
    "slide": "slide / strut travel",
    "gap": "unclosed cut joint",
}

#: opacity of a faded (before) layer
FADED_ALPHA = 0.3


@dataclass(frozen=True)
class Layer:
    """One state to draw: a scene, its legend label and whether it is the faded one."""

    scene: Scene
    label: str
    faded: bool = False


def body_colour(scene: Scene, body: str) -> str:
    idx = scene.bodies.index(body) if body in scene.bodies else 0
    return BODY_COLOURS[idx % len(BODY_COLOURS)]


def segment_colour(scene: Scene, kind: str, owner: str) -> str:
    if kind == "body":
        return body_colour(scene, owner)
    return {"link": LINK, "slide": SLIDE, "gap": GAP}[kind]
