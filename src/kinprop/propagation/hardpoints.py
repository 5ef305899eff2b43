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
from dataclasses import dataclass
from typing import Any

import numpy as np

from kinprop.engine import Engine, State
from kinprop.errors import AddressError
from kinprop.spatial import Array, exp_so3

GLOBAL = re.compile(r"^(?P<kind>hardpoint|axis):(?P<joint>[^\s.\[\]=]+)(\.(?P<side>[ij]))?$")
_FIELDS = {"hardpoint": "s", "axis": "C"}


@dataclass(frozen=True)
class GlobalAddress:
    """A parsed ``hardpoint:J[.i|.j]`` or ``axis:J[.i|.j]`` address."""

    text: str
    kind: str  # "hardpoint" | "axis"
    joint: str
    sides: tuple[int, ...]  # 0 = i, 1 = j

    def fields(self) -> list[str]:
        """The design addresses it writes (``J.s_i``, ``J.C_j``, ...)."""
        f = _FIELDS[self.kind]
        return [f"{self.joint}.{f}_{'ij'[s]}" for s in self.sides]


def is_global(address: str) -> bool:
    """True for ``hardpoint:...`` and ``axis:...`` addresses."""
    return address.strip().startswith(("hardpoint:", "axis:"))


def parse_global(engine: Engine, address: str) -> GlobalAddress:
    """Parse and check a global address against the engine's mechanism."""
    text = address.strip()
    m = GLOBAL.match(text)
    if not m:
        raise AddressError(f"{address!r}: expected hardpoint:JOINT, hardpoint:JOINT.i|j, axis:JOINT or axis:JOINT.i|j")
    joint = m["joint"]
    if joint not in engine.joint_index:
        raise AddressError(
            f"{address!r}: unknown joint {joint!r}; joints are {', '.join(engine.mechanism.joint_names)}"
        )
    sides = (0, 1) if m["side"] is None else (0 if m["side"] == "i" else 1,)
    g = GlobalAddress(text, m["kind"], joint, sides)
    fields = engine.mechanism.joint(joint).fields
    missing = [f for f in g.fields() if f.split(".", 1)[1] not in fields]
    tree = joint in engine.topology.tree_joints
    if len(missing) == len(g.fields()) or (missing and not tree):
        names = " or ".join(f.split(".", 1)[1] for f in missing)
        raise AddressError(f"{address!r}: joint {joint!r} has no {names} design variable; name the side it has")
    # a tree joint whose body j frame is the joint frame (no s_j / C_j): body j follows the joint
    return GlobalAddress(
        text, g.kind, joint, tuple(s for s, f in zip(g.sides, g.fields(), strict=True) if f not in missing)
    )


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


def resolve_changes(engine: Engine, state: State, changes: Mapping[str, Any]) -> dict[str, Any]:
    """``changes`` with every global address replaced by exact body-frame ``s'``/``C`` values
    at the current assembly of ``state`` (all computed from the same, unchanged poses)."""
    if not any(is_global(a) for a in changes):
        return dict(changes)
    _, _, P, R = engine.poses(state)
    out: dict[str, Any] = {}
    for address, value in changes.items():
        if not is_global(address):
            out[address] = value
            continue
        g = parse_global(engine, address)
        k = engine.joint_index[g.joint]
        v = _vector(address, value)
        if g.kind == "axis" and not np.linalg.norm(v) > 0:
            raise AddressError(f"{address!r}: an axis direction must be non-zero")
        for side, fld in zip(g.sides, g.fields(), strict=True):
            A = R[k, side] @ state.C[k, side].T
            if g.kind == "hardpoint":
                out[fld] = state.S[k, side] + A.T @ (v - P[k, side])
            else:
                out[fld] = A.T @ min_rotation(R[k, side][:, 2], v) @ R[k, side]
    return out


def free_addresses(engine: Engine, selectors: Sequence[str]) -> tuple[str, ...]:
    """Free-set selectors with ``hardpoint:J[.i|.j]`` / ``axis:J[.i|.j]`` replaced by the design
    addresses they move (``J.s_i``, ``J.C_j``, ...); groups and addresses pass through."""
    out: list[str] = []
    for sel in selectors:
        out += parse_global(engine, sel).fields() if is_global(sel) else [sel]
    return tuple(dict.fromkeys(out))


def free_weights(engine: Engine, weights: Mapping[str, float] | None) -> dict[str, float] | None:
    """Weights keyed like :func:`free_addresses` (a global address weighs all its fields)."""
    if not weights:
        return None
    out: dict[str, float] = {}
    for sel, w in weights.items():
        for f in free_addresses(engine, [sel]):
            out[f] = w
    return out


def hardpoint_map(engine: Engine, state: State, address: str) -> tuple[list[str], Array, list[str]]:
    """For a ``hardpoint:`` address: the design addresses it moves (``J.s_i``, ``J.s_j``), the
    matrix ``M`` (3 per address, 3) with ``d s' = M d p`` (``M = [A_i^T; A_j^T]``: exact, the
    conversion is affine in ``p``) and the column labels ``hardpoint:J.i[x]`` ... of ``p``."""
    g = parse_global(engine, address)
    if g.kind != "hardpoint":
        raise AddressError(f"{address!r}: only hardpoint: addresses have a per-length derivative (axes: use J.C_i)")
    k = engine.joint_index[g.joint]
    M = np.vstack([body_rotation(engine, state, k, s).T for s in g.sides])
    return g.fields(), M, [f"{g.text}[{c}]" for c in "xyz"]


_COMPONENT = re.compile(r"^(?P<base>hardpoint:[^\s\[\]=]+)\[(?P<c>[xyz012])\]$")
_AXIS = {"x": 0, "y": 1, "z": 2, "0": 0, "1": 1, "2": 2}


def global_columns(engine: Engine, state: State, wrt: Sequence[str]) -> tuple[list[str], dict[str, dict[str, float]]]:
    """For sensitivities per global length unit: ``wrt`` with every ``hardpoint:`` address
    replaced by the ``s'`` addresses it moves, and for each global column label
    (``hardpoint:J.i[x]``) its coefficients over the design column labels (``J.s_i[k]``):
    ``d/dp = sum_side (d/ds'_side) A_side^T`` (exact: the conversion is affine)."""
    design: list[str] = []
    combos: dict[str, dict[str, float]] = {}
    for w in wrt:
        m = _COMPONENT.match(w.strip())
        base = m["base"] if m else w.strip()
        if not (is_global(base) and base.startswith("hardpoint:")):
            design.append(w)
            continue
        fields, M, labels = hardpoint_map(engine, state, base)
        design += fields
        comps = [_AXIS[m["c"]]] if m else [0, 1, 2]
        for c in comps:
            coef: dict[str, float] = {}
            for f_i, fld in enumerate(fields):
                for k in range(3):
                    coef[f"{fld}[{k}]"] = coef.get(f"{fld}[{k}]", 0.0) + float(M[3 * f_i + k, c])
            combos[labels[c]] = coef
    return list(dict.fromkeys(design)), combos


def global_plan(engine: Engine, state: State, addresses: Sequence[str], values: Array) -> tuple[list[str], Array]:
    """A study plan with global hardpoint components (``hardpoint:J.i[z]`` factors) replaced by
    the ``s'`` component columns they set, per sample (exact, at ``state``'s assembly; the other
    components of that point stay where they are)."""
    values = np.atleast_2d(np.asarray(values, dtype=float))
    keep = [k for k, a in enumerate(addresses) if not _COMPONENT.match(a.strip())]
    addrs = [addresses[k] for k in keep]
    cols = [values[:, k] for k in keep]
    groups: dict[str, list[tuple[int, int]]] = {}
    for k, a in enumerate(addresses):
        m = _COMPONENT.match(a.strip())
        if m:
            groups.setdefault(m["base"], []).append((k, _AXIS[m["c"]]))
    _, _, P, _ = engine.poses(state)
    for base, comps in groups.items():
        g = parse_global(engine, base)
        j = engine.joint_index[g.joint]
        for side, fld in zip(g.sides, g.fields(), strict=True):
            p = np.tile(P[j, side], (values.shape[0], 1))
            for k, c in comps:
                p[:, c] = values[:, k]
            s_new = state.S[j, side] + (p - P[j, side]) @ body_rotation(engine, state, j, side)
            for c in range(3):
                addr = f"{fld}[{c}]"
                if addr in addrs or fld in addrs:
                    raise AddressError(f"{base}: {fld} is also varied directly; vary one or the other")
                addrs.append(addr)
                cols.append(s_new[:, c])
    return addrs, np.stack(cols, axis=1) if cols else np.zeros((values.shape[0], 0))


__all__ = [
    "GlobalAddress",
    "free_addresses",
    "free_weights",
    "global_columns",
    "global_plan",
    "hardpoint_map",
    "is_global",
    "min_rotation",
    "parse_global",
    "resolve_changes",
]
