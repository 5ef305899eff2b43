"""Drives in the designer's terms: wheel travel and body roll, and outputs at a drive position.

A designer drives a suspension by wheel travel in millimetres, not by an arm angle. Here a
drive is a joint of its own, added to the model, whose coordinate *is* the quantity, tied to
the mechanism by one constraint row each, and solved by the engine like any other joint
(:meth:`kinprop.Engine.propagate`, :meth:`~kinprop.Engine.solve_batch`,
:meth:`~kinprop.Engine.solve_sequence`):

* ``travel:WHEEL`` — the **wheel travel** (length, positive up): a body on a translational
  joint ``WHEEL_travel`` along the global z axis, and a dot-2 row (eq. 8) holding the wheel
  centre on its horizontal plane through ``wheel_centre_ref``. The coordinate equals
  ``metric:WHEEL.wheel_centre_dz`` exactly, so ``STEPS`` equal steps of the drive are equal
  millimetres of travel. ``travel`` alone is every wheel's travel (one wheel: that wheel; an
  axle: both together, heave).
* ``roll`` — the **body roll angle** of an axle of two wheels (angle, ISO 8855: positive about
  +x, the left side up, so the left wheel droops): a body on a revolute joint ``roll`` about
  the axis along x through the midpoint of the two ``wheel_centre_ref`` points, and one dot-2
  row per wheel holding its centre on the plane of that body through its reference. The road
  plane rolls under the fixed chassis: the wheel centres keep their heights above it (travel
  ``-(y - y_0) tan(phi)`` of a wheel centre at ``y``).

* ``steer:WHEEL`` — the **road-wheel steer angle** (angle, positive to the left): a body on a
  revolute joint ``WHEEL_steer`` about the vertical through the wheel centre, and one dot-1 row
  (eq. 1) holding the spin axis across that body's x axis; it releases the input that steers
  the wheel (the first declared input, not its travel input, that turns it about z: a rack).

Driving one releases the declared input that moved the wheel (the first input in ``inputs:``
whose motion moves the wheel centre; a rack declared after the arms stays held). Drive joints
are added only when a drive or a condition names them; every other joint, body, address and
output keeps its name.

Outputs at a drive position and over a range (the grammar of ``--target`` without ``=VALUE``):

* ``OUTPUT@CONDITION[&CONDITION...]``: the output in the configuration the conditions define,
  e.g. ``camber@travel=50`` (50 above the reference), ``toe@roll=2deg``,
  ``toe@travel:upright_L=30&RACK.q=10``; a condition is a drive (``travel``, ``travel:WHEEL``,
  ``metric:WHEEL.wheel_centre_dz``, ``roll``) or a joint coordinate held at a value (``J.q``,
  ``J.q[k]``);
* ``slope:OUTPUT@COND=A..B``: ``(OUTPUT(B) - OUTPUT(A)) / (B - A)`` (bump steer
  ``slope:toe@travel=-50..50``), output unit per condition unit.

Each configuration is one engine solve from the model's state (a batch of them for a study's
variants or a sweep's steps); values are in solver units (:func:`kinprop.analysis.units.
derivative_scale` takes them to the model's units, as for every output).
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from kinprop.analysis.context import OutputContext, find_point, locate_point
from kinprop.analysis.metrics import wheel_bodies
from kinprop.analysis.outputs import evaluate_outputs, expand_outputs
from kinprop.analysis.sensitivity import OnBase, output_sensitivity_matrix
from kinprop.analysis.statics import LOAD_PREFIXES
from kinprop.analysis.units import derivative_scale
from kinprop.engine import Engine, State
from kinprop.engine import compile as compile_engine
from kinprop.engine.units import METRES_PER, RADIANS_PER
from kinprop.errors import AddressError, ConvergenceError
from kinprop.model import Design, Model
from kinprop.model.design import parse_address
from kinprop.model.mechanism import Body, Joint, Mechanism
from kinprop.propagation.element_points import element_ends, with_element_ends
from kinprop.spatial import Array

TRAVEL, ROLL, STEER = "travel", "roll", "steer"
_NUMBER = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([A-Za-z/]*)\s*$")
#: joint frame whose z'' is the body's x axis (a steer body's forward direction)
_ALONG_X = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
#: joint frame of a revolute turning about -x (z'' = -x): positive roll lifts the left (+y) side
_ABOUT_MINUS_X = np.array([[0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


def is_driven(name: str) -> bool:
    """Whether an output name carries a drive position (``@``) or is a slope (``slope:``).

    A load output's ``@CASE`` (``force:TR@braking_1g``) names its load case, not a drive
    position: it is driven only when its suffix is a condition (``NAME=VALUE``)."""
    if name.startswith("slope:"):
        return True
    head, at, tail = name.partition("@")
    if at and head.startswith(LOAD_PREFIXES) and "=" not in tail:
        return False
    return bool(at)


def is_drive(name: str) -> bool:
    """Whether ``name`` is a drive of this module (``travel``, ``travel:WHEEL``, ``roll``,
    ``steer:WHEEL``)."""
    return name in (TRAVEL, ROLL) or name.startswith((f"{TRAVEL}:", f"{STEER}:"))


# --- the drive joints -----------------------------------------------------------------------


@dataclass(frozen=True)
class Driven:
    """A model with drive joints (module docstring): ``model`` is the augmented model (the
    drive joints are declared inputs: held unless driven); ``addresses[drive]`` the coordinates
    a drive sets; ``released[drive]`` the inputs it frees."""

    model: Model
    base: Model
    addresses: Mapping[str, tuple[str, ...]]
    released: Mapping[str, tuple[str, ...]]
    angle: Mapping[str, bool]
    joints: frozenset[str] = field(default_factory=frozenset)
    #: the augmented model's engine (compiled once, by :func:`augment`)
    engine: Engine | None = None
    #: the model's own engine when one was given or needed (a roll drive), else None: then the
    #: augmented engine evaluates the model's outputs too (:meth:`follower`)
    base_engine: Engine | None = None

    def follower(self) -> Model:
        """The augmented model with the model's own inputs only: its drive joints follow the
        wheels, so its motions, first-order metrics and statics are the model's (a travel or
        steer joint adds one coordinate and one row, and carries no load). Not for a roll joint,
        which ties the wheels."""
        mech = self.model.mechanism
        return replace(self.model, mechanism=replace(mech, inputs=self.base.mechanism.inputs))

    def free(self, free: Sequence[str], drives: Sequence[str]) -> tuple[str, ...]:
        """The free set of a solve driving ``drives``: ``free``, the inputs they release and the
        drive joints not driven there (they follow the wheels)."""
        driven = {a for d in drives for a in self.addresses[d]}
        loose = [a for addrs in self.addresses.values() for a in addrs if a not in driven]
        return tuple(dict.fromkeys([*free, *(r for d in drives for r in self.released[d]), *loose]))

    def base_of(self, engine: Engine, state: State) -> Model:
        """The model without the drive joints at an augmented ``state`` (``engine``: the
        augmented model's): outputs are evaluated on it, so that first-order metrics move the
        suspension by its own inputs."""
        design, coords = engine.unpack(state)
        drop = self.joints
        return self.base.with_state(
            Design({k: v for k, v in design.items() if k.split(".")[0] not in drop}),
            {k: v for k, v in coords.items() if k not in drop},
        )

    def state(self, engine: Engine, model: Model) -> State:
        """The augmented engine's state of ``model`` (a model of the base mechanism: a study's
        variant, a sweep's step): its design and coordinates with the drive joints placed where
        its wheels are."""
        return engine.state_of(_with_drive_state(self, model))


def wheel_for(model: Model, name: str) -> list[str]:
    """The wheels ``travel`` / ``travel:WHEEL`` names (``where`` in messages)."""
    wheels = wheel_bodies(model)
    if name == TRAVEL:
        if not wheels:
            raise AddressError("'travel' needs a wheel body (named points wheel_centre and spin_axis)")
        return wheels
    wheel = name.partition(":")[2]
    if wheel not in wheels:
        raise AddressError(f"{name!r}: no wheel body {wheel!r}; wheels: {', '.join(wheels) or 'none'}")
    return [wheel]


def _reference(model: Model, wheel: str) -> Array:
    """The global ``wheel_centre_ref`` of ``wheel`` (a fixed body's point: no kinematics)."""
    found = find_point(model, wheel, "wheel_centre_ref", on_wheel=False)
    if found is None:
        raise AddressError(f"wheel travel of {wheel!r} needs its reference: a fixed-body point "
                           f"{wheel}.wheel_centre_ref (or wheel_centre_ref with one wheel)")  # fmt: skip
    source = locate_point(model, *found)
    if source[0] == "joint":  # a joint's point on the fixed body: where that joint's frame is
        return OutputContext.of(model).body_point(*found)
    b = model.mechanism.body(found[0])
    return b.r + b.A @ np.asarray(source[2], dtype=float)


def _fixed(model: Model) -> Body:
    for b in model.mechanism.bodies:
        if b.fixed:
            return b
    raise AddressError("a drive needs a fixed body (the chassis)")


def travel_input(model: Model, wheel: str, engine: Engine | None = None) -> str:
    """The declared input that moves ``wheel`` (the first in ``inputs:`` whose motion, the
    others held, moves the wheel centre): the one a travel or roll drive releases."""
    eng = engine if engine is not None else compile_engine(model)
    st = eng.state_of(model)
    present = drive_joints(model)
    inputs = [a if "." in a else f"{a}.q" for a in model.mechanism.inputs if a.split(".")[0] not in present]
    ctx = OutputContext.of(model, engine=eng)
    centre = ctx.body_point(wheel, "wheel_centre")
    body = model.mechanism.body_names.index(wheel)
    scale = max(1.0, eng.length_scale or 1.0)
    for a in inputs:
        ms = eng.motion(st, {b: float(b == a) for b in inputs})
        if ms.ok and abs(ms.point_velocity(body, centre)[2]) > 1e-9 * scale:
            return a
    raise AddressError(
        f"wheel travel of {wheel!r}: no declared input moves it; declare the arm's joint first in 'inputs:'"
    )


def steer_input(model: Model, wheel: str, engine: Engine | None = None) -> str:
    """The declared input that steers ``wheel`` (the first in ``inputs:``, other than its travel
    input, whose motion turns the wheel about the vertical): the one a steer drive releases."""
    eng = engine if engine is not None else compile_engine(model)
    st = eng.state_of(model)
    present = drive_joints(model)
    inputs = [a if "." in a else f"{a}.q" for a in model.mechanism.inputs if a.split(".")[0] not in present]
    body = model.mechanism.body_names.index(wheel)
    try:
        bump: str | None = travel_input(model, wheel, eng)
    except AddressError:  # a steering linkage without wheel travel
        bump = None
    for a in inputs:
        if a == bump:
            continue
        ms = eng.motion(st, {b: float(b == a) for b in inputs})
        if ms.ok and abs(ms.V[body, 5]) > 1e-9:
            return a
    raise AddressError(f"road-wheel steer of {wheel!r}: no declared input steers it (a rack in 'inputs:')")


def drive_joints(model: Model) -> set[str]:
    """The drive joints a model already has (an augmented model's: ``WHEEL_travel``, ``roll``)."""
    names = set(model.mechanism.joint_names)
    out = {j for j in names if j.endswith(("_travel", "_steer")) and f"{j}_hold" in names}
    return out | ({ROLL} if ROLL in names and "roll_plane" in model.mechanism.body_names else set())


def augment(model: Model, drives: Sequence[str], engine: Engine | None = None) -> Driven:
    """``model`` with the drive joints of ``drives`` (``travel:WHEEL``, ``roll``; module
    docstring), placed at the model's state, and its engine (:attr:`Driven.engine`, compiled
    here once). ``engine``: the model's, when the caller has it. Without it the augmented engine
    serves for the model's own kinematics too (the drive joints add bodies, never move the
    model's), and for the inputs a drive releases: a travel or steer joint that is not driven
    follows its wheel (one coordinate, one row), so the model's motions are unchanged; a roll
    joint ties two wheels, so a roll drive compiles the model for those."""
    mech = model.mechanism
    ground = _fixed(model)
    Ag, rg = ground.A, ground.r
    bodies, joints, inputs = list(mech.bodies), list(mech.joints), list(mech.inputs)
    addresses: dict[str, tuple[str, ...]] = {}
    released: dict[str, tuple[tuple[str, str], ...]] = {}  # (kind, wheel): resolved once the engine exists
    angle: dict[str, bool] = {}
    added: set[str] = set()
    taken = set(mech.body_names) | set(mech.joint_names)
    present = drive_joints(model)
    holds: list[tuple[str, str, Array]] = []  # (hold joint, wheel, point on the plane body)
    steers: list[tuple[str, str, str]] = []  # (steer joint, its hold, wheel)
    fixed: dict[str, Array] = {}  # design of the drive joints that needs no kinematics

    def fresh(name: str) -> str:
        if name in taken:
            raise AddressError(f"the model already has a body or joint named {name!r} (a drive's name)")
        taken.add(name)
        return name

    def hold(name: str, body: str, wheel: str, on_body: Array) -> None:
        """The dot-2 row: ``wheel``'s centre on the plane of ``body`` through ``on_body``, normal z."""
        joints.append(Joint(fresh(name), "dot-2", body, wheel, frozenset({"s_i", "s_j", "C_i"}), cut=True))
        holds.append((name, wheel, on_body))
        added.add(name)

    for d in dict.fromkeys(drives):
        if d == ROLL:
            wheels = wheel_bodies(model)
            addresses[d], released[d], angle[d] = (f"{ROLL}.q",), tuple(("travel", w) for w in wheels), True
            if ROLL in present:
                continue
            if len(wheels) != 2:
                raise AddressError(f"'roll' drives an axle of two wheels; this model has {len(wheels)}")
            refs = [_reference(model, w) for w in wheels]
            centre = 0.5 * (refs[0] + refs[1])
            body, joint = fresh("roll_plane"), fresh(ROLL)
            bodies.append(Body(body))
            joints.append(Joint(joint, "revolute", ground.name, body, frozenset({"s_i", "C_i", "s_j", "C_j"}), False))
            fixed |= {f"{joint}.s_i": Ag.T @ (centre - rg), f"{joint}.C_i": Ag.T @ _ABOUT_MINUS_X,
                      f"{joint}.s_j": centre, f"{joint}.C_j": _ABOUT_MINUS_X}  # fmt: skip
            for w, ref in zip(wheels, refs, strict=True):
                hold(f"{w}_roll_hold", body, w, ref)
            inputs.append(joint)
            added.add(joint)
            continue
        if d.startswith(f"{STEER}:"):
            (w,) = wheel_for(model, d)
            addresses[d], released[d], angle[d] = (f"{w}_steer.q",), (("steer", w),), True
            if f"{w}_steer" in present:
                continue
            body = joint = fresh(f"{w}_steer")
            bodies.append(Body(body))
            joints.append(Joint(joint, "revolute", ground.name, body, frozenset({"s_i", "C_i", "s_j"}), False))
            hold_name = fresh(f"{w}_steer_hold")  # the spin axis across the steer body's x axis (eq. 1)
            joints.append(Joint(hold_name, "dot-1", body, w, frozenset({"C_i", "C_j"}), cut=True))
            steers.append((joint, hold_name, w))
            inputs.append(joint)
            added |= {joint, hold_name}
            continue
        for w in wheel_for(model, d):
            key = f"{TRAVEL}:{w}"
            if key in addresses:
                continue
            addresses[key], released[key], angle[key] = (f"{w}_travel.q",), (("travel", w),), False
            if f"{w}_travel" in present:
                continue
            ref = _reference(model, w)
            body = joint = fresh(f"{w}_travel")
            bodies.append(Body(body))
            joints.append(Joint(joint, "translational", ground.name, body, frozenset({"s_i", "C_i"}), False))
            fixed |= {f"{joint}.s_i": Ag.T @ (np.zeros(3) - rg), f"{joint}.C_i": Ag.T}
            hold(f"{w}_travel_hold", body, w, ref)
            inputs.append(joint)
            added.add(joint)
        if d == TRAVEL:
            ws = wheel_for(model, d)
            addresses[d] = tuple(a for w in ws for a in addresses[f"{TRAVEL}:{w}"])
            released[d] = tuple(r for w in ws for r in released[f"{TRAVEL}:{w}"])
            angle[d] = False
    mechanism = Mechanism(tuple(bodies), tuple(joints), mech.name, tuple(inputs), mech.couplings, mech.edits)
    base_design = {k: np.array(v) for k, v in model.design.items()}

    def with_design(design: Mapping[str, Array]) -> Model:
        return replace(model, mechanism=mechanism, design=Design(base_design | dict(design)))

    placed = with_design(fixed)  # the model's bodies placed; the drive joints' own frames follow
    aug_engine = compile_engine(placed)
    ctx = OutputContext.of(model, engine=engine) if engine is not None else OutputContext.of(placed, engine=aug_engine)
    design = dict(fixed)
    for name, wheel, on_body in holds:
        centre = ctx.body_point(wheel, "wheel_centre")
        design[f"{name}.s_i"] = on_body
        design[f"{name}.s_j"] = ctx.kin.A[wheel].T @ (centre - ctx.kin.r[wheel])
        design[f"{name}.C_i"] = np.eye(3)
    for joint, hold_name, w in steers:
        at = ctx.body_point(w, "wheel_centre")
        axis = ctx.body_point(w, "spin_axis") - at
        design |= {f"{joint}.s_i": Ag.T @ (at - rg), f"{joint}.C_i": Ag.T, f"{joint}.s_j": at}
        design |= {f"{hold_name}.C_i": _ALONG_X, f"{hold_name}.C_j": _frame_along(ctx.kin.A[w].T @ axis)}
    drv = Driven(with_design(design), model, addresses, {}, angle, frozenset(added), aug_engine)
    aug = _with_drive_state(drv, model)
    aug_engine = aug_engine.rebased(aug)
    if engine is None and any(k == ROLL for k in released):
        engine = compile_engine(model)  # a roll joint ties the wheels: the inputs are found on the model
    on, eng = (model, engine) if engine is not None else (aug, aug_engine)
    inputs_of = {"travel": travel_input, "steer": steer_input}
    found = {d: tuple(inputs_of[kind](on, w, eng) for kind, w in rel) for d, rel in released.items()}
    return Driven(aug, model, addresses, found, angle, frozenset(added), aug_engine, engine)


def base_view(base: Engine, engine: Engine) -> tuple[Callable[[State], State], Array]:
    """``(view, columns)`` between an augmented model's ``engine`` and its base model's
    ``base``: ``view(state)`` the base engine's state of an augmented state (the drive joints
    dropped, nothing solved), ``columns[c]`` the augmented column of base column ``c`` (the same
    variable by key). A base output's derivative over augmented columns is its derivative over
    ``columns``, zero along the drive joints' own."""
    joints = np.array([engine.joint_index[j.name] for j in base.mechanism.joints], np.int64)
    nj = len(engine.mechanism.joints)
    q = np.zeros(base.n_coordinates, np.int64)
    columns = np.zeros(base.n_columns, np.int64)
    for v in base.layout.variables:
        w = engine.layout[v.key]
        columns[v.columns] = np.arange(w.start, w.start + v.size)
        if v.group == "q":
            q[v.columns] = columns[v.columns]
    lengths = np.concatenate([joints, np.arange(nj, engine.default_state().L.size)])

    def view(st: State) -> State:
        return State(st.Q[..., q], st.S[..., joints, :, :], st.C[..., joints, :, :, :], st.L[..., lengths])

    return view, columns


def _frame_along(z: Array) -> Array:
    """A rotation whose third column (z'') is along ``z``."""
    z = np.asarray(z, float) / np.linalg.norm(z)
    x = np.cross([0.0, 0.0, 1.0] if abs(z[2]) < 0.9 else [1.0, 0.0, 0.0], z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def steer_angle(axis: Array) -> float:
    """The road-wheel steer angle (rad, positive to the left, ISO 8855) of a wheel whose
    outboard spin axis is ``axis``: the angle of its heading in the ground plane."""
    ax, ay = float(axis[0]), float(axis[1])
    return math.atan2(-ax, ay) if ay >= 0 else math.atan2(ax, -ay)


def _with_drive_state(drv: Driven, model: Model) -> Model:
    """The augmented model at ``model``'s design and coordinates: the drive coordinates where
    the wheels are (a travel: the wheel centre's height over its reference; roll: 0 when the
    wheels are at opposite travels, else their mean angle). The model's kinematics come from
    the augmented engine (the drive joints move none of its bodies)."""
    design = {k: np.array(v) for k, v in drv.model.design.items()}
    design |= {k: np.array(v) for k, v in model.design.items()}
    merged = drv.model.with_state(Design(design), dict(model.coordinates))
    ctx = OutputContext.of(merged, engine=drv.engine)
    coords = dict(model.coordinates)
    for d, addrs in drv.addresses.items():
        if d == ROLL:  # opposite travels dz over the track: -tan(roll)
            (dz_l, y_l), (dz_r, y_r) = (
                (ctx.body_point(w, "wheel_centre")[2] - _reference(model, w)[2], _reference(model, w)[1])
                for w in wheel_bodies(model)
            )
            coords[addrs[0].split(".")[0]] = np.array([-math.atan2(dz_l - dz_r, y_l - y_r)])
        elif d.startswith(f"{STEER}:"):
            w = d.partition(":")[2]
            axis = ctx.body_point(w, "spin_axis") - ctx.body_point(w, "wheel_centre")
            coords[addrs[0].split(".")[0]] = np.array([steer_angle(axis)])
        elif d != TRAVEL:
            w = d[len(TRAVEL) + 1 :]
            dz = ctx.body_point(w, "wheel_centre")[2] - _reference(model, w)[2]
            coords[addrs[0].split(".")[0]] = np.array([dz])
    return drv.model.with_state(Design(design), coords)


# --- outputs at a drive position ------------------------------------------------------------


@dataclass(frozen=True)
class DrivenOutput:
    """A parsed driven output: the plain ``output``, its configurations (one, or two for a
    slope), each ``((drive or coordinate address, solver value), ...)``, and a slope's span
    (solver units of the condition)."""

    name: str
    output: str
    configs: tuple[tuple[tuple[str, float], ...], ...]
    span: float | None = None

    @property
    def drives(self) -> list[str]:
        return list(dict.fromkeys(k for cfg in self.configs for k, _ in cfg if is_drive(k)))


def _number(text: str, where: str) -> tuple[float, str]:
    """A number with an optional unit (``-1.5deg``, ``50mm``, ``0``): ``(value, unit)``."""
    m = _NUMBER.match(text)
    if not m:
        raise AddressError(f"{where}: {text!r} is not a number with an optional unit (e.g. -1.5deg, 50mm)")
    return float(m[1]), m[2]


def drive_condition(model: Model, name: str) -> str | None:
    """The drive a condition's name means (``travel``, ``travel:WHEEL``, ``roll``,
    ``steer:WHEEL``; the wheel-centre height ``metric:WHEEL.wheel_centre_dz`` is that wheel's
    travel), validated against the model's wheels, or None when it names no drive."""
    name = name.strip()
    wheels = wheel_bodies(model)
    if name in ("wheel_centre_dz", "metric:wheel_centre_dz", "wheel_travel") and len(wheels) == 1:
        name = TRAVEL
    if name.startswith("metric:") and name.endswith((".wheel_centre_dz", ".wheel_travel")):
        name = f"{TRAVEL}:{name[len('metric:') :].rsplit('.', 1)[0]}"
    if not is_drive(name):
        return None
    if name != ROLL:
        wheel_for(model, name)
    return name


def _condition_key(model: Model, name: str, where: str) -> tuple[str, str]:
    """``(key, kind)`` of a condition's name: a drive (``travel:W``, ``roll``) or a coordinate
    address; kind ``length`` or ``angle``."""
    name = name.strip()
    drive = drive_condition(model, name)
    if drive is not None:
        return drive, "length" if drive.startswith(TRAVEL) else "angle"
    try:
        addr = parse_address(name if "." in name else f"{name}.q")
    except Exception:
        addr = None
    if addr is None or addr.field != "q" or addr.joint not in model.mechanism.joint_names:
        raise AddressError(f"{where}: condition {name!r}: expected travel, travel:WHEEL, roll, steer:WHEEL or a "
                           "joint coordinate JOINT.q[k]")  # fmt: skip
    angles = model.mechanism.joint(addr.joint).jtype.angle_indices
    return str(addr), "angle" if (addr.index or 0) in angles else "length"


def condition_value(model: Model, kind: str, text: str, where: str) -> float:
    """A condition value (model units unless a unit is written) in solver units."""
    v, unit = _number(text, where)
    if kind == "angle":
        if unit and unit not in RADIANS_PER:
            raise AddressError(f"{where}: unit {unit!r} is not an angle unit (deg, rad)")
        return v * RADIANS_PER[unit or model.units.get("angle", "rad")]
    length = model.units.get("length", "m")
    if not unit:
        return v
    if unit not in METRES_PER or length not in METRES_PER:
        raise AddressError(f"{where}: unit {unit!r} does not fit a length (model length unit {length})")
    return v * METRES_PER[unit] / METRES_PER[length]


def parse_driven(model: Model, name: str, engine: Engine | None = None) -> DrivenOutput:
    """Parse ``OUTPUT@COND[&COND]`` / ``slope:OUTPUT@COND=A..B`` (module docstring)."""
    where = f"output {name!r}"
    body, at, conds = name.strip().partition("@")
    slope = body.startswith("slope:")
    out = body[len("slope:") :] if slope else body
    if not at or not conds.strip():
        raise AddressError(f"{where}: expected OUTPUT@CONDITION (camber@travel=50) or slope:OUTPUT@COND=A..B")
    if "=" in out:
        raise AddressError(f"{where}: expected OUTPUT@CONDITION or slope:OUTPUT@COND=A..B, no =VALUE")
    names = expand_outputs(model, [out.strip()], engine)
    if names != [out.strip()]:
        raise AddressError(f"{where}: {out!r} is not a scalar output; name a component, e.g. {names[0]}@{conds}")
    parts = [c for c in conds.split("&") if c.strip()]
    if any("=" not in c for c in parts):
        raise AddressError(f"{where}: a condition is NAME=VALUE (travel=50, roll=2deg, RACK.q=10)")
    if slope:
        if len(parts) != 1 or ".." not in parts[0]:
            raise AddressError(f"{where}: a slope needs one condition range, e.g. slope:toe@travel=-50..50")
        key, _, rng = parts[0].partition("=")
        k, kind = _condition_key(model, key, where)
        a_text, _, b_text = rng.partition("..")
        if _number(b_text, where)[1] and not _number(a_text, where)[1]:
            a_text += _number(b_text, where)[1]  # "-50..50mm": the unit once, for both ends
        a, b = condition_value(model, kind, a_text, where), condition_value(model, kind, b_text, where)
        if a == b:
            raise AddressError(f"{where}: the slope's range is empty")
        return DrivenOutput(name, out.strip(), (((k, a),), ((k, b),)), b - a)
    cfg = []
    for c in parts:
        key, _, val = c.partition("=")
        if ".." in val:
            raise AddressError(f"{where}: a range A..B is a slope's: slope:{out.strip()}@{c}")
        k, kind = _condition_key(model, key, where)
        cfg.append((k, condition_value(model, kind, val, where)))
    if len({k for k, _ in cfg}) != len(cfg):
        raise AddressError(f"{where}: a condition is given twice")
    return DrivenOutput(name, out.strip(), (tuple(sorted(cfg)),))


def expand_driven(model: Model, names: Sequence[str], engine: Engine | None = None) -> list[str]:
    """``names`` with vector outputs expanded (``point:W.wheel_centre@travel=50`` into its
    ``[x]``, ``[y]``, ``[z]``), each driven name validated."""
    out: list[str] = []
    for n in names:
        if not is_driven(n):
            out += expand_outputs(model, [n], engine)
            continue
        body, _, conds = n.strip().partition("@")
        pre = "slope:" if body.startswith("slope:") else ""
        for e in expand_outputs(model, [body[len(pre) :]], engine):
            parse_driven(model, f"{pre}{e}@{conds}", engine)
            out.append(f"{pre}{e}@{conds}")
    return out


class _Positions:
    """Driven outputs of one family of drives (travel and coordinates, or roll), solved by one
    augmented engine (compiled once)."""

    def __init__(self, model: Model, names: Sequence[str], *, free: Sequence[str] = ("q",), tol: float = 1e-10,
                 max_iter: int = 50, engine: Engine | None = None) -> None:  # fmt: skip
        self.specs = [parse_driven(model, n, engine) for n in names]
        drives = list(dict.fromkeys(d for s in self.specs for d in s.drives))
        if ROLL in drives and any(d.startswith(TRAVEL) for d in drives):
            raise AddressError("a roll and a travel condition in one output are not supported")
        self.base_engine = engine if engine is not None else compile_engine(model)
        self.driven = augment(model, drives, self.base_engine)
        self.engine = self.driven.engine
        self.free, self.tol, self.max_iter = tuple(free), tol, max_iter
        self.configs = list(dict.fromkeys(cfg for s in self.specs for cfg in s.configs))

    def states(self, models: Sequence[Model]) -> tuple[list[State], list[Array]]:
        """Per configuration: the solved augmented states (batched over ``models``) and which converged."""
        eng, drv = self.engine, self.driven
        starts = eng.stack([drv.state(eng, m) for m in models])
        out_states, ok = [], []
        for cfg in self.configs:
            targets = starts.copy()
            changed: list[str] = []
            drives = [k for k, _ in cfg if is_drive(k)]
            for k, v in cfg:
                for a in drv.addresses[k] if is_drive(k) else (k,):
                    for i in range(len(models)):
                        eng.set(targets[i], a, v)
                    changed.append(parse_address(a).key)
            cols = eng.columns(drv.free(self.free, drives), changed)
            res = eng.solve_batch(targets, cols, start=starts, tol=self.tol, max_iter=self.max_iter)
            out_states.append(res.state)
            ok.append(np.asarray(res.converged, bool))
        return out_states, ok

    def values(self, models: Sequence[Model]) -> dict[str, Array]:
        """``{name: values}`` over ``models`` in solver units (NaN where a configuration failed)."""
        n = len(models)
        states, ok = self.states(models)
        plain: dict[tuple, dict[str, Array]] = {}
        for c, cfg in enumerate(self.configs):
            names = list(dict.fromkeys(s.output for s in self.specs if cfg in s.configs))
            vals = {o: np.full(n, np.nan) for o in names}
            for i in np.flatnonzero(ok[c]):
                m = self.driven.base_of(self.engine, states[c][i])
                if models[i].elements != m.elements:  # a study variant's own element points
                    m = with_element_ends(m, element_ends(models[i]))
                got = evaluate_outputs(m, names, units="solver", engine=self.base_engine)
                for o in names:
                    vals[o][i] = got[o]
            plain[cfg] = vals
        out: dict[str, Array] = {}
        for s in self.specs:
            if s.span is None:
                out[s.name] = plain[s.configs[0]][s.output]
            else:
                out[s.name] = (plain[s.configs[1]][s.output] - plain[s.configs[0]][s.output]) / s.span
        return out


class DrivenOutputs:
    """The values of driven outputs (module docstring) of models of one mechanism:
    ``values(models)`` for a study's variants or a sweep's steps, each drive position one
    batched engine solve. Roll positions and travel positions are solved by two augmented
    engines (a roll joint and a wheel's travel joint would both set the wheel's height)."""

    def __init__(self, model: Model, names: Sequence[str], *, free: Sequence[str] = ("q",), tol: float = 1e-10,
                 max_iter: int = 50, engine: Engine | None = None) -> None:  # fmt: skip
        specs = [parse_driven(model, n, engine) for n in names]
        groups = ([s.name for s in specs if ROLL in s.drives], [s.name for s in specs if ROLL not in s.drives])
        opts = {"free": free, "tol": tol, "max_iter": max_iter, "engine": engine}
        self.parts = [_Positions(model, g, **opts) for g in groups if g]  # type: ignore[arg-type]

    def values(self, models: Sequence[Model]) -> dict[str, Array]:
        """``{name: values}`` over ``models`` in solver units (NaN where a configuration failed)."""
        return {k: v for p in self.parts for k, v in p.values(models).items()}


def driven_sensitivity(
    model: Model,
    of: Sequence[str],
    wrt: Sequence[str],
    free: Sequence[str] = ("q",),
    weights: Mapping[str, float] | None = None,
    *,
    tol: float = 1e-10,
    max_iter: int = 50,
) -> tuple[Array, list[str], list[str]]:
    """``(D, of, design column labels)``: derivatives of outputs at drive positions (``of``,
    module docstring) with respect to the design addresses ``wrt`` (no ``hardpoint:``; see
    :func:`kinprop.propagation.hardpoints.global_columns`), in solver units: at each drive
    position solved from the model's state, the implicit-function tangent with the drive held
    (:func:`kinprop.analysis.sensitivity.output_sensitivity_matrix`), the outputs' derivatives
    along it the base model's (a first-order metric, ``camber_gain@travel=50``, exact: its
    velocity analysis by the suspension's own inputs, as :func:`outputs_at` evaluates it); a
    slope's is the difference of its two ends' over the span."""
    per: dict[tuple, dict[str, Array]] = {}
    columns: list[str] = []
    rows: dict[str, DrivenOutput] = {}
    s_calc: dict[str, int] = {}
    for calc in DrivenOutputs(model, of, free=free, tol=tol, max_iter=max_iter).parts:
        for s in calc.specs:
            rows[s.name] = s
        view, cols = base_view(calc.base_engine, calc.engine)
        held = [k for cfg in calc.configs for k, _ in cfg if not is_drive(k)]
        loose = [k for k in held if k.split(".")[0] not in model.mechanism.inputs]
        if loose:
            raise AddressError(f"sensitivity at a drive position: {loose[0]!r} is not a declared input (held there)")
        states, ok = calc.states([model])
        for c, cfg in enumerate(calc.configs):
            if not ok[c][0]:
                raise ConvergenceError(f"sensitivity at {cfg}: the drive position could not be reached")
            at = calc.engine.model_of(states[c][0], calc.driven.model)
            names = list(dict.fromkeys(s.output for s in calc.specs if cfg in s.configs))
            drives = [k for k, _ in cfg if is_drive(k)]
            loose_free = calc.driven.free(free, drives)
            # the tangent with the drive held (the augmented model's), the outputs the base
            # model's there: a first-order metric moves the suspension by its own inputs
            base = OnBase(calc.driven.base_of(calc.engine, states[c][0]), calc.base_engine, view, cols)
            D, out_rows, columns, _ = output_sensitivity_matrix(
                at, names, wrt, loose_free, weights, engine=calc.engine, units="solver", base=base
            )
            per[(id(calc), cfg)] = dict(zip(out_rows, np.asarray(D), strict=True))
            for s in calc.specs:
                if cfg in s.configs:
                    rows[s.name] = s
                    s_calc[s.name] = id(calc)
    out = np.zeros((len(of), len(columns)))
    for r, name in enumerate(of):
        spec, key = rows[name], s_calc[name]
        end = per[(key, spec.configs[-1])][spec.output]
        out[r] = end if spec.span is None else (end - per[(key, spec.configs[0])][spec.output]) / spec.span
    return out, list(of), columns


def model_at(model: Model, condition: str, *, engine: Engine | None = None, tol: float = 1e-10,
             max_iter: int = 50) -> Model:  # fmt: skip
    """The model at a drive position, ``condition`` as after an output's ``@`` (``travel=50``,
    ``roll=2deg``, ``RACK.q=10``): one engine solve from the model's state; the drive joints
    are not part of the returned model. Raises :class:`ConvergenceError` when it is out of reach."""
    wheels = wheel_bodies(model)
    probe = f"metric:{wheels[0]}.camber@{condition}" if wheels else f"{model.mechanism.joints[0].name}.q@{condition}"
    pos = _Positions(model, [probe], tol=tol, max_iter=max_iter, engine=engine)
    states, ok = pos.states([model])
    if not ok[0][0]:
        raise ConvergenceError(f"{condition!r}: the drive position could not be reached from the model's state")
    return pos.driven.base_of(pos.engine, states[0][0])


def outputs_at(
    model: Model, names: Sequence[str], *, engine: Engine | None = None, tol: float = 1e-10, max_iter: int = 50
) -> dict[str, float]:
    """Values of ``names`` (module docstring; plain names too) for the model's design, in the
    model's units. Raises :class:`ConvergenceError` when a configuration cannot be reached
    (e.g. a travel beyond the mechanism's range)."""
    driven = [n for n in names if is_driven(n)]
    out: dict[str, float] = {}
    if driven:
        calc = DrivenOutputs(model, driven, tol=tol, max_iter=max_iter, engine=engine)
        vals = calc.values([model])
        for n in driven:
            if not np.isfinite(vals[n][0]):
                raise ConvergenceError(f"output {n!r}: its drive position could not be reached from the model's state")
            out[n] = float(vals[n][0]) * derivative_scale(model, n, engine)
    plain = [n for n in names if not is_driven(n)]
    if plain:
        out |= evaluate_outputs(model, plain, engine=engine)
    return {n: out[n] for n in names}


__all__ = ["Driven", "DrivenOutput", "DrivenOutputs", "augment", "base_view", "condition_value", "drive_condition",
           "driven_sensitivity", "expand_driven", "is_drive", "is_driven", "model_at", "outputs_at", "parse_driven",
           "travel_input"]  # fmt: skip
