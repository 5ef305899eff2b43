"""MuJoCo MJCF files as kinprop models: bodies, joints and ``<equality>`` loop closures.

A pure-Python reader (no MuJoCo needed at run time); the tests check it against MuJoCo's own
compiler and constraint solver. What is read, and how:

* ``<compiler angle eulerseq>``; ``<default>`` classes (nested, ``class`` and ``childclass``)
  for joints and sites; ``<worldbody>``, ``<body>``, ``<frame>``, ``<joint>``,
  ``<freejoint>``, ``<site>`` and ``<keyframe>``.
* Frames: ``pos`` with ``quat``, ``axisangle``, ``euler``, ``xyaxes`` or ``zaxis``. Each
  kinprop body frame is the MJCF body frame, so body poses compare one to one.
* Joints become tree joints: ``hinge`` -> revolute, ``slide`` -> translational, ``ball`` ->
  spherical, ``free`` -> free. The joint frame's z'' is the MJCF axis at the MJCF anchor, on
  both bodies. Coordinates are ``q = qpos - ref`` (``ref`` in the compiler's angle unit), so
  the reference configuration (``qpos0``) is q = 0 and every body sits where the file puts it.
  A body with several joints becomes a chain through massless bodies ``BODY__JOINT`` applying
  them in file order, as MuJoCo does; a body without joints is welded to its parent (a
  ``fixed`` tree joint ``BODY__weld``), or is a fixed body when nothing moves it.
* ``<equality>``: ``connect`` -> a cut spherical joint (anchor on body1; its point on body2 is
  where the anchor lies at the reference configuration, MuJoCo's rule), ``weld`` -> a cut
  fixed joint (``relpose``, or the reference relative pose), both also in their site forms.
  ``<joint joint1 joint2 polycoef>`` -> a coupling (:class:`kinprop.model.Coupling`) of two
  hinge/slide joints, ``joint1`` driven: MuJoCo's ``y - y0 = poly(x - x0)`` about ``qpos0``
  is, with ``q = qpos - ref``, ``q[joint1] = sum(c_k q[joint2]^k)`` (offsets 0, ``polycoef`` as
  is, in radians and metres). A ``<joint>`` without ``joint2`` (a joint held at a constant)
  and ``tendon``, ``flex`` and ``distance`` equalities are located errors.
* Named sites become named body points (outputs ``point:BODY.SITE``).
* Geoms, meshes, inertials, tendons, actuators, sensors, contacts, ... are ignored with one note
  per kind; mesh files are never opened.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from kinprop.constraints.coupling import N_COEF
from kinprop.errors import ModelError, Problem
from kinprop.imports.rotations import (
    axis_angle_matrix,
    euler_matrix,
    matrix_to_quat,
    quat_to_matrix,
    xyaxes_matrix,
    zaxis_matrix,
)
from kinprop.imports.xmltree import Node, parse_xml
from kinprop.io.hardpoints import axis_frame
from kinprop.model import Body, Design, Joint, Mechanism, Model, as_coordinates
from kinprop.model import Coupling as ModelCoupling
from kinprop.spatial import Array

WORLD_BODY = "world"
#: larger numbers would overflow in the kinematics (products of coordinates)
MAX_NUMBER = 1e100

#: top-level sections that do not change the kinematics (one note each when present)
IGNORED_SECTIONS = {
    "option": "simulation options",
    "size": "memory sizes",
    "visual": "visualisation settings",
    "statistic": "statistics",
    "asset": "assets (meshes, textures, materials; files are not opened)",
    "custom": "custom numeric/text data",
    "extension": "plugins",
    "contact": "contact pairs/exclusions",
    "tendon": "tendons",
    "actuator": "actuators",
    "sensor": "sensors",
}
#: body children that do not change the kinematics
IGNORED_IN_BODY = {"geom", "inertial", "camera", "light", "plugin"}
#: elements that would change the kinematics and are not read
UNSUPPORTED = {
    "include": "<include> is not resolved: merge the included file first",
    "composite": "<composite> bodies are not supported",
    "flexcomp": "<flexcomp> (deformable) bodies are not supported",
    "replicate": "<replicate> is not expanded",
    "attach": "<attach> (model composition) is not supported",
    "deformable": "deformable objects are not supported",
}
JOINT_TYPES = {"hinge": "revolute", "slide": "translational", "ball": "spherical", "free": "free"}
ORIENTATIONS = ("quat", "axisangle", "euler", "xyaxes", "zaxis")


@dataclass
class MjcfJoint:
    """One MJCF joint of a body (frame of the body, values as in the file, angles in radians)."""

    name: str
    type: str
    pos: Array
    axis: Array
    ref: float
    node: Node


@dataclass
class MjcfBody:
    """One MJCF body: pose relative to its parent at the reference configuration."""

    name: str
    parent: str | None
    pos: Array
    R: Array
    joints: list[MjcfJoint]
    sites: dict[str, tuple[Array, Array]]
    node: Node | None


@dataclass
class Coupling:
    """An MJCF ``<equality><joint>`` (a :class:`kinprop.model.Coupling` in the model).

    MuJoCo's constraint is ``y - y0 = a0 + a1 (x - x0) + ... + a4 (x - x0)^4`` with ``y`` the
    position of ``joint1``, ``x`` that of ``joint2`` and ``y0``, ``x0`` their ``qpos0`` (= ``ref``)
    — checked against MuJoCo's ``efc_pos``. The kinprop joints carry the MJCF names and
    coordinates ``q = qpos - ref``, so in kinprop terms the row is
    ``q[joint1] - sum(a_k q[joint2]^k) = 0``; without ``joint2``, ``q[joint1] = a0``.
    """

    name: str
    joint1: str
    joint2: str | None
    polycoef: tuple[float, ...]
    node: Node


@dataclass
class MjcfDocument:
    """The kinematic content of an MJCF file, before it becomes a kinprop Model."""

    file: str
    name: str
    bodies: dict[str, MjcfBody]
    cut_joints: list[Joint]
    cut_values: dict[str, Array]
    couplings: list[Coupling]
    keyframes: dict[str, Array]
    notes: list[str] = field(default_factory=list)
    #: declared units kinprop wrote (``<custom><text name="kinprop.units">``); default m, rad
    units: dict[str, str] = field(default_factory=dict)

    @property
    def joints(self) -> list[MjcfJoint]:
        """Joints in MuJoCo's order (qpos order)."""
        return [j for b in self.bodies.values() for j in b.joints]

    @property
    def nq(self) -> int:
        return sum({"free": 7, "ball": 4}.get(j.type, 1) for j in self.joints)

    def coordinates(self, qpos: Array) -> dict[str, Array]:
        """kinprop coordinates (``q = qpos - ref``; quaternions as Euler parameters) of a MuJoCo qpos."""
        qpos = np.asarray(qpos, dtype=float)
        out: dict[str, Array] = {}
        k = 0
        for j in self.joints:
            n = {"free": 7, "ball": 4}.get(j.type, 1)
            q = qpos[k : k + n].copy()
            if j.type in ("hinge", "slide"):
                q = q - j.ref
            else:  # MuJoCo normalises quaternions before use
                q[-4:] = q[-4:] / np.linalg.norm(q[-4:])
            out[j.name] = q
            k += n
        return out

    def qpos(self, coordinates: dict[str, Array]) -> Array:
        """The MuJoCo qpos of kinprop coordinates (inverse of :meth:`coordinates`)."""
        parts = []
        for j in self.joints:
            q = np.asarray(coordinates[j.name], dtype=float)
            parts.append(q + j.ref if j.type in ("hinge", "slide") else q)
        return np.concatenate(parts) if parts else np.zeros(0)


class _Reader:
    """Walks the XML tree, collecting problems instead of stopping at the first."""

    def __init__(self, root: Node, file: str):
        self.root = root
        self.file = file
        self.problems: list[Problem] = []
        self.ignored: Counter[str] = Counter()
        self.angle_scale = math.pi / 180.0
        self.eulerseq = "xyz"
        self.defaults: dict[str, dict[str, dict[str, str]]] = {"main": {}}
        self.bodies: dict[str, MjcfBody] = {}
        self.joint_names: set[str] = set()
        self.sites: dict[str, str] = {}
        self.n_joints = 0

    # --- helpers ---------------------------------------------------------------------------
    def problem(self, node: Node | None, message: str) -> None:
        self.problems.append(Problem(node.where() if node is not None else "mujoco", message, self.file))

    def numbers(self, node: Node, key: str, n: int | tuple[int, ...], text: str | None) -> Array | None:
        """``text`` as ``n`` numbers (a located problem and None when it is not)."""
        if text is None:
            return None
        try:
            values = np.array([float(x) for x in text.split()], dtype=float)
        except ValueError:
            self.problem(node, f"{key}={text!r}: expected numbers")
            return None
        sizes = (n,) if isinstance(n, int) else n
        if values.size not in sizes:
            want = " or ".join(str(s) for s in sizes)
            self.problem(node, f"{key}={text!r}: expected {want} numbers, found {values.size}")
            return None
        if not np.all(np.isfinite(values)) or np.any(np.abs(values) > MAX_NUMBER):
            self.problem(node, f"{key}={text!r}: expected finite numbers of magnitude below {MAX_NUMBER:g}")
            return None
        return values

    def attr(self, node: Node, key: str, cls: str | None) -> str | None:
        """The element's attribute, else its default class's (MuJoCo's inheritance)."""
        if key in node.attrib:
            return node.attrib[key]
        return self.defaults.get(cls or "main", {}).get(node.tag, {}).get(key)

    def element_class(self, node: Node, childclass: str | None) -> str:
        cls = node.get("class") or childclass or "main"
        if cls not in self.defaults:
            self.problem(node, f"class={cls!r}: no such default class; classes are {sorted(self.defaults)}")
            return "main"
        return cls

    def orientation(self, node: Node, cls: str | None = None) -> Array:
        """Rotation of an element from whichever one orientation specifier it carries."""
        given = [k for k in ORIENTATIONS if k in node.attrib]
        if not given and cls is not None:
            given = [k for k in ORIENTATIONS if self.attr(node, k, cls) is not None][:1]
        if len(given) > 1:
            self.problem(node, f"more than one orientation given ({', '.join(given)}); MuJoCo takes exactly one")
            return np.eye(3)
        if not given:
            return np.eye(3)
        key = given[0]
        text = self.attr(node, key, cls)
        if key == "quat":
            v = self.numbers(node, key, 4, text)
            if v is None or np.linalg.norm(v) < 1e-14:
                if v is not None:
                    self.problem(node, "quat: expected a non-zero quaternion")
                return np.eye(3)
            return quat_to_matrix(v)
        if key == "axisangle":
            v = self.numbers(node, key, 4, text)
            if v is None or np.linalg.norm(v[:3]) < 1e-14:
                if v is not None:
                    self.problem(node, "axisangle: expected a non-zero axis")
                return np.eye(3)
            return axis_angle_matrix(v[:3], v[3] * self.angle_scale)
        if key == "euler":
            v = self.numbers(node, key, 3, text)
            return np.eye(3) if v is None else euler_matrix(v * self.angle_scale, self.eulerseq)
        if key == "xyaxes":
            v = self.numbers(node, key, 6, text)
            if v is None:
                return np.eye(3)
            x, y = v[:3], v[3:]
            if np.linalg.norm(x) < 1e-14 or np.linalg.norm(y - (x @ y) * x / (x @ x)) < 1e-14:
                self.problem(node, "xyaxes: expected two non-parallel, non-zero axes")
                return np.eye(3)
            return xyaxes_matrix(x, y)
        v = self.numbers(node, key, 3, text)
        if v is None or np.linalg.norm(v) < 1e-14:
            if v is not None:
                self.problem(node, "zaxis: expected a non-zero axis")
            return np.eye(3)
        return zaxis_matrix(v)

    def position(self, node: Node, cls: str | None = None) -> Array:
        text = self.attr(node, "pos", cls) if cls is not None else node.get("pos")
        v = self.numbers(node, "pos", 3, text)
        return np.zeros(3) if v is None else v

    # --- sections --------------------------------------------------------------------------
    def compiler(self, node: Node) -> None:
        angle = node.get("angle")
        if angle is not None:
            if angle not in ("degree", "radian"):
                self.problem(node, f"angle={angle!r}: expected 'degree' or 'radian'")
            else:
                self.angle_scale = math.pi / 180.0 if angle == "degree" else 1.0
        seq = node.get("eulerseq")
        if seq is not None:
            if len(seq) != 3 or any(c not in "xyzXYZ" for c in seq):
                self.problem(node, f"eulerseq={seq!r}: expected three of x, y, z, X, Y, Z")
            else:
                self.eulerseq = seq
        if node.get("coordinate", "local") != "local":
            self.problem(node, "coordinate='global' is not supported (MuJoCo removed it); use local frames")

    def default(self, node: Node, inherited: dict[str, dict[str, str]], top: bool) -> None:
        name = node.get("class") or ("main" if top else None)
        if name is None:
            self.problem(node, "a nested <default> needs a class name")
            return
        if name in self.defaults and not (top and name == "main" and not self.defaults["main"]):
            self.problem(node, f"default class {name!r} is defined twice")
        attrs = {tag: dict(v) for tag, v in inherited.items()}
        for ch in node:
            if ch.tag != "default":
                attrs.setdefault(ch.tag, {}).update(ch.attrib)
        self.defaults[name] = attrs
        for ch in node:
            if ch.tag == "default":
                self.default(ch, attrs, False)

    def unique_joint_name(self, node: Node, name: str | None) -> str:
        self.n_joints += 1
        if name is None:
            name = f"joint{self.n_joints - 1}"
        clean = "_".join(name.split())
        if clean != name:
            self.ignored[f"whitespace in joint name {name!r} replaced by '_'"] += 1
        if clean in self.joint_names:
            self.problem(node, f"duplicate joint name {clean!r}")
        self.joint_names.add(clean)
        return clean

    def joint(self, node: Node, cls: str) -> MjcfJoint | None:
        if node.tag == "freejoint":
            return MjcfJoint(
                self.unique_joint_name(node, node.get("name")), "free", np.zeros(3), np.zeros(3), 0.0, node
            )
        jtype = self.attr(node, "type", cls) or "hinge"
        if jtype not in JOINT_TYPES:
            self.problem(node, f"type={jtype!r}: expected one of {', '.join(JOINT_TYPES)}")
            return None
        pos = self.position(node, cls)
        axis = self.numbers(node, "axis", 3, self.attr(node, "axis", cls) or "0 0 1")
        if axis is None:
            axis = np.array([0.0, 0.0, 1.0])
        if jtype in ("hinge", "slide") and np.linalg.norm(axis) < 1e-14:
            self.problem(node, "axis: expected a non-zero direction")
            axis = np.array([0.0, 0.0, 1.0])
        ref_text = self.attr(node, "ref", cls) or "0"
        ref = self.numbers(node, "ref", 1, ref_text)
        ref_value = 0.0 if ref is None else float(ref[0]) * (self.angle_scale if jtype == "hinge" else 1.0)
        name = self.unique_joint_name(node, node.get("name"))
        return MjcfJoint(name, jtype, pos, axis / max(np.linalg.norm(axis), 1e-300), ref_value, node)

    def body(self, node: Node, parent: str, pose: tuple[Array, Array], childclass: str | None) -> None:
        """A ``<body>`` at ``pose`` (accumulated ``<frame>`` transforms) in its parent's frame."""
        name = node.get("name") or f"body{len(self.bodies)}"
        if name in self.bodies:
            self.problem(node, f"duplicate body name {name!r}")
            name = f"{name}__{len(self.bodies)}"
        own = node.get("childclass")
        if own is not None and own not in self.defaults:
            self.problem(node, f"childclass={own!r}: no such default class; classes are {sorted(self.defaults)}")
        childclass = own or childclass
        fp, fR = pose
        pos = fp + fR @ self.position(node)
        R = fR @ self.orientation(node)
        b = MjcfBody(name, parent, pos, R, [], {}, node)
        self.bodies[name] = b
        if node.get("mocap") == "true":
            self.ignored["mocap bodies (treated as fixed at their pose)"] += 1
        self.children(node, b, (np.zeros(3), np.eye(3)), childclass, in_frame=False)

    def children(
        self, node: Node, body: MjcfBody, pose: tuple[Array, Array], childclass: str | None, in_frame: bool
    ) -> None:
        for ch in node:
            tag = ch.tag
            if tag == "body":
                self.body(ch, body.name, pose, childclass)
            elif tag == "frame":
                own = ch.get("childclass")
                if own is not None and own not in self.defaults:
                    self.problem(ch, f"childclass={own!r}: no such default class; classes are {sorted(self.defaults)}")
                fp, fR = pose
                sub = (fp + fR @ self.position(ch), fR @ self.orientation(ch))
                self.children(ch, body, sub, ch.get("childclass") or childclass, in_frame=True)
            elif tag in ("joint", "freejoint"):
                if body.parent is None:
                    self.problem(ch, "a joint in <worldbody> itself: joints belong to bodies")
                    continue
                if in_frame:
                    self.problem(ch, "a joint inside a <frame>: MuJoCo does not allow it")
                    continue
                j = self.joint(ch, self.element_class(ch, childclass))
                if j is not None:
                    body.joints.append(j)
            elif tag == "site":
                cls = self.element_class(ch, childclass)
                fp, fR = pose
                site_pos = fp + fR @ self.position(ch, cls)
                site_R = fR @ self.orientation(ch, cls)
                site_name = ch.get("name")
                if site_name is not None:
                    if site_name in self.sites:
                        self.problem(ch, f"duplicate site name {site_name!r}")
                    body.sites[site_name] = (site_pos, site_R)
                    self.sites[site_name] = body.name
                self.ignored["unnamed sites"] += site_name is None
            elif tag in IGNORED_IN_BODY:
                self.ignored[f"<{tag}>"] += 1
            elif tag in UNSUPPORTED:
                self.problem(ch, UNSUPPORTED[tag])
            else:
                self.problem(ch, f"unknown element <{tag}> in <{node.tag}>")


def _check_free(reader: _Reader) -> None:
    for b in reader.bodies.values():
        free = [j for j in b.joints if j.type == "free"]
        if free and (len(b.joints) > 1 or b.parent != WORLD_BODY):
            reader.problem(free[0].node, "a free joint must be the only joint of a top-level body")


def global_poses(bodies: dict[str, MjcfBody]) -> dict[str, tuple[Array, Array]]:
    """Every body's global pose at the reference configuration (qpos0)."""
    poses: dict[str, tuple[Array, Array]] = {}
    for b in bodies.values():
        if b.parent is None:
            poses[b.name] = (np.zeros(3), np.eye(3))
        else:
            pp, pR = poses[b.parent]
            poses[b.name] = (pp + pR @ b.pos, pR @ b.R)
    return poses


def read_mjcf(path: str | Path) -> MjcfDocument:
    """Parse an MJCF file into its kinematic content; every problem is reported at once."""
    path = Path(path)
    file = str(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ModelError([Problem("file", f"cannot read: {exc.strerror or exc}", file)]) from None
    except UnicodeDecodeError as exc:
        raise ModelError([Problem("file", f"not UTF-8 text (byte {exc.start})", file)]) from None
    return read_mjcf_text(text, file)


def read_mjcf_text(text: str, file: str = "<mjcf>") -> MjcfDocument:
    """:func:`read_mjcf` from text."""
    root = parse_xml(text, file)
    if root.tag != "mujoco":
        raise ModelError([Problem(root.where(), f"expected a <mujoco> root element, found <{root.tag}>", file)])
    r = _Reader(root, file)
    for node in root:
        if node.tag == "compiler":
            r.compiler(node)
    for node in root:
        if node.tag == "default":
            r.default(node, {}, True)
    world = MjcfBody(WORLD_BODY, None, np.zeros(3), np.eye(3), [], {}, None)
    r.bodies[WORLD_BODY] = world
    worldbodies = [n for n in root if n.tag == "worldbody"]
    for node in worldbodies:
        r.children(node, world, (np.zeros(3), np.eye(3)), node.get("childclass"), in_frame=False)
    _check_free(r)
    equalities = [n for n in root if n.tag == "equality"]
    keyframes: dict[str, Array] = {}
    units: dict[str, str] | None = None
    for node in root:
        tag = node.tag
        if tag in ("compiler", "default", "worldbody", "equality"):
            continue
        if tag == "keyframe":
            for k, key in enumerate(node):
                if key.tag != "key":
                    r.problem(key, f"unknown element <{key.tag}> in <keyframe>")
                    continue
                q = key.get("qpos")
                if q is not None:
                    v = r.numbers(key, "qpos", tuple(range(1, 100000)), q)
                    if v is not None:
                        keyframes[key.get("name") or f"key{k}"] = v
        elif tag == "custom" and _units_text(node) is not None:
            units = _units_text(node)
            if len(list(node)) > 1:
                r.ignored[f"<{tag}> ({IGNORED_SECTIONS[tag]})"] += 1
        elif tag in IGNORED_SECTIONS:
            r.ignored[f"<{tag}> ({IGNORED_SECTIONS[tag]})"] += 1
        elif tag in UNSUPPORTED:
            r.problem(node, UNSUPPORTED[tag])
        else:
            r.problem(node, f"unknown element <{tag}> in <mujoco>")
    doc = MjcfDocument(file, root.get("model") or Path(file).stem, r.bodies, [], {}, [], keyframes, units=units or {})
    if not r.problems:
        _equalities(r, doc, equalities)
    nq = doc.nq
    for name, q in keyframes.items():
        if q.size != nq:
            r.problems.append(
                Problem(f"keyframe {name!r}", f"qpos has {q.size} numbers, the model has nq = {nq}", file)
            )
    if r.problems:
        raise ModelError(r.problems)
    doc.notes = [f"ignored {n} x {what}: only the kinematics are read" for what, n in r.ignored.items() if n]
    return doc


#: the units kinprop's exporter records, and the values each may take
_UNIT_VALUES = {"length": ("m", "mm"), "angle": ("rad", "deg"), "axes": ("ISO8855", "SAE", "right-handed")}


def _units_text(node: Node) -> dict[str, str] | None:
    """The units of a ``<custom><text name="kinprop.units" data="length=mm angle=deg ...">``
    (:func:`kinprop.imports.mjcf_export.model_to_mjcf`); None when absent or not understood."""
    for ch in node:
        if ch.tag == "text" and ch.get("name") == "kinprop.units":
            pairs = [p.partition("=") for p in (ch.get("data") or "").split()]
            units = {k: v for k, _, v in pairs if k and v}
            known = all(v in _UNIT_VALUES[k] for k, v in units.items() if k in _UNIT_VALUES)
            return units if known and {"length", "angle"} <= set(units) else None
    return None


def _equalities(r: _Reader, doc: MjcfDocument, sections: list[Node]) -> None:
    poses = global_poses(r.bodies)
    names = set(r.joint_names) | {f"{b}__weld" for b in r.bodies}
    k = 0
    for section in sections:
        for node in section:
            k += 1
            cls = r.element_class(node, None)
            if (r.attr(node, "active", cls) or "true") == "false":
                r.ignored["inactive <equality> elements (active='false')"] += 1
                continue
            tag = node.tag
            if tag in ("tendon", "flex", "distance"):
                what = {
                    "tendon": "a tendon equality (tendon lengths are not kinematics kinprop reads)",
                    "flex": "a flex equality (deformables are not supported)",
                    "distance": "a distance equality (removed from MuJoCo; write it as a connect to a rod body)",
                }[tag]
                r.problem(node, f"{what} is not supported")
                continue
            if tag == "joint":
                j1, j2 = node.get("joint1"), node.get("joint2")
                for key, jn in (("joint1", j1), ("joint2", j2)):
                    if jn is not None and jn not in r.joint_names:
                        r.problem(node, f"{key}={jn!r}: no such joint")
                if j1 is None:
                    r.problem(node, "joint1: missing (the coupled joint)")
                    continue
                coef = r.numbers(node, "polycoef", 5, r.attr(node, "polycoef", cls) or "0 1 0 0 0")
                doc.couplings.append(
                    Coupling(node.get("name") or f"coupling{k}", j1, j2, tuple(coef if coef is not None else ()), node)
                )
                continue
            if tag not in ("connect", "weld"):
                r.problem(node, f"unknown element <{tag}> in <equality>")
                continue
            sides = _equality_sides(r, node, poses)
            if sides is None:
                continue
            (b1, p1, R1), (b2, p2, R2) = sides
            if b1 == b2:
                r.problem(node, f"{tag} joins body {b1!r} to itself")
                continue
            name = "_".join((node.get("name") or f"{tag}_{b1}_{b2}").split())
            base, n = name, 1
            while name in names:
                n += 1
                name = f"{base}_{n}"
            names.add(name)
            jtype = "spherical" if tag == "connect" else "fixed"
            fields = ("s_i", "s_j") if tag == "connect" else ("s_i", "s_j", "C_i", "C_j")
            doc.cut_joints.append(Joint(name, jtype, b1, b2, frozenset(fields), cut=True))
            doc.cut_values.update({f"{name}.s_i": p1, f"{name}.s_j": p2})
            if tag == "weld":
                doc.cut_values.update({f"{name}.C_i": R1, f"{name}.C_j": R2})


def _equality_sides(
    r: _Reader, node: Node, poses: dict[str, tuple[Array, Array]]
) -> tuple[tuple[str, Array, Array], tuple[str, Array, Array]] | None:
    """``(body, point, frame)`` on each side, in the bodies' frames (MuJoCo's reference rule)."""
    cls = r.element_class(node, None)
    if node.get("site1") is not None or node.get("site2") is not None:
        out = []
        for key in ("site1", "site2"):
            site = node.get(key)
            if site is None or site not in r.sites:
                r.problem(node, f"{key}={site!r}: no such site; name both site1 and site2")
                return None
            body = r.bodies[r.sites[site]]
            p, R = body.sites[site]
            out.append((body.name, p, R))
        return out[0], out[1]
    b1, b2 = node.get("body1"), node.get("body2") or WORLD_BODY
    for key, b in (("body1", b1), ("body2", b2)):
        if b is None:
            r.problem(node, f"{key}: missing (or give site1 and site2)")
            return None
        if b not in r.bodies:
            known = ", ".join(sorted(r.bodies))
            r.problem(node, f"{key}={b!r}: no such body; bodies are {known}")
            return None
    g1, G1 = poses[b1]
    g2, G2 = poses[b2]
    if node.tag == "connect":
        anchor = r.numbers(node, "anchor", 3, r.attr(node, "anchor", cls))
        if anchor is None:
            if "anchor" not in node.attrib:
                r.problem(node, "anchor: missing (the point on body1, body1's frame)")
            return None
        point = g1 + G1 @ anchor
        return (b1, anchor, np.eye(3)), (b2, G2.T @ (point - g2), np.eye(3))
    rel = r.numbers(node, "relpose", 7, r.attr(node, "relpose", cls) or "0 1 0 0 0 0 0")
    if rel is not None and np.linalg.norm(rel[3:]) > 0:
        # body2's pose in body1's frame
        return (b1, rel[:3], quat_to_matrix(rel[3:])), (b2, np.zeros(3), np.eye(3))
    return (b1, G1.T @ (g2 - g1), G1.T @ G2), (b2, np.zeros(3), np.eye(3))


# --- to a kinprop model ----------------------------------------------------------------------


def _fixed_bodies(doc: MjcfDocument) -> set[str]:
    """Bodies that nothing moves: the world and joint-less chains hanging from it."""
    fixed = {WORLD_BODY}
    for b in doc.bodies.values():
        if b.parent in fixed and not b.joints:
            fixed.add(b.name)
    return fixed


def _couplings(doc: MjcfDocument) -> tuple[tuple[ModelCoupling, ...], dict[str, Array]]:
    """kinprop couplings (offsets 0: ``q = qpos - ref``) and their coefficients ``NAME.coef``;
    a coupling kinprop cannot express is a located error."""
    types = {j.name: j.type for j in doc.joints}
    taken = {j.name for j in doc.joints} | {f"{b}__weld" for b in doc.bodies} | {j.name for j in doc.cut_joints}
    out: list[ModelCoupling] = []
    values: dict[str, Array] = {}
    problems: list[Problem] = []
    for c in doc.couplings:
        if c.joint2 is None:
            problems.append(Problem(c.node.where(), f"a joint equality without joint2 holds {c.joint1} at a constant: "
                                    "not supported (declare the joint an input instead)", doc.file))  # fmt: skip
            continue
        bad = [n for n in (c.joint1, c.joint2) if types.get(n) not in ("hinge", "slide")]
        if bad:
            problems += [Problem(c.node.where(), f"{n} is a {types.get(n)} joint: a coupling takes hinge and slide "
                                 "joints", doc.file) for n in bad]  # fmt: skip
            continue
        if len(c.polycoef) != N_COEF:
            continue  # the reader reported it
        name = c.name if c.name not in taken else f"{c.name}__coupling"
        taken.add(name)
        out.append(ModelCoupling(name, c.joint1, c.joint2))
        values[f"{name}.coef"] = np.array(c.polycoef, dtype=float)
    if problems:
        raise ModelError(problems)
    return tuple(out), values


def document_to_model(doc: MjcfDocument, keyframe: str | None = None) -> Model:
    """The kinprop Model of an MJCF document, at the reference configuration or a keyframe."""
    couplings, coefs = _couplings(doc)
    poses = global_poses(doc.bodies)
    fixed = _fixed_bodies(doc)
    world_used = any(WORLD_BODY in (j.body_i, j.body_j) for j in doc.cut_joints) or any(
        b.parent == WORLD_BODY and b.joints for b in doc.bodies.values()
    )
    bodies: list[Body] = []
    joints: list[Joint] = []
    values: dict[str, object] = {}
    coords: dict[str, Array] = {}
    all_fields = frozenset({"s_i", "s_j", "C_i", "C_j"})
    for b in doc.bodies.values():
        points = tuple((name, tuple(p.tolist())) for name, (p, _) in b.sites.items())
        if b.name in fixed:
            if b.name == WORLD_BODY and not world_used and not points:
                continue
            g, G = poses[b.name]
            bodies.append(Body(b.name, True, tuple(g.tolist()), tuple(map(tuple, G.tolist())), points))
            continue
        assert b.parent is not None
        if not b.joints:
            name = f"{b.name}__weld"
            bodies.append(Body(b.name, points=points))
            joints.append(Joint(name, "fixed", b.parent, b.name, all_fields, cut=False))
            values.update(
                {f"{name}.s_i": b.pos, f"{name}.C_i": b.R, f"{name}.s_j": np.zeros(3), f"{name}.C_j": np.eye(3)}
            )
            continue
        parent, off_p, off_R = b.parent, b.pos, b.R
        for k, j in enumerate(b.joints):
            last = k == len(b.joints) - 1
            child = b.name if last else f"{b.name}__{j.name}"
            bodies.append(Body(child, points=points if last else ()))
            if j.type == "free":
                s_i, C_i, s_j, C_j = np.zeros(3), np.eye(3), np.zeros(3), np.eye(3)
                g, G = poses[b.name]
                coords[j.name] = np.concatenate([g, matrix_to_quat(G)])
            elif j.type == "ball":
                s_i, C_i, s_j, C_j = off_p + off_R @ j.pos, off_R, j.pos, np.eye(3)
                coords[j.name] = np.array([1.0, 0.0, 0.0, 0.0])
            else:
                F = axis_frame(j.axis)
                s_i, C_i, s_j, C_j = off_p + off_R @ j.pos, off_R @ F, j.pos, F
                coords[j.name] = np.zeros(1)
            joints.append(Joint(j.name, JOINT_TYPES[j.type], parent, child, all_fields, cut=False))
            values.update({f"{j.name}.s_i": s_i, f"{j.name}.C_i": C_i, f"{j.name}.s_j": s_j, f"{j.name}.C_j": C_j})
            parent, off_p, off_R = child, np.zeros(3), np.eye(3)
    joints += doc.cut_joints
    values.update(doc.cut_values)
    if keyframe is not None:
        if keyframe not in doc.keyframes:
            known = ", ".join(doc.keyframes) or "none"
            raise ModelError([Problem("keyframe", f"no keyframe {keyframe!r}; keyframes: {known}", doc.file)])
        coords.update(doc.coordinates(doc.keyframes[keyframe]))
    values.update(coefs)
    try:
        mech = Mechanism(tuple(bodies), tuple(joints), doc.name, couplings=couplings)
    except ModelError as exc:
        raise ModelError(exc.problems, doc.file) from None
    units = dict(doc.units) or {"length": "m", "angle": "rad"}
    return Model(mech, Design(values), as_coordinates(coords), units, doc.file)


def load_mjcf(path: str | Path, keyframe: str | None = None) -> Model:
    """Read an MJCF file as a kinprop Model (see the module docstring for what is read)."""
    return document_to_model(read_mjcf(path), keyframe)


__all__ = ["Coupling", "MjcfDocument", "document_to_model", "global_poses", "load_mjcf", "read_mjcf", "read_mjcf_text"]
