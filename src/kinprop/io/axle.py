"""An axle from one corner: mirror a hardpoint-style left corner into left and right (y -> -y).

:func:`mirror_corner` takes the data of a hardpoint-style file of a left corner (ISO 8855: y
left) and returns the data of the axle: the fixed bodies are shared, every moving body and
every joint appears twice with the suffixes (``_L``, ``_R``), every point and direction of the
right side is the left's with ``y`` negated, and names that refer to a body or a joint
(``kingpin``, point references, ``inputs``, a fixed body's ``WHEEL.NAME`` points) follow.
Optionally a **steering rack**: a body ``rack`` on a translational joint ``RACK`` to the fixed
body along y, carrying both tie rods' inner points (the joints named in ``tie_rods``): rack
travel ``RACK.q`` (positive to the left) steers both wheels; it is a declared input (held
unless named in a free set or driven).
"""

from __future__ import annotations

import copy
from typing import Any

from kinprop.errors import ModelError, Problem

#: hardpoint keys holding points (y negated) and directions (y negated)
POINT_KEYS = ("point", "point_i", "point_j")
AXIS_KEYS = ("axis", "axis_i", "axis_j")


def _mirror(v: list[float]) -> list[float]:
    return [float(v[0]), -float(v[1]), float(v[2])]


def mirror_corner(
    data: dict[str, Any],
    suffixes: tuple[str, str] = ("_L", "_R"),
    *,
    rack: dict[str, Any] | None = None,
    tie_rods: tuple[str, ...] = (),
    name: str | None = None,
) -> dict[str, Any]:
    """Axle data (hardpoint style) from a left corner's (module docstring). ``rack``:
    ``{"point": [x, y, z], "axis": [0, 1, 0]}`` of the rack slide (default: the global origin,
    along y) when ``tie_rods`` names the tie-rod joints to carry on it."""
    if data.get("style") != "hardpoints":
        raise ModelError([Problem("style", "mirror_corner takes a hardpoint-style corner (style: hardpoints)")])
    fixed = {n for n, b in data["bodies"].items() if b.get("fixed")}
    moving = [n for n in data["bodies"] if n not in fixed]
    joints = list(data["joints"])
    left, right = suffixes
    # couplings and elements name one corner's joints and bodies: not carried (say so in the name)
    drop = ("bodies", "joints", "inputs", "couplings", "elements")
    out = {k: copy.deepcopy(v) for k, v in data.items() if k not in drop}
    out["name"] = name or f"{data.get('name', 'corner')} (axle)"
    bodies: dict[str, Any] = {}
    for n in fixed:
        b = copy.deepcopy(data["bodies"][n])
        pts = {}
        for k, v in b.get("points", {}).items():
            if isinstance(v, str):
                raise ModelError([Problem(f"bodies.{n}.points.{k}", "a fixed body's point given by a joint")])
            # a fixed body's points belong to a wheel (wheel_centre_ref, ...): one per side
            pts[f"{moving_wheel(data)}{left}.{k}"] = v
            pts[f"{moving_wheel(data)}{right}.{k}"] = _mirror(v)
        if pts:
            b["points"] = pts
        bodies[n] = b
    if tie_rods:
        bodies["rack"] = {}
    for side, sfx in ((0, left), (1, right)):
        for n in moving:
            b = copy.deepcopy(data["bodies"][n])
            if side:
                b["points"] = {k: (v if isinstance(v, str) else _mirror(v)) for k, v in b.get("points", {}).items()}
            b["points"] = {
                k: (_ref(v, sfx, joints) if isinstance(v, str) else v) for k, v in b.get("points", {}).items()
            }
            if not b["points"]:
                del b["points"]
            if "kingpin" in b:
                b["kingpin"] = [_ref(r, sfx, joints) for r in b["kingpin"]]
            bodies[f"{n}{sfx}"] = b
    out["bodies"] = bodies
    js: dict[str, Any] = {}
    if tie_rods:
        r = rack or {}
        js["RACK"] = {
            "type": "translational",
            "bodies": [next(iter(sorted(fixed))), "rack"],
            "point": list(r.get("point", [0.0, 0.0, 0.0])),
            "axis": list(r.get("axis", [0.0, 1.0, 0.0])),
        }
    for side, sfx in ((0, left), (1, right)):
        for n in joints:
            j = copy.deepcopy(data["joints"][n])
            j["bodies"] = [b if b in fixed else f"{b}{sfx}" for b in j["bodies"]]
            if n in tie_rods:
                j["bodies"] = ["rack" if b in fixed else b for b in j["bodies"]]
            if side:
                for k in POINT_KEYS + AXIS_KEYS:
                    if k in j:
                        j[k] = _mirror(j[k])
                if "pivots" in j:
                    j["pivots"] = {k: _mirror(v) for k, v in j["pivots"].items()}
            js[f"{n}{sfx}"] = j
    out["joints"] = js
    inputs = [f"{i}{s}" for s in suffixes for i in data.get("inputs", [])]
    out["inputs"] = inputs + (["RACK"] if tie_rods else [])
    return out


def moving_wheel(data: dict[str, Any]) -> str:
    """The corner's wheel body (with ``wheel_centre`` and ``spin_axis`` points)."""
    for n, b in data["bodies"].items():
        if {"wheel_centre", "spin_axis"} <= set(b.get("points", {})):
            return n
    raise ModelError([Problem("bodies", "no wheel body (named points wheel_centre and spin_axis)")])


def _ref(text: str, sfx: str, joints: list[str]) -> str:
    joint, dot, side = text.partition(".")
    return f"{joint}{sfx}{dot}{side}" if joint in joints else text


__all__ = ["mirror_corner"]
