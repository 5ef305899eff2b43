"""Variable layout: the columns of the assembled Jacobian, addressed by name.

Columns are ordered by group — coordinates ``q`` (tree joints' relative coordinates and cut
joints' own coordinates), position vectors ``s``, orientations ``C`` (three virtual-rotation
columns ``xi'`` each, body frame), lengths ``l`` — then by joint order in the model; last the
coupling coefficients ``coef`` (``c0..c4`` of each coupling, in coupling order).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from kinprop.constraints.coupling import N_COEF
from kinprop.errors import AddressError, ModelError, Problem
from kinprop.model.design import GROUPS, parse_address
from kinprop.model.mechanism import Mechanism
from kinprop.topology import Topology

SIZES = {"s_i": 3, "s_j": 3, "C_i": 3, "C_j": 3, "length": 1}


@dataclass(frozen=True)
class Variable:
    key: str  # "J12.s_j" or "J01.q"
    joint: str  # the joint's name (a coupling's for ``coef``)
    field: str  # s_i, s_j, C_i, C_j, length, q, coef
    group: str  # q, s, C, l, coef
    start: int
    size: int

    @property
    def columns(self) -> slice:
        return slice(self.start, self.start + self.size)


@dataclass(frozen=True)
class VariableLayout:
    variables: tuple[Variable, ...]
    n: int
    #: columns of the declared inputs (driven coordinates): the group ``q`` leaves them out
    #: (held unless named), the group ``inputs`` selects them
    inputs: frozenset[int] = frozenset()

    def __post_init__(self) -> None:
        object.__setattr__(self, "_by_key", {v.key: v for v in self.variables})

    def __getitem__(self, key: str) -> Variable:
        return self._by_key[key]  # type: ignore[attr-defined]

    def __contains__(self, key: str) -> bool:
        return key in self._by_key  # type: ignore[attr-defined]

    def group(self, name: str) -> tuple[Variable, ...]:
        return tuple(v for v in self.variables if v.group == name)

    @property
    def coordinate_joints(self) -> tuple[str, ...]:
        return tuple(v.joint for v in self.variables if v.group == "q")

    def columns(self, selectors: list[str] | tuple[str, ...], exclude: set[str] = frozenset()) -> np.ndarray:
        """Column indices for groups (``q`` — the coordinates other than the declared inputs —,
        ``inputs``, ``s``, ``C``, ``l``, ``coef``) and addresses, minus the ``exclude`` variable keys."""
        cols: list[int] = []
        for sel in selectors:
            if sel in GROUPS or sel == "inputs":
                for v in self.group("q" if sel == "inputs" else sel):
                    if v.key not in exclude:
                        span = range(v.start, v.start + v.size)
                        if sel == "q":
                            cols.extend(c for c in span if c not in self.inputs)
                        elif sel == "inputs":
                            cols.extend(c for c in span if c in self.inputs)
                        else:
                            cols.extend(span)
                continue
            addr = parse_address(sel)
            if addr.key not in self:
                raise AddressError(f"{sel!r} is not a variable of this model; variables: {', '.join(self._by_key)}")  # type: ignore[attr-defined]
            v = self[addr.key]
            if v.key in exclude:
                continue
            if addr.index is None:
                cols.extend(range(v.start, v.start + v.size))
            elif addr.index < v.size:
                cols.append(v.start + addr.index)
            else:
                raise AddressError(f"{sel!r}: index out of range for a variable of size {v.size}")
        return np.array(sorted(set(cols)), dtype=int)


def build_layout(mech: Mechanism, topo: Topology) -> VariableLayout:
    tree = set(topo.tree_joints)
    rows: list[tuple[str, str, str, int]] = []
    for j in mech.joints:
        jt = j.jtype
        n = jt.n_coordinates if j.name in tree else jt.n_cut_coordinates
        if n:
            rows.append((j.name, "q", "q", n))
    for group, fields in (("s", ("s_i", "s_j")), ("C", ("C_i", "C_j")), ("l", ("length",))):
        for j in mech.joints:
            for f in fields:
                if f in j.fields:
                    rows.append((j.name, f, group, SIZES[f]))
    for c in mech.couplings:
        rows.append((c.name, "coef", "coef", N_COEF))
    variables, start = [], 0
    for joint, field, group, size in rows:
        variables.append(Variable(f"{joint}.{field}", joint, field, group, start, size))
        start += size
    layout = VariableLayout(tuple(variables), start)
    inputs: set[int] = set()
    problems = []
    for k, name in enumerate(mech.inputs):
        address = name if ".q" in name else f"{name}.q"
        if f"{address.split('[')[0]}" not in layout or address.split(".q")[0] not in tree:
            problems.append(Problem(f"inputs[{k}]", f"{name!r} is not a tree joint with coordinates to drive"))
            continue
        inputs.update(int(c) for c in layout.columns([address]))
    if problems:
        raise ModelError(problems)
    return VariableLayout(tuple(variables), start, frozenset(inputs))


def column_labels(layout: VariableLayout) -> list[str]:
    """One label per column: ``J01.q``, ``J32.q[1]``, ``J12.s_j[0]``, ``J01.C_i[2]`` (xi' component)."""
    out: list[str] = []
    for v in layout.variables:
        out += [v.key] if v.size == 1 else [f"{v.key}[{k}]" for k in range(v.size)]
    return out
