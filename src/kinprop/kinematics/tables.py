"""The compiled model's flat tables: a mechanism's topology and variable layout as named
integer columns (MJX-style flat model; docs/architecture.md has the picture).

Every table has one row per item and named column constants, used by the kernels
(:mod:`kinprop.kinematics.kernels`) instead of positional magic numbers:

* ``joint`` per joint (model order): ``J_CODE`` type code, ``J_BODY_I``/``J_BODY_J``,
  ``J_QCOL``/``J_NQ`` its coordinate columns, ``J_COL_S_I``..``J_COL_L`` first layout column of
  each design field (``-1``: not a design variable);
* ``tree`` per tree joint, parent before child: ``T_JOINT``, ``T_PARENT``, ``T_CHILD``, ``T_REVERSED``;
* ``cut`` per cut joint: ``K_JOINT``, rows ``K_ROW0``/``K_NROWS``, basic constraints
  ``K_BASIC0``..``K_BASIC1``, loop-path entries ``K_PATH0``..``K_PATH1``;
* ``basic`` per basic constraint: ``B_KIND``, ``B_ON_J``; ``basic_axes`` (float) ``[a''_i, a''_j]``;
* ``path`` per loop-path entry: ``P_TREE`` (tree index), ``P_SIDE`` (0: body i's path, 1: body j's);
* ``euler`` per normalisation row: ``E_ROW``, ``E_COL`` (first Euler-parameter column);
* ``coupling`` per coupling: ``CP_ROW`` its row, ``CP_QA``/``CP_QB`` the coordinate columns
  of the driven joint a and the driving joint b, ``CP_L0`` the slot of ``c0`` in the state's
  ``L`` (``c0..c4`` at ``CP_L0..CP_L0+4``), ``CP_COL`` the first layout column of the
  coefficients; ``coupling_q0`` (float) the offsets ``[q_a0, q_b0]``;
* ``column`` per layout column: ``V_KIND`` (``VAR_Q``, ``VAR_S``, ``VAR_C``, ``VAR_L``),
  ``V_JOINT``, ``V_SIDE`` (0: ``_i``, 1: ``_j``), ``V_COMPONENT``; a coupling coefficient is a
  ``VAR_L`` column whose ``V_JOINT`` is its slot in ``L``;
* ``fixed``, ``r0``, ``A0`` per body: fixed flag and pose of fixed bodies;
* ``rigid`` per axis pair a cut joint keeps parallel (``JointType.rigid_axes``): ``R_JOINT``,
  ``R_AXIS_I``, ``R_AXIS_J``.

State of one variant (the design variables and coordinates as arrays): ``Q`` (layout q
columns), ``S`` (nj, 2, 3) = s'_i, s'_j; ``C`` (nj, 2, 3, 3) = C_i, C_j; ``L`` (nj + 5 nc,) the
joints' lengths, then each coupling's coefficients c0..c4.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from kinprop.constraints.coupling import N_COEF
from kinprop.kinematics.layout import VariableLayout
from kinprop.model.mechanism import Mechanism
from kinprop.spatial import Array
from kinprop.topology import Topology

J_CODE, J_BODY_I, J_BODY_J, J_QCOL, J_NQ, J_COL_S_I, J_COL_S_J, J_COL_C_I, J_COL_C_J, J_COL_L = range(10)
T_JOINT, T_PARENT, T_CHILD, T_REVERSED = range(4)
K_JOINT, K_ROW0, K_NROWS, K_BASIC0, K_BASIC1, K_PATH0, K_PATH1 = range(7)
B_KIND, B_ON_J = range(2)
P_TREE, P_SIDE = range(2)
E_ROW, E_COL = range(2)
V_KIND, V_JOINT, V_SIDE, V_COMPONENT = range(4)
CP_ROW, CP_QA, CP_QB, CP_L0, CP_COL = range(5)
R_JOINT, R_AXIS_I, R_AXIS_J = range(3)
VAR_Q, VAR_S, VAR_C, VAR_L = range(4)
#: design fields in the order of the J_COL_* columns and of the state's side axis
FIELDS = ("s_i", "s_j", "C_i", "C_j", "length")


class Tables(NamedTuple):
    joint: Array
    tree: Array
    cut: Array
    basic: Array
    basic_axes: Array
    path: Array
    euler: Array
    column: Array
    fixed: Array
    r0: Array
    A0: Array
    coupling: Array
    coupling_q0: Array
    #: per axis pair a cut joint keeps parallel (``JointType.rigid_axes``): ``R_JOINT``,
    #: ``R_AXIS_I``, ``R_AXIS_J`` (the solver keeps ``x''_a(i) . x''_b(j)`` on the start's side)
    rigid: Array


class RowBlock(NamedTuple):
    """Rows of Phi belonging to one cut joint or one normalisation."""

    joint: str
    kind: str  # "cut", "euler" or "coupling" (``joint`` is then the coupling's name)
    rows: slice
    labels: tuple[str, ...]


def row_blocks(mech: Mechanism, topo: Topology) -> tuple[RowBlock, ...]:
    """Each cut joint's basic constraints in joint order, then one Euler normalisation row
    ``p.p - 1`` (eq. 41) per tree joint with Euler parameters, then one row per coupling."""
    blocks, m = [], 0
    for name in topo.cut_joints:
        raw: list[str] = []
        for c in mech.joint(name).jtype.constraints():
            cname = type(c).__name__.lower()
            raw += [cname] if c.rows == 1 else [f"{cname}[{k}]" for k in range(c.rows)]
        # unique within the joint: a revolute's two dot-1 rows are dot1[3], dot1[4]
        labels = [lab if raw.count(lab) == 1 else f"{lab}[{k}]" for k, lab in enumerate(raw)]
        blocks.append(RowBlock(name, "cut", slice(m, m + len(labels)), tuple(labels)))
        m += len(labels)
    for t in topo.tree:
        if mech.joint(t.joint).jtype.euler is not None:
            blocks.append(RowBlock(t.joint, "euler", slice(m, m + 1), ("normalisation",)))
            m += 1
    for cp in mech.couplings:
        blocks.append(RowBlock(cp.name, "coupling", slice(m, m + 1), ("coupling",)))
        m += 1
    return tuple(blocks)


def build_tables(mech: Mechanism, topo: Topology, layout: VariableLayout, blocks: tuple[RowBlock, ...]) -> Tables:
    """Flat integer tables of one mechanism (structure only: no design numbers)."""
    jidx = {j.name: k for k, j in enumerate(mech.joints)}
    bidx = {b.name: k for k, b in enumerate(mech.bodies)}
    tree_names = set(topo.tree_joints)
    joint = -np.ones((len(mech.joints), 10), dtype=np.int64)
    for k, j in enumerate(mech.joints):
        jt = j.jtype
        in_tree = j.name in tree_names
        joint[k, J_CODE] = jt.code if in_tree or jt.n_cut_coordinates else -1
        joint[k, J_BODY_I], joint[k, J_BODY_J] = bidx[j.body_i], bidx[j.body_j]
        joint[k, J_NQ] = jt.n_coordinates if in_tree else jt.n_cut_coordinates
        if joint[k, J_NQ]:
            joint[k, J_QCOL] = layout[f"{j.name}.q"].start
        for f, fld in enumerate(FIELDS):
            key = f"{j.name}.{fld}"
            if key in layout:
                joint[k, J_COL_S_I + f] = layout[key].start
    tree = np.array(
        [[jidx[t.joint], bidx[t.parent], bidx[t.child], int(t.reversed)] for t in topo.tree], dtype=np.int64
    ).reshape(-1, 4)
    tpos = {t.joint: k for k, t in enumerate(topo.tree)}
    loops = {lp.cut_joint: lp for lp in topo.loops}
    by_joint = {b.joint: b for b in blocks if b.kind == "cut"}
    cut, basic, axes, path = [], [], [], []
    for name in topo.cut_joints:
        blk, lp = by_joint[name], loops[name]
        b0, p0 = len(basic), len(path)
        for c in mech.joint(name).jtype.constraints():
            basic.append([c.kind, int(c.on_j)])
            axes.append(np.concatenate(c.axes()))
        for side, p in ((0, lp.path_i), (1, lp.path_j)):
            path += [[tpos[t], side] for t in p]
        cut.append([jidx[name], blk.rows.start, blk.rows.stop - blk.rows.start, b0, len(basic), p0, len(path)])
    euler = [
        [b.rows.start, layout[f"{b.joint}.q"].start + mech.joint(b.joint).jtype.euler.start]
        for b in blocks
        if b.kind == "euler"
    ]
    column = np.zeros((layout.n, 4), dtype=np.int64)
    kinds = {"q": VAR_Q, "s": VAR_S, "C": VAR_C, "l": VAR_L, "coef": VAR_L}
    slot = {cp.name: len(mech.joints) + N_COEF * k for k, cp in enumerate(mech.couplings)}
    for v in layout.variables:
        side = 1 if v.field in ("s_j", "C_j") else 0
        for x in range(v.size):
            where = slot[v.joint] + x if v.group == "coef" else jidx[v.joint]
            column[v.start + x] = kinds[v.group], where, side, x
    crow = {b.joint: b.rows.start for b in blocks if b.kind == "coupling"}
    coupling = [
        [crow[cp.name], layout[f"{cp.joint_a}.q"].start, layout[f"{cp.joint_b}.q"].start, slot[cp.name],
         layout[f"{cp.name}.coef"].start]
        for cp in mech.couplings
    ]  # fmt: skip
    coupling_q0 = [[cp.q_a0, cp.q_b0] for cp in mech.couplings]
    rigid = [[jidx[name], a, b] for name in topo.cut_joints for a, b in mech.joint(name).jtype.rigid_axes]
    nb = len(mech.bodies)
    fixed = np.array([int(b.fixed) for b in mech.bodies], dtype=np.int64)
    r0, A0 = np.zeros((nb, 3)), np.tile(np.eye(3), (nb, 1, 1))
    for k, b in enumerate(mech.bodies):
        if b.fixed:
            r0[k], A0[k] = b.r, b.A

    def arr(x: list, width: int, dtype: type = np.int64) -> Array:
        return np.ascontiguousarray(np.array(x, dtype=dtype).reshape(-1, width))

    out = Tables(joint, tree, arr(cut, 7), arr(basic, 2), arr(axes, 6, float), arr(path, 2), arr(euler, 2),
                 column, fixed, r0, A0, arr(coupling, 5), arr(coupling_q0, 2, float), arr(rigid, 3))  # fmt: skip
    for a in out:
        a.setflags(write=False)
    return out
