"""Load model files: parse (YAML/JSON), validate (schema, then semantics), build a Model.

Every problem is collected and reported at once as a :class:`ModelError`, each naming the
file, the location (``joints.J12.C_i``) and what was expected versus found. Two styles:
``frames`` (the paper's body-frame vectors, :func:`build_model`) and ``hardpoints`` (global
points and axes, :mod:`kinprop.io.hardpoints`).
"""

from __future__ import annotations

import json
import math
from collections import Counter
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
import yaml
from pydantic import BaseModel, ValidationError

from kinprop.engine.engine import ABSURD
from kinprop.engine.units import tree_coordinates
from kinprop.errors import ModelError, Problem
from kinprop.io.couplings import build_couplings
from kinprop.io.elements import build_elements, build_torsion_springs, build_vehicle
from kinprop.io.loads import build_loads
from kinprop.io.points import attach_references, point_order, point_references
from kinprop.io.schema import ModelFile
from kinprop.joints import REGISTRY, joint_type
from kinprop.model import Body, Design, Joint, Mechanism, Model, as_coordinates
from kinprop.model.mechanism import validate_couplings, validate_structure
from kinprop.spatial import euler_to_matrix, is_rotation
from kinprop.topology import WORLD, build_topology

#: orthonormality tolerance of rotation matrices in files (printed matrices carry ~6 digits)
ROTATION_TOL = 1e-4
#: largest |p.p - 1| accepted for Euler-parameter coordinates in a file
EULER_TOL = 0.1
ROTATION_EXPECTED = "expected a proper rotation matrix (C^T C = I, det +1)"
STYLES = ("frames", "hardpoints")
T = TypeVar("T", bound=BaseModel)
#: libyaml's C parser when PyYAML was built with it (about 10x faster on large models), else pure Python
_SafeLoader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def _walk_duplicates(node: yaml.Node, path: str, seen: set[int], out: list[Problem]) -> None:
    """Collect duplicate mapping keys anywhere under ``node`` (aliases visited once)."""
    if id(node) in seen:
        return
    seen.add(id(node))
    if isinstance(node, yaml.MappingNode):
        first: dict[tuple[str, str], int] = {}
        for key, value in node.value:
            name = key.value if isinstance(key, yaml.ScalarNode) else None
            sub = f"{path}.{name}" if path else str(name)
            if isinstance(key, yaml.ScalarNode) and key.value != "<<":
                ident = (key.tag, key.value)
                if ident in first:
                    out.append(
                        Problem(
                            sub, f"duplicate name {name!r} (lines {first[ident] + 1} and {key.start_mark.line + 1})"
                        )
                    )
                else:
                    first[ident] = key.start_mark.line
            _walk_duplicates(value, sub, seen, out)
    elif isinstance(node, yaml.SequenceNode):
        for k, item in enumerate(node.value):
            _walk_duplicates(item, f"{path}[{k}]", seen, out)


class _JsonObject(dict):
    """A JSON object that remembers the names it saw twice (the last value is kept)."""

    duplicates: list[str]


def _json_object(pairs: list[tuple[str, Any]]) -> _JsonObject:
    out = _JsonObject()
    counts = Counter(k for k, _ in pairs)
    out.duplicates = [k for k, _ in pairs if counts[k] > 1]
    out.update(pairs)
    return out


def _json_duplicates(tree: Any, path: str, out: list[Problem]) -> None:
    if isinstance(tree, _JsonObject):
        for k in dict.fromkeys(tree.duplicates):
            out.append(Problem(f"{path}.{k}" if path else k, f"duplicate name {k!r}"))
    if isinstance(tree, dict):
        for k, v in tree.items():
            _json_duplicates(v, f"{path}.{k}" if path else str(k), out)
    elif isinstance(tree, list):
        for k, v in enumerate(tree):
            _json_duplicates(v, f"{path}[{k}]", out)


def parse_document(text: str, file: str) -> tuple[Any, list[Problem]]:
    """Parsed data (duplicates: the last wins) and the duplicate-name problems."""
    dups: list[Problem] = []
    try:
        if file.endswith(".json"):
            data = json.loads(text, object_pairs_hook=_json_object)
            _json_duplicates(data, "", dups)
        else:
            loader = _SafeLoader(text)
            try:
                node = loader.get_single_node()
                if node is not None:
                    _walk_duplicates(node, "", set(), dups)
                data = None if node is None else loader.construct_document(node)
            finally:
                loader.dispose()
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        where = f"line {mark.line + 1}, column {mark.column + 1}" if mark is not None else "syntax"
        what = " ".join(x for x in (exc.context, exc.problem) if x)
        raise ModelError([Problem(where, f"YAML syntax: {what}", file)]) from None
    except (yaml.YAMLError, json.JSONDecodeError) as exc:
        raise ModelError([Problem("syntax", " ".join(str(exc).split()), file)]) from None
    except RecursionError:
        raise ModelError([Problem("syntax", "nested too deeply", file)]) from None
    return data, [Problem(p.location, p.message, file) for p in dups]


def read_text(path: Path) -> str:
    """A file's text (UTF-8), or a :class:`ModelError` naming it (cannot read, not UTF-8)."""
    file = str(path)
    try:
        return path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ModelError([Problem("file", f"cannot read: {exc.strerror or exc}", file)]) from None
    except UnicodeDecodeError as exc:
        raise ModelError([Problem("file", f"not UTF-8 text (byte {exc.start})", file)]) from None


def parse_text(text: str, file: str = "<string>") -> Any:
    """Parse YAML (or JSON, a subset) text; syntax errors and duplicate names become a ModelError."""
    data, dups = parse_document(text, file)
    if dups:
        raise ModelError(dups)
    return data


def _loc(parts: tuple[Any, ...]) -> str:
    """``joints.J12.s_i[1]``; a bad mapping key (pydantic's ``[key]``) as ``bodies.KEY``."""
    if parts and parts[-1] == "[key]":
        head = _loc(parts[:-2])
        return f"{head}.{parts[-2]}" if parts[:-2] else str(parts[-2])
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out or "model"


#: what a missing top-level or joint key should hold
MISSING_HINTS = {
    "units": "declare the units, e.g. units: {length: mm, angle: deg}",
    "length": "one of m, mm",
    "angle": "one of deg, rad",
    "axes": "one of ISO8855 (x forward, y left, z up), SAE (x forward, y right, z down), right-handed",
    "bodies": "a mapping of body names, at least one with fixed: true",
    "joints": "a mapping of joint names",
    "type": f"a joint type, one of {', '.join(sorted(REGISTRY))}",
    "style": "'hardpoints' for a hardpoint-style file",
}


def describe_found(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _message(e: Any) -> str:
    """Expected versus found for one pydantic error."""
    loc, found, kind, ctx = tuple(e["loc"]), e.get("input"), e["type"], e.get("ctx") or {}
    if loc and loc[-1] == "[key]":
        return f"expected a name (text), found {describe_found(loc[-2])}"
    if kind == "missing":
        key = str(loc[-1]) if loc else ""
        return "missing" + (f": {MISSING_HINTS[key]}" if key in MISSING_HINTS else " (required)")
    if kind == "extra_forbidden":
        if loc and loc[-1] in ("point", "axis", "axis_i", "axis_j", "point_i", "point_j"):
            return "unknown key (hardpoint keys need 'style: hardpoints' at the top level)"
        if loc and loc[-1] in ("s_i", "s_j", "C_i", "C_j", "euler_parameters"):
            return "unknown key (s_i, s_j, C_i and C_j belong in a frame-style file)"
        return "unknown key"
    if kind in ("model_type", "dict_type", "model_attributes_type"):
        return f"expected a mapping, found {type(found).__name__}"
    if kind == "list_type":
        return f"expected a list, found {type(found).__name__}"
    if kind in ("too_short", "too_long") and "actual_length" in ctx:
        n = ctx.get("min_length") if kind == "too_short" else ctx.get("max_length")
        if ctx.get("min_length") is not None and ctx.get("max_length") is not None:
            n = ctx["min_length"] if kind == "too_short" else ctx["max_length"]
        return f"expected {'at least' if kind == 'too_short' else 'at most'} {n} items, found {ctx['actual_length']}"
    text = e["msg"]
    if not isinstance(found, (dict, list)):
        text += f" (found {describe_found(found)})"
    return text


def pydantic_problems(exc: ValidationError, file: str) -> list[Problem]:
    """One Problem per pydantic error: location, what was expected, what was found."""
    return [Problem(_loc(tuple(e["loc"])), _message(e), file) for e in exc.errors()]


#: stand-in values that let the semantic checks run when a top-level key is invalid
_STAND_INS = {"units": {"length": "m", "angle": "rad", "axes": "right-handed"}}


def validate_file(data: dict[str, Any], schema: type[T], file: str) -> tuple[T | None, list[Problem], bool]:
    """Validate ``data`` against ``schema``; on errors, also a salvaged spec for semantic checks.

    The salvaged spec drops what failed (a bad field of a body or joint, a joint whose type or
    bodies are bad, a bad top-level key, replaced by a stand-in where required), so the
    semantic checks can still report the rest at once. Returns ``(spec, schema problems,
    structure_changed)``; the spec is None when nothing can be salvaged, and
    ``structure_changed`` says that salvaging touched a body's existence or fixedness or a
    joint's connectivity (so connectivity findings would be artefacts).
    """
    try:
        return schema.model_validate(data), [], False
    except ValidationError as exc:
        errors = exc.errors()
        problems = pydantic_problems(exc, file)
    partial: dict[str, Any] = dict(data)
    structural = False
    for e in errors:
        loc = tuple(e["loc"])
        if not loc:
            return None, problems, True
        top = loc[0]
        if top in ("bodies", "joints") and len(loc) >= 2 and isinstance(partial.get(top), dict):
            if partial[top] is data.get(top):
                partial[top] = dict(partial[top])
            section, name = partial[top], loc[1]
            entry = section.get(name)
            field = loc[2] if len(loc) > 2 and loc[-1] != "[key]" else None
            if field is None or not isinstance(entry, dict) or (top == "joints" and field in ("type", "bodies")):
                section.pop(name, None)
                if top == "bodies" and loc[-1] != "[key]":
                    section[name] = {}  # keep the name: joints refer to it
                structural = True
                continue
            structural |= field in ("fixed", "cut")
            section[name] = {k: v for k, v in entry.items() if k != field}
        elif top in _STAND_INS:
            partial[top] = _STAND_INS[top]
        else:
            partial.pop(top, None)
            structural |= top in ("bodies", "joints")
    try:
        return schema.model_validate(partial), problems, structural
    except (ValidationError, TypeError, ValueError):
        return None, problems, True


#: semantic findings that a salvaged structure can fake
_STRUCTURAL = ("no fixed body", "not connected", "reachable from a fixed body", "closes a loop", "no bodies")


def _overlap(a: str, b: str) -> bool:
    """One location contains the other (``joints.J12.point`` and ``joints.J12.point[1]``)."""
    short, long = sorted((a, b), key=len)
    return long == short or long.startswith((short + ".", short + "["))


def merge_problems(schema: list[Problem], semantic: list[Problem], structural: bool) -> list[Problem]:
    """Schema problems, then the semantic ones that are not about the same places (nor, when
    salvaging changed the structure, about connectivity)."""
    seen = [p.location for p in schema]
    out = list(schema)
    for p in semantic:
        if any(_overlap(p.location, s) for s in seen):
            continue
        if structural and any(k in p.message for k in _STRUCTURAL):
            continue
        out.append(p)
    return out


def build_or_report(data: dict[str, Any], schema: type[T], build: Any, file: str) -> Model:
    """Validate, build, and raise one ModelError with the schema and the semantic problems."""
    spec, problems, structural = validate_file(data, schema, file)
    # huge numbers may overflow in the checks (e.g. C^T C): they fail them, quietly
    with np.errstate(over="ignore", invalid="ignore"):
        if not problems:
            return build(spec, file)
        semantic: list[Problem] = []
        if spec is not None:
            try:
                build(spec, file)
            except ModelError as exc:
                semantic = exc.problems
    raise ModelError(merge_problems(problems, semantic, structural))


def _body(name: str, b: Any, file: str, problems: list[Problem]) -> Body:
    loc = f"bodies.{name}"
    rot = np.eye(3)
    if name == WORLD:
        problems.append(Problem(loc, f"the body name {WORLD!r} is reserved", file))
    if b.orientation is not None and b.euler_parameters is not None:
        problems.append(Problem(loc, "give either 'orientation' or 'euler_parameters', not both", file))
    if b.orientation is not None:
        rot = np.array(b.orientation)
        if not is_rotation(rot, ROTATION_TOL):
            problems.append(Problem(f"{loc}.orientation", ROTATION_EXPECTED, file))
    elif b.euler_parameters is not None:
        p = np.array(b.euler_parameters)
        if abs(p @ p - 1) > 1e-6:
            problems.append(
                Problem(
                    f"{loc}.euler_parameters", f"expected unit Euler parameters, |p| = {math.sqrt(p @ p):.6g}", file
                )
            )
        rot = euler_to_matrix(p)
    if not b.fixed and (b.position is not None or b.orientation is not None or b.euler_parameters is not None):
        problems.append(Problem(loc, "only fixed bodies take a pose; moving bodies follow from the joints", file))
    points = tuple((k, tuple(v)) for k, v in b.points.items() if not isinstance(v, str))
    return Body(name, b.fixed, tuple(b.position or (0.0, 0.0, 0.0)), tuple(map(tuple, rot.tolist())), points)


def build_model(spec: ModelFile, file: str) -> Model:
    """Build a frame-style Model from a validated file; semantic problems are collected."""
    problems: list[Problem] = absurd_lengths(spec, file)
    if problems:
        raise ModelError(problems)
    deg = spec.units.angle == "deg"
    bodies = [_body(name, b, file, problems) for name, b in spec.bodies.items()]
    refs = {}
    for name, b in spec.bodies.items():
        refs[name], found = point_references(name, b, file)
        problems += found
    if not bodies:
        problems.append(Problem("bodies", "no bodies: expected at least one, marked 'fixed: true'", file))
    joints, values, coords = [], {}, {}
    for name, j in spec.joints.items():
        loc = f"joints.{name}"
        fields = frozenset(f for f in ("s_i", "s_j", "C_i", "C_j", "length") if getattr(j, f) is not None)
        for f in ("C_i", "C_j"):
            c = getattr(j, f)
            if c is not None:
                if not is_rotation(np.array(c), ROTATION_TOL):
                    problems.append(Problem(f"{loc}.{f}", f"{ROTATION_EXPECTED}, found {c}", file))
                values[f"{name}.{f}"] = np.array(c, dtype=float)
        for f in ("s_i", "s_j"):
            if getattr(j, f) is not None:
                values[f"{name}.{f}"] = np.array(getattr(j, f), dtype=float)
        if j.length is not None:
            values[f"{name}.length"] = float(j.length)
        joints.append(Joint(name, j.type, j.bodies[0], j.bodies[1], fields, j.cut))
    problems += [
        Problem(p.location, p.message, file)
        for p in validate_structure(tuple(bodies), tuple(joints), tuple(spec.inputs))
    ]
    couplings, coefs, cproblems = build_couplings(spec.couplings, {j.name: j for j in joints}, deg, file)
    values.update(coefs)
    problems += cproblems
    problems += [Problem(p.location, p.message, file) for p in validate_couplings(tuple(joints), couplings)]
    elements, eproblems = build_elements(spec.elements, {b.name for b in bodies}, "frames", file)
    torsion, tproblems = build_torsion_springs(spec.elements, {j.name: j.type for j in joints}, file)
    problems += eproblems + tproblems
    loads, lproblems = build_loads(spec.loads, {b.name: [n for n, _ in b.points] for b in bodies}, "frames", file)
    problems += lproblems
    if problems:
        raise ModelError(problems)
    mech = Mechanism(tuple(bodies), tuple(joints), spec.name, tuple(spec.inputs), couplings, spec.edits)
    try:
        topo = build_topology(mech)
    except ModelError as exc:
        raise ModelError(exc.problems, file) from None
    tree = set(topo.tree_joints)
    for name in topo.cut_joints:
        if not mech.joint(name).jtype.cut:
            problems.append(
                Problem(
                    f"joints.{name}", f"a {mech.joint(name).jtype.name} joint cannot be cut, but it closes a loop", file
                )
            )
    for name, j in spec.joints.items():
        jt = joint_type(j.type)
        n = jt.n_coordinates if name in tree else jt.n_cut_coordinates
        if j.q is None:
            if n:
                coords[name] = jt.default_coordinates() if name in tree else jt.default_cut_coordinates()
            continue
        if len(j.q) != n:
            role = "tree" if name in tree else "cut"
            problems.append(
                Problem(
                    f"joints.{name}.q", f"expected {n} coordinates for a {role} {jt.name} joint, found {len(j.q)}", file
                )
            )
            continue
        q = np.array(j.q, dtype=float)
        if name in tree and jt.euler is not None:
            p = q[jt.euler]
            if abs(p @ p - 1) > EULER_TOL:
                problems.append(
                    Problem(
                        f"joints.{name}.q", f"expected Euler parameters with p.p = 1, found p.p = {p @ p:.6g}", file
                    )
                )
        coords[name] = tree_coordinates(q, jt.angle_indices if name in tree else (), spec.units.angle, True)
    if problems:
        raise ModelError(problems)
    units = {"length": spec.units.length, "angle": spec.units.angle}
    if spec.units.axes is not None:
        units["axes"] = spec.units.axes
    if spec.units.force is not None:
        units["force"] = spec.units.force
    model = Model(mech, Design(values), as_coordinates(coords), units, file, elements, build_vehicle(spec.vehicle),
                  loads, torsion)  # fmt: skip
    return attach_references(model, refs, file, point_order(spec.bodies))


def absurd_lengths(spec: Any, file: str) -> list[Problem]:
    """Lengths in a file beyond ``ABSURD`` times its length scale, one problem each.

    The scale is the median size of the file's non-zero positions, points and lengths (a
    single absurd number cannot inflate it, as it would the largest); the limit is
    ``ABSURD * max(1, scale)``, the rule ``--set`` applies (:meth:`kinprop.engine.Engine.set`).
    Checked before anything is computed from the numbers, so nothing overflows. Values that
    are not numbers (a point given by reference) are left to the other checks.
    """
    found: list[tuple[str, float]] = []

    def add(loc: str, v: Any) -> None:
        if isinstance(v, dict):
            for k, x in v.items():
                add(f"{loc}.{k}", x)
            return
        vals = v if isinstance(v, (list, tuple)) else [v]
        if vals and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in vals):
            found.append((loc, float(np.max(np.abs(np.asarray(vals, dtype=float))))))

    for name, b in spec.bodies.items():
        add(f"bodies.{name}.position", getattr(b, "position", None))
        for k, v in (getattr(b, "points", None) or {}).items():
            add(f"bodies.{name}.points.{k}", v)
    for name, j in spec.joints.items():
        for f in ("s_i", "s_j", "point", "point_i", "point_j", "length", "pivots"):
            v = getattr(j, f, None)
            if v is not None:
                add(f"joints.{name}.{f}", v)
    sizes = [v for _, v in found if v > 0]
    if not sizes:
        return []
    scale = float(np.median(sizes))
    bound = ABSURD * max(1.0, scale)
    why = f"times the model's length scale (L = {scale:.3g}, the median size of its lengths; the limit is {bound:.3g})"
    return [
        Problem(loc, f"{v:.3g} is beyond {ABSURD:g} {why}; no mechanism assembles there", file)
        for loc, v in found
        if v > bound
    ]


def known_joint_types() -> list[str]:
    return sorted(REGISTRY)
