"""Global points of a model at its current state: joint hardpoints, named body points, frames.

A joint's hardpoints are the global origins of its joint frame on its first body (``i``) and
on its second body (``j``): ``P_i = r_i + A_i s'_i`` and ``P_j = r_j + A_j s'_j`` (for a tree
joint from the forward kinematics over the spanning tree, eq. 28; for a cut joint from its
two bodies' poses). For a T-D joint ``P_i`` is the rack's origin, without the q3 slide.
At an assembled state the two hardpoints of a revolute, universal or spherical joint coincide.

Everything is evaluated from one forward-kinematics pass at the coordinates as given; the
model is not re-assembled here. Lengths are in the model's length unit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from kinprop.engine import Engine, JointFrames, Kinematics
from kinprop.engine import compile as compile_engine
from kinprop.errors import AddressError
from kinprop.model import Model
from kinprop.propagation.hardpoints import parse_global
from kinprop.spatial import Array


@dataclass(frozen=True)
class Snapshot:
    """A model's body poses and every joint's global frames at its current state."""

    model: Model
    kin: Kinematics
    #: every joint (tree and cut), in the model's joint order
    frames: dict[str, JointFrames]

    @property
    def r(self) -> dict[str, Array]:
        """Body frame origins (global)."""
        return self.kin.r

    @property
    def A(self) -> dict[str, Array]:
        """Body orientations (body frame to global)."""
        return self.kin.A

    def cut_point(self, joint: str) -> Array:
        """The point on body i that a cut joint acts at: ``P_i + R_i u(qc)`` (T-D: the slid
        rack end); ``P_i`` for joints without own coordinates and for tree joints."""
        j = self.model.mechanism.joint(joint)
        f = self.frames[joint]
        if not j.jtype.n_cut_coordinates:  # only cut-only joints (T-D) have own coordinates
            return f.P_i
        u, _ = j.jtype.cut_offset(np.asarray(self.model.coordinates[joint], dtype=float))
        return f.P_i + f.R_i @ u


def snapshot(model: Model, engine: Engine | None = None) -> Snapshot:
    """Forward kinematics of ``model`` and the global frames of all its joints."""
    kin = (engine or compile_engine(model.mechanism)).kinematics(model.design, model.coordinates)
    return Snapshot(model, kin, kin.frames)


def _xyz(v: Array) -> list[float]:
    return [float(x) for x in np.asarray(v, dtype=float)]


def joint_hardpoints(model: Model, engine: Engine | None = None) -> dict[str, list[float]]:
    """``{"JOINT.i": [x, y, z], "JOINT.j": [x, y, z]}``: each joint's frame origin on its first
    and second body, global, in the model's length unit (joint order, ``i`` before ``j``)."""
    snap = snapshot(model, engine)
    out: dict[str, list[float]] = {}
    for name, f in snap.frames.items():
        out[f"{name}.i"] = _xyz(f.P_i)
        out[f"{name}.j"] = _xyz(f.P_j)
    return out


def named_points(model: Model, engine: Engine | None = None) -> dict[str, list[float]]:
    """``{"BODY.NAME": [x, y, z]}``: the bodies' named points (``Body.points``), global."""
    snap = snapshot(model, engine)
    out: dict[str, list[float]] = {}
    for b in model.mechanism.bodies:
        for name, p in b.points:
            ref = b.joint_point(name)
            if ref is not None:  # a joint's point follows the joint
                f = snap.frames[ref[0]]
                out[f"{b.name}.{name}"] = _xyz(f.P_i if ref[1] == "i" else f.P_j)
            else:
                out[f"{b.name}.{name}"] = _xyz(snap.r[b.name] + snap.A[b.name] @ np.asarray(p, dtype=float))
    return out


#: the groups of a suspension's hardpoint table, in the order a designer reads them
HARDPOINT_GROUPS = ("chassis pickups", "upright points", "steering", "spring/damper", "wheel", "other")
#: joint-name prefixes of a tie rod (a distance link to the wheel that steers it)
TIE_ROD_NAMES = ("TR", "TIE", "TOE", "STEER")


def hardpoint_table(model: Model, engine: Engine | None = None) -> list[dict[str, object]]:
    """A model's hardpoints in the order a suspension designer reads them (OptimumK, Adams Car):
    chassis pickups (the arms' pivots ``front``/``rear``, the chassis ends of links and struts,
    any joint on the fixed body), upright points (the ball joints on the wheel body), steering
    (the rack, each tie rod's inner and outer end), spring/damper (each element's two ends),
    wheel (``wheel_centre``, ``spin_axis``, ``contact_patch``); then the others (joints between
    moving bodies, the moving bodies' other named points). Rows ``{"group", "point", "x", "y",
    "z", "address", "body"}``: global, the model's length unit, joint order within a group;
    ``address`` the ``hardpoint:`` address an edit of the point takes (``kinprop propagate --set
    ADDRESS=x,y,z``, the workbench), None for a point that follows its body; ``body`` the body
    it is on (``i/j`` for a joint's point on both)."""
    mech = model.mechanism
    eng = engine if engine is not None else compile_engine(model)
    wheels = {b.name for b in mech.bodies if {"wheel_centre", "spin_axis"} <= {n for n, _ in b.points}}
    fixed = {b.name for b in mech.bodies if b.fixed}
    racks = {j.body_j if j.body_i in fixed else j.body_i for j in mech.joints
             if j.type == "translational" and (j.body_i in fixed) != (j.body_j in fixed)}  # fmt: skip
    snap = snapshot(model, eng)
    points = named_points(model, eng)
    rows: list[tuple[str, str, list[float], str | None, str]] = []

    def editable(address: str) -> str | None:
        try:
            parse_global(eng, address)
        except AddressError:
            return None
        return address

    def add(group: str, name: str, p: list[float], address: str | None, body: str) -> None:
        rows.append((group, name, p, address, body))

    for j in mech.joints:
        f = snap.frames[j.name]
        ends = (j.body_i, j.body_j)
        side = {j.body_i: _xyz(f.P_i), j.body_j: _xyz(f.P_j)}
        at = {j.body_i: editable(f"hardpoint:{j.name}.i"), j.body_j: editable(f"hardpoint:{j.name}.j")}
        whole = editable(f"hardpoint:{j.name}") if j.type != "distance" else None
        on_wheel = [b for b in ends if b in wheels]
        other = [b for b in ends if b not in wheels]
        steering = j.name.upper().startswith(TIE_ROD_NAMES) or any(b in racks for b in ends)
        if on_wheel and other and steering:
            add("steering", f"{j.name} inner", side[other[0]], at[other[0]], other[0])
            add("steering", f"{j.name} outer", side[on_wheel[0]], at[on_wheel[0]], on_wheel[0])
        elif any(b in racks for b in ends) and any(b in fixed for b in ends):
            add("steering", j.name, side[j.body_i], whole or at[j.body_i], "/".join(ends))
        elif on_wheel and other and other[0] in fixed:  # a strut or link straight to the chassis
            add("chassis pickups", j.name, side[other[0]], at[other[0]] or whole, other[0])
            add("upright points", j.name, side[on_wheel[0]], at[on_wheel[0]] or whole, on_wheel[0])
        elif any(b in fixed for b in ends):
            chassis = next(b for b in ends if b in fixed)
            pivots = [k for k in points if k.startswith(f"{chassis}.{j.name}.")]
            for k in pivots:
                pivot = k.rsplit(".", 1)[1]
                add("chassis pickups", f"{j.name} {pivot}", points[k], editable(f"hardpoint:{j.name}.{pivot}"), chassis)
            if not pivots and (whole or j.type != "distance"):
                add("chassis pickups", j.name, side[chassis], whole or at[chassis], "/".join(ends))
            elif not pivots:  # a link from the chassis: its two ends
                moving = next(b for b in ends if b != chassis)
                add("chassis pickups", f"{j.name} inner", side[chassis], at[chassis], chassis)
                add("other", f"{j.name} outer", side[moving], at[moving], moving)
        elif on_wheel:
            group = "upright points"
            if whole is not None:
                add(group, j.name, side[on_wheel[0]], whole, "/".join(ends))
            else:  # a link to the wheel from a moving body: its two ends
                add("other", f"{j.name} ({other[0]})" if other else j.name, side[ends[0]], at[ends[0]], ends[0])
                add(group, f"{j.name} ({on_wheel[0]})", side[ends[1]], at[ends[1]], ends[1])
        elif whole is not None:
            add("other", j.name, side[j.body_i], whole, "/".join(ends))
        else:
            for k, b in enumerate(ends):
                add("other", f"{j.name} {'ij'[k]} ({b})", side[b], at[b], b)
    for e in model.elements:
        for body, s_, end in ((e.body_i, e.s_i, "i"), (e.body_j, e.s_j, "j")):
            p = snap.r[body] + snap.A[body] @ np.asarray(s_, dtype=float)
            add("spring/damper", f"{e.name} {end}", _xyz(p), None, body)
    listed = set()
    for w in sorted(wheels, key=mech.body_names.index):
        for n in ("wheel_centre", "spin_axis", "contact_patch"):
            if f"{w}.{n}" in points:
                add("wheel", f"{w}.{n}" if len(wheels) > 1 else n, points[f"{w}.{n}"], None, w)
                listed.add(f"{w}.{n}")
    for b in mech.bodies:
        if b.fixed:
            continue
        for name, _ in b.points:
            if b.joint_point(name) is None and f"{b.name}.{name}" not in listed:
                add("other", f"{b.name}.{name}", points[f"{b.name}.{name}"], None, b.name)
    order = {g: k for k, g in enumerate(HARDPOINT_GROUPS)}
    rows.sort(key=lambda r: order[r[0]])  # stable: joint order within a group
    return [{"group": g, "point": n, "x": p[0], "y": p[1], "z": p[2], "address": a, "body": b}
            for g, n, p, a, b in rows]  # fmt: skip


__all__ = ["HARDPOINT_GROUPS", "Snapshot", "hardpoint_table", "joint_hardpoints", "named_points", "snapshot"]
