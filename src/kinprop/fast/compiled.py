"""Compile a mechanism once into flat index tables; pack designs into batched state arrays.

:func:`compile_model` turns the topology and variable layout of an
:class:`~kinprop.kinematics.Assembly` into integer tables (see :mod:`kinprop.fast.kernels`);
:func:`pack` turns one or many ``(Design, coordinates)`` pairs into arrays with a leading
variant axis, and :func:`unpack` turns one variant back into ``(Design, coordinates)``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from kinprop.constraints.basic import Distance, Dot1, Dot2, Spherical
from kinprop.fast import kernels as kn
from kinprop.kinematics.assembly import Assembly
from kinprop.model.design import Design, as_coordinates
from kinprop.model.mechanism import Mechanism
from kinprop.propagation.propagate import assembly_for
from kinprop.spatial import Array

CODES = {
    "revolute": kn.REVOLUTE,
    "translational": kn.PRISMATIC,
    "cylindrical": kn.CYLINDRICAL,
    "universal": kn.UNIVERSAL,
    "spherical": kn.SPHERICAL,
    "fixed": kn.FIXED,
    "free": kn.FREE,
    "spherical-translational": kn.ST,
    "translational-distance": kn.TD,
    "revolute-spherical": kn.CUTONLY,
    "dot-1": kn.CUTONLY,
    "dot-2": kn.CUTONLY,
    "spherical-point": kn.CUTONLY,
    "distance": kn.CUTONLY,
}
STATUS = {
    kn.CONVERGED: "converged",
    kn.NOT_CONVERGED: "not_converged",
    kn.DIVERGED: "diverged",
    kn.NO_FREE: "no_free",
    kn.SINGULAR: "singular",
}
_FIELD_SLOT = {"s_i": 0, "s_j": 1, "C_i": 2, "C_j": 3, "length": 4}


class NotCompilableError(ValueError):
    """The mechanism uses a joint type the fast path does not know (use the reference)."""


@dataclass
class State:
    """Batched state: ``Q`` (N, nq) coordinates, ``S`` (N, nj, 2, 3), ``C`` (N, nj, 2, 3, 3), ``L`` (N, nj)."""

    Q: Array
    S: Array
    C: Array
    L: Array

    @property
    def size(self) -> int:
        return int(self.Q.shape[0])

    def copy(self) -> State:
        return State(self.Q.copy(), self.S.copy(), self.C.copy(), self.L.copy())

    def take(self, index: slice | Array) -> State:
        return State(self.Q[index], self.S[index], self.C[index], self.L[index])


@dataclass
class Compiled:
    """Flat tables of one mechanism (structure only: no design numbers)."""

    assembly: Assembly
    jint: Array
    tint: Array
    cint: Array
    bint: Array
    bflt: Array
    pint: Array
    eint: Array
    fixed: Array
    r0: Array
    A0: Array
    colinfo: Array
    rows: Array
    cols: Array
    m: int
    n: int
    nq: int
    joint_index: dict[str, int] = field(repr=False)

    @property
    def tables(self) -> tuple[Array, ...]:
        return (
            self.jint,
            self.tint,
            self.cint,
            self.bint,
            self.bflt,
            self.pint,
            self.eint,
            self.fixed,
            self.r0,
            self.A0,
        )

    @property
    def mechanism(self) -> Mechanism:
        return self.assembly.mechanism

    def free_columns(self, free: Sequence[str] = ("q",), exclude: set[str] | frozenset[str] = frozenset()) -> Array:
        """Layout column indices of ``free`` (groups or addresses) minus the ``exclude`` keys."""
        return self.assembly.layout.columns(list(free), exclude=set(exclude)).astype(np.int64)

    def column(self, address: str) -> int:
        """Layout column of a scalar address (``J.q[0]``, ``J.s_i[2]``, ``J.length``)."""
        cols = self.assembly.layout.columns([address])
        if cols.size != 1:
            raise ValueError(f"{address!r} is not a scalar variable (give a component, e.g. {address}[0])")
        return int(cols[0])


def _basic(c: object) -> tuple[int, int, Array, Array]:
    z = np.zeros(3)
    if isinstance(c, Dot1):
        return kn.DOT1, 0, np.asarray(c.a_i, float), np.asarray(c.a_j, float)
    if isinstance(c, Dot2):
        return kn.DOT2, int(c.on == "j"), np.asarray(c.a, float), z
    if isinstance(c, Spherical):
        return kn.SPH, 0, z, z
    if isinstance(c, Distance):
        return kn.DIST, 0, z, z
    raise NotCompilableError(f"basic constraint {type(c).__name__} has no fast kernel")


def compile_model(mechanism: Mechanism) -> Compiled:
    """Build the flat tables of ``mechanism`` (topology and layout from the cached Assembly)."""
    asm = assembly_for(mechanism)
    topo, layout = asm.topology, asm.layout
    joints = mechanism.joints
    jidx = {j.name: k for k, j in enumerate(joints)}
    bidx = {b.name: k for k, b in enumerate(mechanism.bodies)}
    tree_names = set(topo.tree_joints)
    jint = -np.ones((len(joints), 10), dtype=np.int64)
    for k, j in enumerate(joints):
        if j.type not in CODES and j.jtype.name not in CODES:
            raise NotCompilableError(f"joint type {j.type!r} has no fast kernel")
        code = CODES.get(j.jtype.name, kn.CUTONLY)
        if j.name not in tree_names and code != kn.TD:
            code = kn.CUTONLY
        jint[k, 0:3] = code, bidx[j.body_i], bidx[j.body_j]
        nq = j.jtype.n_coordinates if j.name in tree_names else j.jtype.n_cut_coordinates
        jint[k, 4] = nq
        if nq:
            jint[k, 3] = layout[f"{j.name}.q"].start
        for f, slot in _FIELD_SLOT.items():
            key = f"{j.name}.{f}"
            if key in layout:
                jint[k, 5 + slot] = layout[key].start
    tint = np.array(
        [[jidx[t.joint], bidx[t.parent], bidx[t.child], int(t.reversed)] for t in topo.tree], dtype=np.int64
    ).reshape(-1, 4)
    tpos = {t.joint: k for k, t in enumerate(topo.tree)}
    loops = {lp.cut_joint: lp for lp in topo.loops}
    blocks = {b.joint: b for b in asm.row_blocks if b.kind == "cut"}
    cint, bint, bflt, pint = [], [], [], []
    for name in topo.cut_joints:
        j = mechanism.joint(name)
        blk, lp = blocks[name], loops[name]
        b0, p0 = len(bint), len(pint)
        for c in j.jtype.constraints():
            kind, on, ai, aj = _basic(c)
            bint.append([kind, on])
            bflt.append(np.concatenate([ai, aj]))
        for side, path in ((0, lp.path_i), (1, lp.path_j)):
            pint += [[tpos[t], side] for t in path]
        cint.append([jidx[name], blk.rows.start, blk.rows.stop - blk.rows.start, b0, len(bint), p0, len(pint)])
    eint = []
    for b in asm.row_blocks:
        if b.kind == "euler":
            jt = mechanism.joint(b.joint).jtype
            eint.append([b.rows.start, layout[f"{b.joint}.q"].start + jt.euler.start])
    nb = len(mechanism.bodies)
    fixed = np.array([int(b.fixed) for b in mechanism.bodies], dtype=np.int64)
    r0 = np.zeros((nb, 3))
    A0 = np.tile(np.eye(3), (nb, 1, 1))
    for k, b in enumerate(mechanism.bodies):
        if b.fixed:
            r0[k], A0[k] = b.r, b.A
    colinfo = np.zeros((layout.n, 4), dtype=np.int64)
    nq = 0
    for v in layout.variables:
        kind = {"q": 0, "s": 1, "C": 2, "l": 3}[v.group]
        side = 1 if v.field in ("s_j", "C_j") else 0
        for x in range(v.size):
            colinfo[v.start + x] = kind, jidx[v.joint], side, x
        if kind == 0:
            nq = max(nq, v.start + v.size)

    def arr(x: list, width: int, dtype: type = np.int64) -> Array:
        return np.array(x, dtype=dtype).reshape(-1, width)

    comp = Compiled(
        asm, jint, tint, arr(cint, 7), arr(bint, 2), arr(bflt, 6, float), arr(pint, 2), arr(eint, 2),
        fixed, r0, A0, colinfo, np.zeros(0, np.int64), np.zeros(0, np.int64), asm.n_rows, layout.n, nq, jidx,
    )  # fmt: skip
    st = pack(comp, mechanism_default_design(comp), {})
    Phi = np.zeros(comp.m)
    nnz = kn.evaluate_entries(comp.tables, st.Q[0], st.S[0], st.C[0], st.L[0], Phi, np.zeros(0), False)
    comp.rows, comp.cols = kn.structure(comp.tables, st.Q[0], st.S[0], st.C[0], st.L[0], comp.m, nnz)
    return comp


def mechanism_default_design(comp: Compiled) -> Design:
    """A placeholder design (zeros, identities, unit lengths) for structure passes."""
    vals: dict[str, object] = {}
    for v in comp.assembly.layout.variables:
        if v.group == "s":
            vals[v.key] = np.zeros(3)
        elif v.group == "C":
            vals[v.key] = np.eye(3)
        elif v.group == "l":
            vals[v.key] = 1.0
    return Design(vals)


def pack(
    comp: Compiled, designs: Design | Sequence[Design], coords: Mapping[str, Array] | Sequence[Mapping[str, Array]]
) -> State:
    """Batched state arrays from one or many designs and coordinate mappings (broadcast)."""
    ds = [designs] if isinstance(designs, Design) else list(designs)
    cs = [coords] if isinstance(coords, Mapping) else list(coords)
    N = max(len(ds), len(cs))
    if len(ds) not in (1, N) or len(cs) not in (1, N):
        raise ValueError(f"designs ({len(ds)}) and coordinates ({len(cs)}) do not broadcast")
    mech, layout = comp.mechanism, comp.assembly.layout
    nj = len(mech.joints)
    S = np.zeros((len(ds), nj, 2, 3))
    C = np.zeros((len(ds), nj, 2, 3, 3))
    L = np.zeros((len(ds), nj))
    for d_k, d in enumerate(ds):
        for k, j in enumerate(mech.joints):
            S[d_k, k, 0], S[d_k, k, 1] = d.value(j.name, "s_i"), d.value(j.name, "s_j")
            C[d_k, k, 0], C[d_k, k, 1] = d.value(j.name, "C_i"), d.value(j.name, "C_j")
            if j.jtype.has_length and f"{j.name}.length" in d:
                L[d_k, k] = float(d[f"{j.name}.length"])
    Q = np.zeros((len(cs), comp.nq))
    for c_k, c in enumerate(cs):
        for v in layout.group("q"):
            jt = mech.joint(v.joint).jtype
            val = c.get(v.joint)
            if val is None:
                val = jt.default_coordinates() if v.size == jt.n_coordinates else jt.default_cut_coordinates()
            Q[c_k, v.columns] = val
    return State(
        np.array(np.broadcast_to(Q, (N, comp.nq))),
        np.array(np.broadcast_to(S, (N, nj, 2, 3))),
        np.array(np.broadcast_to(C, (N, nj, 2, 3, 3))),
        np.array(np.broadcast_to(L, (N, nj))),
    )


def unpack(comp: Compiled, state: State, k: int = 0) -> tuple[Design, Mapping[str, Array]]:
    """Variant ``k`` of a state as ``(Design, coordinates)``."""
    mech, layout = comp.mechanism, comp.assembly.layout
    vals: dict[str, object] = {}
    coords: dict[str, Array] = {}
    for v in layout.variables:
        j = comp.joint_index[v.joint]
        if v.group == "q":
            coords[v.joint] = state.Q[k, v.columns].copy()
        elif v.group == "s":
            vals[v.key] = state.S[k, j, 1 if v.field == "s_j" else 0].copy()
        elif v.group == "C":
            vals[v.key] = state.C[k, j, 1 if v.field == "C_j" else 0].copy()
        else:
            vals[v.key] = float(state.L[k, j])
    del mech
    return Design(vals), as_coordinates(coords)
