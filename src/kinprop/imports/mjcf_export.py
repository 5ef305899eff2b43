"""Write any kinprop model as a kinematic MJCF file that MuJoCo loads.

The body tree is kinprop's spanning tree; each body's ``pos``/``quat`` is its pose relative
to its tree parent at the model's current coordinates, which become MuJoCo's reference
configuration (``qpos0``; all joint ``ref`` are 0). Tree joints: revolute -> ``hinge``,
translational -> ``slide``, cylindrical -> ``hinge`` + ``slide``, universal -> two ``hinge``
(about axes chosen so that MuJoCo's sequential joints reproduce ``Rz(q0) Ry(q1)``); a joint
with two coordinates becomes MuJoCo joints ``NAME__q0`` and ``NAME__q1`` (qpos = q - q_now),
spherical -> ``ball``, free -> ``freejoint``, fixed -> none (the body is welded). Cut joints:
spherical -> ``<connect>``, fixed -> ``<weld relpose>``, revolute -> two ``<connect>`` on its
axis, distance -> a massless rod body (ball-jointed on body i, pointing at body j) with a
``<connect>`` at its tip. MuJoCo places a connect's point on body2 from the reference
configuration, so export an assembled model (``kinprop assemble -o`` first). Fixed bodies
other than a world at the origin are bodies welded to ``<worldbody>``. Named body points are
written as sites. Moving bodies get a placeholder ``<inertial>`` (MuJoCo needs mass to
compile); no geoms are written.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from kinprop.errors import ModelError, Problem
from kinprop.imports.rotations import matrix_to_quat
from kinprop.model import Model
from kinprop.propagation.propagate import assembly_for
from kinprop.spatial import EY, EZ, Array, rot_y, rot_z

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


def _unit(v: Array) -> Array:
    return np.asarray(v, dtype=float) / np.linalg.norm(v)


def model_to_mjcf(model: Model) -> tuple[str, list[str]]:
    """MJCF text of ``model`` at its current coordinates, and warnings (one line each)."""
    mech = model.mechanism
    asm = assembly_for(mech)
    topo = asm.topology
    kin = asm.kinematics(model.design, model.coordinates)
    design = model.design
    warnings: list[str] = []
    problems: list[Problem] = []

    root = ET.Element("mujoco", model=mech.name)
    ET.SubElement(root, "compiler", angle="radian")
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
        if t.reversed:
            anchor, C, sign = design.value(j.name, "s_i"), design.value(j.name, "C_i"), -1.0
        else:
            anchor, C, sign = design.value(j.name, "s_j"), design.value(j.name, "C_j"), 1.0
        q = np.asarray(model.coordinates.get(j.name, np.zeros(0)), dtype=float)
        axis = sign * (C @ EZ)
        name = j.name
        if jt == "revolute":
            ET.SubElement(el, "joint", name=name, type="hinge", pos=_vec(anchor), axis=_vec(axis))
        elif jt == "translational":
            ET.SubElement(el, "joint", name=name, type="slide", pos=_vec(anchor), axis=_vec(axis))
        elif jt == "cylindrical":
            ET.SubElement(el, "joint", name=f"{name}__q0", type="hinge", pos=_vec(anchor), axis=_vec(axis))
            ET.SubElement(el, "joint", name=f"{name}__q1", type="slide", pos=_vec(anchor), axis=_vec(axis))
        elif jt == "universal":
            # MuJoCo applies a body's joints in order, each about its axis in the body frame
            if t.reversed:  # body i moves: Ry(-q1) first, then Rz(-q0)
                hinges = [("q1", -(C @ rot_z(q[0]) @ EY)), ("q0", -(C @ EZ))]
            else:
                hinges = [("q0", C @ rot_y(-q[1]) @ EZ), ("q1", C @ EY)]
            for suffix, a in hinges:
                ET.SubElement(el, "joint", name=f"{name}__{suffix}", type="hinge", pos=_vec(anchor), axis=_vec(a))
        elif jt == "spherical":
            ET.SubElement(el, "joint", name=name, type="ball", pos=_vec(anchor))
        elif jt == "free":
            ET.SubElement(el, "freejoint", name=name)
        elif jt != "fixed":
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
        elif jt == "distance":
            length = float(design[f"{name}.length"])
            d = P_j - P_i
            gap = abs(float(np.linalg.norm(d)) - length)
            if np.linalg.norm(d) < 1e-12:
                problems.append(Problem(f"joints.{name}", "the two points coincide: no rod direction for MJCF"))
                continue
            A_i = kin.A[j.body_i]
            x = _unit(A_i.T @ d)
            helper = EZ if abs(x[2]) < 0.9 else EY
            y = _unit(np.cross(helper, x))
            rod = ET.SubElement(
                elements[j.body_i],
                "body",
                name=f"{name}__rod",
                pos=_vec(s_i),
                quat=_vec(matrix_to_quat(np.column_stack([x, y, np.cross(x, y)]))),
            )
            ET.SubElement(rod, "inertial", pos="0 0 0", mass=MASS, diaginertia=INERTIA)
            ET.SubElement(rod, "joint", name=f"{name}__ball", type="ball", pos="0 0 0")
            ET.SubElement(
                equality, "connect", name=name, body1=f"{name}__rod", body2=b2, anchor=_vec([length, 0.0, 0.0])
            )
        else:
            problems.append(Problem(f"joints.{name}", f"a cut joint of type {jt!r} has no MJCF form yet"))
            continue
        if gap > GAP_TOL:
            warnings.append(
                f"joints.{name}: not assembled (gap {gap:.3g}); MuJoCo takes its reference configuration as "
                "satisfying the constraint (run kinprop assemble first)"
            )
    if problems:
        raise ModelError(problems, model.source)
    if len(equality):
        root.append(equality)
    ET.indent(root)
    return ET.tostring(root, encoding="unicode") + "\n", warnings


__all__ = ["model_to_mjcf"]
