"""Global hardpoint and axis addresses, converted exactly to body-frame design changes.

Designers know where joints are in the assembled machine. These addresses take global values
(the model's global frame and length unit) at the *current assembly* of a state:

* ``hardpoint:J.i=x,y,z`` — the joint's attachment on its first body i moves to the global
  point ``p``: ``s'_i <- A_i^T (p - r_i) = s'_i + A_i^T (p - P_i)`` with ``P_i = r_i + A_i s'_i``
  the current global joint origin on body i (``A_i = R_i C_i^T`` from the joint frame ``R_i``);
* ``hardpoint:J.j=...`` — the same on body j;
* ``hardpoint:J=...`` — both sides: the joint moves, the assembly stays closed (both
  attachments shift by the same global vector, so no body moves). A tree joint whose body j
  frame *is* its joint frame (no ``s_j``/``C_j`` design variable, the usual paper-style tree
  joint) has only side i to move: body j then moves with the joint and the propagation
  re-assembles; for a cut joint a missing side is an error;
* ``axis:J=x,y,z`` (and ``axis:J.i``, ``axis:J.j``) — the joint frame's z'' axis turns to the
  global direction ``u`` (any length) by the smallest rotation ``R_d`` (about ``z x u``), applied
  to the joint frame(s) in global: ``C <- A^T R_d R`` — so the relative joint value is kept.

:func:`resolve_changes` turns a change set with such addresses into plain ``J.s_i``/``J.C_i``
changes (other addresses pass through); :func:`hardpoint_map` gives the linear map
``d(design columns)/d(global coordinates)`` used for sensitivities per global length unit.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from kinprop.engine import Engine, State
from kinprop.errors import AddressError
from kinprop.spatial import Array, exp_so3, log_so3

#: the one grammar of global addresses: ``hardpoint:J[.i|.j|.PIVOT][[x|y|z]]``, ``axis:J[.i|.j]``
GLOBAL = re.compile(
    r"^(?P<kind>hardpoint|axis):(?P<joint>[^\s.\[\]=]+)(\.(?P<side>[^\s.\[\]=]+))?(\[(?P<c>[^\]]*)\])?$"
)
#: a global component's index
_AXIS = {"x": 0, "y": 1, "z": 2, "0": 0, "1": 1, "2": 2}
_FIELDS = {"hardpoint": "s", "axis": "C"}
#: edit readings (:attr:`kinprop.model.Mechanism.edits`)
DESIGN, MECHANISM = "design", "mechanism"
#: joint types whose pivots may be addressed
PIVOT_TYPES = ("revolute", "cylindrical")


@dataclass(frozen=True)
class GlobalAddress:
    """A parsed ``hardpoint:J[.i|.j|.PIVOT][[c]]`` or ``axis:J[.i|.j]`` address."""

    text: str  # the whole point's address (without a component)
    kind: str  # "hardpoint" | "axis"
    joint: str
    sides: tuple[int, ...]  # 0 = i, 1 = j
    #: the pivot named (``hardpoint:UCA.front``), or None
    pivot: str | None = None
    #: the design fields it writes besides the sides' s' (pivots, re-derived lengths)
    extra: tuple[str, ...] = ()
    #: the one global coordinate named (``hardpoint:TR.i[z]`` -> 2), or None for the whole point
    component: int | None = None

    def fields(self) -> list[str]:
        """The design addresses it writes (``J.s_i``, ``J.C_j``, ``J.length``, ...)."""
        if self.pivot is not None:
            return list(self.extra)
        f = _FIELDS[self.kind]
        return [f"{self.joint}.{f}_{'ij'[s]}" for s in self.sides] + list(self.extra)


def is_global(address: str) -> bool:
    """True for ``hardpoint:...`` and ``axis:...`` addresses."""
    return address.strip().startswith(("hardpoint:", "axis:"))


def pivots(engine: Engine, joint: str) -> tuple[int, dict[str, Array]] | None:
    """``(fixed side, {name: global point})`` of a joint given by its two pivots (the fixed
    body's named points ``JOINT.NAME``), or None. The axis runs from the second to the first."""
    mech = engine.mechanism
    j = mech.joint(joint)
    if j.jtype.name not in PIVOT_TYPES:
        return None
    for side, name in enumerate((j.body_i, j.body_j)):
        b = mech.body(name)
        pts = {k.split(".", 1)[1]: np.asarray(v, dtype=float) for k, v in b.points if k.startswith(f"{joint}.")}
        if b.fixed and len(pts) == 2:
            return side, {k: b.r + b.A @ v for k, v in pts.items()}
    return None


def _edits(engine: Engine, edits: str | None) -> str:
    e = edits or engine.mechanism.edits
    if e not in (DESIGN, MECHANISM):
        raise AddressError(f"edits: expected {DESIGN!r} or {MECHANISM!r}, found {e!r}")
    return e


def parse_global(engine: Engine, address: str, edits: str | None = None) -> GlobalAddress:
    """Parse and check a global address against the engine's mechanism."""
    m = GLOBAL.match(address.strip())
    if not m:
        raise AddressError(
            f"{address!r}: expected hardpoint:JOINT, hardpoint:JOINT.i|j, hardpoint:JOINT.PIVOT (each with an "
            "optional [x|y|z]), axis:JOINT or axis:JOINT.i|j"
        )
    text = address.strip().partition("[")[0]
    component = None
    if m["c"] is not None:
        if m["kind"] == "axis":
            raise AddressError(f"{address!r}: an axis is a direction; give all of {text}=x,y,z")
        if m["c"] not in _AXIS:
            raise AddressError(f"{address!r}: expected a component [x], [y] or [z], found [{m['c']}]")
        component = _AXIS[m["c"]]
    joint = m["joint"]
    if joint not in engine.joint_index:
        raise AddressError(
            f"{address!r}: unknown joint {joint!r}; joints are {', '.join(engine.mechanism.joint_names)}"
        )
    mode = _edits(engine, edits)
    jt = engine.mechanism.joint(joint)
    side_text = m["side"]
    if side_text is not None and side_text not in ("i", "j"):
        found = pivots(engine, joint) if m["kind"] == "hardpoint" else None
        if found is None or side_text not in found[1]:
            names = ", ".join(f"{joint}.{k}" for k in found[1]) if found else ""
            raise AddressError(
                f"{address!r}: expected {joint}.i or {joint}.j"
                + (f", or a pivot ({names})" if names else f" (joint {joint!r} is not given by pivots)")
            )
        f, _ = found
        extra = [f"{joint}.s_{'ij'[f]}", f"{joint}.C_{'ij'[f]}"]
        if mode == DESIGN:
            extra += [f"{joint}.s_{'ij'[1 - f]}", f"{joint}.C_{'ij'[1 - f]}"]
        missing = [x for x in extra if x.split(".", 1)[1] not in jt.fields]
        if missing:
            raise AddressError(
                f"{address!r}: moving a pivot with edits={mode!r} writes {', '.join(extra)}; joint {joint!r} has no "
                f"{', '.join(x.split('.', 1)[1] for x in missing)} (a hardpoint file with edits: design defines them)"
            )
        return GlobalAddress(text, "hardpoint", joint, (f,), side_text, tuple(extra), component)
    sides = (0, 1) if side_text is None else (0 if side_text == "i" else 1,)
    g = GlobalAddress(text, m["kind"], joint, sides)
    fields = jt.fields
    missing = [f for f in g.fields() if f.split(".", 1)[1] not in fields]
    tree = joint in engine.topology.tree_joints
    if len(missing) == len(g.fields()) or (missing and not tree):
        names = " or ".join(f.split(".", 1)[1] for f in missing)
        raise AddressError(f"{address!r}: joint {joint!r} has no {names} design variable; name the side it has")
    extra = (f"{joint}.length",) if mode == DESIGN and g.kind == "hardpoint" and "length" in fields else ()
    # a tree joint whose body j frame is the joint frame (no s_j / C_j): body j follows the joint
    kept = tuple(s for s, f in zip(g.sides, g.fields(), strict=True) if f not in missing)
    return GlobalAddress(text, g.kind, joint, kept, None, extra, component)


def body_rotation(engine: Engine, state: State, joint: int, side: int) -> Array:
    """``A`` of the body on ``side`` of joint ``joint``: ``R C^T`` (joint frame, global)."""
    _, _, _, R = engine.poses(state)
    return R[joint, side] @ state.C[joint, side].T


def _vector(address: str, value: Any) -> Array:
    v = np.asarray(value, dtype=float).ravel()
    if v.size != 3 or not np.all(np.isfinite(v)):
        raise AddressError(f"{address!r}: expected three finite global coordinates x,y,z, found {v.size} numbers")
    return v


def min_rotation(a: Array, b: Array) -> Array:
    """The smallest rotation taking direction ``a`` to direction ``b`` (both any length)."""
    a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
    c = np.cross(a, b)
    s, cos = np.linalg.norm(c), float(a @ b)
    if s < 1e-15:
        if cos > 0:
            return np.eye(3)
        perp = np.cross(a, np.eye(3)[int(np.argmin(np.abs(a)))])  # half turn about any normal
        return exp_so3(np.pi * perp / np.linalg.norm(perp))
    return exp_so3(c / s * np.arctan2(s, cos))


def whole_points(
    engine: Engine, state: State, changes: Mapping[str, Any], edits: str | None = None
) -> dict[str, tuple[GlobalAddress | None, Any]]:
    """``changes`` keyed by whole addresses: a global address's components
    (``hardpoint:TR.i[z]=54``) merged into its whole point, the others taken from the current
    assembly of ``state``; non-global addresses map to ``(None, value)``."""
    out: dict[str, tuple[GlobalAddress | None, Any]] = {}
    parts: dict[str, dict[int, float]] = {}
    given: dict[str, str] = {}
    for address, value in changes.items():
        if not is_global(address):
            out[address] = (None, value)
            continue
        g = parse_global(engine, address, edits)
        if g.text in given and (g.component is None or given[g.text] == g.text):
            raise AddressError(f"{address!r}: {g.text} is already given by {given[g.text]!r}; give it once")
        given.setdefault(g.text, address.strip())
        if g.component is None:
            out[g.text] = (g, _vector(address, value))
            continue
        c = np.asarray(value, dtype=float).ravel()
        if c.size != 1 or not np.isfinite(c[0]):
            raise AddressError(f"{address!r}: expected one finite global coordinate, found {c.size} numbers")
        if g.component in parts.setdefault(g.text, {}):
            raise AddressError(f"{address!r}: that component is given twice")
        parts[g.text][g.component] = float(c[0])
        if g.text not in out:
            out[g.text] = (replace(g, component=None), current_point(engine, state, g.text))
    for base, comps in parts.items():
        v = np.array(out[base][1], dtype=float)
        for c, x in comps.items():
            v[c] = x
        out[base] = (out[base][0], v)
    return out


def resolve_changes(
    engine: Engine, state: State, changes: Mapping[str, Any], edits: str | None = None
) -> dict[str, Any]:
    """``changes`` with every global address replaced by exact body-frame ``s'``/``C`` values
    (and, with ``edits="design"``, re-derived lengths) at the current assembly of ``state``, all
    computed from the same, unchanged poses; ``edits`` defaults to the mechanism's."""
    if not any(is_global(a) for a in changes):
        return dict(changes)
    mode = _edits(engine, edits)
    _, _, P, R = engine.poses(state)
    out: dict[str, Any] = {}
    moved: dict[tuple[int, int], Array] = {}  # new global joint points, (joint, side)
    lengths: set[int] = set()
    pivot_moves: dict[str, dict[str, Array]] = {}
    for address, (g, v) in whole_points(engine, state, changes, mode).items():
        if g is None:
            out[address] = v
            continue
        k = engine.joint_index[g.joint]
        if g.pivot is not None:
            pivot_moves.setdefault(g.joint, {})[g.pivot] = v
            continue
        if g.kind == "axis" and not np.linalg.norm(v) > 0:
            raise AddressError(f"{address!r}: an axis direction must be non-zero")
        for side, fld in zip(g.sides, g.fields()[: len(g.sides)], strict=True):
            A = R[k, side] @ state.C[k, side].T
            if g.kind == "hardpoint":
                out[fld] = state.S[k, side] + A.T @ (v - P[k, side])
                moved[(k, side)] = v
            else:
                out[fld] = A.T @ min_rotation(R[k, side][:, 2], v) @ R[k, side]
        if g.extra:
            lengths.add(k)
    for k in sorted(lengths):
        out.update(_rederived_length(engine, state, P, R, k, moved))
    for joint, moves in pivot_moves.items():
        out.update(_pivot_changes(engine, state, P, R, joint, moves, mode))
    return out


def _rederived_length(
    engine: Engine, state: State, P: Array, R: Array, k: int, moved: Mapping[tuple[int, int], Array]
) -> dict[str, Any]:
    """The length of joint ``k`` from its (moved) points: a distance joint's two ends; an R-S
    ball's distance from the revolute axis (its foot ``s_i`` moves with it); a T-D rod from
    the slid rack point."""
    j = engine.mechanism.joint_names[k]
    jt = engine.mechanism.joint(j).jtype
    p_i, p_j = moved.get((k, 0), P[k, 0]), moved.get((k, 1), P[k, 1])
    out: dict[str, Any] = {}
    if jt.name == "revolute-spherical":
        z = R[k, 0][:, 2]
        foot = p_i + ((p_j - p_i) @ z) * z
        A = R[k, 0] @ state.C[k, 0].T
        out[f"{j}.s_i"] = state.S[k, 0] + A.T @ (foot - P[k, 0])
        p_i = foot
    elif jt.name == "translational-distance" and jt.n_cut_coordinates:
        u, _ = jt.cut_offset(np.asarray(engine.get(state, f"{j}.q"), dtype=float))
        p_i = p_i + R[k, 0] @ u
    length = float(np.linalg.norm(p_j - p_i))
    if not length > 0:
        raise AddressError(f"joint {j!r}: the edit puts its two points together (length 0)")
    out[f"{j}.length"] = length
    return out


def _pivot_changes(
    engine: Engine, state: State, P: Array, R: Array, joint: str, moves: Mapping[str, Array], mode: str
) -> dict[str, Any]:
    """Design changes of moving pivots of ``joint``: the fixed side's joint frame to the new
    midpoint and axis (turned by the smallest rotation); with ``edits="design"`` the moving
    side's frame follows it at the same joint value, and its body keeps its pose."""
    k = engine.joint_index[joint]
    f, old = pivots(engine, joint)  # type: ignore[misc]
    new = {n: moves.get(n, p) for n, p in old.items()}
    first, second = new.values()
    if not np.linalg.norm(first - second) > 0:
        raise AddressError(f"{joint}: the two pivots coincide and define no axis")
    z0 = R[k, f][:, 2]
    Rf = min_rotation(z0, first - second) @ R[k, f]
    Pf = (first + second) / 2
    # keep the joint frame's origin where the old axis line's point maps (midpoint of the pivots)
    A_f = R[k, f] @ state.C[k, f].T
    r_f = P[k, f] - A_f @ state.S[k, f]
    fs = "ij"[f]
    out: dict[str, Any] = {f"{joint}.s_{fs}": A_f.T @ (Pf - r_f), f"{joint}.C_{fs}": A_f.T @ Rf}
    if mode == DESIGN:
        a = 1 - f
        turn = Rf @ R[k, f].T
        Ra, Pa = turn @ R[k, a], Pf + turn @ (P[k, a] - P[k, f])
        A_a = R[k, a] @ state.C[k, a].T
        r_a = P[k, a] - A_a @ state.S[k, a]
        out[f"{joint}.s_{'ij'[a]}"] = A_a.T @ (Pa - r_a)
        out[f"{joint}.C_{'ij'[a]}"] = A_a.T @ Ra
    return out


def pivot_updates(engine: Engine, changes: Mapping[str, Any]) -> dict[str, dict[str, Array]]:
    """``{fixed body: {JOINT.PIVOT: body-frame point}}`` of the pivots ``changes`` move: the
    stored pivots a propagation's result carries."""
    out: dict[str, dict[str, Array]] = {}
    if not any(is_global(a) for a in changes):
        return out
    for g, v in whole_points(engine, engine.reference, changes).values():  # pivots: fixed, any state
        if g is None or g.pivot is None:
            continue
        j = engine.mechanism.joint(g.joint)
        body = engine.mechanism.body(j.body_i if g.sides[0] == 0 else j.body_j)
        out.setdefault(body.name, {})[f"{g.joint}.{g.pivot}"] = body.A.T @ (v - body.r)
    return out


def free_addresses(engine: Engine, selectors: Sequence[str]) -> tuple[str, ...]:
    """Free-set selectors with ``hardpoint:J[.i|.j]`` / ``axis:J[.i|.j]`` replaced by the design
    addresses they move (``J.s_i``, ``J.C_j``, ...), a component (``hardpoint:TR.i[z]``) by the
    design columns a change of it writes at the model's assembly (:func:`component_columns`);
    groups and addresses pass through."""
    out: list[str] = []
    for sel in selectors:
        if not is_global(sel):
            out.append(sel)
            continue
        g = parse_global(engine, sel)
        out += g.fields() if g.component is None else component_columns(engine, engine.reference, sel)
    return tuple(dict.fromkeys(out))


def _component_coefficients(engine: Engine, state: State, g: GlobalAddress) -> dict[str, float]:
    """``{design column label: d(column)/d(component)}`` of a global component ``g`` at
    ``state`` (:func:`hardpoint_map`'s column), the entries above round-off."""
    fields, M, _ = hardpoint_map(engine, state, g.text)
    rows = [lab for f in fields for lab in _labels(engine, f)]
    col = M[:, g.component]
    big = 1e-8 * max(1.0, float(np.abs(col).max()))
    return {lab: float(x) for lab, x in zip(rows, col, strict=True) if abs(x) > big}


def component_columns(engine: Engine, state: State, address: str) -> list[str]:
    """The design column labels (``TR.s_i[2]``, ``TR.length``, a pivot's ``UCA.C_i[k]``) that a
    change of one global component (``hardpoint:TR.i[z]``) writes at ``state``. A joint's point
    on a body whose frame is turned from the global axes would need a combination of ``s'``
    columns: that is refused (name the body-frame columns ``J.s_i[k]`` instead)."""
    g = parse_global(engine, address)
    if g.component is None:
        raise AddressError(f"{address!r}: expected a component, e.g. {address.strip()}[z]")
    hit = list(_component_coefficients(engine, state, g))
    if g.pivot is None:
        for fld in g.fields()[: len(g.sides)]:
            mine = [lab for lab in hit if lab.startswith(fld + "[")]
            if len(mine) > 1:
                raise AddressError(
                    f"{address!r}: the body frame of {fld} is turned from the global axes, so this global "
                    f"coordinate moves {', '.join(mine)} together; free those columns (or the whole {g.text})"
                )
    return hit


def free_tie(engine: Engine, state: State, selectors: Sequence[str]) -> tuple[tuple[str, ...], Array | None]:
    """``(addresses, tie)`` of a target solve's free set (:func:`kinprop.engine.targets.solve_targets`):
    :func:`free_addresses`, and the columns that must move together. A component of a point two
    moving bodies share (``hardpoint:UBJ[z]``: ``UBJ.s_i[2]`` and ``UBJ.s_j[2]``) is one unknown,
    its global coordinate: both bodies' s' move by the same global step, so no body moves at
    the assembly the point is given at (freed one by one, the loop would close by turning an arm,
    moving the point in x and y too). ``tie`` is None when there is no such component."""
    addresses = free_addresses(engine, selectors)
    cols = engine.columns(addresses) if addresses else np.zeros(0, np.int64)
    labels = engine.column_labels
    pos = {labels[c]: i for i, c in enumerate(cols.tolist())}
    tied: list[Array] = []
    used: set[int] = set()
    for sel in selectors:
        if not is_global(sel):
            continue
        g = parse_global(engine, sel)
        if g.component is None or g.pivot is not None:
            continue
        entries = {lab: x for lab, x in _component_coefficients(engine, state, g).items() if ".s_" in lab}
        if len({lab.split("[")[0] for lab in entries}) < 2:
            continue  # a point on one moving body: its columns are the unknowns themselves
        t = np.zeros(cols.size)
        for lab, x in entries.items():
            t[pos[lab]] = x
            used.add(pos[lab])
        tied.append(t)
    if not tied:
        return addresses, None
    eye = np.eye(cols.size)
    rest = [eye[:, i] for i in range(cols.size) if i not in used]
    return addresses, np.column_stack(tied + rest)


def free_weights(engine: Engine, weights: Mapping[str, float] | None) -> dict[str, float] | None:
    """Weights keyed like :func:`free_addresses` (a global address weighs all its fields)."""
    if not weights:
        return None
    out: dict[str, float] = {}
    for sel, w in weights.items():
        for f in free_addresses(engine, [sel]):
            out[f] = w
    return out


def current_point(engine: Engine, state: State, address: str) -> Array:
    """The global point a ``hardpoint:`` address names, at ``state`` (a joint's point on its
    first named side, or the stored pivot)."""
    g = parse_global(engine, address)
    if g.kind != "hardpoint":
        raise AddressError(f"{address!r}: only hardpoint: addresses name a point (axes: use J.C_i)")
    if g.pivot is not None:
        return pivots(engine, g.joint)[1][g.pivot]  # type: ignore[index]
    _, _, P, _ = engine.poses(state)
    return P[engine.joint_index[g.joint], g.sides[0]].copy()


def _flat(engine: Engine, state: State, field: str, value: Any) -> Array:
    """A design field's change as its columns' coordinates: s' and lengths as they are, C as
    the rotation vector ``xi'`` with ``C = exp(xi') C_state`` (:meth:`Engine.retract`)."""
    if ".C_" in field:
        return log_so3(np.asarray(value, dtype=float) @ engine.get(state, field).reshape(3, 3).T)
    return np.atleast_1d(np.asarray(value, dtype=float)).ravel()


#: central-difference step of the point -> design map, relative to the model's length scale
MAP_STEP = 1e-6


def hardpoint_map(engine: Engine, state: State, address: str) -> tuple[list[str], Array, list[str]]:
    """For a ``hardpoint:`` address: the design addresses it writes, the matrix ``M`` (one row
    per design column, 3) with ``d(design columns) = M d p`` at ``state`` and the column labels
    ``hardpoint:J.i[x]`` ... of ``p``. Affine conversions (s') are exact; pivots (C) and
    re-derived lengths are differenced centrally (the conversion, not the mechanism)."""
    g = parse_global(engine, address)
    p0 = current_point(engine, state, address)
    fields = g.fields() if g.kind == "hardpoint" else []
    if g.kind != "hardpoint":
        raise AddressError(f"{address!r}: only hardpoint: addresses have a per-length derivative (axes: use J.C_i)")
    h = MAP_STEP * max(1.0, float(np.max(np.abs(p0))))
    cols = []
    for c in range(3):
        e = np.zeros(3)
        e[c] = h
        plus = resolve_changes(engine, state, {address: p0 + e})
        minus = resolve_changes(engine, state, {address: p0 - e})
        cols.append(
            np.concatenate(
                [(_flat(engine, state, f, plus[f]) - _flat(engine, state, f, minus[f])) / (2 * h) for f in fields]
            )
        )
    return fields, np.column_stack(cols), [f"{g.text}[{c}]" for c in "xyz"]


def _labels(engine: Engine, field: str) -> list[str]:
    """Column labels of one design field (``J.s_i[0..2]``, ``J.C_i[0..2]``, ``J.length``)."""
    return [c for c in engine.column_labels if c == field or c.startswith(field + "[")]


def global_columns(engine: Engine, state: State, wrt: Sequence[str]) -> tuple[list[str], dict[str, dict[str, float]]]:
    """For sensitivities per global length unit: ``wrt`` with every ``hardpoint:`` address
    replaced by the design addresses it writes, and for each global column label
    (``hardpoint:J.i[x]``) its coefficients over the design column labels (``J.s_i[k]``,
    ``J.C_i[k]``, ``J.length``): the chain rule through :func:`hardpoint_map`."""
    design: list[str] = []
    combos: dict[str, dict[str, float]] = {}
    for w in wrt:
        if not w.strip().startswith("hardpoint:"):
            design.append(w)
            continue
        g = parse_global(engine, w)
        fields, M, labels = hardpoint_map(engine, state, g.text)
        design += fields
        rows = [lab for f in fields for lab in _labels(engine, f)]
        comps = [g.component] if g.component is not None else [0, 1, 2]
        for c in comps:
            coef: dict[str, float] = {}
            for r, lab in enumerate(rows):
                coef[lab] = coef.get(lab, 0.0) + float(M[r, c])
            combos[labels[c]] = coef
    return list(dict.fromkeys(design)), combos


def global_plan(engine: Engine, state: State, addresses: Sequence[str], values: Array) -> tuple[list[str], Array]:
    """A study plan with global hardpoint components (``hardpoint:J.i[z]``, ``hardpoint:UCA.front[z]``
    factors) replaced by the design component columns they set, per sample (exact, at
    ``state``'s assembly; the other components of that point stay where they are)."""
    values = np.atleast_2d(np.asarray(values, dtype=float))
    parsed = {k: parse_global(engine, a) for k, a in enumerate(addresses) if a.strip().startswith("hardpoint:")}
    keep = [k for k in range(len(addresses)) if k not in parsed or parsed[k].component is None]
    addrs = [addresses[k] for k in keep]
    cols = [values[:, k] for k in keep]
    groups: dict[str, list[tuple[int, int]]] = {}
    for k, g in parsed.items():
        if g.component is not None:
            groups.setdefault(g.text, []).append((k, g.component))
    for base, comps in groups.items():
        g = parse_global(engine, base)
        p0 = current_point(engine, state, base)
        rows: list[dict[str, Any]] = []
        for n in range(values.shape[0]):
            p = p0.copy()
            for k, c in comps:
                p[c] = values[n, k]
            rows.append(resolve_changes(engine, state, {base: p}))
        for fld in g.fields():
            if fld in addrs or any(a.startswith(fld + "[") for a in addrs):
                raise AddressError(f"{base}: {fld} is also varied directly; vary one or the other")
            block = np.array([np.atleast_1d(np.asarray(r[fld], dtype=float)).ravel() for r in rows])
            if block.shape[1] == 1:
                addrs.append(fld)
                cols.append(block[:, 0])
                continue
            for c in range(block.shape[1]):
                addrs.append(f"{fld}[{c}]")
                cols.append(block[:, c])
    return addrs, np.stack(cols, axis=1) if cols else np.zeros((values.shape[0], 0))


__all__ = [
    "DESIGN",
    "MECHANISM",
    "GlobalAddress",
    "current_point",
    "free_addresses",
    "free_tie",
    "free_weights",
    "global_columns",
    "global_plan",
    "hardpoint_map",
    "is_global",
    "min_rotation",
    "parse_global",
    "pivot_updates",
    "pivots",
    "resolve_changes",
]
