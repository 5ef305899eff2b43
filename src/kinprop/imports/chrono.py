"""Project Chrono vehicle suspension templates (JSON) as hardpoint-style kinprop models.

A Chrono suspension file names hardpoints (metres, x forward, y left, z up; left side); the
C++ template class named by ``"Template"`` says which joints connect the bodies. kinprop reads
the left side and builds, per template (topology as in Chrono::Vehicle's ``ChDoubleWishbone``,
``ChMacPhersonStrut`` and ``ChMultiLink``):

* ``DoubleWishbone``: control arms ``uca``/``lca`` revolute to the chassis about the line
  through their two chassis points, written as ``pivots: {front, rear}`` (addresses
  ``hardpoint:UCA.front``, :mod:`kinprop.propagation.hardpoints`), ball joints ``UCA_U``/``LCA_U`` to
  the upright, tie rod ``TIEROD`` a distance joint from the rack point (on the chassis) to the
  upright; spring and shock between the chassis and the lower arm.
* ``MacPhersonStrut``: lower arm ``lca`` revolute to the chassis and ball-jointed to the
  upright (``LCA_U``, the cut joint); the strut universal-jointed to the chassis at the
  spring's chassis point (``STRUT_TOP``) and cylindrical to the upright along the spring axis
  (``STRUT``); tie rod as above; spring and shock between the chassis and the upright.
* ``MultiLink``: upper arm ``upper_arm`` revolute to the chassis, ball-jointed to the
  upright; lateral and trailing links universal-jointed to the chassis (axes as given in the
  file: ``Universal Joint Axis Chassis`` on the chassis, ``... Link`` on the link) and
  ball-jointed to the upright; tie rod as above; spring and shock between the chassis and the
  trailing link.

Common to all: the chassis is fixed; the steering rack is held (the tie rod's inner point is a
chassis point), so the mobility is 1 (wheel travel). The spindle's revolute joint is left out
(wheel spin moves no hardpoint); the wheel is declared on the upright by named points
(``wheel_centre`` = the spindle location, ``spin_axis`` from the file's camber and toe angles,
``kingpin: [UPPER, LOWER]`` by reference to the joints where the template has a steering axis
(the two ball joints; McPherson: the strut top mount and the lower ball joint), so it follows
every edit of them, ``contact_patch`` when a tyre radius is given) and the chassis point
``wheel_centre_ref``, so camber, toe, caster, KPI, scrub radius, trail and wheel-centre travel
work at once. Spring and shock end points are named points: their length is the output
``distance:chassis.spring_chassis,BODY.spring_BODY`` (not a constraint). Masses, inertias,
spring and damper data are not kinematics and are not read.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from kinprop.engine.units import RADIANS_PER
from kinprop.errors import ModelError, Problem
from kinprop.io.hardpoints import model_from_hardpoints
from kinprop.model import Model
from kinprop.spatial import Array, rot_x, rot_z

#: larger coordinates would overflow in the kinematics (products of coordinates)
MAX_NUMBER = 1e100
#: the spin axis point is this far along the unit spin axis from the wheel centre
SPIN_AXIS_LENGTH = 1.0


class _Reader:
    def __init__(self, data: dict[str, Any], file: str):
        self.data = data
        self.file = file
        self.problems: list[Problem] = []

    def point(self, section: str, key: str) -> Array:
        """A 3-vector ``data[section][key]`` (a located problem and zeros when it is not)."""
        sec = self.data.get(section)
        if not isinstance(sec, dict):
            found = "missing" if sec is None else f"a {type(sec).__name__}"
            self.problems.append(Problem(section, f"expected an object with {key!r}, found {found}", self.file))
            return np.zeros(3)
        v = sec.get(key)
        ok = (
            isinstance(v, list)
            and len(v) == 3
            and all(
                isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) and abs(x) <= MAX_NUMBER
                for x in v
            )
        )
        if not ok:
            found = "missing" if v is None else repr(v)[:60]
            self.problems.append(
                Problem(
                    f"{section}.{key}",
                    f"expected [x, y, z] in metres (finite, below {MAX_NUMBER:g}), found {found}",
                    self.file,
                )
            )
            return np.zeros(3)
        return np.array(v, dtype=float)

    def angle(self, key: str) -> float:
        v = self.data.get(key, 0.0)
        if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v):
            self.problems.append(Problem(key, f"expected a number (degrees), found {v!r}", self.file))
            return 0.0
        return float(v) * RADIANS_PER["deg"]


def _l(v: Array) -> list[float]:
    return [float(x) for x in v]


def _revolute(body: str, front: Array, back: Array) -> dict[str, Any]:
    """A control arm's chassis revolute by its two chassis pivots (the axis runs back -> front)."""
    return {"type": "revolute", "bodies": ["chassis", body], "pivots": {"front": _l(front), "rear": _l(back)}}


def _ball(body_i: str, body_j: str, p: Array, cut: bool = False) -> dict[str, Any]:
    spec: dict[str, Any] = {"type": "spherical", "bodies": [body_i, body_j], "point": _l(p)}
    if cut:
        spec["cut"] = True
    return spec


def _wheel(r: _Reader, tire_radius: float | None) -> dict[str, list[float]]:
    """Wheel points on the upright: centre, spin axis (camber/toe of the file), contact patch."""
    centre = r.point("Spindle", "COM")
    # Chrono's left spindle: Rz(-toe) Rx(-camber) applied to the chassis y axis
    axis = rot_z(-r.angle("Toe Angle (deg)")) @ rot_x(-r.angle("Camber Angle (deg)")) @ np.array([0.0, 1.0, 0.0])
    pts = {"wheel_centre": _l(centre), "spin_axis": _l(centre + SPIN_AXIS_LENGTH * axis)}
    if tire_radius is not None:
        down = np.array([0.0, 0.0, -1.0]) + axis[2] * axis
        pts["contact_patch"] = _l(centre + tire_radius * down / np.linalg.norm(down))
    return pts


def _double_wishbone(r: _Reader, tire_radius: float | None) -> tuple[dict[str, Any], dict[str, Any], str]:
    uca_f, uca_b, uca_u = (
        r.point("Upper Control Arm", f"Location {k}") for k in ("Chassis Front", "Chassis Back", "Upright")
    )
    lca_f, lca_b, lca_u = (
        r.point("Lower Control Arm", f"Location {k}") for k in ("Chassis Front", "Chassis Back", "Upright")
    )
    tr_c, tr_u = r.point("Tierod", "Location Chassis"), r.point("Tierod", "Location Upright")
    spring_c, spring_a = r.point("Spring", "Location Chassis"), r.point("Spring", "Location Arm")
    shock_c, shock_a = r.point("Shock", "Location Chassis"), r.point("Shock", "Location Arm")
    wheel = _wheel(r, tire_radius)
    bodies = {
        "chassis": {
            "fixed": True,
            "points": {
                "wheel_centre_ref": wheel["wheel_centre"],
                "spring_chassis": _l(spring_c),
                "shock_chassis": _l(shock_c),
            },
        },
        "uca": {},
        "lca": {"points": {"spring_lca": _l(spring_a), "shock_lca": _l(shock_a)}},
        "upright": {"points": wheel, "kingpin": ["UCA_U", "LCA_U"]},
    }
    joints = {
        "LCA": _revolute("lca", lca_f, lca_b),
        "LCA_U": _ball("lca", "upright", lca_u),
        "UCA": _revolute("uca", uca_f, uca_b),
        "UCA_U": _ball("uca", "upright", uca_u, cut=True),
        "TIEROD": {"type": "distance", "bodies": ["chassis", "upright"], "point_i": _l(tr_c), "point_j": _l(tr_u)},
    }
    return bodies, joints, "lca"


def _macpherson(r: _Reader, tire_radius: float | None) -> tuple[dict[str, Any], dict[str, Any], str]:
    lca_f, lca_b, lca_u = (
        r.point("Control Arm", f"Location {k}") for k in ("Chassis Front", "Chassis Back", "Upright")
    )
    tr_c, tr_u = r.point("Tierod", "Location Chassis"), r.point("Tierod", "Location Upright")
    spring_c, spring_u = r.point("Spring", "Location Chassis"), r.point("Spring", "Location Upright")
    shock_c, shock_u = r.point("Shock", "Location Chassis"), r.point("Shock", "Location Upright")
    wheel = _wheel(r, tire_radius)
    # strut frame as Chrono builds it: w along the strut (upright -> chassis), v normal to the
    # plane of the strut and the arm's rear pivot, u = v x w; the universal's axes are u
    # (chassis) and v (strut)
    w = spring_c - spring_u
    v = np.cross(spring_u - lca_b, spring_c - lca_b)
    if np.linalg.norm(w) < 1e-12 or np.linalg.norm(v) < 1e-12:
        r.problems.append(
            Problem("Spring", "the strut (spring chassis -> upright) is degenerate or passes through LCA back", r.file)
        )
        w, v = np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0])
    w, v = w / np.linalg.norm(w), v / np.linalg.norm(v)
    u = np.cross(v, w)
    bodies = {
        "chassis": {
            "fixed": True,
            "points": {
                "wheel_centre_ref": wheel["wheel_centre"],
                "spring_chassis": _l(spring_c),
                "shock_chassis": _l(shock_c),
            },
        },
        "lca": {},
        "strut": {},
        "upright": {
            "points": {**wheel, "spring_upright": _l(spring_u), "shock_upright": _l(shock_u)},
            "kingpin": ["STRUT_TOP", "LCA_U"],
        },
    }
    joints = {
        "LCA": _revolute("lca", lca_f, lca_b),
        "LCA_U": _ball("lca", "upright", lca_u, cut=True),
        "STRUT_TOP": {
            "type": "universal",
            "bodies": ["chassis", "strut"],
            "point": _l(spring_c),
            "axis_i": _l(u),
            "axis_j": _l(v),
        },
        "STRUT": {
            "type": "cylindrical",
            "bodies": ["strut", "upright"],
            "point": _l(spring_u),
            "axis": _l(w),
        },
        "TIEROD": {"type": "distance", "bodies": ["chassis", "upright"], "point_i": _l(tr_c), "point_j": _l(tr_u)},
    }
    return bodies, joints, "upright"


def _multilink(r: _Reader, tire_radius: float | None) -> tuple[dict[str, Any], dict[str, Any], str]:
    ua_f, ua_b, ua_u = (r.point("Upper Arm", f"Location {k}") for k in ("Chassis Front", "Chassis Back", "Upright"))
    lat_c, lat_u = r.point("Lateral", "Location Chassis"), r.point("Lateral", "Location Upright")
    lat_ac, lat_al = r.point("Lateral", "Universal Joint Axis Chassis"), r.point("Lateral", "Universal Joint Axis Link")
    tl_c, tl_u = r.point("Trailing Link", "Location Chassis"), r.point("Trailing Link", "Location Upright")
    tl_ac = r.point("Trailing Link", "Universal Joint Axis Chassis")
    tl_al = r.point("Trailing Link", "Universal Joint Axis Link")
    tr_c, tr_u = r.point("Tierod", "Location Chassis"), r.point("Tierod", "Location Upright")
    spring_c, spring_l = r.point("Spring", "Location Chassis"), r.point("Spring", "Location Link")
    shock_c, shock_l = r.point("Shock", "Location Chassis"), r.point("Shock", "Location Link")
    wheel = _wheel(r, tire_radius)
    bodies = {
        "chassis": {
            "fixed": True,
            "points": {
                "wheel_centre_ref": wheel["wheel_centre"],
                "spring_chassis": _l(spring_c),
                "shock_chassis": _l(shock_c),
            },
        },
        "upper_arm": {},
        "lateral": {},
        "trailing_link": {"points": {"spring_trailing_link": _l(spring_l), "shock_trailing_link": _l(shock_l)}},
        "upright": {"points": wheel},
    }
    joints = {
        "UA": _revolute("upper_arm", ua_f, ua_b),
        "UA_U": _ball("upper_arm", "upright", ua_u),
        "LAT_C": {
            "type": "universal",
            "bodies": ["chassis", "lateral"],
            "point": _l(lat_c),
            "axis_i": _l(lat_ac),
            "axis_j": _l(lat_al),
        },
        "LAT_U": _ball("lateral", "upright", lat_u, cut=True),
        "TL_C": {
            "type": "universal",
            "bodies": ["chassis", "trailing_link"],
            "point": _l(tl_c),
            "axis_i": _l(tl_ac),
            "axis_j": _l(tl_al),
        },
        "TL_U": _ball("trailing_link", "upright", tl_u, cut=True),
        "TIEROD": {"type": "distance", "bodies": ["chassis", "upright"], "point_i": _l(tr_c), "point_j": _l(tr_u)},
    }
    return bodies, joints, "trailing_link"


Builder = Callable[[_Reader, float | None], tuple[dict[str, Any], dict[str, Any], str]]
TEMPLATES: dict[str, Builder] = {
    "DoubleWishbone": _double_wishbone,
    "MacPhersonStrut": _macpherson,
    "MultiLink": _multilink,
}
#: the revolute joint that drives wheel travel, per template
DRIVERS = {"DoubleWishbone": "LCA", "MacPhersonStrut": "LCA", "MultiLink": "UA"}


def chrono_hardpoints(
    data: Any, file: str = "<chrono>", tire_radius: float | None = None
) -> tuple[dict[str, Any], list[str]]:
    """Hardpoint-style file data (``style: hardpoints``) of a Chrono suspension, with notes."""
    if not isinstance(data, dict):
        raise ModelError([Problem("file", f"expected a JSON object, found {type(data).__name__}", file)])
    template = data.get("Template")
    if not isinstance(template, str) or template not in TEMPLATES:
        raise ModelError([Problem("Template", f"expected one of {', '.join(TEMPLATES)}, found {template!r}", file)])
    if data.get("Type", "Suspension") != "Suspension":
        raise ModelError([Problem("Type", f"expected 'Suspension', found {data.get('Type')!r}", file)])
    if tire_radius is not None and not (math.isfinite(tire_radius) and tire_radius > 0):
        raise ModelError([Problem("tire radius", f"expected a positive length in metres, found {tire_radius!r}", file)])
    r = _Reader(data, file)
    bodies, joints, spring_body = TEMPLATES[template](r, tire_radius)
    if r.problems:
        raise ModelError(r.problems)
    name = data.get("Name") if isinstance(data.get("Name"), str) else Path(file).stem
    hp = {
        "kinprop": 1,
        "name": f"{name} (Project Chrono {template}, left side)",
        "style": "hardpoints",
        "units": {"length": "m", "angle": "deg", "axes": "ISO8855"},
        "bodies": bodies,
        "joints": joints,
    }
    notes = [
        f"template {template}: wheel travel is driven by {DRIVERS[template]}.q; the rack (tie rod inner point) is held",
        "spindle revolute left out (wheel spin moves no hardpoint); masses, inertias, spring and damper data not read",
        f"spring length: output distance:chassis.spring_chassis,{spring_body}.spring_{spring_body}",
    ]
    if "Mass" in (data.get("Tierod") or {}):
        notes.append("tie-rod bodies (spherical + universal) read as a distance joint: same upright motion")
    if tire_radius is None:
        notes.append("no tyre radius given: scrub radius and trail need --tire-radius")
    if template == "MultiLink":
        notes.append("MultiLink has no steering axis through two ball joints: caster and KPI are not defined")
    return hp, notes


def read_chrono(path: str | Path, tire_radius: float | None = None) -> tuple[Model, list[str]]:
    """A Chrono suspension JSON file as a kinprop Model (hardpoint style), with notes."""
    path = Path(path)
    file = str(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ModelError([Problem("file", f"cannot read: {exc.strerror or exc}", file)]) from None
    except UnicodeDecodeError as exc:
        raise ModelError([Problem("file", f"not UTF-8 text (byte {exc.start})", file)]) from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ModelError(
            [Problem(f"line {exc.lineno}, column {exc.colno}", f"malformed JSON: {exc.msg}", file)]
        ) from None
    hp, notes = chrono_hardpoints(data, file, tire_radius)
    return model_from_hardpoints(hp, file), notes


def is_chrono(data: Any) -> bool:
    """Whether parsed JSON looks like a Chrono subsystem file (has ``Template``, no ``kinprop``)."""
    return isinstance(data, dict) and "Template" in data and "kinprop" not in data


__all__ = ["DRIVERS", "TEMPLATES", "chrono_hardpoints", "is_chrono", "read_chrono"]
