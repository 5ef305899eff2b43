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
from kinprop.model import Model
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


def joint_hardpoints(model: Model) -> dict[str, list[float]]:
    """``{"JOINT.i": [x, y, z], "JOINT.j": [x, y, z]}``: each joint's frame origin on its first
    and second body, global, in the model's length unit (joint order, ``i`` before ``j``)."""
    snap = snapshot(model)
    out: dict[str, list[float]] = {}
    for name, f in snap.frames.items():
        out[f"{name}.i"] = _xyz(f.P_i)
        out[f"{name}.j"] = _xyz(f.P_j)
    return out


def named_points(model: Model) -> dict[str, list[float]]:
    """``{"BODY.NAME": [x, y, z]}``: the bodies' named points (``Body.points``), global."""
    snap = snapshot(model)
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


__all__ = ["Snapshot", "joint_hardpoints", "named_points", "snapshot"]
