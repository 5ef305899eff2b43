"""What a stick figure of a mechanism shows, as plain numbers (no plotting library needed).

A :class:`Scene` is computed from a model at its coordinates as given (one forward-kinematics
pass, :func:`kinprop.analysis.points.snapshot`) and holds:

* body segments — from each moving body's frame origin ``r_b`` to the joint points it carries
  (``P_i`` of the joints whose first body it is, ``P_j`` of the others) and to its named points;
  a fixed body (``ground``, a chassis) has none: its joints' markers and named points show where
  it is (lines to a point that is not on the mechanism, such as the mean of the chassis points,
  would draw a body that is not there);
* joint segments — ``link`` for a joint with a length (S-S, R-S, the T-D rod), ``slide`` for a
  joint's travel (prismatic, cylindrical, S-T strut, free, the T-D rack's q3), and ``gap`` for
  a cut joint whose two points should coincide but do not (an unassembled model);
* joint markers by kind (a composite joint has several: R-S = revolute + spherical);
* joint axes — unit vectors along ``z''`` of the joint frame (both axes of a universal joint:
  ``z''_i`` and ``y''_j``; the strut axis ``z''_j`` of an S-T joint);
* named points.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from kinprop.analysis.points import snapshot
from kinprop.model import Model
from kinprop.spatial import Array


@dataclass(frozen=True)
class Segment:
    kind: str  # body, link, slide, gap
    owner: str  # body name (body, ground) or joint name
    start: Array
    end: Array


@dataclass(frozen=True)
class Marker:
    joint: str
    kind: str  # revolute, spherical, universal, translational, cylindrical, fixed, other
    position: Array


@dataclass(frozen=True)
class Axis:
    joint: str
    label: str  # "z''" or "y''"
    origin: Array
    direction: Array  # unit vector


@dataclass(frozen=True)
class Scene:
    """A model's stick figure: segments, joint markers, joint axes and named points."""

    name: str
    unit: str
    bodies: tuple[str, ...]
    segments: tuple[Segment, ...]
    markers: tuple[Marker, ...]
    axes: tuple[Axis, ...]
    points: dict[str, Array]

    def all_points(self) -> Array:
        pts = [s.start for s in self.segments] + [s.end for s in self.segments]
        pts += [m.position for m in self.markers] + list(self.points.values())
        return np.array(pts, dtype=float).reshape(-1, 3)


def scale(scenes: Iterable[Scene]) -> float:
    """Largest extent of the scenes' points (1 when they are all at one point)."""
    pts = np.vstack([s.all_points() for s in scenes])
    ext = float(np.max(np.ptp(pts, axis=0))) if pts.size else 0.0
    return ext if ext > 0 else 1.0


def bounds(scenes: Iterable[Scene], pad: float = 0.08, min_fraction: float = 0.15) -> tuple[Array, Array]:
    """``(lo, hi)`` of a box around every point: padded, and no side shorter than
    ``min_fraction`` of the longest (so a planar mechanism keeps some depth)."""
    scenes = list(scenes)
    pts = np.vstack([s.all_points() for s in scenes])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    centre, half = (lo + hi) / 2, (hi - lo) / 2
    big = max(float(half.max()), 0.5)
    half = np.maximum(half, min_fraction * big) * (1 + pad)
    return centre - half, centre + half


def _unit(v: Array) -> Array:
    n = float(np.linalg.norm(v))
    return v / n if n > 0 else v


def build_scene(model: Model) -> Scene:
    """The stick figure of ``model`` at its coordinates as given."""
    snap = snapshot(model)
    mech = model.mechanism
    tree = snap.kin.tree
    segments: list[Segment] = []
    markers: list[Marker] = []
    axes: list[Axis] = []
    carried: dict[str, list[Array]] = {b.name: [] for b in mech.bodies}

    for j in mech.joints:
        f = snap.frames[j.name]
        kind = j.jtype.name
        carried[j.body_i].append(f.P_i)
        carried[j.body_j].append(f.P_j)
        zi, zj = f.R_i[:, 2], f.R_j[:, 2]
        if kind in ("revolute", "dot-1", "dot-2"):
            markers.append(Marker(j.name, "revolute" if kind == "revolute" else "other", f.P_i))
            axes.append(Axis(j.name, "z''", f.P_i, zi))
        elif kind == "universal":
            markers.append(Marker(j.name, "universal", f.P_i))
            axes += [Axis(j.name, "z''", f.P_i, zi), Axis(j.name, "y''", f.P_i, f.R_j[:, 1])]
        elif kind in ("spherical", "spherical-point"):
            markers.append(Marker(j.name, "spherical", f.P_i))
        elif kind == "fixed":
            markers.append(Marker(j.name, "fixed", f.P_i))
        elif kind in ("translational", "cylindrical"):
            segments.append(Segment("slide", j.name, f.P_i, f.P_j))
            markers.append(Marker(j.name, kind, f.P_j))
            axes.append(Axis(j.name, "z''", f.P_j, zi))
        elif kind == "spherical-translational":
            segments.append(Segment("slide", j.name, f.P_i, f.P_j))
            markers += [Marker(j.name, "spherical", f.P_i), Marker(j.name, "translational", f.P_j)]
            axes.append(Axis(j.name, "z''", f.P_j, zj))
        elif kind == "free":
            segments.append(Segment("slide", j.name, f.P_i, f.P_j))
        elif kind == "revolute-spherical":
            segments.append(Segment("link", j.name, f.P_i, f.P_j))
            markers += [Marker(j.name, "revolute", f.P_i), Marker(j.name, "spherical", f.P_j)]
            axes.append(Axis(j.name, "z''", f.P_i, zi))
        elif kind == "translational-distance":
            rack_end = snap.cut_point(j.name)
            segments += [Segment("slide", j.name, f.P_i, rack_end), Segment("link", j.name, rack_end, f.P_j)]
            markers += [
                Marker(j.name, "translational", f.P_i),
                Marker(j.name, "spherical", rack_end),
                Marker(j.name, "spherical", f.P_j),
            ]
            axes.append(Axis(j.name, "z''", f.P_i, zi))
        elif kind == "distance":
            segments.append(Segment("link", j.name, f.P_i, f.P_j))
            markers += [Marker(j.name, "spherical", f.P_i), Marker(j.name, "spherical", f.P_j)]
        else:
            markers.append(Marker(j.name, "other", f.P_i))
        if j.name not in tree and j.jtype.origins_coincide:  # their gap shows the loop not closed
            segments.append(Segment("gap", j.name, f.P_i, f.P_j))

    points: dict[str, Array] = {}
    for b in mech.bodies:
        r, A = snap.r[b.name], snap.A[b.name]
        for name, p in b.points:
            points[f"{b.name}.{name}"] = r + A @ np.asarray(p, dtype=float)
            carried[b.name].append(points[f"{b.name}.{name}"])
        if not b.fixed:
            segments += [Segment("body", b.name, r, P) for P in carried[b.name]]

    size = max(
        (float(np.linalg.norm(s.end - s.start)) for s in segments),
        default=0.0,
    )
    tiny = 1e-9 * max(size, 1.0)
    segments = [s for s in segments if float(np.linalg.norm(s.end - s.start)) > tiny]
    axes = [Axis(a.joint, a.label, a.origin, _unit(a.direction)) for a in axes]
    return Scene(
        mech.name,
        model.units.get("length", ""),
        tuple(mech.body_names),
        tuple(segments),
        tuple(markers),
        tuple(axes),
        points,
    )


__all__ = ["Axis", "Marker", "Scene", "Segment", "bounds", "build_scene", "scale"]
