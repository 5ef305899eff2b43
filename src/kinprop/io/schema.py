"""Schema of kinprop model files (YAML or JSON), validated with pydantic.

Frame style (the paper's): bodies with fixed poses; joints with the body-frame position
vectors ``s_i``/``s_j``, joint-frame orientations ``C_i``/``C_j`` and ``length`` where the
model defines them, and initial coordinate estimates ``q`` in the declared angle unit.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator

Finite = Annotated[float, Field(allow_inf_nan=False)]
Vec3 = Annotated[list[Finite], Field(min_length=3, max_length=3)]
Vec4 = Annotated[list[Finite], Field(min_length=4, max_length=4)]
Mat3 = Annotated[list[Vec3], Field(min_length=3, max_length=3)]


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class Units(Strict):
    length: Literal["m", "mm"]
    angle: Literal["deg", "rad"]


class BodySpec(Strict):
    fixed: bool = False
    position: Vec3 | None = None
    orientation: Mat3 | None = None
    euler_parameters: Vec4 | None = None
    points: dict[str, Vec3] = Field(default_factory=dict)


class JointSpec(Strict):
    type: str
    bodies: Annotated[list[str], Field(min_length=2, max_length=2)]
    cut: bool | None = None
    s_i: Vec3 | None = None
    s_j: Vec3 | None = None
    C_i: Mat3 | None = None
    C_j: Mat3 | None = None
    length: Annotated[float, Field(gt=0, allow_inf_nan=False)] | None = None
    q: list[Finite] | None = None

    @field_validator("q", mode="before")
    @classmethod
    def _scalar_q(cls, v: object) -> object:
        return [v] if isinstance(v, (int, float)) and not isinstance(v, bool) else v


class ModelFile(Strict):
    kinprop: Literal[1] = 1
    name: str = "mechanism"
    description: str | None = None
    style: Literal["frames"] = "frames"
    units: Units
    bodies: dict[str, BodySpec]
    joints: dict[str, JointSpec]
