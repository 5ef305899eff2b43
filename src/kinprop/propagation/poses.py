"""Body poses and every joint's relative value (tree and cut joints alike) from one state.

A body's pose is ``(A, r)``: orientation (body frame to global) and origin, global. A joint's
relative value is read from its two global joint frames ``(P_i, R_i)``, ``(P_j, R_j)``
(:meth:`kinprop.engine.Engine.poses`): ``R'' = R_i^T R_j`` and ``d'' = R_i^T (P_j - P_i)``
(frame i), by the joint type's own convention — so a tree joint's value equals its
coordinates and a cut joint gets the value it would have as a tree joint:

* revolute: ``angle`` about z''; translational: ``displacement`` along z''; cylindrical: both;
* universal (``R'' = Rz(q0) Ry(q1)``): ``angle_1 = atan2(-R''_01, R''_11)``,
  ``angle_2 = atan2(-R''_20, R''_22)``;
* spherical: ``euler`` parameters [e0..e3] (e0 >= 0) and ``rotation_vector``;
  spherical-translational adds ``displacement`` along the rotated z''; free: ``translation``
  (frame i) and ``euler``;
* distance-like cut joints (distance, revolute-spherical, translational-distance,
  spherical-point): ``distance`` ``|P_j - P_i|``; dot-1: ``angle`` between z''_i and z''_j.

Every joint also carries ``rotation_vector`` and ``translation`` (frame i). Angles in
radians, lengths in the model's length unit. Each type's values are its own
(:meth:`kinprop.joints.base.JointType.relative_values`).
"""

from __future__ import annotations

import numpy as np

from kinprop.engine import Engine, State
from kinprop.joints import joint_type
from kinprop.spatial import Array, log_so3


def body_poses(engine: Engine, state: State) -> dict[str, dict[str, Array]]:
    """``{BODY: {"R": A (3, 3), "t": r (3,)}}``: every body's global orientation and origin."""
    r, A, _, _ = engine.poses(state)
    return {b: {"R": A[k].copy(), "t": r[k].copy()} for k, b in enumerate(engine.mechanism.body_names)}


def joint_value(jtype: str, Rr: Array, d: Array) -> dict[str, float | Array]:
    """The named relative values of a joint type from ``R''`` and ``d''`` (the type's own
    :meth:`~kinprop.joints.base.JointType.relative_values`), with ``rotation_vector`` and
    ``translation``."""
    out = joint_type(jtype).relative_values(Rr, d)
    out["rotation_vector"] = np.asarray(log_so3(Rr), dtype=float)
    out["translation"] = d.copy()
    return out


def joint_values(engine: Engine, state: State) -> dict[str, dict[str, float | Array]]:
    """``{JOINT: {name: value}}`` for every joint, tree and cut (module docstring)."""
    _, _, P, R = engine.poses(state)
    out = {}
    for k, j in enumerate(engine.mechanism.joints):
        Rr = R[k, 0].T @ R[k, 1]
        d = R[k, 0].T @ (P[k, 1] - P[k, 0])
        out[j.name] = joint_value(j.jtype.name, Rr, d)
    return out


__all__ = ["body_poses", "joint_value", "joint_values"]
