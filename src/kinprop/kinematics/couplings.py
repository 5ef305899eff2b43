"""Compiled coupling rows: ``Phi`` and the Jacobian entries of every coupling
(:mod:`kinprop.constraints.coupling`), appended by :func:`kinprop.kinematics.kernels.evaluate`.

Per coupling, in this order: ``Phi_qa`` (1), ``Phi_qb``, then ``Phi_c0 .. Phi_c4`` — seven
entries (:data:`ENTRIES`). The coordinates are layout q columns (both joints are tree joints);
the coefficients live in the state's ``L`` after the joints' lengths (``CP_L0``).
"""

from __future__ import annotations

from kinprop.constraints.coupling import N_COEF, coupling_value
from kinprop.jit import inlined
from kinprop.kinematics.tables import CP_COL, CP_L0, CP_QA, CP_QB, CP_ROW

#: Jacobian entries per coupling row: q_a, q_b, c0..c4
ENTRIES = 2 + N_COEF


@inlined
def coupling_rows(tb, Q, L, Phi, vals, need, rows, cols, record, k):
    """Write every coupling's row of ``Phi`` and its entries from entry ``k`` on (same ``need``
    and ``record`` rules as ``evaluate``); returns the next entry index."""
    for i in range(tb.coupling.shape[0]):
        row, qa, qb = tb.coupling[i, CP_ROW], tb.coupling[i, CP_QA], tb.coupling[i, CP_QB]
        l0, col = tb.coupling[i, CP_L0], tb.coupling[i, CP_COL]
        x = Q[qb] - tb.coupling_q0[i, 1]
        phi, phi_qb = coupling_value(Q[qa], Q[qb], tb.coupling_q0[i, 0], tb.coupling_q0[i, 1], L[l0 : l0 + N_COEF])
        Phi[row] = phi
        if need[qa]:
            vals[k] = 1.0
            if record:
                rows[k], cols[k] = row, qa
        if need[qb]:
            vals[k + 1] = phi_qb
            if record:
                rows[k + 1], cols[k + 1] = row, qb
        k += 2
        xk = 1.0
        for m in range(N_COEF):
            if need[col]:
                vals[k] = -xk
                if record:
                    rows[k], cols[k] = row, col + m
            k += 1
            xk *= x
    return k


__all__ = ["ENTRIES", "coupling_rows"]
