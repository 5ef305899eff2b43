"""Velocity transformation matrices B, M, N of eqs. (34)-(35), as global twists.

A tree joint's variables move its child body and every descendant rigidly. Each column is
the twist ``[dr + tilde(r) dpi ; dpi]`` (the paper's state variation ``z^``) that one unit of
the variable imparts, which is the same for every body of the subtree:

* coordinates q:   ``B = [dd/dq + tilde(P_j) H ; H]``, ``H = R_i H''(q)``, ``dd/dq = R_i dd''/dq``
  (eq. 34 with the ``dd/dq`` term; P_j = r_j in the paper's convention);
* ``s'`` on the parent side: ``M = [A_p ; 0]``; on the child side ``[-A_c ; 0]``;
* ``C`` on the parent side (``xi'`` in the parent body frame): ``N = [tilde(P_a) A_p ; A_p]``,
  the paper's ``[tilde(r_j) - tilde(d_ij) ; I]`` applied to ``A_p xi'``; on the child side
  ``[-tilde(P_b) A_c ; -A_c]``.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from kinprop.kinematics.layout import VariableLayout
from kinprop.model.mechanism import Mechanism
from kinprop.spatial import Array, tilde
from kinprop.topology import Topology
from oracle.forward import Kinematics


def twist(v: Array, w: Array) -> Array:
    return np.vstack([v, w])


def tree_joint_twists(
    mech: Mechanism, topo: Topology, layout: VariableLayout, kin: Kinematics, coords: Mapping[str, Array]
) -> dict[str, list[tuple[slice, Array]]]:
    """For each tree joint, ``[(columns, 6 x n twist block), ...]`` over its layout variables."""
    out: dict[str, list[tuple[slice, Array]]] = {}
    for t in topo.tree:
        f = kin.frames[t.joint]
        Ap, Ac = kin.A[t.parent], kin.A[t.child]
        blocks: list[tuple[slice, Array]] = []
        key = f"{t.joint}.q"
        if key in layout:
            dd, H = mech.joint(t.joint).jtype.motion(coords[t.joint])
            w = f.R_i @ H
            B = twist(f.R_i @ dd + tilde(f.P_j) @ w, w)
            blocks.append((layout[key].columns, -B if t.reversed else B))
        par, chi = ("j", "i") if t.reversed else ("i", "j")
        P_par, P_chi = (f.P_j, f.P_i) if t.reversed else (f.P_i, f.P_j)
        Z = np.zeros((3, 3))
        cand = {
            f"s_{par}": twist(Ap, Z),
            f"C_{par}": twist(tilde(P_par) @ Ap, Ap),
            f"s_{chi}": twist(-Ac, Z),
            f"C_{chi}": twist(-tilde(P_chi) @ Ac, -Ac),
        }
        for field, T in cand.items():
            k = f"{t.joint}.{field}"
            if k in layout:
                blocks.append((layout[k].columns, T))
        out[t.joint] = blocks
    return out
