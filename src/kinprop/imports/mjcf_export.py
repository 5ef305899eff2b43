"""Write any kinprop model as a kinematic MJCF file that MuJoCo loads.

The body tree is kinprop's spanning tree; each body's ``pos``/``quat`` is its pose relative
to its tree parent at the model's current coordinates, which become MuJoCo's reference
configuration (``qpos0``; all joint ``ref`` are 0). Tree joints: revolute -> ``hinge``,
translational -> ``slide``, cylindrical -> ``hinge`` + ``slide``, universal -> two ``hinge``
(about axes chosen so that MuJoCo's sequential joints reproduce ``Rz(q0) Ry(q1)``); a joint
with two coordinates becomes MuJoCo joints ``NAME__q0`` and ``NAME__q1`` (qpos = q - q_now),
spherical -> ``ball``, free -> ``freejoint``, fixed -> none (the body is welded). Cut joints:
spherical -> ``<connect>``, fixed -> ``<weld relpose>``, revolute -> two ``<connect>`` on its
axis; distance, R-S and T-D -> a rod body of the joint's length on body i (ball-jointed;
hinged about z''_i for R-S; on a slider along z''_i for T-D) with a ``<connect>`` at its tip
to body j; S-T -> a slider on body j's axis connected to body i's point; translational,
cylindrical and universal -> a copy of body j carried from body i by the joint's MuJoCo
joints (``NAME__copy``) and welded to body j. Dot-1 and dot-2 joints have no MJCF form.
Couplings -> ``<joint joint1 joint2 polycoef>``: MuJoCo's polynomial is about ``qpos0`` (the
current coordinates), so kinprop's ``q_a - q_a0 = P(q_b - q_b0)`` is re-expanded exactly about
the current ``q_b`` (:func:`recentred_coefficients`).
MuJoCo places a connect's point on body2 from the reference configuration, so export an
assembled model (``kinprop assemble -o`` first). Fixed bodies other than a world at the
origin are bodies welded to ``<worldbody>``. Named body points are written as sites. Moving
bodies get a placeholder ``<inertial>`` (MuJoCo needs mass to compile); no geoms are written.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np

from kinprop.analysis.points import snapshot
from kinprop.errors import ModelError, Problem
from kinprop.imports.rotations import matrix_to_quat
from kinprop.model import Design, Model
from kinprop.spatial import EY, EZ, Array, euler_to_matrix, rot_y, rot_z
from kinprop.topology import build_topology

#: placeholder inertia of moving bodies (MuJoCo refuses massless moving bodies)
MASS = "1"
INERTIA = "0.01 0.01 0.01"
#: distance between the two connects that close a cut revolute joint (model length unit)
REVOLUTE_SPAN = 1.0
#: a gap at a cut joint larger than this is reported (the export is then not exact)
GAP_TOL = 1e-9

WORLD = "world"


def _num(v: float) -> str:
    return repr(float(v) + 0.0)


def _vec(v: Array) -> str:
    return " ".join(_num(x) for x in np.asarray(v, dtype=float).ravel())


#: name of the ``<custom><text>`` element that carries the model's declared units
UNITS_TEXT = "kinprop.units"


def _unit(v: Array) -> Array:
    return np.asarray(v, dtype=float) / np.linalg.norm(v)


def joint_elements(el: ET.Element, name: str, jt: str, design: Design, reversed_: bool, q: Array) -> bool:
    """MuJoCo joints in body ``el`` (the joint's child body) reproducing kinprop joint ``name``.

    MuJoCo applies a body's joints in order, each about its axis in the body frame, from the
    reference pose (the current ``q``); False when the type has no MJCF form.
    """
    if reversed_:  # the child is body i
        anchor, C = design.value(name, "s_i"), design.value(name, "C_i")
    else:
        anchor, C = design.value(name, "s_j"), design.value(name, "C_j")
    axis = (-1.0 if reversed_ else 1.0) * (C @ EZ)

    def add(suffix: str, kind: str, pos: Array, a: Array | None = None) -> None:
        attrs = {"name": f"{name}{suffix}", "type": kind, "pos": _vec(pos)}
        if a is not None:
            attrs["axis"] = _vec(a)
        ET.SubElement(el, "joint", attrs)

    if jt == "revolute":
        add("", "hinge", anchor, axis)
    elif jt == "translational":
        add("", "slide", anchor, axis)
    elif jt == "cylindrical":
        add("__q0", "hinge", anchor, axis)
        add("__q1", "slide", anchor, axis)
    elif jt == "universal":
        if reversed_:  # body i moves: Ry(-q1) first, then Rz(-q0)
            add("__q1", "hinge", anchor, -(C @ rot_z(q[0]) @ EY))
            add("__q0", "hinge", anchor, -(C @ EZ))
        else:
            add("__q0", "hinge", anchor, C @ rot_y(-q[1]) @ EZ)
            add("__q1", "hinge", anchor, C @ EY)
    elif jt == "spherical":
        add("", "ball", anchor)
    elif jt == "spherical-translational":
        A, t = euler_to_matrix(q[0:4]), q[4]
        if reversed_:  # body i slides along body j's (parent-fixed) strut axis, then turns about its point
            add("__slide", "slide", anchor, -(C @ A @ EZ))
            add("__ball", "ball", anchor)
        else:  # body j turns about the sphere centre, then slides along its own axis
            add("__ball", "ball", anchor - (C @ EZ) * t)
            add("__slide", "slide", anchor, C @ EZ)
    elif jt != "fixed":
        return False
    return True


def recentred_coefficients(coef: Array, s: float, t: float) -> Array:
    """Coefficients ``c'`` with ``sum c'_m x^m = P(x + s) - t`` for ``P(x) = sum c_k x^k``:
    ``c'_m = sum_{k >= m} binom(k, m) c_k s^(k - m)``, then ``c'_0 -= t`` (exact for degree 4).
    With ``x = q_b - q_b,now``, ``s = q_b,now - q_b0`` and ``t = q_a,now - q_a0`` this is the
    coupling about the current coordinates (MuJoCo's ``qpos0``); ``c'_0`` is the gap there."""
    n = len(coef)
    out = np.array([sum(math.comb(k, m) * coef[k] * s ** (k - m) for k in range(m, n)) for m in range(n)])
    out[0] -= t
    return out


def model_to_mjcf(model: Model) -> tuple[str, list[str]]:
    """MJCF text of ``model`` at its current coordinates, and warnings (one line each)."""
    mech = model.mechanism
    topo = build_topology(mech)
    kin = snapshot(model)  # body poses r, A at the model's coordinates
    design = model.design
    warnings: list[str] = []
    problems: list[Problem] = []

    root = ET.Element("mujoco", model=mech.name)
    ET.SubElement(root, "compiler", angle="radian")
    # the declared units, read back by kinprop's importer (MuJoCo keeps custom text as data)
    units = " ".join(f"{k}={v}" for k, v in model.units.items() if v)
    ET.SubElement(ET.SubElement(root, "custom"), "text", name=UNITS_TEXT, data=units)
    worldbody = ET.SubElement(root, "worldbody")
    equality = ET.Element("equality")
    elements: dict[str, ET.Element] = {}

    world_body = next(
        (b for b in mech.bodies if b.fixed and b.name == WORLD and np.allclose(b.r, 0) and np.allclose(b.A, np.eye(3))),
        None,
    )
    if world_body is not None:
        elements[WORLD] = worldbody
    point_names = [p for b in mech.bodies for p, _ in b.points]

    def sites(el: ET.Element, body_name: str) -> None:
        for p, v in mech.body(body_name).points:
            name = p if point_names.count(p) == 1 else f"{body_name}.{p}"
            ET.SubElement(el, "site", name=name, pos=_vec(v))

    def body_element(parent: ET.Element, name: str, pos: Array, R: Array, moving: bool) -> ET.Element:
        el = ET.SubElement(parent, "body", name=name, pos=_vec(pos), quat=_vec(matrix_to_quat(R)))
        if moving:
            ET.SubElement(el, "inertial", pos="0 0 0", mass=MASS, diaginertia=INERTIA)
        return el

    for b in mech.bodies:
        if b.fixed and b.name not in elements:
            if b.name == WORLD:
                problems.append(Problem(f"bodies.{b.name}", "a fixed body named 'world' must sit at the origin"))
                continue
            elements[b.name] = body_element(worldbody, b.name, b.r, b.A, moving=False)
        if b.fixed:
            sites(elements[b.name], b.name)

    for t in topo.tree:
        j = mech.joint(t.joint)
        jt = j.jtype.name
        parent_el = elements[t.parent]
        r_p, A_p = kin.r[t.parent], kin.A[t.parent]
        if jt == "free":
            if not mech.body(t.parent).fixed:
                problems.append(Problem(f"joints.{j.name}", "MJCF allows a free joint only on a body of the world"))
                continue
            parent_el, r_p, A_p = worldbody, np.zeros(3), np.eye(3)
        r_c, A_c = kin.r[t.child], kin.A[t.child]
        el = body_element(parent_el, t.child, A_p.T @ (r_c - r_p), A_p.T @ A_c, moving=True)
        elements[t.child] = el
        q = np.asarray(model.coordinates.get(j.name, np.zeros(0)), dtype=float)
        if jt == "free":
            ET.SubElement(el, "freejoint", name=j.name)
        elif not joint_elements(el, j.name, jt, design, t.reversed, q):
            problems.append(Problem(f"joints.{j.name}", f"a tree joint of type {jt!r} has no MJCF form yet"))
        sites(el, t.child)

    def ref(body: str) -> str:
        return WORLD if elements.get(body) is worldbody else body

    for name in topo.cut_joints:
        j = mech.joint(name)
        jt = j.jtype.name
        s_i, s_j = design.value(name, "s_i"), design.value(name, "s_j")
        C_i, C_j = design.value(name, "C_i"), design.value(name, "C_j")
        P_i = kin.r[j.body_i] + kin.A[j.body_i] @ s_i
        P_j = kin.r[j.body_j] + kin.A[j.body_j] @ s_j
        b1, b2 = ref(j.body_i), ref(j.body_j)
        if jt in ("spherical", "spherical-point", "revolute"):
            gap = float(np.linalg.norm(P_i - P_j))
            ET.SubElement(equality, "connect", name=name, body1=b1, body2=b2, anchor=_vec(s_i))
            if jt == "revolute":
                gap = max(gap, float(np.linalg.norm(kin.A[j.body_i] @ C_i @ EZ - kin.A[j.body_j] @ C_j @ EZ)))
                far = s_i + REVOLUTE_SPAN * (C_i @ EZ)
                ET.SubElement(equality, "connect", name=f"{name}__axis", body1=b1, body2=b2, anchor=_vec(far))
        elif jt == "fixed":
            R = C_i @ C_j.T
            rel = np.concatenate([s_i - R @ s_j, matrix_to_quat(R)])
            ET.SubElement(equality, "weld", name=name, body1=b1, body2=b2, relpose=_vec(rel))
            gap = float(np.linalg.norm(P_i - P_j) + np.linalg.norm(kin.A[j.body_i] @ C_i - kin.A[j.body_j] @ C_j))
        elif jt in ("distance", "revolute-spherical", "translational-distance"):
            # a rod of the joint's length from body i's point (slid along the rack for T-D,
            # turning about z''_i for R-S, free to turn for a distance joint) to body j's point
            length = float(design[f"{name}.length"])
            A_i, R_i = kin.A[j.body_i], kin.A[j.body_i] @ C_i
            holder, base = elements[j.body_i], s_i
            if jt == "translational-distance":
                qc = float(np.asarray(model.coordinates[name])[0])
                base = s_i + C_i @ EZ * qc
                holder = ET.SubElement(holder, "body", name=f"{name}__rack", pos=_vec(base), quat="1 0 0 0")
                ET.SubElement(holder, "inertial", pos="0 0 0", mass=MASS, diaginertia=INERTIA)
                ET.SubElement(holder, "joint", name=f"{name}__slide", type="slide", pos="0 0 0", axis=_vec(C_i @ EZ))
                base = np.zeros(3)
            P_base = kin.r[j.body_i] + A_i @ (s_i if jt != "translational-distance" else s_i + C_i @ EZ * qc)
            d = P_j - P_base
            gap = abs(float(np.linalg.norm(d)) - length)
            if jt == "revolute-spherical":
                gap += abs(float(d @ (R_i @ EZ)))
                d = d - (d @ (R_i @ EZ)) * (R_i @ EZ)
            if np.linalg.norm(d) < 1e-12:
                problems.append(Problem(f"joints.{name}", "the rod has no direction (its ends coincide) for MJCF"))
                continue
            x = _unit(A_i.T @ d)
            z = C_i @ EZ if jt == "revolute-spherical" else (EZ if abs(x[2]) < 0.9 else EY)
            y = _unit(np.cross(z, x))
            rod = ET.SubElement(
                holder,
                "body",
                name=f"{name}__rod",
                pos=_vec(base),
                quat=_vec(matrix_to_quat(np.column_stack([x, y, np.cross(x, y)]))),
            )
            ET.SubElement(rod, "inertial", pos="0 0 0", mass=MASS, diaginertia=INERTIA)
            if jt == "revolute-spherical":  # the rod's z is the revolute axis
                ET.SubElement(rod, "joint", name=f"{name}__hinge", type="hinge", pos="0 0 0", axis="0 0 1")
            else:
                ET.SubElement(rod, "joint", name=f"{name}__rod_ball", type="ball", pos="0 0 0")
            ET.SubElement(
                equality, "connect", name=name, body1=f"{name}__rod", body2=b2, anchor=_vec([length, 0.0, 0.0])
            )
        elif jt == "spherical-translational":
            # body i's point slides on body j's axis: a slider on body j, connected to the point
            z_j = kin.A[j.body_j] @ C_j @ EZ
            t = float((P_i - P_j) @ z_j)
            gap = float(np.linalg.norm(P_i - P_j - t * z_j))
            slider = ET.SubElement(
                elements[j.body_j], "body", name=f"{name}__slider", pos=_vec(s_j + C_j @ EZ * t), quat="1 0 0 0"
            )
            ET.SubElement(slider, "inertial", pos="0 0 0", mass=MASS, diaginertia=INERTIA)
            ET.SubElement(slider, "joint", name=f"{name}__slide", type="slide", pos="0 0 0", axis=_vec(C_j @ EZ))
            ET.SubElement(equality, "connect", name=name, body1=f"{name}__slider", body2=b1, anchor="0 0 0")
        elif jt in ("translational", "cylindrical", "universal"):
            # a copy of body j carried by the joint's tree form from body i, welded to body j
            R_i, R_j = kin.A[j.body_i] @ C_i, kin.A[j.body_j] @ C_j
            A_rel, d_rel = R_i.T @ R_j, R_i.T @ (P_j - P_i)
            if jt == "translational":
                q = np.array([d_rel[2]])
            elif jt == "cylindrical":
                q = np.array([np.arctan2(A_rel[1, 0], A_rel[0, 0]), d_rel[2]])
            else:
                q = np.array([np.arctan2(-A_rel[0, 1], A_rel[1, 1]), np.arctan2(-A_rel[2, 0], A_rel[2, 2])])
            A2, d2 = j.jtype.placement(q)
            R_rel = C_i @ A2 @ C_j.T
            p_rel = s_i + C_i @ d2 - R_rel @ s_j
            ghost = body_element(elements[j.body_i], f"{name}__copy", p_rel, R_rel, moving=True)
            joint_elements(ghost, name, jt, design, False, q)
            ET.SubElement(equality, "weld", name=name, body1=f"{name}__copy", body2=b2, relpose="0 0 0 1 0 0 0")
            A_pred = kin.A[j.body_i] @ R_rel
            r_pred = kin.r[j.body_i] + kin.A[j.body_i] @ p_rel
            gap = float(np.linalg.norm(r_pred - kin.r[j.body_j]) + np.linalg.norm(A_pred - kin.A[j.body_j]))
        else:
            problems.append(Problem(f"joints.{name}", f"a cut joint of type {jt!r} has no MJCF form yet"))
            continue
        if gap > GAP_TOL:
            warnings.append(
                f"joints.{name}: not assembled (gap {gap:.3g}); MuJoCo takes its reference configuration as "
                "satisfying the constraint (run kinprop assemble first)"
            )
    for c in mech.couplings:
        qa, qb = (float(np.asarray(model.coordinates[n])[0]) for n in (c.joint_a, c.joint_b))
        coef = recentred_coefficients(np.asarray(design[f"{c.name}.coef"], float), qb - c.q_b0, qa - c.q_a0)
        ET.SubElement(equality, "joint", name=c.name, joint1=c.joint_a, joint2=c.joint_b, polycoef=_vec(coef))
        if abs(coef[0]) > GAP_TOL:
            gap = abs(coef[0])
            warnings.append(f"couplings.{c.name}: not assembled (gap {gap:.3g}); MuJoCo takes its reference "
                            "configuration as satisfying the constraint (run kinprop assemble first)")  # fmt: skip
    if problems:
        raise ModelError(problems, model.source)
    if len(equality):
        root.append(equality)
    ET.indent(root)
    return ET.tostring(root, encoding="unicode") + "\n", warnings


__all__ = ["model_to_mjcf", "recentred_coefficients"]
