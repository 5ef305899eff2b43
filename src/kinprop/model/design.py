"""Design: the numbers a designer changes — s'_ij, C_ij and lengths — addressed by name.

Addresses: ``JOINT.s_i``, ``JOINT.s_j`` (position vector of the joint frame on the joint's
first / second body, body frame), ``JOINT.C_i``, ``JOINT.C_j`` (joint frame to body frame),
``JOINT.length``. Components: ``JOINT.s_i[2]``. Joint coordinates: ``JOINT.q``,
``JOINT.q[k]``. Coupling coefficients c0..c4: ``COUPLING.coef``, ``COUPLING.coef[k]``.
Groups: ``q``, ``s``, ``C``, ``l``, ``coef``.
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from kinprop.errors import AddressError
from kinprop.spatial import Array

GROUPS = {
    "q": "coordinates",
    "s": "position vectors",
    "C": "orientations",
    "l": "lengths",
    "coef": "coupling coefficients",
}
FIELD_GROUP = {"s_i": "s", "s_j": "s", "C_i": "C", "C_j": "C", "length": "l", "q": "q", "coef": "coef"}
DEFAULTS = {"s_i": np.zeros(3), "s_j": np.zeros(3), "C_i": np.eye(3), "C_j": np.eye(3)}

_ADDRESS = re.compile(r"^(?P<joint>[^\s\[\]]+)\.(?P<field>s_i|s_j|C_i|C_j|length|q|coef)(\[(?P<index>\d+)\])?$")


@dataclass(frozen=True)
class Address:
    joint: str
    field: str
    index: int | None = None

    def __str__(self) -> str:
        base = f"{self.joint}.{self.field}"
        return base if self.index is None else f"{base}[{self.index}]"

    @property
    def key(self) -> str:
        return f"{self.joint}.{self.field}"

    @property
    def group(self) -> str:
        return FIELD_GROUP[self.field]


def parse_address(text: str) -> Address:
    """Parse ``JOINT.field`` or ``JOINT.field[k]``; raise :class:`AddressError` otherwise."""
    m = _ADDRESS.match(text.strip())
    if not m:
        raise AddressError(
            f"bad address {text!r}: expected JOINT.s_i, JOINT.s_j, JOINT.C_i, JOINT.C_j, "
            "JOINT.length, JOINT.q or COUPLING.coef (optionally with [k])"
        )
    idx = m.group("index")
    return Address(m.group("joint"), m.group("field"), None if idx is None else int(idx))


def _frozen(value: Array) -> Array:
    a = np.array(value, dtype=float)
    a.setflags(write=False)
    return a


class Design(Mapping[str, Array]):
    """Immutable mapping ``"JOINT.field" -> array`` of the design variables a model defines."""

    __slots__ = ("_values",)

    def __init__(self, values: Mapping[str, object]):
        self._values = MappingProxyType({k: _frozen(v) for k, v in values.items()})

    def __getitem__(self, key: str) -> Array:
        try:
            return self._values[key]
        except KeyError:
            raise AddressError(f"design variable {key!r} is not defined by this model") from None

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def __repr__(self) -> str:
        return f"Design({dict(self._values)!r})"

    def __reduce__(self) -> tuple[type, tuple[dict[str, Array]]]:  # picklable (Dask, multiprocessing)
        return (type(self), (dict(self._values),))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Design):
            return NotImplemented
        return self._values.keys() == other._values.keys() and all(
            np.array_equal(v, other._values[k]) for k, v in self._values.items()
        )

    __hash__ = None  # type: ignore[assignment]

    def value(self, joint: str, field: str) -> Array:
        """The joint's field, or its default (zero vector / identity) when not a design variable."""
        v = self._values.get(f"{joint}.{field}")
        return DEFAULTS[field] if v is None else v

    def replace(self, changes: Mapping[str, object]) -> Design:
        """A new design with ``changes`` applied (keys must exist)."""
        new = dict(self._values)
        for k, v in changes.items():
            if k not in new:
                raise AddressError(f"design variable {k!r} is not defined by this model")
            new[k] = v
        return Design(new)


class Coordinates(Mapping[str, Array]):
    """Immutable mapping ``joint -> coordinates`` (read-only arrays); picklable."""

    __slots__ = ("_values",)

    def __init__(self, values: Mapping[str, object]):
        self._values = MappingProxyType({k: _frozen(v) for k, v in values.items()})

    def __getitem__(self, key: str) -> Array:
        return self._values[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def __repr__(self) -> str:
        return f"Coordinates({dict(self._values)!r})"

    def __reduce__(self) -> tuple[type, tuple[dict[str, Array]]]:
        return (type(self), (dict(self._values),))


def as_coordinates(values: Mapping[str, object]) -> Coordinates:
    """Immutable mapping ``joint -> coordinates``."""
    return values if isinstance(values, Coordinates) else Coordinates(values)
