"""Forward kinematics over the spanning tree (eq. 28 and section 3.1).

For a tree joint from parent body p to child body c, with joint frame a on p and b on c:
``R_a = A_p C_a``, ``P_a = r_p + A_p s'_a``; ``R_b = R_a A''(q)``, ``P_b = P_a + R_a d''(q)``
(frames swapped and A'', d'' inverted when the joint is traversed from its body j);
``A_c = R_b C_b^T``, ``r_c = P_b - A_c s'_b``. With the paper's convention (no child frame:
``s'_b = 0``, ``C_b = I``) this is ``r_j = r_i + A_i s'_ij + d_ij``, ``A_j = A_i C_ij A''_ij``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from kinprop.model.design import Design
from kinprop.model.mechanism import Mechanism
from kinprop.spatial import Array
from kinprop.topology import Topology


@dataclass
class JointFrames:
    """Global joint frames of one joint: origins ``P_i``, ``P_j`` and orientations ``R_i``, ``R_j``."""

    P_i: Array
    R_i: Array
    P_j: Array
    R_j: Array


@dataclass
class Kinematics:
    r: dict[str, Array]
    A: dict[str, Array]
    frames: dict[str, JointFrames]  # tree joints


def frames_on_bodies(design: Design, joint: str, r_i: Array, A_i: Array, r_j: Array, A_j: Array) -> JointFrames:
    """Joint frames of a joint from its two bodies' poses (cut joints)."""
    return JointFrames(
        r_i + A_i @ design.value(joint, "s_i"),
        A_i @ design.value(joint, "C_i"),
        r_j + A_j @ design.value(joint, "s_j"),
        A_j @ design.value(joint, "C_j"),
    )


def joint_frames(mech: Mechanism, design: Design, kin: Kinematics, joint: str) -> JointFrames:
    """Global frames of any joint: tree joints from the recursion, cut joints from their bodies."""
    f = kin.frames.get(joint)
    if f is None:
        j = mech.joint(joint)
        f = frames_on_bodies(design, joint, kin.r[j.body_i], kin.A[j.body_i], kin.r[j.body_j], kin.A[j.body_j])
    return f


def forward_kinematics(mech: Mechanism, topo: Topology, design: Design, coords: Mapping[str, Array]) -> Kinematics:
    r: dict[str, Array] = {}
    A: dict[str, Array] = {}
    for b in mech.bodies:
        if b.fixed:
            r[b.name], A[b.name] = b.r, b.A
    frames: dict[str, JointFrames] = {}
    for t in topo.tree:
        j = mech.joint(t.joint)
        q = coords.get(t.joint, np.zeros(0))
        App, dpp = j.jtype.placement(q)
        rp, Ap = r[t.parent], A[t.parent]
        if not t.reversed:
            P_i = rp + Ap @ design.value(t.joint, "s_i")
            R_i = Ap @ design.value(t.joint, "C_i")
            R_j = R_i @ App
            P_j = P_i + R_i @ dpp
            Ac = R_j @ design.value(t.joint, "C_j").T
            rc = P_j - Ac @ design.value(t.joint, "s_j")
        else:
            P_j = rp + Ap @ design.value(t.joint, "s_j")
            R_j = Ap @ design.value(t.joint, "C_j")
            R_i = R_j @ App.T
            P_i = P_j - R_i @ dpp
            Ac = R_i @ design.value(t.joint, "C_i").T
            rc = P_i - Ac @ design.value(t.joint, "s_i")
        r[t.child], A[t.child] = rc, Ac
        frames[t.joint] = JointFrames(P_i, R_i, P_j, R_j)
    return Kinematics(r, A, frames)


def retract(layout, design, coords, dx):
    """``(design, coords) (+) dx``: additive for q, s', l; ``C <- exp(tilde(dxi')) C``."""
    from kinprop.model.design import as_coordinates
    from kinprop.spatial import exp_so3

    new_q = dict(coords)
    new_d: dict[str, np.ndarray] = {}
    for v in layout.variables:
        step = dx[v.columns]
        if not np.any(step):
            continue
        if v.group == "q":
            new_q[v.joint] = coords[v.joint] + step
        elif v.group == "C":
            new_d[v.key] = exp_so3(step) @ design[v.key]
        elif v.group == "l":
            new_d[v.key] = design[v.key] + step[0]
        else:
            new_d[v.key] = design[v.key] + step
    return (design.replace(new_d) if new_d else design), as_coordinates(new_q)


def read(layout, design, coords, key):
    """Current value of a layout variable as a flat array (C flattened)."""
    v = layout[key]
    if v.group == "q":
        return np.asarray(coords[v.joint], dtype=float)
    return np.atleast_1d(np.asarray(design[key], dtype=float)).ravel()
