"""Units at the user boundary (docs/units.md).

**One rule**: every number a user gives or reads is in the model's declared units — lengths in
``units.length``, angles in ``units.angle`` (``deg`` or ``rad``). That covers ``--set``,
``--drive``, ``--vary``, ``--tolerance`` sigmas, sensitivity rows and columns, targets, and
every printed, CSV, JSON and Parquet value. Inside, the solver works in *solver units*: the
model's length unit and radians. This module converts between the two; nothing else does.

Which numbers are angles: the angle components of a tree joint's coordinates (a revolute's
``q``, a cylindrical joint's ``q[0]``, both of a universal joint; ``JOINT.q`` addresses) and, for
derivatives, the body-frame rotation of a ``C`` column. Euler parameters, slides, positions,
lengths and rotation matrices have no angle unit. Suspension metrics (``metric:W.camber``) are
computed in degrees and converted like coordinates. A coupling coefficient ``COUPLING.coef[k]``
has the unit ``[q_a] / [q_b]^k`` of its two joints (:mod:`kinprop.io.couplings`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from kinprop.analysis.metrics import METRIC_ALIASES, METRICS, metric_unit
from kinprop.engine import compile as compile_engine
from kinprop.io.couplings import coef_factors
from kinprop.model import Model, parse_address


def angle_indices(model: Model, joint: str) -> list[int]:
    """Indices of a joint's coordinates that are angles (tree joints only)."""
    if joint not in compile_engine(model.mechanism).topology.tree_joints:
        return []
    return list(model.mechanism.joint(joint).jtype.angle_indices)


def _degrees(model: Model) -> bool:
    return model.units.get("angle") == "deg"


def _angle_mask(model: Model, address: str, size: int) -> np.ndarray:
    """Which components of ``address``'s value (``size`` of them) are joint angles."""
    mask = np.zeros(size, dtype=bool)
    try:
        addr = parse_address(address)
    except Exception:  # not an address (an output name): no angle components
        return mask
    if addr.field != "q" or addr.joint not in model.mechanism.joint_names:
        return mask
    idx = angle_indices(model, addr.joint)
    if addr.index is None:
        mask[[i for i in idx if i < size]] = True
    elif addr.index in idx:
        mask[:] = True
    return mask


def _coef_scale(model: Model, address: str, size: int) -> np.ndarray | None:
    """Solver value / model value of each component of a coupling-coefficient address
    (``f_a / f_b^k``), or None when ``address`` is not one."""
    try:
        addr = parse_address(address)
    except Exception:
        return None
    couplings = {c.name: c for c in model.mechanism.couplings}
    if addr.field != "coef" or addr.joint not in couplings:
        return None
    c = couplings[addr.joint]
    F = coef_factors(model.mechanism.joint(c.joint_a), model.mechanism.joint(c.joint_b), _degrees(model))[0]
    return np.full(size, F[addr.index]) if addr.index is not None and addr.index < F.size else np.resize(F, size)


def to_solver_units(model: Model, address: str, value: object) -> np.ndarray:
    """A value for ``address`` given in the model's units -> solver units (radians).

    ``J01.q = [45]`` on a degree model -> ``[0.785...]``; lengths, positions and rotation
    matrices are returned unchanged (as float arrays)."""
    v = np.array(value, dtype=float)
    if not _degrees(model):
        return v
    flat = v.reshape(-1)
    coef = _coef_scale(model, address, flat.size)
    if coef is not None:
        return (flat * coef).reshape(v.shape)
    mask = _angle_mask(model, address, flat.size)
    flat[mask] = np.radians(flat[mask])
    return flat.reshape(v.shape)


def from_solver_units(model: Model, address: str, value: object) -> np.ndarray:
    """The inverse of :func:`to_solver_units`: solver units (radians) -> the model's units."""
    v = np.array(value, dtype=float)
    if not _degrees(model):
        return v
    flat = v.reshape(-1)
    coef = _coef_scale(model, address, flat.size)
    if coef is not None:
        return (flat / coef).reshape(v.shape)
    mask = _angle_mask(model, address, flat.size)
    flat[mask] = np.degrees(flat[mask])
    return flat.reshape(v.shape)


def changes_to_internal(model: Model, changes: Mapping[str, object]) -> dict[str, np.ndarray]:
    """``{address: value}`` in the model's units -> solver units (see :func:`to_solver_units`)."""
    return {a: to_solver_units(model, a, v) for a, v in changes.items()}


def changes_to_model_units(model: Model, changes: Mapping[str, object]) -> dict[str, np.ndarray]:
    """``{address: value}`` in solver units -> the model's units."""
    return {a: from_solver_units(model, a, v) for a, v in changes.items()}


def unit_of(model: Model, name: str) -> str:
    """The unit, in the model's units, of an address, a column label or an output name:
    ``J01.q`` -> ``deg`` (a revolute in a degree model), ``J03.q`` -> ``m`` (a slide),
    ``J12.s_j[0]``, ``J12.length``, ``point:...``, ``hardpoint:...`` -> the length unit,
    ``J.C_i`` -> ``""`` (a rotation matrix), Euler parameters -> ``""``, ``metric:W.camber`` ->
    the angle unit."""
    length, angle = model.units.get("length", "m"), model.units.get("angle", "rad")
    if name.startswith(("point:", "hardpoint:")):
        return length
    if name.startswith("metric:") or "." not in name:
        short = name.split(".")[-1]
        if METRIC_ALIASES.get(short, short) not in METRICS:
            return ""  # not a quantity (step, status, iterations, ...)
        return angle if metric_unit(short, length) == "deg" else length
    try:
        addr = parse_address(name)
    except Exception:
        return ""
    if addr.field in ("s_i", "s_j", "length"):
        return length
    if addr.field in ("C_i", "C_j"):
        return ""
    if addr.field == "coef":
        return _coef_unit(model, addr.joint, addr.index)
    if addr.field == "q" and addr.joint in model.mechanism.joint_names:
        jt = model.mechanism.joint(addr.joint).jtype
        tree = addr.joint in compile_engine(model.mechanism).topology.tree_joints
        angles = set(angle_indices(model, addr.joint))
        euler = set(range(jt.euler.start, jt.euler.stop)) if tree and jt.euler is not None else set()
        k = addr.index
        if k is None:
            n = jt.n_coordinates if tree else jt.n_cut_coordinates
            kinds = [angle if i in angles else ("" if i in euler else length) for i in range(n)]
            return kinds[0] if len(set(kinds)) == 1 else ",".join(kinds)
        return angle if k in angles else ("" if k in euler else length)
    return ""


def _coef_unit(model: Model, coupling: str, k: int | None) -> str:
    """``[q_a] / [q_b]^k`` of a coupling coefficient ``c_k`` (``""`` for ``c1`` between like
    units; ``deg/deg^k`` for the whole ``coef`` without an index)."""
    c = next((c for c in model.mechanism.couplings if c.name == coupling), None)
    if c is None:
        return ""
    ua, ub = unit_of(model, f"{c.joint_a}.q"), unit_of(model, f"{c.joint_b}.q")
    if k is None:
        return f"{ua}/{ub}^k"
    if k == 0:
        return ua
    if k == 1:
        return "" if ua == ub else f"{ua}/{ub}"
    return f"{ua}/{ub}^{k}"


def derivative_scale(model: Model, name: str) -> float:
    """Factor taking a quantity named ``name`` from the units it is computed in to the model's
    units: ``180/pi`` for a joint angle or a ``C`` column (per radian of body-frame rotation)
    in a degree model, ``pi/180`` for an angle metric (computed in degrees) in a radian model,
    else 1.

    A derivative d(out)/d(in) computed in solver units becomes
    ``d_model = d_solver * derivative_scale(out) / derivative_scale(in)``."""
    deg = _degrees(model)
    if name.startswith("metric:") or ("." not in name and not name.startswith(("point:", "hardpoint:"))):
        angle_metric = unit_of(model, name) == model.units.get("angle", "rad")
        return math.pi / 180.0 if (angle_metric and not deg) else 1.0
    if not deg:
        return 1.0
    try:
        addr = parse_address(name)
    except Exception:
        return 1.0
    if addr.field in ("C_i", "C_j"):
        return 180.0 / math.pi
    if addr.field == "coef":  # model value = solver value / (f_a / f_b^k)
        scale = _coef_scale(model, name, 1)
        return 1.0 if scale is None or addr.index is None else float(1.0 / scale[0])
    return 180.0 / math.pi if unit_of(model, name) == "deg" else 1.0


__all__ = [
    "angle_indices",
    "changes_to_internal",
    "changes_to_model_units",
    "derivative_scale",
    "from_solver_units",
    "to_solver_units",
    "unit_of",
]
