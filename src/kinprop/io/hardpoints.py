"""Hardpoint-style models: global joint points and axes at a reference configuration.

A hardpoint file (``style: hardpoints``) gives, for the assembled mechanism at a reference
configuration, where each joint is and which way its axes point, in global coordinates
(:class:`kinprop.io.schema.HardpointFile`; keys per joint type in :data:`KEYS`). kinprop
derives the frame-style model from it:

* **Body frames.** Fixed bodies: as declared (``position``, ``orientation``; default the
  global frame). Each moving body's frame has its origin at the point of its tree joint
  (the spanning tree of :mod:`kinprop.topology`) and, with ``body_frames: global`` (the
  default), axes parallel to the global axes at the reference; with ``body_frames: joint``
  the axes of that tree joint's frame (the paper's convention, ``s'_ji = 0``, ``C_ji = I``).
* **Joint frames** at the reference, one per joint, shared by both bodies: origin at the
  joint point and ``z''`` along the joint axis. ``x''`` follows :func:`axis_frame`; for a
  universal joint ``z''`` is the first axis (on body i) and ``y''`` the second (on body j),
  so that after ``q0`` the second axis is ``y''`` (:mod:`kinprop.joints.universal`). Joints
  without an axis (spherical, fixed, free, distance) use the global axes.
* **Design.** ``s' = A^T (P - r)`` and ``C = A^T R`` on each side. A tree joint defines the
  parent side's ``s'`` and ``C`` (and, with global body frames, the child side's ``C``; the
  child side's ``s'`` is zero); a cut joint defines the ``s'`` and ``C`` its constraints use
  (:data:`CUT_FIELDS`) and its ``length`` (given, or derived from the two points).
* **Coordinates** are zero at the reference (identity Euler parameters), unless a tree joint
  gives ``q``: its keys then describe joint frame i, and frame j is placed from it by the
  joint at ``q`` (``A''(q)``, ``d''(q)``), so the file describes the configuration at ``q``.

Named body points are given globally at the reference and stored in the body frame.
Lengths stay in the file's unit; the axis convention (:data:`kinprop.io.schema.AXES`) is
recorded, never converted. :func:`model_to_hardpoints` goes the other way, evaluating the
joints' global points and axes at a model's current coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from kinprop.analysis.points import snapshot
from kinprop.engine import JointFrames
from kinprop.engine import compile as compile_engine
from kinprop.engine.units import tree_coordinates
from kinprop.errors import AddressError, ModelError, Problem
from kinprop.io.couplings import build_couplings, couplings_to_data
from kinprop.io.elements import build_elements, build_torsion_springs, build_vehicle, elements_to_data, vehicle_to_data
from kinprop.io.loader import EULER_TOL, absurd_lengths, build_or_report
from kinprop.io.loads import build_loads, loads_to_data
from kinprop.io.points import attach_references, point_order, point_references, written_points
from kinprop.io.schema import HardpointFile, HardpointJointSpec
from kinprop.joints import REGISTRY, joint_type
from kinprop.model import Body, Design, Joint, Mechanism, Model, as_coordinates, parse_address
from kinprop.model.mechanism import validate_couplings, validate_structure
from kinprop.spatial import EY, EZ, Array, is_rotation, log_so3
from kinprop.topology import WORLD, build_topology

#: hardpoint keys per joint type: (required, optional) (each type's ``hardpoint_keys``)
KEYS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    name: jt.hardpoint_keys for name, jt in REGISTRY.items() if jt.hardpoint_keys is not None
}

#: what each hardpoint key means, for messages and docs
KEY_MEANING = {
    "point": "the joint point (both bodies)",
    "axis": "the joint axis (revolute, slide or strut axis; R-S, T-D, dot-2: on body i)",
    "axis_i": "the axis on body i (universal: the first axis)",
    "axis_j": "the axis on body j (universal: the second axis)",
    "point_i": "the joint point on body i (R-S: on the revolute axis; T-D: on the rack)",
    "point_j": "the joint point on body j (the ball or rod end)",
    "length": "the link length (default: the distance between point_i and point_j)",
}

#: design fields a cut joint defines: those its constraints use (each type's ``cut_fields``)
CUT_FIELDS: dict[str, tuple[str, ...]] = {name: jt.cut_fields for name, jt in REGISTRY.items() if jt.cut}

#: joint types that may be given by two pivots (their axis runs from the second to the first)
PIVOT_TYPES = ("revolute", "cylindrical")
#: a direction shorter than this is "zero"
ZERO_AXIS = 1e-12
#: largest |cos| between the two axes of a universal joint (they are made exactly perpendicular)
PERPENDICULAR_TOL = 1e-3
#: orthonormality tolerance of a fixed body's orientation matrix
ROTATION_TOL = 1e-4


def direction(v: object) -> Array:
    """Unit vector along ``v`` (scaled first, so huge or tiny components do not overflow)."""
    v = np.asarray(v, dtype=float)
    v = v / np.max(np.abs(v))
    return v / np.linalg.norm(v)


def axis_frame(z: Array) -> Array:
    """Joint frame ``[x'', y'', z'']`` (columns, global) with ``z''`` along ``z``.

    Rule: with ``k`` the index of the largest ``|z_k|`` (the first on ties), ``x''`` is the
    global axis ``e_(k+1 mod 3)`` made perpendicular to ``z''``; ``y'' = z'' x x''``. A joint
    along global x gets ``x'' = y, y'' = z``; along y ``x'' = z, y'' = x``; along z the global
    axes — the paper's C01, C03 and the identity.
    """
    z = direction(z)
    k = int(np.argmax(np.abs(z)))
    e = np.zeros(3)
    e[(k + 1) % 3] = 1.0
    x = e - (e @ z) * z
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def axes_frame(z: Array, y: Array) -> Array:
    """Joint frame with ``z''`` along ``z`` and ``y''`` along ``y`` made exactly perpendicular."""
    z = direction(z)
    y = direction(y)
    y = y - (y @ z) * z
    y /= np.linalg.norm(y)
    return np.column_stack([np.cross(y, z), y, z])


@dataclass(frozen=True)
class _Reference:
    """Global joint frames of one joint at the reference configuration."""

    p_i: Array
    r_i: Array
    p_j: Array
    r_j: Array


def _vec(v: list[float] | None) -> Array | None:
    return None if v is None else np.array(v, dtype=float)


def _check_keys(name: str, jtype: str, spec: HardpointJointSpec, file: str) -> list[Problem]:
    required, optional = KEYS[jtype]
    takes = ", ".join(required + optional)
    problems = []
    for key in required:
        if getattr(spec, key) is None:
            problems.append(
                Problem(f"joints.{name}.{key}", f"missing: a {jtype} joint takes {takes} ({KEY_MEANING[key]})", file)
            )
    for key in KEY_MEANING:
        if getattr(spec, key) is not None and key not in required + optional:
            problems.append(
                Problem(
                    f"joints.{name}.{key}",
                    f"a {jtype} joint does not take {key!r}; it takes {takes or 'no hardpoints'}",
                    file,
                )
            )
    for key in ("axis", "axis_i", "axis_j"):
        v = _vec(getattr(spec, key))
        if v is not None and np.max(np.abs(v)) <= ZERO_AXIS:
            problems.append(Problem(f"joints.{name}.{key}", f"expected a non-zero direction, found {v.tolist()}", file))
    if jtype == "universal" and not problems:
        cos = float(direction(spec.axis_i) @ direction(spec.axis_j))
        if abs(cos) > PERPENDICULAR_TOL:
            angle = float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))
            problems.append(
                Problem(f"joints.{name}.axis_j", f"expected perpendicular to axis_i, found {angle:.6g} deg", file)
            )
    return problems


def _pivot_problems(name: str, spec: HardpointJointSpec, fixed: set[str], file: str) -> list[Problem]:
    """A joint by its pivots: a revolute (or cylindrical) to a fixed body, no point or axis."""
    loc = f"joints.{name}.pivots"
    out = []
    try:
        jtype = joint_type(spec.type).name
    except KeyError:
        jtype = None  # reported with the known types
    if jtype is not None and jtype not in PIVOT_TYPES:
        out.append(Problem(loc, f"only {' and '.join(PIVOT_TYPES)} joints take pivots, found type {spec.type!r}", file))
    if spec.point is not None or spec.axis is not None:
        out.append(Problem(loc, "give either pivots or point and axis, not both", file))
    if not set(spec.bodies) & fixed:
        out.append(Problem(loc, "pivots are on a fixed body: one of the joint's bodies must be fixed", file))
    (_, a), (_, b) = spec.pivots.items()  # type: ignore[union-attr]
    if np.linalg.norm(np.subtract(a, b)) <= ZERO_AXIS:
        out.append(Problem(loc, "the two pivots coincide: they define no axis", file))
    return out


def _reference(jtype: str, spec: HardpointJointSpec) -> _Reference:
    """The joint's global frames at the reference (keys already checked)."""
    point, axis = _vec(spec.point), _vec(spec.axis)
    if jtype == "free" and point is None:
        point = np.zeros(3)
    if point is not None:
        if jtype == "universal":
            rot = axes_frame(_vec(spec.axis_i), _vec(spec.axis_j))
        elif axis is not None:
            rot = axis_frame(axis)
        else:
            rot = np.eye(3)
        return _Reference(point, rot, point, rot)
    if jtype == "dot-1":
        return _Reference(np.zeros(3), axis_frame(_vec(spec.axis_i)), np.zeros(3), axis_frame(_vec(spec.axis_j)))
    p_i, p_j = _vec(spec.point_i), _vec(spec.point_j)
    rot = np.eye(3) if axis is None else axis_frame(axis)
    if jtype == "revolute-spherical":
        # any point on the revolute axis: move it to the foot of the perpendicular from the ball
        z = rot[:, 2]
        p_i = p_i + ((p_j - p_i) @ z) * z
    return _Reference(p_i, rot, p_j, rot)


def file_coordinates(jt: Any, values: list[float], deg: bool) -> tuple[Array, str]:
    """A tree joint's coordinates from a file (angles in the declared unit) in solver units,
    and a problem ("" when none): the count, and Euler parameters with ``p.p = 1``."""
    q = np.array(values, dtype=float)
    if len(q) != jt.n_coordinates:
        return q, f"expected {jt.n_coordinates} coordinates for a tree {jt.name} joint, found {len(q)}"
    if jt.euler is not None:
        p = q[jt.euler]
        if abs(p @ p - 1) > EULER_TOL:
            return q, f"expected Euler parameters with p.p = 1, found p.p = {p @ p:.6g}"
    return tree_coordinates(q, jt.angle_indices, "deg" if deg else "rad", True), ""


def _placed(ref: _Reference, jt: Any, q: Array) -> _Reference:
    """The reference with frame j placed from frame i by the joint at ``q`` (eq. 24's A'', d'')."""
    a, d = jt.placement(q)
    return _Reference(ref.p_i, ref.r_i, ref.p_i + ref.r_i @ d, ref.r_i @ a)


def model_from_hardpoints(data: Any, file: str = "<data>") -> Model:
    """Validate hardpoint-style file data and build the frame-style Model (coordinates zero)."""
    return build_or_report(data, HardpointFile, build_from_hardpoints, file)


def build_from_hardpoints(spec: HardpointFile, file: str) -> Model:
    """Derive body frames, s', C, lengths and the coordinates (module docstring)."""
    problems: list[Problem] = absurd_lengths(spec, file)
    if problems:
        raise ModelError(problems)
    bodies: list[Body] = []
    pose: dict[str, tuple[Array, Array]] = {}
    for name, b in spec.bodies.items():
        loc = f"bodies.{name}"
        rot = np.eye(3)
        if not b.fixed and (b.position is not None or b.orientation is not None):
            problems.append(Problem(loc, "only fixed bodies take a pose; moving bodies follow from the joints", file))
        if b.orientation is not None:
            rot = np.array(b.orientation, dtype=float)
            if not is_rotation(rot, ROTATION_TOL):
                problems.append(
                    Problem(f"{loc}.orientation", "expected a proper rotation matrix (A^T A = I, det +1)", file)
                )
        if name == WORLD:
            problems.append(Problem(loc, f"the body name {WORLD!r} is reserved", file))
        pos = np.zeros(3) if b.position is None else np.array(b.position, dtype=float)
        if b.fixed:
            pose[name] = (pos, rot)
        bodies.append(Body(name, b.fixed, tuple(pos.tolist()), tuple(map(tuple, rot.tolist()))))
    if not spec.bodies:
        problems.append(Problem("bodies", "no bodies: expected at least one, marked 'fixed: true'", file))

    refs: dict[str, _Reference] = {}
    provisional: list[Joint] = []
    pivots: dict[str, tuple[str, dict[str, list[float]]]] = {}
    fixed_bodies = {n for n, b in spec.bodies.items() if b.fixed}
    for name, j in list(spec.joints.items()):
        if j.pivots is None:
            continue
        found = _pivot_problems(name, j, fixed_bodies, file)
        problems += found
        if not found:
            (_, front), (_, rear) = j.pivots.items()
            front, rear = np.array(front, dtype=float), np.array(rear, dtype=float)
            spec.joints[name] = j.model_copy(
                update={"point": ((front + rear) / 2).tolist(), "axis": (front - rear).tolist()}
            )
            pivots[name] = (j.bodies[0] if j.bodies[0] in fixed_bodies else j.bodies[1], dict(j.pivots))
    for name, j in spec.joints.items():
        try:
            jt = joint_type(j.type)
        except KeyError:
            jt = None  # validate_structure reports it with the known names
        if jt is not None:
            if jt.name not in KEYS:
                problems.append(Problem(f"joints.{name}.type", f"joint type {jt.name!r} has no hardpoint form", file))
            else:
                jp = _check_keys(name, jt.name, j, file)
                problems += jp
                if not jp:
                    refs[name] = _reference(jt.name, j)
        fields = frozenset({"length"}) if jt is not None and jt.has_length else frozenset()
        provisional.append(Joint(name, j.type, j.bodies[0], j.bodies[1], fields, j.cut))
    problems += [
        Problem(p.location, p.message, file)
        for p in validate_structure(tuple(bodies), tuple(provisional), tuple(spec.inputs))
    ]
    couplings, coefs, cproblems = build_couplings(
        spec.couplings, {j.name: j for j in provisional}, spec.units.angle == "deg", file
    )
    problems += cproblems
    problems += [Problem(p.location, p.message, file) for p in validate_couplings(tuple(provisional), couplings)]
    if problems:
        raise ModelError(problems)
    try:
        topo = build_topology(Mechanism(tuple(bodies), tuple(provisional), spec.name, couplings=couplings))
    except ModelError as exc:
        raise ModelError(exc.problems, file) from None
    for name in topo.cut_joints:
        jt = joint_type(spec.joints[name].type)
        if not jt.cut:
            problems.append(Problem(f"joints.{name}", f"a {jt.name} joint cannot be cut, but it closes a loop", file))
    if problems:
        raise ModelError(problems)

    # coordinates at the described configuration: frame j follows from frame i (module docstring)
    tree = {t.joint: t for t in topo.tree}
    coords: dict[str, Array] = {}
    deg = spec.units.angle == "deg"
    for name, j in spec.joints.items():
        if j.q is None:
            continue
        if name not in tree:
            problems.append(Problem(f"joints.{name}.q", "only tree joints take coordinates (this joint is cut)", file))
            continue
        q, problem = file_coordinates(joint_type(j.type), j.q, deg)
        if problem:
            problems.append(Problem(f"joints.{name}.q", problem, file))
            continue
        coords[name] = q
        refs[name] = _placed(refs[name], joint_type(j.type), q)
    if problems:
        raise ModelError(problems)

    # body frames: fixed as declared; moving at their tree joint's point (module docstring)
    for t in topo.tree:
        ref = refs[t.joint]
        point, rot = (ref.p_i, ref.r_i) if t.reversed else (ref.p_j, ref.r_j)
        pose[t.child] = (point, rot if spec.body_frames == "joint" else np.eye(3))
    design_edits = spec.edits == "design"

    values: dict[str, object] = {}
    joints: list[Joint] = []
    for j in provisional:
        jt = j.jtype
        ref = refs[j.name]
        if j.name in tree:
            parent, child = ("j", "i") if tree[j.name].reversed else ("i", "j")
            fields = {f"s_{parent}", f"C_{parent}"}
            if spec.body_frames == "global" or design_edits:
                fields.add(f"C_{child}")
            if design_edits:  # the joint moves without moving its child body (design position kept)
                fields.add(f"s_{child}")
            coords.setdefault(j.name, jt.default_coordinates())
        else:
            fields = set(CUT_FIELDS[jt.name])
            if jt.n_cut_coordinates:
                coords[j.name] = jt.default_cut_coordinates()
        for side, body, point, rot in (("i", j.body_i, ref.p_i, ref.r_i), ("j", j.body_j, ref.p_j, ref.r_j)):
            r, a = pose[body]
            if f"s_{side}" in fields:
                values[f"{j.name}.s_{side}"] = a.T @ (point - r)
            if f"C_{side}" in fields:
                values[f"{j.name}.C_{side}"] = a.T @ rot
        if jt.has_length:
            given = spec.joints[j.name].length
            length = float(np.linalg.norm(ref.p_j - ref.p_i)) if given is None else given
            if given is None and length <= ZERO_AXIS:
                where = "lies on the revolute axis" if jt.name == "revolute-spherical" else "coincides with point_i"
                problems.append(Problem(f"joints.{j.name}.length", f"point_j {where}: give the length", file))
            values[f"{j.name}.length"] = length
            fields.add("length")
        joints.append(Joint(j.name, j.type, j.body_i, j.body_j, frozenset(fields), j.cut))
        for f in sorted(fields):
            if not np.all(np.isfinite(values[f"{j.name}.{f}"])):
                problems.append(Problem(f"joints.{j.name}", f"{f} overflows: the coordinates are too large", file))
    if problems:
        raise ModelError(problems)

    final = []
    refs = {}
    for b in bodies:
        r, a = pose[b.name]
        refs[b.name], found = point_references(b.name, spec.bodies[b.name], file)
        problems += found
        declared = dict(spec.bodies[b.name].points)
        for joint, (body, pair) in pivots.items():
            if body == b.name:
                declared.update({f"{joint}.{k}": v for k, v in pair.items()})
        pts = tuple(
            (k, tuple((a.T @ (np.array(v) - r)).tolist())) for k, v in declared.items() if not isinstance(v, str)
        )
        if not all(np.all(np.isfinite(v)) for _, v in pts):
            problems.append(Problem(f"bodies.{b.name}.points", "overflow: the coordinates are too large", file))
        final.append(Body(b.name, b.fixed, b.position, b.orientation, pts))
    if problems:
        raise ModelError(problems)
    elements, eproblems = build_elements(spec.elements, set(pose), "hardpoints", file, lambda b: pose[b])
    torsion, tproblems = build_torsion_springs(spec.elements, {j.name: j.type for j in joints}, file)
    eproblems += tproblems
    loads, lproblems = build_loads(spec.loads, {b.name: [n for n, _ in b.points] for b in final}, "hardpoints", file,
                                   lambda b: pose[b])  # fmt: skip
    if eproblems or lproblems:
        raise ModelError(eproblems + lproblems)
    mech = Mechanism(tuple(final), tuple(joints), spec.name, tuple(spec.inputs), couplings, spec.edits)
    values.update(coefs)
    units = {"length": spec.units.length, "angle": spec.units.angle, "axes": spec.units.axes}
    if spec.units.force is not None:
        units["force"] = spec.units.force
    model = Model(mech, Design(values), as_coordinates(coords), units, file, elements, build_vehicle(spec.vehicle),
                  loads, torsion)  # fmt: skip
    return attach_references(model, refs, file, point_order(spec.bodies))


# --- frames -> hardpoints ----------------------------------------------------------------------


def joint_frames(model: Model) -> dict[str, JointFrames]:
    """Global joint frames of every joint at the model's coordinates (T-D: at the slid point)."""
    snap = snapshot(model)
    return {name: JointFrames(snap.cut_point(name), f.R_i, f.P_j, f.R_j) for name, f in snap.frames.items()}


def _clean(v: Array) -> list[float]:
    """Floats for a file: components below 1e-14 of the vector's size become 0."""
    v = np.asarray(v, dtype=float)
    scale = max(1.0, float(np.max(np.abs(v))) if v.size else 1.0)
    v = np.where(np.abs(v) < 1e-14 * scale, 0.0, v)
    return [float(x) + 0.0 for x in v.ravel()]


def _unit(v: Array) -> list[float]:
    return _clean(v / np.linalg.norm(v))


def hardpoint_keys(jtype: str, f: JointFrames) -> dict[str, Any]:
    """The hardpoint keys of one joint from its global frames (see :data:`KEYS`)."""
    z_i, z_j = f.R_i @ EZ, f.R_j @ EZ
    if jtype in ("translational", "cylindrical"):
        return {"point": _clean(f.P_j), "axis": _unit(z_i)}
    if jtype == "universal":
        return {"point": _clean(f.P_i), "axis_i": _unit(z_i), "axis_j": _unit(f.R_j @ EY)}
    if jtype == "spherical-translational":
        return {"point": _clean(f.P_i), "axis": _unit(z_j)}
    if jtype == "revolute":
        return {"point": _clean(f.P_i), "axis": _unit(z_i)}
    if jtype in ("spherical", "spherical-point", "fixed"):
        return {"point": _clean(f.P_i)}
    if jtype == "free":
        return {"point": _clean(f.P_j)}
    if jtype == "dot-1":
        return {"axis_i": _unit(z_i), "axis_j": _unit(z_j)}
    if jtype == "distance":
        return {"point_i": _clean(f.P_i), "point_j": _clean(f.P_j)}
    return {"point_i": _clean(f.P_i), "axis": _unit(z_i), "point_j": _clean(f.P_j)}


def model_to_hardpoints(model: Model, body_frames: str = "global", keep_coordinates: bool = True) -> dict[str, Any]:
    """Hardpoint-style file data: joint points and axes at the model's current coordinates.

    Exact when the model is assembled; otherwise each joint keeps the point on its first body
    (see :func:`joint_mismatch`). Lengths are written as the design's values. A tree joint
    whose frame on body i the loader rebuilds from its keys (e.g. a revolute on a fixed body)
    keeps its coordinates as ``q``, so a model propagated from the file drives from the same
    zero; the others (and every joint with ``keep_coordinates=False``) are re-zeroed at the
    current pose, which is exact all the same.
    """
    mech = model.mechanism
    frames = joint_frames(model)
    kin = compile_engine(mech).kinematics(model.design, model.coordinates)
    bodies: dict[str, Any] = {}
    for b in mech.bodies:
        spec: dict[str, Any] = {}
        if b.fixed:
            spec["fixed"] = True
            if np.any(b.r):
                spec["position"] = _clean(b.r)
            if not np.array_equal(b.A, np.eye(3)):
                spec["orientation"] = [_clean(row) for row in b.A]
        if b.points:
            spec["points"] = {
                k: v if isinstance(v, str) else _clean(v) for k, v in written_points(model, b, True).items()
            }
        bodies[b.name] = spec
    for j in mech.joints:  # pivots are written with their joint
        if _pivots_of(model, j.name) is not None:
            for b in (j.body_i, j.body_j):
                for k in [k for k in bodies[b].get("points", {}) if k.startswith(f"{j.name}.")]:
                    del bodies[b]["points"][k]
                if "points" in bodies[b] and not bodies[b]["points"]:
                    del bodies[b]["points"]
    joints: dict[str, Any] = {}
    kept: set[str] = set()
    tree = set(compile_engine(mech).topology.tree_joints)
    deg = model.units.get("angle") == "deg"
    for j in mech.joints:
        if j.jtype.name not in KEYS:
            raise ModelError([Problem(f"joints.{j.name}.type", f"joint type {j.jtype.name!r} has no hardpoint form")])
        spec = {"type": j.type, "bodies": [j.body_i, j.body_j]}
        if j.cut is not None:
            spec["cut"] = j.cut
        q = model.coordinates.get(j.name) if keep_coordinates and j.name in tree else None
        keys = _keys_keeping(j, frames[j.name], q)
        if keys is None:
            spec.update(hardpoint_keys(j.jtype.name, frames[j.name]))
        else:
            spec.update(keys)
            kept.add(j.name)
            qf = tree_coordinates(q, j.jtype.angle_indices, "deg" if deg else "rad", False)
            spec["q"] = [float(x) + 0.0 for x in qf]
        pair = _pivots_of(model, j.name)
        if pair is not None:
            for key in ("point", "axis"):
                spec.pop(key, None)
            spec["pivots"] = pair
        if j.jtype.has_length:
            spec["length"] = float(model.design[f"{j.name}.length"])
        joints[j.name] = spec
    units = {"length": model.units.get("length", "m"), "angle": model.units.get("angle", "rad")}
    units["axes"] = model.units.get("axes") or "right-handed"
    if model.units.get("force"):
        units["force"] = model.units["force"]
    return {
        "kinprop": 1,
        "name": mech.name,
        "style": "hardpoints",
        "units": units,
        "body_frames": body_frames,
        "bodies": bodies,
        "joints": joints,
        **({"inputs": list(mech.inputs)} if mech.inputs else {}),
        **({"couplings": couplings_to_data(model, _coupled_now(model, kept))} if mech.couplings else {}),
        **({"edits": mech.edits} if mech.edits != "design" else {}),
        **({"elements": elements_to_data(model.elements, "hardpoints", lambda b: (kin.r[b], kin.A[b]),
                                         model.torsion_springs)}
           if model.elements or model.torsion_springs else {}),
        **({"vehicle": vehicle_to_data(model.vehicle)} if model.vehicle is not None else {}),
        **({"loads": loads_to_data(model.loads, "hardpoints", lambda b: (kin.r[b], kin.A[b]))}
           if model.loads is not None else {}),
    }  # fmt: skip


def pivot_points(model: Model, joint: str) -> tuple[str, dict[str, Array]] | None:
    """``(fixed body, {name: global point})`` of a joint given by its pivots (the fixed body's
    named points ``JOINT.NAME``, two of them), or None."""
    j = model.mechanism.joint(joint)
    for name in (j.body_i, j.body_j):
        b = model.mechanism.body(name)
        pts = {k.split(".", 1)[1]: np.asarray(v, dtype=float) for k, v in b.points if k.startswith(f"{joint}.")}
        if b.fixed and len(pts) == 2:
            return name, {k: b.r + b.A @ v for k, v in pts.items()}
    return None


def _pivots_of(model: Model, joint: str) -> dict[str, list[float]] | None:
    """The pivots to write for a joint, when its axis still runs through them."""
    found = pivot_points(model, joint)
    if found is None or model.mechanism.joint(joint).jtype.name not in PIVOT_TYPES:
        return None
    f = joint_frames(model)[joint]
    z = f.R_i @ EZ
    for p in found[1].values():
        d = p - f.P_i
        if np.linalg.norm(d - (d @ z) * z) > 1e-9 * max(1.0, float(np.max(np.abs(p)))):
            return None
    return {k: _clean(v) for k, v in found[1].items()}


def _coupled_now(model: Model, kept: set[str]) -> dict[str, float]:
    """Current coordinates of the coupled joints written without ``q``: the file's coordinates
    are zero there, so the couplings' offsets shift by them."""
    mech = model.mechanism
    return {n: float(model.coordinates[n][0]) for n in mech.coupled_joints if n in model.coordinates and n not in kept}


def _keys_keeping(joint: Joint, f: JointFrames, q: Array | None) -> dict[str, Any] | None:
    """Hardpoint keys that describe joint frame i, so that the joint keeps its coordinates
    ``q`` (written as ``q``); None when the loader would not rebuild frame i from the keys
    (its ``x''`` is not the one :func:`axis_frame` picks), so the joint is written re-zeroed.

    Zero coordinates need no ``q``; the pose is exact either way, only the zero differs.
    """
    jt = joint.jtype
    if q is None or jt.n_coordinates == 0 or np.array_equal(q, jt.default_coordinates()):
        return None
    frame_i = JointFrames(f.P_i, f.R_i, f.P_i, f.R_i)
    keys = hardpoint_keys(jt.name, frame_i)
    spec = HardpointJointSpec(type=joint.type, bodies=[joint.body_i, joint.body_j], **keys)
    ref = _placed(_reference(jt.name, spec), jt, np.asarray(q, dtype=float))
    scale = max(1.0, float(np.max(np.abs(f.P_i))))
    if np.max(np.abs(ref.r_i - f.R_i)) > 1e-12 or np.max(np.abs(ref.r_j - f.R_j)) > 1e-12:
        return None
    if np.max(np.abs(ref.p_j - f.P_j)) > 1e-12 * scale:
        return None
    return keys


def joint_mismatch(model: Model) -> dict[str, float]:
    """Norm of each cut joint's rows at the model's coordinates, unscaled (model units: a
    point row's gap is a distance), not the scaled ``||Phi||`` a solve reports.

    Zero (to rounding) for an assembled model. A hardpoint file has one point (or axis) where
    the two sides of a joint meet, so :func:`model_to_hardpoints` drops these gaps.
    """
    asm = compile_engine(model.mechanism)
    phi = asm.residual(model.design, model.coordinates)
    return {b.joint: float(np.linalg.norm(phi[b.rows])) for b in asm.row_blocks if b.kind == "cut"}


# --- the same design value in another model's body frames ----------------------------------------


def _body_pose(model: Model, body: str) -> tuple[Array, Array]:
    kin = compile_engine(model.mechanism).kinematics(model.design, model.coordinates)
    return kin.r[body], kin.A[body]


def express_in(src: Model, dst: Model, address: str, value: object) -> Array:
    """``value`` of design variable ``address`` in ``src``'s body frames, expressed in ``dst``'s.

    Both models describe the same mechanism (same joint and body names) at the same physical
    configuration, e.g. a frame-style file and its hardpoint form. ``s_i``/``s_j`` transfer as
    body-fixed points (``s_dst = A_dst^T (r_src + A_src s_src - r_dst)``), ``C_i``/``C_j`` as
    body-fixed frames (``C_dst = A_dst^T A_src C_src``) and lengths unchanged.
    """
    addr = parse_address(address)
    if addr.field == "q" or addr.index is not None:
        raise AddressError(
            f"{address!r}: only whole s_i, s_j, C_i, C_j or length values can be expressed in another model"
        )
    if addr.field == "length":
        return np.asarray(value, dtype=float)
    joint = src.mechanism.joint(addr.joint)
    body = joint.body_i if addr.field.endswith("_i") else joint.body_j
    r_s, a_s = _body_pose(src, body)
    r_d, a_d = _body_pose(dst, body)
    v = np.asarray(value, dtype=float)
    if addr.field.startswith("s"):
        return a_d.T @ (r_s + a_s @ v - r_d)
    return a_d.T @ a_s @ v


def rotate_into(src: Model, dst: Model, body: str, vector: object) -> Array:
    """A free vector (e.g. the change of an ``s'``) of ``body``'s frame in ``src``, in ``dst``'s."""
    _, a_s = _body_pose(src, body)
    _, a_d = _body_pose(dst, body)
    return a_d.T @ a_s @ np.asarray(vector, dtype=float)


def rotation_change(before: Array, after: Array) -> Array:
    """Rotation vector of ``after @ before^T`` (the body-frame ``xi'`` a C moved by)."""
    return log_so3(np.asarray(after) @ np.asarray(before).T)


__all__ = [
    "CUT_FIELDS",
    "KEYS",
    "axes_frame",
    "axis_frame",
    "express_in",
    "hardpoint_keys",
    "joint_frames",
    "joint_mismatch",
    "model_from_hardpoints",
    "model_to_hardpoints",
    "pivot_points",
    "rotate_into",
    "rotation_change",
]
