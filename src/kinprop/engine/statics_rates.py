"""Exact rates of the loads of an assembled state along directions of the state: design
derivatives of reactions, rod tensions, element forces and input efforts (direct method).

A direction ``xdot`` (every layout column: coordinates and design variables; the caller
makes it tangent to the constraints, ``Phi_x xdot = 0``, e.g. ``e_k + dq/dp_k`` from the
implicit-function theorem) moves every body with a twist ``V`` and every joint frame with a
twist ``U``: in the tree ``U_a = V_parent + D_a``, ``U_b = U_a + T_t qdot_t``, ``V_child = U_b
- D_b``; on a cut joint ``U_s = V_body + D_s``, where ``D_s = [A s'dot + P x A xi'dot ; A
xi'dot]`` is the frame's own design motion on its body (the kernel's M and N twists, eq. 35).

Equilibrium ``G(x, y) = Phi_q^T lambda + Q + E_D^T tau = 0`` with ``y = (lambda, tau)`` is
linear in ``y``; along ``xdot``: ``[Phi_q^T  E_D^T] ydot = -((Phi_q^T lambda)_x + Q_x) xdot``
(the terms ``(Phi_q^T lambda)_q dq/dp + (Phi_q^T lambda)_p + dQ/dp``). The right-hand side is
written analytically in the twist form of :mod:`kinprop.engine.statics`: ``G_t = T_t^T
W_sub(t)`` with ``W`` every wrench (applied, elements, cut-joint ``Z^T lambda``), so ``dG_t =
dT_t^T W_sub + T_t^T dW_sub`` with

* ``dT_t = U_i x T_t + sign Ad_i dt_loc`` (``x`` the spatial cross product, ``U_i`` joint
  frame i's twist, ``dt_loc`` the rate of the joint's local twist ``[dd'' + d'' x H'' ; H'']``
  from its coordinates' rates: universal, spherical, S-T and free joints);
* a cut joint's wrench ``[-f ; f x P_i + m_i]`` on body i and ``[f ; -f x P_j + m_j]`` on
  body j (``f = Phi_d^T lambda``, ``m = Phi_w^T lambda``) with the basic constraints' partial
  rates: dot-1 ``d(a_i x a_j)``, dot-2 ``da``, ``d(a x d)``, distance ``2 dd``, spherical 0;
* loads at material points ``dM_O = v_P x F + P x dF`` (``dF = omega x F`` in body axes); a
  wheel's contact point moves as the lowest point of the wheel circle, not with the wheel;
  elements ``d(f u)`` with ``df = -k dL`` (0 for a force held at its preload);
* Euler rows ``2 pdot lambda``; coupling rows ``lambda d(Phi_qb)``; a T-D joint's own
  column ``-(df . e + f . de)``.

The same solve as the statics (SVD of the scaled matrix; a redundant mechanism's
undetermined components stay NaN, the determined ones have exact rates). The reactions'
rates follow from ``ydot``: ``dZ^T lambda + Z^T lambda_dot`` on cut joints, minus the
subtree sums' rates on tree joints, then moved to the joint points and into joint frame i.
Every rate is batched over the directions (leading axis ``K``). Tests check each against
central differences of re-solved models (tests/engine/test_statics_rates.py).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from kinprop.engine import statics_kernels as sk
from kinprop.engine.motion import _Frames
from kinprop.engine.statics import Law, PointForces, StaticsState, _statics, _tables
from kinprop.spatial import Array

if TYPE_CHECKING:
    from kinprop.engine.engine import Engine, State


@dataclass(frozen=True)
class StaticsRates:
    """The loads (``statics``) and their rates along ``K`` directions (leading axis): the
    arrays of :class:`~kinprop.engine.statics.StaticsState` per unit of each direction (NaN
    where the value is undetermined)."""

    statics: StaticsState
    efforts: Array  # (K, nd)
    wrench: Array  # (K, nj, 2, 6) about the origin
    at_point: Array  # (K, nj, 2, 6) force, moment about the joint's point (global)
    local: Array  # (K, nj, 2, 6) the same in joint frame i's axes
    member: Array  # (K, nj)
    element_force: Array  # (K, ne)
    element_length: Array  # (K, ne)
    #: (K, nj, 2, 3) rates of the joint frames' origins (the reactions' points)
    point_rates: Array
    #: (K, nb, 6) body twists
    V: Array


def twists(engine: Engine, fr: _Frames, X: Array) -> tuple[Array, Array]:
    """``(V, U)``: body twists (K, nb, 6) and joint frame twists (K, nj, 2, 6) of the state
    directions ``X`` (K, n_columns) (module docstring)."""
    return sk.twists(engine.tables, fr.A, fr.P, fr.Tq, np.ascontiguousarray(X, dtype=float))


def statics_rates(
    engine: Engine,
    state: State,
    loads: PointForces,
    X: Array,
    driven: Sequence[int] = (),
    laws: Sequence[Law] | tuple[Array, Array] = (),
    held: Sequence[bool] | None = None,
    frames: _Frames | None = None,
) -> StaticsRates:
    """The loads of the assembled ``state`` and their exact rates along the directions ``X``
    (K, n_columns), tangent to the constraints (module docstring). ``held[k]``: element k's
    force does not change with its length (a preload given at the current pose); ``frames``:
    the kernel's evaluation of ``state`` when the caller has it."""
    X = np.ascontiguousarray(np.atleast_2d(np.asarray(X, dtype=float)))
    K = X.shape[0]
    li, lf = _tables(laws)
    ne = li.shape[0]
    held_a = np.zeros(ne, bool) if held is None else np.array(held, dtype=bool).reshape(ne)
    fr = frames if frames is not None else _Frames(engine, state)
    tb, st = engine.tables, fr.state
    nb, nj, nd = tb.fixed.shape[0], tb.joint.shape[0], len(driven)
    ss, terms = _statics(engine, fr, loads.wrenches(nb), driven, (li, lf))
    if terms is None:
        nan = np.full((K, nj, 2, 6), np.nan)
        return StaticsRates(ss, np.full((K, nd), np.nan), nan, nan, nan, np.full((K, nj), np.nan),
                            np.full((K, ne), np.nan), np.full((K, ne), np.nan), np.full((K, nj, 2, 3), np.nan),
                            np.full((K, nb, 6), np.nan))  # fmt: skip
    dtau, dwrench, dat, dloc, dmember, df_el, dL_el, vP, V = sk.rates_core(
        tb, fr.r, fr.A, fr.P, fr.R, fr.Tq, st.Q, st.L, X, ss.lam, li, lf, held_a, *loads.arrays(), terms.W, terms.cut,
        terms.U, terms.s, terms.Vt, terms.rank, terms.unscale, terms.cs, terms.wrench,
    )  # fmt: skip
    und = ss.undetermined
    if und.any():
        dloc[:, und] = np.nan
        dat[:, np.isnan(ss.at_point)] = np.nan
        dwrench[:, und.any(axis=2)] = np.nan
    dmember[:, np.isnan(ss.member)] = np.nan
    dtau = np.where(np.isnan(ss.efforts)[None], np.nan, dtau)
    return StaticsRates(ss, dtau, dwrench, dat, dloc, dmember, df_el, dL_el, vP, V)


def design_rates(
    engine: Engine,
    state: State,
    loads: PointForces,
    wrt: Sequence[int],
    driven: Sequence[int] = (),
    laws: Sequence[Law] | tuple[Array, Array] = (),
    held: Sequence[bool] | None = None,
) -> tuple[StaticsRates, Array]:
    """The loads of the assembled ``state`` and their exact derivatives with respect to the
    design columns ``wrt`` (layout columns), the ``driven`` coordinates held: one evaluation,
    the coordinates' response ``dq/dp = -Phi_q^+ Phi_p`` (minimum norm over the free
    coordinates, as :func:`kinprop.propagation.sensitivity.design_sensitivity` without
    weights) and the direct method along ``X = e_p + dq/dp``. Returns the rates and ``X``
    (len(wrt), n_columns)."""
    fr = _Frames(engine, state, design=True)
    J = fr.jacobian()
    nq = engine.n_coordinates
    keep = np.ones(nq, bool)
    keep[list(driven)] = False
    free = np.flatnonzero(keep)
    wrt = np.asarray(wrt, dtype=np.int64)
    X = np.zeros((wrt.size, engine.n_columns))
    X[np.arange(wrt.size), wrt] = 1.0
    Jf, Jp = J[:, free], J[:, wrt]
    try:  # square and regular: the one response
        if Jf.shape[0] != Jf.shape[1]:
            raise np.linalg.LinAlgError
        X[:, free] = -np.linalg.solve(Jf, Jp).T
    except np.linalg.LinAlgError:
        X[:, free] = -np.linalg.lstsq(Jf, Jp, rcond=None)[0].T
    return statics_rates(engine, state, loads, X, driven, laws, held, fr), X


__all__ = ["StaticsRates", "design_rates", "statics_rates", "twists"]
