"""Units: the one module that owns unit factors and conversions (docs/units.md).

**One rule**: every number a user gives or reads is in the model's declared units — lengths in
``units.length``, angles in ``units.angle`` (``deg`` or ``rad``). That covers ``--set``,
``--drive``, ``--vary``, ``--tolerance`` sigmas, sensitivity rows and columns, targets, the
Python API (``units="model"``, the default) and every printed, CSV, JSON and Parquet value.
Inside, the solver works in *solver units*: the model's length unit and radians; the engine's
SI metric (``Engine.si_scale``) reads metres per length unit from :data:`METRES_PER`.

Which numbers are angles: the angle components of a tree joint's coordinates (a revolute's
``q``, a cylindrical joint's ``q[0]``, both of a universal joint; ``JOINT.q`` addresses) and, for
derivatives, the body-frame rotation of a ``C`` column. Euler parameters, slides, positions,
lengths and rotation matrices have no angle unit. A coupling coefficient ``COUPLING.coef[k]``
has the unit ``[q_a] / [q_b]^k`` of its two joints (:func:`coef_factors`). Which coordinate
components are angles is resolved once per compiled engine (:class:`UnitTable`,
``Engine.unit_table``); the functions here take that engine (or resolve it from the mechanism's
topology when none is given). Suspension metrics (``metric:W.camber``) are computed in degrees;
:mod:`kinprop.analysis.units` names their units with the factors of this module.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Protocol
from weakref import WeakKeyDictionary

import numpy as np

from kinprop.constraints.coupling import N_COEF
from kinprop.joints import joint_type
from kinprop.model import Joint, Mechanism, Model, parse_address
from kinprop.spatial import Array
from kinprop.topology import Topology, build_topology

#: metres per length unit: the units a model may declare (``m``, ``mm``) and those a value may
#: carry (a target's ``50mm``, ``2in``)
METRES_PER = {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "in": 0.0254, "inch": 0.0254}
#: radians per angle unit
RADIANS_PER = {"rad": 1.0, "deg": math.pi / 180.0}

#: the angle components of a body pose output (``body:B[roll]``, kinprop.analysis.outputs)
BODY_ANGLES = ("[roll]", "[pitch]", "[yaw]")


class HasUnits(Protocol):
    """What the conversions read of a compiled engine (:class:`kinprop.engine.Engine`)."""

    @property
    def unit_table(self) -> UnitTable: ...


@dataclass(frozen=True)
class UnitTable:
    """Which coordinate components of each joint are angles and which Euler parameters,
    resolved once from a mechanism's topology (tree joints only: a cut joint has no
    coordinates of the tree's kind); ``Engine.unit_table`` holds its engine's."""

    #: joint -> indices of its coordinates that are angles (tree joints)
    angles: Mapping[str, tuple[int, ...]]
    #: joint -> indices of its coordinates that are Euler parameters (tree joints)
    euler: Mapping[str, tuple[int, ...]]
    #: joint -> number of coordinates (tree or cut form)
    n_coordinates: Mapping[str, int]

    @classmethod
    def of(cls, mechanism: Mechanism, topology: Topology | None = None) -> UnitTable:
        tree = (topology or build_topology(mechanism)).tree_joints
        angles, euler, n = {}, {}, {}
        for j in mechanism.joints:
            jt = j.jtype
            is_tree = j.name in tree
            angles[j.name] = tuple(jt.angle_indices) if is_tree else ()
            euler[j.name] = tuple(range(jt.euler.start, jt.euler.stop)) if is_tree and jt.euler is not None else ()
            n[j.name] = jt.n_coordinates if is_tree else jt.n_cut_coordinates
        return cls(angles, euler, n)


#: tables resolved without an engine, once per mechanism (kept while the mechanism lives)
_TABLES: WeakKeyDictionary[Mechanism, UnitTable] = WeakKeyDictionary()


def _table(model: Model, engine: HasUnits | None) -> UnitTable:
    """The engine's table (compiled from the model's mechanism) when given, else the
    mechanism's, resolved once."""
    if engine is not None:
        return engine.unit_table
    table = _TABLES.get(model.mechanism)
    if table is None:
        table = _TABLES[model.mechanism] = UnitTable.of(model.mechanism)
    return table


def angle_indices(model: Model, joint: str, engine: HasUnits | None = None) -> list[int]:
    """Indices of a joint's coordinates that are angles (tree joints only)."""
    return list(_table(model, engine).angles.get(joint, ()))


def tree_coordinates(q: object, angles: tuple[int, ...] | list[int], angle_unit: str, to_solver: bool) -> Array:
    """A tree joint's coordinates between a file's angle unit and radians: its ``angles``
    components (``JointType.angle_indices``) scaled by :data:`RADIANS_PER` (a copy)."""
    out = np.array(q, dtype=float)
    idx = list(angles)
    if idx and RADIANS_PER[angle_unit] != 1.0:
        out[idx] = out[idx] * RADIANS_PER[angle_unit] if to_solver else out[idx] / RADIANS_PER[angle_unit]
    return out


def degrees(model: Model) -> bool:
    """Whether the model declares its angles in degrees (``units.angle``): the one place that
    reads the model's angle unit."""
    return model.units.get("angle") == "deg"


def radians_per_angle(model: Model) -> float:
    """Radians per unit of the model's angles (:data:`RADIANS_PER`)."""
    return RADIANS_PER["deg"] if degrees(model) else 1.0


def _angle_mask(model: Model, address: str, size: int, engine: HasUnits | None = None) -> np.ndarray:
    """Which components of ``address``'s value (``size`` of them) are joint angles."""
    mask = np.zeros(size, dtype=bool)
    try:
        addr = parse_address(address)
    except Exception:  # not an address (an output name): no angle components
        return mask
    if addr.field != "q" or addr.joint not in model.mechanism.joint_names:
        return mask
    idx = angle_indices(model, addr.joint, engine)
    if addr.index is None:
        mask[[i for i in idx if i < size]] = True
    elif addr.index in idx:
        mask[:] = True
    return mask


def _angle_factor(joint: Joint | None, deg: bool) -> float:
    """Radians per model unit of a single-coordinate joint's coordinate."""
    if joint is None or not deg:
        return 1.0
    try:
        return RADIANS_PER["deg"] if joint_type(joint.type).angle_indices else 1.0
    except KeyError:
        return 1.0


def coef_factors(joint_a: Joint | None, joint_b: Joint | None, deg: bool) -> tuple[Array, float, float]:
    """``(F, f_a, f_b)`` of a coupling: solver value = model value times ``F[k]`` for ``c_k``
    (``f_a / f_b^k``), ``f_a`` for ``q_a0``, ``f_b`` for ``q_b0`` (``f = pi/180`` for an angle in
    a degree model, else 1)."""
    fa, fb = _angle_factor(joint_a, deg), _angle_factor(joint_b, deg)
    return np.array([fa / fb**k for k in range(N_COEF)]), fa, fb


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
    F = coef_factors(model.mechanism.joint(c.joint_a), model.mechanism.joint(c.joint_b), degrees(model))[0]
    return np.full(size, F[addr.index]) if addr.index is not None and addr.index < F.size else np.resize(F, size)


def _convert(model: Model, address: str, value: object, engine: HasUnits | None, to_solver: bool) -> np.ndarray:
    """Angles (and coupling coefficients) of ``address``: model units <-> solver units."""
    v = np.array(value, dtype=float)
    if not degrees(model):
        return v
    flat = v.reshape(-1)
    coef = _coef_scale(model, address, flat.size)
    if coef is not None:
        return (flat * coef if to_solver else flat / coef).reshape(v.shape)
    mask = _angle_mask(model, address, flat.size, engine)
    flat[mask] = np.radians(flat[mask]) if to_solver else np.degrees(flat[mask])
    return flat.reshape(v.shape)


def to_solver_units(model: Model, address: str, value: object, engine: HasUnits | None = None) -> np.ndarray:
    """A value for ``address`` given in the model's units -> solver units (radians).

    ``J01.q = [45]`` on a degree model -> ``[0.785...]``; lengths, positions and rotation
    matrices are returned unchanged (as float arrays)."""
    return _convert(model, address, value, engine, True)


def from_solver_units(model: Model, address: str, value: object, engine: HasUnits | None = None) -> np.ndarray:
    """The inverse of :func:`to_solver_units`: solver units (radians) -> the model's units."""
    return _convert(model, address, value, engine, False)


def changes_to_internal(
    model: Model, changes: Mapping[str, object], engine: HasUnits | None = None
) -> dict[str, np.ndarray]:
    """``{address: value}`` in the model's units -> solver units (see :func:`to_solver_units`;
    ``engine``: one compiled from the model's mechanism, to skip compiling here)."""
    return {a: to_solver_units(model, a, v, engine) for a, v in changes.items()}


def changes_to_model_units(
    model: Model, changes: Mapping[str, object], engine: HasUnits | None = None
) -> dict[str, np.ndarray]:
    """``{address: value}`` in solver units -> the model's units."""
    return {a: from_solver_units(model, a, v, engine) for a, v in changes.items()}


def address_unit(model: Model, name: str, engine: HasUnits | None = None) -> str:
    """The unit, in the model's units, of an address or a layout column label: ``J01.q`` ->
    ``deg`` (a revolute in a degree model), ``J03.q`` -> ``m`` (a slide), ``J12.s_j[0]``,
    ``J12.length``, ``point:...``, ``hardpoint:...``, ``distance:...``, ``body:B[x]`` -> the
    length unit, ``body:B[roll]`` -> the angle unit, ``J.C_i`` -> ``""`` (a rotation matrix),
    Euler parameters -> ``""``; anything else ``""`` (metric names:
    :func:`kinprop.analysis.units.unit_of`)."""
    length, angle = model.units.get("length", "m"), model.units.get("angle", "rad")
    if name.startswith(("point:", "hardpoint:", "distance:")):
        return length
    if name.startswith("body:"):  # a pose component (kinprop.analysis.outputs)
        return angle if name.endswith(BODY_ANGLES) else length if name.endswith("]") else ""
    try:
        addr = parse_address(name)
    except Exception:
        return ""
    if addr.field in ("s_i", "s_j", "length"):
        return length
    if addr.field in ("C_i", "C_j"):
        return ""
    if addr.field == "coef":
        return _coef_unit(model, addr.joint, addr.index, engine)
    if addr.field == "q" and addr.joint in model.mechanism.joint_names:
        table = _table(model, engine)
        angles, euler = set(table.angles[addr.joint]), set(table.euler[addr.joint])
        k = addr.index
        if k is None:
            n = table.n_coordinates[addr.joint]
            kinds = [angle if i in angles else ("" if i in euler else length) for i in range(n)]
            return kinds[0] if len(set(kinds)) == 1 else ",".join(kinds)
        return angle if k in angles else ("" if k in euler else length)
    return ""


def _coef_unit(model: Model, coupling: str, k: int | None, engine: HasUnits | None = None) -> str:
    """``[q_a] / [q_b]^k`` of a coupling coefficient ``c_k`` (``""`` for ``c1`` between like
    units; ``deg/deg^k`` for the whole ``coef`` without an index)."""
    c = next((c for c in model.mechanism.couplings if c.name == coupling), None)
    if c is None:
        return ""
    ua, ub = address_unit(model, f"{c.joint_a}.q", engine), address_unit(model, f"{c.joint_b}.q", engine)
    if k is None:
        return f"{ua}/{ub}^k"
    if k == 0:
        return ua
    if k == 1:
        return "" if ua == ub else f"{ua}/{ub}"
    return f"{ua}/{ub}^{k}"


def address_scale(model: Model, name: str, engine: HasUnits | None = None) -> float:
    """Factor from solver units to the model's units of an address's value or of a derivative
    by it: ``180/pi`` for a joint angle or a ``C`` column (per radian of body-frame rotation)
    in a degree model, else 1."""
    if not degrees(model) or name.startswith(("point:", "hardpoint:", "distance:", "element:")):
        return 1.0
    if name.startswith("body:"):
        return 180.0 / math.pi if name.endswith(BODY_ANGLES) else 1.0
    try:
        addr = parse_address(name)
    except Exception:
        return 1.0
    if addr.field in ("C_i", "C_j"):
        return 1.0 / RADIANS_PER["deg"]
    if addr.field == "coef":  # model value = solver value / (f_a / f_b^k)
        scale = _coef_scale(model, name, 1)
        return 1.0 if scale is None or addr.index is None else float(1.0 / scale[0])
    return 1.0 / RADIANS_PER["deg"] if address_unit(model, name, engine) == "deg" else 1.0


#: joint-value names (:mod:`kinprop.propagation.poses`) that are angles (``rotation_vector``: an
#: angle times a unit axis)
ANGLE_VALUES = ("angle", "angle_1", "angle_2", "rotation_vector")


def joint_values_to_model_units(model: Model, values: Mapping[str, Mapping[str, object]]) -> dict[str, dict]:
    """``{JOINT: {name: value}}`` joint values (radians) -> the model's angle unit; distances and
    translations are in the length unit either way, Euler parameters have no unit."""
    k = 1.0 / RADIANS_PER["deg"] if degrees(model) else 1.0
    out: dict[str, dict] = {}
    for j, vals in values.items():
        out[j] = {
            n: (float(v) * k if np.ndim(v) == 0 else np.asarray(v, dtype=float) * k) if n in ANGLE_VALUES else v
            for n, v in vals.items()
        }
    return out


def check_units(units: str) -> bool:
    """``True`` for ``"model"`` (values in the model's declared units), ``False`` for
    ``"solver"`` (the model's length unit and radians); anything else is a ValueError."""
    if units not in ("model", "solver"):
        raise ValueError(f"units={units!r}: expected 'model' (the model's declared units) or 'solver' (radians)")
    return units == "model"


__all__ = [
    "ANGLE_VALUES",
    "METRES_PER",
    "RADIANS_PER",
    "UnitTable",
    "address_scale",
    "address_unit",
    "angle_indices",
    "changes_to_internal",
    "changes_to_model_units",
    "check_units",
    "coef_factors",
    "degrees",
    "from_solver_units",
    "joint_values_to_model_units",
    "radians_per_angle",
    "to_solver_units",
    "tree_coordinates",
]
