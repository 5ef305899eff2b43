"""Model: a mechanism with its design and joint coordinates, as read from a file."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace

from kinprop.model.design import Design, as_coordinates
from kinprop.model.mechanism import Mechanism
from kinprop.spatial import Array


@dataclass(frozen=True)
class Model:
    """Everything needed to solve: structure, design numbers, coordinates (estimates or solved)."""

    mechanism: Mechanism
    design: Design
    coordinates: Mapping[str, Array]
    #: unit system of the source file, kept for writing it back
    units: Mapping[str, str] = field(default_factory=lambda: {"length": "m", "angle": "rad"})
    source: str | None = None

    def with_state(self, design: Design, coordinates: Mapping[str, Array]) -> Model:
        return replace(self, design=design, coordinates=as_coordinates(coordinates))
