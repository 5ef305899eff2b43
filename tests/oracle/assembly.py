"""The assembled constraint vector Phi and its Jacobian over every variable (eqs. 38-51).

Rows: each cut joint's basic constraints (in joint order), then one Euler-parameter
normalisation row ``p.p - 1`` (eq. 41) per tree joint that has Euler parameters.

For a cut joint between bodies i and j the basic-constraint partials with respect to the
joint-frame origins and rotations become, by the chain rule,

* ``Phi_z^_i = [Phi_P_i , -Phi_P_i tilde(P_i) + Phi_w_i]`` (and likewise for j), the state
  Jacobian of eq. (38) in the ``z^`` variables (PAPER-NOTES 4);
* ``Phi_s'_i = Phi_P_i A_i``, ``Phi_xi'_i = (Phi_w_i - Phi_P_i tilde(R_i u)) A_i`` (Table 1,
  with ``xi'`` in the body frame), ``Phi_l``, and the own-coordinate column
  ``Phi_P_i R_i du/dqc`` (eq. 57);

and the tree variables enter through the loop paths from the junction (eqs. 43, 49-51):
``Phi_q = Phi_z^_i sum_{path i} B + Phi_z^_j sum_{path j} B`` (and M, N alike). Tree
variables above the junction move the whole loop rigidly; dot-1, dot-2 and distance rows are
invariant to that (``Phi_z^_i + Phi_z^_j = 0``, eq. 48). Spherical rows (the gap ``d``, global
axes) are invariant only at ``d = 0``: away from assembly this Jacobian is the exact derivative
of those rows resolved in the junction body's axes — the same zeros and norm — which converges
better than the global derivative (tests/kinematics/test_jacobians.py measures both).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from kinprop.kinematics.layout import VariableLayout, build_layout
from kinprop.model.design import Design
from kinprop.model.mechanism import Mechanism
from kinprop.spatial import Array, tilde
from kinprop.topology import Topology, build_topology
from oracle.forward import Kinematics, forward_kinematics, frames_on_bodies
from oracle.transforms import tree_joint_twists


@dataclass(frozen=True)
class RowBlock:
    """Rows of Phi belonging to one cut joint or one normalisation."""

    joint: str
    kind: str  # "cut" or "euler"
    rows: slice
    labels: tuple[str, ...]


@dataclass
class Assembly:
    """Mechanism + topology + layout; evaluates Phi and its Jacobian at (design, coordinates)."""

    mechanism: Mechanism
    topology: Topology = field(init=False)
    layout: VariableLayout = field(init=False)
    row_blocks: tuple[RowBlock, ...] = field(init=False)
    n_rows: int = field(init=False)

    def __post_init__(self) -> None:
        self.topology = build_topology(self.mechanism)
        self.layout = build_layout(self.mechanism, self.topology)
        blocks, m = [], 0
        for name in self.topology.cut_joints:
            cons = self.mechanism.joint(name).jtype.constraints()
            raw = []
            for c in cons:
                cname = type(c).__name__.lower()
                raw += [cname] if c.rows == 1 else [f"{cname}[{k}]" for k in range(c.rows)]
            # unique within the joint: a revolute's two dot-1 rows are dot1[3], dot1[4]
            labels = [lab if raw.count(lab) == 1 else f"{lab}[{k}]" for k, lab in enumerate(raw)]
            blocks.append(RowBlock(name, "cut", slice(m, m + len(labels)), tuple(labels)))
            m += len(labels)
        for t in self.topology.tree:
            if self.mechanism.joint(t.joint).jtype.euler is not None:
                blocks.append(RowBlock(t.joint, "euler", slice(m, m + 1), ("normalisation",)))
                m += 1
        self.row_blocks = tuple(blocks)
        self.n_rows = m

    @property
    def row_labels(self) -> list[str]:
        return [f"{b.joint}:{lab}" for b in self.row_blocks for lab in b.labels]

    def kinematics(self, design: Design, coords: Mapping[str, Array]) -> Kinematics:
        return forward_kinematics(self.mechanism, self.topology, design, coords)

    def residual(self, design: Design, coords: Mapping[str, Array]) -> Array:
        return self.evaluate(design, coords, jacobian=False)[0]

    def evaluate(
        self, design: Design, coords: Mapping[str, Array], jacobian: bool = True
    ) -> tuple[Array, Array | None]:
        """``(Phi, Phi_x)`` with ``Phi_x`` over every layout column (None when not asked)."""
        mech, topo, layout = self.mechanism, self.topology, self.layout
        kin = self.kinematics(design, coords)
        Phi = np.zeros(self.n_rows)
        J = np.zeros((self.n_rows, layout.n)) if jacobian else None
        twists = tree_joint_twists(mech, topo, layout, kin, coords) if jacobian else {}
        loops = {lp.cut_joint: lp for lp in topo.loops}
        for blk in self.row_blocks:
            j = mech.joint(blk.joint)
            jt = j.jtype
            if blk.kind == "euler":
                p = coords[j.name][jt.euler]
                Phi[blk.rows] = p @ p - 1.0
                if J is not None:
                    c0 = layout[f"{j.name}.q"].start
                    J[blk.rows.start, c0 + jt.euler.start : c0 + jt.euler.stop] = 2.0 * p
                continue
            bi, bj = j.body_i, j.body_j
            A_i, A_j = kin.A[bi], kin.A[bj]
            f = frames_on_bodies(design, j.name, kin.r[bi], A_i, kin.r[bj], A_j)
            qc = coords.get(j.name, np.zeros(0))
            u, du = jt.cut_offset(qc)
            Ru = f.R_i @ u
            P_i = f.P_i + Ru
            d = f.P_j - P_i
            length = float(design.value(j.name, "length")) if jt.has_length else 0.0
            vals, Pd, Wi, Wj, Pl = [], [], [], [], []
            for c in jt.constraints():
                bv = c.evaluate(d, f.R_i, f.R_j, length)
                (
                    vals.append(bv.value),
                    Pd.append(bv.Phi_d),
                    Wi.append(bv.Phi_wi),
                    Wj.append(bv.Phi_wj),
                    Pl.append(bv.Phi_l),
                )
            Phi[blk.rows] = np.concatenate(vals)
            if J is None:
                continue
            Phi_Pj = np.vstack(Pd)
            Phi_Pi = -Phi_Pj
            Phi_wi, Phi_wj = np.vstack(Wi), np.vstack(Wj)
            rows = blk.rows
            own = {
                "s_i": Phi_Pi @ A_i,
                "s_j": Phi_Pj @ A_j,
                "C_i": (Phi_wi - Phi_Pi @ tilde(Ru)) @ A_i,
                "C_j": Phi_wj @ A_j,
                "length": np.concatenate(Pl)[:, None],
                "q": Phi_Pi @ f.R_i @ du,
            }
            for fld, block in own.items():
                key = f"{j.name}.{fld}"
                if key in layout:
                    J[rows, layout[key].columns] += block
            Zi = np.hstack([Phi_Pi, -Phi_Pi @ tilde(P_i) + Phi_wi])
            Zj = np.hstack([Phi_Pj, -Phi_Pj @ tilde(f.P_j) + Phi_wj])
            lp = loops[j.name]
            for path, Z in ((lp.path_i, Zi), (lp.path_j, Zj)):
                for tj in path:
                    for cols, T in twists[tj]:
                        J[rows, cols] += Z @ T
        return Phi, J


def build_assembly(mechanism: Mechanism) -> Assembly:
    return Assembly(mechanism)


__all__ = ["Assembly", "RowBlock", "build_assembly", "build_layout"]
