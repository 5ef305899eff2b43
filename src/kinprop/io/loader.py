"""Load model files: parse (YAML/JSON), validate (schema, then semantics), build a Model.

Every problem is collected and reported at once as a :class:`ModelError`, each naming the
file, the location (``joints.J12.C_i``) and what was expected versus found.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from pydantic import ValidationError

from kinprop.errors import ModelError, Problem
from kinprop.io.schema import ModelFile
from kinprop.joints import REGISTRY, joint_type
from kinprop.model import Body, Design, Joint, Mechanism, Model, as_coordinates
from kinprop.model.mechanism import validate_structure
from kinprop.spatial import euler_to_matrix, is_rotation
from kinprop.topology import build_topology

#: orthonormality tolerance of rotation matrices in files (printed matrices carry ~6 digits)
ROTATION_TOL = 1e-4


class _UniqueKeyLoader(yaml.SafeLoader):
    """SafeLoader that reports duplicate mapping keys instead of silently keeping the last."""


def _construct_mapping(loader: _UniqueKeyLoader, node: yaml.MappingNode, deep: bool = False) -> dict:
    seen: dict[Any, int] = {}
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=deep)
        if key in seen:
            raise yaml.constructor.ConstructorError(
                None, None, f"duplicate name {key!r} (first at line {seen[key] + 1})", key_node.start_mark
            )
        seen[key] = key_node.start_mark.line
    return yaml.SafeLoader.construct_mapping(loader, node, deep=deep)


_UniqueKeyLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)


def parse_text(text: str, file: str = "<string>") -> Any:
    """Parse YAML (or JSON, a subset) text; syntax errors become a ModelError."""
    try:
        if file.endswith(".json"):
            return json.loads(text)
        return yaml.load(text, Loader=_UniqueKeyLoader)
    except (yaml.YAMLError, json.JSONDecodeError) as exc:
        raise ModelError([Problem("syntax", " ".join(str(exc).split()), file)]) from None


def _loc(parts: tuple[Any, ...]) -> str:
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out or "model"


def pydantic_problems(exc: ValidationError, file: str) -> list[Problem]:
    problems = []
    for e in exc.errors():
        found = e.get("input")
        text = e["msg"]
        if e["type"] not in ("missing",) and not isinstance(found, (dict, list)):
            text += f" (found {found!r})"
        problems.append(Problem(_loc(tuple(e["loc"])), text, file))
    return problems


def load_model(path: str | Path) -> Model:
    """Read and validate a model file (YAML or JSON)."""
    path = Path(path)
    file = str(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise ModelError([Problem("file", f"cannot read: {exc.strerror}", file)]) from None
    return model_from_data(parse_text(text, file), file)


def model_from_data(data: Any, file: str = "<data>") -> Model:
    """Validate parsed file data and build a Model; raise ModelError with every problem."""
    if not isinstance(data, dict):
        raise ModelError([Problem("model", f"expected a mapping at the top level, found {type(data).__name__}", file)])
    if data.get("style") == "hardpoints":
        from kinprop.io.hardpoints import model_from_hardpoints

        return model_from_hardpoints(data, file)
    try:
        spec = ModelFile.model_validate(data)
    except ValidationError as exc:
        raise ModelError(pydantic_problems(exc, file)) from None
    return build_model(spec, file)


def build_model(spec: ModelFile, file: str) -> Model:
    problems: list[Problem] = []
    deg = spec.units.angle == "deg"
    bodies = []
    for name, b in spec.bodies.items():
        loc = f"bodies.{name}"
        A = np.eye(3)
        if b.orientation is not None and b.euler_parameters is not None:
            problems.append(Problem(loc, "give either 'orientation' or 'euler_parameters', not both", file))
        if b.orientation is not None:
            A = np.array(b.orientation)
            if not is_rotation(A, ROTATION_TOL):
                problems.append(
                    Problem(f"{loc}.orientation", "expected a proper rotation matrix (C^T C = I, det +1)", file)
                )
        elif b.euler_parameters is not None:
            p = np.array(b.euler_parameters)
            if abs(p @ p - 1) > 1e-6:
                problems.append(
                    Problem(
                        f"{loc}.euler_parameters", f"expected unit Euler parameters, |p| = {math.sqrt(p @ p):.6g}", file
                    )
                )
            A = euler_to_matrix(p)
        if not b.fixed and (b.position is not None or b.orientation is not None or b.euler_parameters is not None):
            problems.append(Problem(loc, "only fixed bodies take a pose; moving bodies follow from the joints", file))
        bodies.append(
            Body(
                name,
                b.fixed,
                tuple(b.position or (0.0, 0.0, 0.0)),
                tuple(map(tuple, A.tolist())),
                tuple((k, tuple(v)) for k, v in b.points.items()),
            )
        )
    joints, values, coords = [], {}, {}
    for name, j in spec.joints.items():
        loc = f"joints.{name}"
        fields = frozenset(f for f in ("s_i", "s_j", "C_i", "C_j", "length") if getattr(j, f) is not None)
        for f in ("C_i", "C_j"):
            C = getattr(j, f)
            if C is not None:
                if not is_rotation(np.array(C), ROTATION_TOL):
                    problems.append(
                        Problem(f"{loc}.{f}", f"expected a proper rotation matrix (C^T C = I, det +1), found {C}", file)
                    )
                values[f"{name}.{f}"] = np.array(C, dtype=float)
        for f in ("s_i", "s_j"):
            if getattr(j, f) is not None:
                values[f"{name}.{f}"] = np.array(getattr(j, f), dtype=float)
        if j.length is not None:
            values[f"{name}.length"] = float(j.length)
        joints.append(Joint(name, j.type, j.bodies[0], j.bodies[1], fields, j.cut))
    problems += [Problem(p.location, p.message, file) for p in validate_structure(tuple(bodies), tuple(joints))]
    if problems:
        raise ModelError(problems)
    mech = Mechanism(tuple(bodies), tuple(joints), spec.name)
    try:
        topo = build_topology(mech)
    except ModelError as exc:
        raise ModelError(exc.problems, file) from None
    tree = set(topo.tree_joints)
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
        if deg and name in tree:
            idx = list(jt.angle_indices)
            q[idx] = np.radians(q[idx])
        coords[name] = q
    if problems:
        raise ModelError(problems)
    units = {"length": spec.units.length, "angle": spec.units.angle}
    return Model(mech, Design(values), as_coordinates(coords), units, file)


def known_joint_types() -> list[str]:
    return sorted(REGISTRY)
