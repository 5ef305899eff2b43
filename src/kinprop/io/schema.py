"""Schema of kinprop model files (YAML or JSON), validated with pydantic.

Frame style (the paper's, ``style: frames``, the default): bodies with fixed poses; joints
with the body-frame position vectors ``s_i``/``s_j``, joint-frame orientations ``C_i``/``C_j``
and ``length`` where the model defines them, and initial coordinate estimates ``q`` in the
declared angle unit.

Hardpoint style (``style: hardpoints``): global joint points and axes at a reference
(assembled) configuration, from which :mod:`kinprop.io.hardpoints` derives body frames,
s' and C, and the coordinates there (zero unless a joint gives ``q``). Which keys a joint takes depends on its type
(:data:`kinprop.io.hardpoints.KEYS`); the schema accepts them all and the builder checks.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator

Finite = Annotated[float, Field(allow_inf_nan=False)]
Vec3 = Annotated[list[Finite], Field(min_length=3, max_length=3)]
Vec4 = Annotated[list[Finite], Field(min_length=4, max_length=4)]
Mat3 = Annotated[list[Vec3], Field(min_length=3, max_length=3)]
Positive = Annotated[float, Field(gt=0, allow_inf_nan=False)]
#: a named point: coordinates, or a reference to a joint's point (``UBJ``, ``TR.j``;
#: :mod:`kinprop.model.joint_points`)
PointValue = Annotated[Vec3 | str, Field(union_mode="left_to_right")]
#: a wheel body's steering axis by its joints, upper first (``[UBJ, LBJ]``)
Kingpin = Annotated[list[str], Field(min_length=2, max_length=2)]

#: axis conventions a file may declare (all right-handed; kept as declared, never converted)
AXES = {
    "ISO8855": "ISO 8855: x forward, y left, z up",
    "SAE": "SAE J670: x forward, y right, z down",
    "right-handed": "a right-handed x, y, z with no vehicle meaning",
}
AxesName = Literal["ISO8855", "SAE", "right-handed"]


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class Units(Strict):
    length: Literal["m", "mm"]
    angle: Literal["deg", "rad"]
    axes: AxesName | None = None
    #: the force unit of element stiffness / damping and the wheel rate (a label, e.g. N, kN, lbf)
    force: Annotated[str, Field(min_length=1, max_length=16)] | None = None


class HardpointUnits(Units):
    axes: AxesName


class BodySpec(Strict):
    fixed: bool = False
    position: Vec3 | None = None
    orientation: Mat3 | None = None
    euler_parameters: Vec4 | None = None
    points: dict[str, PointValue] = Field(default_factory=dict)
    #: the steering axis by its joints (points ``kingpin_upper``, ``kingpin_lower``)
    kingpin: Kingpin | None = None


class JointSpec(Strict):
    type: str
    bodies: Annotated[list[str], Field(min_length=2, max_length=2)]
    cut: bool | None = None
    s_i: Vec3 | None = None
    s_j: Vec3 | None = None
    C_i: Mat3 | None = None
    C_j: Mat3 | None = None
    length: Positive | None = None
    q: list[Finite] | None = None

    @field_validator("q", mode="before")
    @classmethod
    def _scalar_q(cls, v: object) -> object:
        return [v] if isinstance(v, (int, float)) and not isinstance(v, bool) else v


class CouplingSpec(Strict):
    """A coupling ``q_a - q_a0 = c0 + c1 (q_b - q_b0) + ... + c4 (q_b - q_b0)^4`` between the
    coordinates of ``joints: [a, b]`` (a driven), in the model's units (:mod:`kinprop.io.couplings`)."""

    joints: Annotated[list[str], Field(min_length=2, max_length=2)]
    #: c0..c4 (1 to 5 numbers; the missing ones are 0)
    coef: list[Finite]
    #: offsets ``[q_a0, q_b0]`` (default 0)
    q0: Annotated[list[Finite], Field(min_length=2, max_length=2)] | None = None


class ElementSpec(Strict):
    """A spring, damper or spring-damper between two bodies, or a torsion spring on a joint's
    angle (:mod:`kinprop.model.elements`). Frame style: ``s_i``, ``s_j`` in the bodies' frames;
    hardpoint style: ``point_i``, ``point_j`` global at the reference configuration. Numbers in
    the model's units (a torsion spring's stiffness: torque per angle unit)."""

    type: Literal["spring", "damper", "spring_damper", "torsion"]
    bodies: Annotated[list[str], Field(min_length=2, max_length=2)] | None = None
    #: a torsion spring's joint (a revolute, or a cylindrical's angle)
    joint: str | None = None
    s_i: Vec3 | None = None
    s_j: Vec3 | None = None
    point_i: Vec3 | None = None
    point_j: Vec3 | None = None
    #: force per length
    stiffness: Annotated[float, Field(ge=0, allow_inf_nan=False)] | None = None
    #: force per (length / second)
    damping: Annotated[float, Field(ge=0, allow_inf_nan=False)] | None = None
    free_length: Positive | None = None
    #: force at the model's configuration (positive: compressed spring pushing the ends apart);
    #: a torsion spring's torque
    preload: Finite | None = None
    #: a torsion spring's angle at zero torque (the model's angle unit)
    free_angle: Finite | None = None


Share = Annotated[float, Field(ge=0, le=1, allow_inf_nan=False)]


class VehicleSpec(Strict):
    """Vehicle parameters of a suspension model (:class:`kinprop.model.elements.Vehicle`)."""

    wheelbase: Positive
    cg_height: Positive
    #: share of the braking force on the front axle
    brake_front: Share = 0.6
    #: share of the drive force on the front axle
    drive_front: Share = 0.0
    #: where the brakes react their torque: on the wheel carrier (outboard) or the chassis (inboard)
    brakes: Literal["outboard", "inboard"] = "outboard"
    #: where the drive reacts its torque: on the chassis (inboard, half shafts) or the carrier (outboard)
    drive: Literal["outboard", "inboard"] = "inboard"
    #: the axle of the model's corner
    axle: Literal["front", "rear"] = "front"
    #: rack travel per turn (360 deg) of the steering wheel, the length unit: the steering ratio's input
    rack_travel_per_turn: Positive | None = None


class VehicleUnits(Strict):
    length: Literal["m", "mm"]


class VehicleFile(Strict):
    """A vehicle file (:mod:`kinprop.io.vehicle`): two axle model files and the vehicle's
    parameters, in the file's own units."""

    kinprop: Literal[1]
    name: str = "vehicle"
    units: VehicleUnits
    vehicle: VehicleSpec
    #: the axle model files, relative to the vehicle file
    front: str
    rear: str


class PointLoadSpec(Strict):
    """A force and a couple on a body point (:class:`kinprop.model.loads.PointLoad`): ``point`` a
    named point of the body, or coordinates (frame style: the body's frame; hardpoint style:
    global at the reference configuration). Force unit ``units.force``, moments force x length."""

    body: str
    point: str | Vec3
    force: Vec3 | None = None
    moment: Vec3 | None = None
    #: components in the global axes or in the body's axes
    axes: Literal["global", "body"] = "global"


class MassSpec(Strict):
    """A body's weight (force at 1 g, ``units.force``) at its centre of mass (named point or coordinates)."""

    weight: Annotated[float, Field(ge=0, allow_inf_nan=False)]
    cm: str | Vec3


class LoadCaseSpec(Strict):
    """One named load case (:class:`kinprop.model.loads.LoadCase`)."""

    forces: list[PointLoadSpec] = Field(default_factory=list)
    #: contact-patch force of a wheel body, ``[Fx, Fy, Fz]`` in ISO 8855 axes (Fz > 0: vertical load)
    wheels: dict[str, Vec3] = Field(default_factory=dict)
    #: gravity in multiples of g (``[0, 0, -1]``: 1 g down in a z-up model); weights from ``masses``
    gravity: Vec3 | None = None


class LoadsSpec(Strict):
    """The ``loads:`` section: body masses and named load cases (:mod:`kinprop.io.loads`)."""

    masses: dict[str, MassSpec] = Field(default_factory=dict)
    cases: dict[str, LoadCaseSpec] = Field(default_factory=dict)


class ModelFile(Strict):
    kinprop: Literal[1] = 1
    name: str = "mechanism"
    description: str | None = None
    style: Literal["frames"] = "frames"
    units: Units
    bodies: dict[str, BodySpec]
    joints: dict[str, JointSpec]
    #: driven joints (``JOINT`` or ``JOINT.q[k]``): held unless named in a free set
    inputs: list[str] = Field(default_factory=list)
    #: couplings between joint coordinates (one constraint row each)
    couplings: dict[str, CouplingSpec] = Field(default_factory=dict)
    #: how an edit of a global hardpoint is read (hardpoint files: ``design``)
    edits: Literal["design", "mechanism"] = "mechanism"
    #: springs and dampers (``s_i``/``s_j`` in the bodies' frames)
    elements: dict[str, ElementSpec] = Field(default_factory=dict)
    vehicle: VehicleSpec | None = None
    #: applied loads: body masses and named load cases
    loads: LoadsSpec | None = None


class HardpointBodySpec(Strict):
    """A body: fixed bodies may declare their frame's pose (default: the global frame);
    ``points`` are named points given globally at the reference configuration."""

    fixed: bool = False
    position: Vec3 | None = None
    orientation: Mat3 | None = None
    points: dict[str, PointValue] = Field(default_factory=dict)
    #: the steering axis by its joints (points ``kingpin_upper``, ``kingpin_lower``)
    kingpin: Kingpin | None = None


class HardpointJointSpec(Strict):
    """A joint by its global points and axes at the reference configuration."""

    type: str
    bodies: Annotated[list[str], Field(min_length=2, max_length=2)]
    cut: bool | None = None
    point: Vec3 | None = None
    axis: Vec3 | None = None
    axis_i: Vec3 | None = None
    axis_j: Vec3 | None = None
    point_i: Vec3 | None = None
    point_j: Vec3 | None = None
    length: Positive | None = None
    #: a revolute to a fixed body by its two pivots (instead of point and axis):
    #: ``{front: [x, y, z], rear: [x, y, z]}``; the axis runs rear -> front (second -> first)
    pivots: Annotated[dict[str, Vec3], Field(min_length=2, max_length=2)] | None = None
    #: a tree joint's coordinates at the configuration the hardpoints describe (default zero),
    #: in the declared angle unit; the points and axes then give the joint frame on body i
    q: list[Finite] | None = None

    @field_validator("q", mode="before")
    @classmethod
    def _scalar_q(cls, v: object) -> object:
        return [v] if isinstance(v, (int, float)) and not isinstance(v, bool) else v


class HardpointFile(Strict):
    kinprop: Literal[1] = 1
    name: str = "mechanism"
    description: str | None = None
    style: Literal["hardpoints"]
    units: HardpointUnits
    #: body-frame rule: ``global`` (axes parallel to the global axes at the reference) or
    #: ``joint`` (axes of the body's tree-joint frame, the paper's convention)
    body_frames: Literal["global", "joint"] = "global"
    #: what an edit of a hardpoint keeps: ``design`` (the design position: the other hardpoints
    #: stay, link lengths are re-derived; hardpoint tools') or ``mechanism`` (the paper's: the
    #: lengths stay and the mechanism moves); :mod:`kinprop.propagation.hardpoints`
    edits: Literal["design", "mechanism"] = "design"
    bodies: dict[str, HardpointBodySpec]
    joints: dict[str, HardpointJointSpec]
    #: driven joints (``JOINT`` or ``JOINT.q[k]``): held unless named in a free set
    inputs: list[str] = Field(default_factory=list)
    #: couplings between joint coordinates (one constraint row each)
    couplings: dict[str, CouplingSpec] = Field(default_factory=dict)
    #: springs and dampers (``point_i``/``point_j`` global at the reference)
    elements: dict[str, ElementSpec] = Field(default_factory=dict)
    vehicle: VehicleSpec | None = None
    #: applied loads: body masses and named load cases
    loads: LoadsSpec | None = None
