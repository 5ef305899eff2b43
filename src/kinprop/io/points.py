"""Named points given by reference to joints, at load time (both file styles).

A named point may be written as a joint (``kingpin_upper: UBJ``, ``tie_rod_outer: TR.j``)
and a wheel body may declare ``kingpin: [UPPER, LOWER]`` (points ``kingpin_upper`` and
``kingpin_lower``); plain points that coincide with a joint's point on their body are bound
to it as well (:mod:`kinprop.model.joint_points`). Bound points follow every edit of their
joint. A declared steering-axis point that does not coincide with the joint the default
steering axis takes is reported (:class:`JointPointWarning`): it is used as declared.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import numpy as np

from kinprop.analysis.metrics import steering_axis_mismatch
from kinprop.engine import compile as compile_engine
from kinprop.errors import ModelError, Problem
from kinprop.model import Body, Mechanism, Model
from kinprop.model.joint_points import bind_coincident, joint_s, parse_reference

KINGPIN_POINTS = ("kingpin_upper", "kingpin_lower")


class JointPointWarning(UserWarning):
    """A declared named point that should coincide with a joint and does not."""


def point_references(name: str, spec: Any, file: str) -> tuple[dict[str, tuple[str, str]], list[Problem]]:
    """``{point: (reference, location)}`` of one body spec (string points and ``kingpin``)."""
    refs = {k: (v, f"bodies.{name}.points.{k}") for k, v in spec.points.items() if isinstance(v, str)}
    problems = []
    if getattr(spec, "kingpin", None) is not None:
        for k, (key, ref) in enumerate(zip(KINGPIN_POINTS, spec.kingpin, strict=True)):
            if key in spec.points:
                problems.append(
                    Problem(f"bodies.{name}.points.{key}", "given twice: by the point and by 'kingpin'; keep one", file)
                )
            refs[key] = (ref, f"bodies.{name}.kingpin[{k}]")
    return refs, problems


def attach_references(
    model: Model, refs: Mapping[str, Mapping[str, tuple[str, str]]], file: str, order: Any = None
) -> Model:
    """``model`` with the referenced points added (body-frame positions at the model's
    coordinates), coincident plain points bound, and steering-axis mismatches warned about."""
    mech = model.mechanism
    joints = {j.name: j for j in mech.joints}
    problems: list[Problem] = []
    resolved: dict[str, dict[str, tuple[str, str]]] = {}
    for body, points in refs.items():
        for point, (text, where) in points.items():
            hit = parse_reference(text, joints, body)
            if isinstance(hit, str):
                problems.append(Problem(where, hit, file))
            else:
                resolved.setdefault(body, {})[point] = hit
    if problems:
        raise ModelError(problems)
    bodies = []
    kin = None
    for b in mech.bodies:
        new = resolved.get(b.name, {})
        if not new:
            bodies.append(b)
            continue
        pts = dict(b.points)
        for point, (joint, side) in new.items():
            j = joints[joint]
            if (j.body_i if side == "i" else j.body_j) == b.name:
                pts[point] = tuple(joint_s(j, side, model.design).tolist())
            else:
                if kin is None:
                    kin = compile_engine(mech).kinematics(model.design, model.coordinates)
                f = kin.frames[joint]
                p = f.P_i if side == "i" else f.P_j
                pts[point] = tuple((kin.A[b.name].T @ (p - kin.r[b.name])).tolist())
        names = list(order[b.name]) if order is not None and b.name in order else list(pts)
        names += [n for n in pts if n not in names]
        points = tuple((n, pts[n]) for n in names if n in pts)
        links = b.joint_points + tuple((n, *new[n], True) for n in names if n in new)
        bodies.append(Body(b.name, b.fixed, b.position, b.orientation, points, links))
    if resolved:
        mech = Mechanism(tuple(bodies), mech.joints, mech.name, mech.inputs, mech.couplings, mech.edits)
    bound = bind_coincident(mech, model.design)
    if bound is not model.mechanism:
        model = replace(model, mechanism=bound)
    for message in steering_axis_mismatch(model):
        warnings.warn(f"{file}: {message}", JointPointWarning, stacklevel=4)
    return model


def point_order(specs: Mapping[str, Any]) -> dict[str, list[str]]:
    """The order points are written in, per body (kingpin points last)."""
    out = {}
    for name, spec in specs.items():
        names = list(spec.points)
        if getattr(spec, "kingpin", None) is not None:
            names += [k for k in KINGPIN_POINTS if k not in names]
        out[name] = names
    return out


def written_points(model: Model, body: Body, global_frame: bool) -> dict[str, Any]:
    """A body's points for a file: declared references as ``JOINT.side``, the others as
    coordinates at the model's current state (body frame, or global with ``global_frame``)."""
    declared = {n: f"{j}.{s}" for n, j, s, d in body.joint_points if d}
    bound = {n: (j, s) for n, j, s, d in body.joint_points}
    kin = None
    out: dict[str, Any] = {}
    for name, p in body.points:
        if name in declared:
            out[name] = declared[name]
            continue
        v = np.asarray(p, dtype=float)
        if name in bound or global_frame:
            if kin is None:
                kin = compile_engine(model.mechanism).kinematics(model.design, model.coordinates)
            if name in bound:
                f = kin.frames[bound[name][0]]
                g = f.P_i if bound[name][1] == "i" else f.P_j
            else:
                g = kin.r[body.name] + kin.A[body.name] @ v
            v = g if global_frame else kin.A[body.name].T @ (g - kin.r[body.name])
        out[name] = v
    return out


__all__ = ["JointPointWarning", "attach_references", "point_order", "point_references", "written_points"]
