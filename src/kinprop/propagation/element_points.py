"""Element points as design variables: the global ends of a spring or damper (``elements:``).

Addresses, in the grammar of the global hardpoints (docs/guide/targets.md), named by the file's
own keys of a hardpoint-style element:

* ``element:NAME.point_i`` / ``element:NAME.point_j``: the element's end on its first / second
  body, a global point ``x,y,z`` in the model's length unit at the current assembly;
* ``element:NAME.point_i[x|y|z]``: one global component.

An element's ends are stored in their bodies' frames (``s_i``, ``s_j``; :mod:`kinprop.model.
elements`), so setting a global end ``p`` writes ``s <- A^T (p - r)`` with the body's pose
``(r, A)`` at the current assembly (exact, affine). Kinematics never reads them: changing one
moves no body, and a derivative with respect to one moves only the element's end, by
``A^T e_c`` per global unit along axis ``c`` (what :meth:`kinprop.analysis.firstorder.
FirstOrderProgram.derivatives` takes as ``elements``).
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Mapping, Sequence

import numpy as np

from kinprop.engine import Engine, State
from kinprop.errors import AddressError
from kinprop.model import Model
from kinprop.spatial import Array

ELEMENT = re.compile(r"^element:(?P<name>[^.\s\[\]]+)\.(?P<end>[^\s.\[\]]+)(\[(?P<c>[^\]]*)\])?$")
_ENDS = {"point_i": 0, "point_j": 1}
_AXES = {"x": 0, "y": 1, "z": 2, "0": 0, "1": 1, "2": 2}


def is_element_address(address: str) -> bool:
    """True for an ``element:NAME.point_i|point_j[...]`` address."""
    return address.strip().startswith("element:")


def parse_element_address(model: Model, address: str) -> tuple[int, int, list[int]]:
    """``(element index, side 0 | 1, components)`` of an element-point address (module
    docstring); raises :class:`AddressError` naming what is wrong and what exists."""
    text = address.strip()
    m = ELEMENT.match(text)
    if not m:
        raise AddressError(f"{text!r}: expected element:NAME.point_i or element:NAME.point_j[x|y|z]")
    names = [e.name for e in model.elements]
    if m["name"] not in names:
        raise AddressError(f"{text!r}: unknown element {m['name']!r}; elements are {', '.join(names) or 'none'}")
    if m["end"] not in _ENDS:
        raise AddressError(f"{text!r}: an element's ends are point_i and point_j, found {m['end']!r}")
    if m["c"] is not None and m["c"] not in _AXES:
        raise AddressError(f"{text!r}: a component is x, y or z, found {m['c']!r}")
    comps = [_AXES[m["c"]]] if m["c"] is not None else [0, 1, 2]
    return names.index(m["name"]), _ENDS[m["end"]], comps


def _pose(model: Model, engine: Engine, state: State, element: int, side: int) -> tuple[Array, Array, Array]:
    """``(r, A, s)``: the pose of the element end's body at ``state`` and the end in its frame."""
    e = model.elements[element]
    body = engine.body_index[e.body_i if side == 0 else e.body_j]
    r, A, _, _ = engine.poses(state)
    return r[body], A[body], np.asarray(e.s_i if side == 0 else e.s_j, dtype=float)


def element_point(model: Model, engine: Engine, state: State, address: str) -> Array:
    """The global position(s) an element-point address names at ``state``."""
    k, side, comps = parse_element_address(model, address)
    r, A, s = _pose(model, engine, state, k, side)
    return (r + A @ s)[comps]


def element_labels(model: Model, address: str) -> list[str]:
    """The column labels of an address: one per global component (``element:spring.point_i[x]``)."""
    m = ELEMENT.match(address.strip())
    _, _, comps = parse_element_address(model, address)
    return [f"element:{m['name']}.{m['end']}[{'xyz'[c]}]" for c in comps]  # type: ignore[index]


def element_directions(model: Model, engine: Engine, state: State, wrt: Sequence[str]) -> tuple[list[str], Array]:
    """``(labels, moves)`` of the element-point addresses in ``wrt``: a label per global
    component and ``moves`` (ne, 2, 3, k), the body-frame move of each element end per global
    unit of each component (``A^T e_c``; module docstring)."""
    labels: list[str] = []
    cols: list[tuple[int, int, Array]] = []
    for w in wrt:
        k, side, comps = parse_element_address(model, w)
        _, A, _ = _pose(model, engine, state, k, side)
        for lab, c in zip(element_labels(model, w), comps, strict=True):
            if lab not in labels:
                labels.append(lab)
                cols.append((k, side, A[c].copy()))  # A^T e_c
    moves = np.zeros((len(model.elements), 2, 3, len(cols)))
    for i, (k, side, d) in enumerate(cols):
        moves[k, side, :, i] = d
    return labels, moves


def apply_element_changes(
    model: Model, engine: Engine, state: State, changes: Mapping[str, object]
) -> tuple[Model, dict[str, object]]:
    """``(model with the element points set, the other changes)``: each ``element:`` address
    of ``changes`` (a global point, or one component) written into its body frame at ``state``
    (module docstring); the rest returned untouched."""
    rest: dict[str, object] = {}
    elements = list(model.elements)
    for address, value in changes.items():
        if not is_element_address(address):
            rest[address] = value
            continue
        k, side, comps = parse_element_address(model, address)
        v = np.atleast_1d(np.asarray(value, dtype=float)).ravel()
        if v.size != len(comps):
            raise AddressError(f"{address}: expected {len(comps)} number(s), found {v.size}")
        r, A, s = _pose(model, engine, state, k, side)
        p = r + A @ s
        p[comps] = v
        new = tuple(float(x) for x in A.T @ (p - r))
        elements[k] = dataclasses.replace(elements[k], **{"s_i" if side == 0 else "s_j": new})
    if len(rest) == len(changes):
        return model, rest
    return dataclasses.replace(model, elements=tuple(elements)), rest


__all__ = [
    "apply_element_changes",
    "element_directions",
    "element_labels",
    "element_point",
    "is_element_address",
    "parse_element_address",
]
