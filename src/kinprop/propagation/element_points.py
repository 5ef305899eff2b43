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
        r, A, _ = _pose(model, engine, state, k, side)
        s = np.asarray(elements[k].s_i if side == 0 else elements[k].s_j, dtype=float)  # earlier changes kept
        p = r + A @ s
        p[comps] = v
        new = tuple(float(x) for x in A.T @ (p - r))
        elements[k] = dataclasses.replace(elements[k], **{"s_i" if side == 0 else "s_j": new})
    if len(rest) == len(changes):
        return model, rest
    return dataclasses.replace(model, elements=tuple(elements)), rest


def element_ends(model: Model) -> Array:
    """``(ne, 2, 3)``: every element's ends ``s_i``, ``s_j`` in their bodies' frames."""
    return np.array([[e.s_i, e.s_j] for e in model.elements], dtype=float).reshape(len(model.elements), 2, 3)


def with_element_ends(model: Model, ends: Array) -> Model:
    """``model`` with its elements' body-frame ends set to ``ends`` (ne, 2, 3)."""
    ends = np.asarray(ends, dtype=float)
    if not model.elements or np.array_equal(ends, element_ends(model)):
        return model
    elements = tuple(dataclasses.replace(e, s_i=tuple(map(float, ends[k, 0])), s_j=tuple(map(float, ends[k, 1])))
                     for k, e in enumerate(model.elements))  # fmt: skip
    return dataclasses.replace(model, elements=elements)


def element_factors(model: Model, engine: Engine, state: State, addresses: Sequence[str]) -> dict[str, list[float]]:
    """``{address: [element, side, d_x, d_y, d_z, p_c]}`` of one-component element addresses
    (``element:spring.point_i[z]``), each a scalar design variable: its value ``v`` (global, at
    ``state``'s assembly) puts the end at ``s + d (v - p_c)`` in its body's frame, ``d = A^T e_c``
    and ``p_c`` the end's current global component (exact, affine; module docstring). Raises
    :class:`AddressError` for an address that is not one component."""
    out: dict[str, list[float]] = {}
    for a in addresses:
        k, side, comps = parse_element_address(model, a)
        if ELEMENT.match(a.strip())["c"] is None:  # type: ignore[index]
            raise AddressError(f"{a!r}: a scalar design variable is one component, e.g. {a.strip()}[z]")
        r, A, s = _pose(model, engine, state, k, side)
        c = comps[0]
        out[a.strip()] = [float(k), float(side), *map(float, A[c]), float((r + A @ s)[c])]
    return out


def factor_ends(model: Model, factors: Mapping[str, Sequence[float]], addresses: Sequence[str], values: Array) -> Array:
    """``(N, ne, 2, 3)``: the model's element ends (body frames) with the element factors
    (:func:`element_factors`) set to ``values`` (N, len(addresses)); other addresses ignored."""
    values = np.atleast_2d(np.asarray(values, dtype=float))
    ends = np.repeat(element_ends(model)[None], values.shape[0], axis=0)
    for k, a in enumerate(addresses):
        f = factors.get(a.strip())
        if f is None:
            continue
        e, side = int(f[0]), int(f[1])
        ends[:, e, side] += (values[:, k] - f[5])[:, None] * np.asarray(f[2:5])[None, :]
    return ends


__all__ = [
    "apply_element_changes",
    "element_directions",
    "element_ends",
    "element_factors",
    "element_labels",
    "element_point",
    "factor_ends",
    "is_element_address",
    "parse_element_address",
    "with_element_ends",
]
