"""The coupling constraint between two joint coordinates (MuJoCo's ``<equality><joint>``).

With ``x = q_b - q_b0`` and coefficients ``c0..c4`` (a design variable)::

    Phi     = (q_a - q_a0) - (c0 + c1 x + c2 x^2 + c3 x^3 + c4 x^4)
    Phi_qa  = 1
    Phi_qb  = -(c1 + 2 c2 x + 3 c3 x^2 + 4 c4 x^3)
    Phi_ck  = -x^k

One row; a linear gear ratio ``q_a = r q_b`` is ``c = (0, r, 0, 0, 0)``. The row is in the
unit of ``q_a`` (radians for a revolute, the length unit for a slide).
"""

from __future__ import annotations

from kinprop.jit import kernel

#: number of polynomial coefficients (c0..c4, MuJoCo's ``polycoef``)
N_COEF = 5


@kernel
def coupling_value(qa, qb, qa0, qb0, c):
    """``(Phi, Phi_qb)`` of one coupling row at coordinates ``qa``, ``qb`` with coefficients
    ``c`` (5 numbers); ``Phi_qa = 1`` and ``Phi_ck = -(qb - qb0)^k``."""
    x = qb - qb0
    p, dp, xk = 0.0, 0.0, 1.0
    for m in range(N_COEF):
        p += c[m] * xk
        if m + 1 < N_COEF:
            dp += (m + 1) * c[m + 1] * xk
        xk *= x
    return (qa - qa0) - p, -dp


__all__ = ["N_COEF", "coupling_value"]
