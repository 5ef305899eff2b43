"""Model: a mechanism with its design and joint coordinates, as read from a file."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace

from kinprop.model.design import Design, as_coordinates
from kinprop.model.elements import Element, TorsionSpring, Vehicle
from kinprop.model.loads import Loads
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
    #: force elements (springs, dampers) by declaration order (``elements:``, kinprop.model.elements)
    elements: tuple[Element, ...] = ()
    #: vehicle parameters of a suspension model (``vehicle:``), or None
    vehicle: Vehicle | None = None
    #: applied loads: body weights and named load cases (``loads:``, kinprop.model.loads), or None
    loads: Loads | None = None
    #: torsion springs on joint angles (``elements:`` of ``type: torsion``), declaration order
    torsion_springs: tuple[TorsionSpring, ...] = ()

    def element(self, name: str) -> Element:
        for e in self.elements:
            if e.name == name:
                return e
        raise KeyError(f"unknown element {name!r}; elements: {', '.join(e.name for e in self.elements) or 'none'}")

    def with_state(self, design: Design, coordinates: Mapping[str, Array]) -> Model:
        return replace(self, design=design, coordinates=as_coordinates(coordinates))

    def __repr__(self) -> str:
        """One line: the name, the counts, the units and the inputs (the design is ``design``,
        the coordinates ``coordinates``; ``kp.dump_model(model, path)`` writes the whole file)."""
        mech = self.mechanism
        units = ", ".join(f"{k}: {v}" for k, v in self.units.items())
        parts = [f"{len(mech.bodies)} bodies", f"{len(mech.joints)} joints"]
        if mech.couplings:
            parts.append(f"{len(mech.couplings)} couplings")
        if self.elements:
            parts.append(f"{len(self.elements)} elements")
        inputs = f"; inputs: {', '.join(mech.inputs)}" if mech.inputs else ""
        source = f"; from {self.source}" if self.source else ""
        return f"<Model {mech.name!r}: {', '.join(parts)}; units {{{units}}}{inputs}{source}>"
