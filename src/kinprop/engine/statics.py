"""Kinetostatics of an assembled state (Haug, *Computer-Aided Kinematics and Dynamics of
Mechanical Systems*, 1989, sec. 6.3 (equilibrium), 6.6 (reaction forces)), on the compiled
kernel's Jacobian and tree twists: one formulation of the kinematics, nothing differenced.

**Generalised forces.** A wrench ``W = [F ; M_O]`` on body ``b`` (force, and moment about the
global origin: ``M_O = M + P x F`` for a force ``F`` at ``P`` with a couple ``M``) does the
virtual work ``V_b . W`` with ``V_b = [v_O ; omega]`` the body's twist. With the kernel's tree
twists ``T_t`` (eq. 34, ``V_child = V_parent + T_t dq_t``) the generalised force on the
coordinates of tree joint ``t`` is ``Q_t = T_t^T W_sub(t)``, ``W_sub(t)`` the sum of the
wrenches on the subtree beyond ``t`` (accumulated from the leaves: one backward pass).

**Equilibrium.** ``Phi_q^T lambda + Q + E_D^T tau = 0`` (Haug eq. 6.3.5 with the driven
coordinates' efforts ``tau``: ``E_D`` picks their columns). ``tau`` is the generalised force
the input applies to its coordinate (a torque about a revolute's axis, a force along a slide;
positive in the direction of increasing ``q``) to hold the pose: by virtual work ``tau = -Q .
dq/dq_D``. Solved by SVD of ``[Phi_q^T  E_D^T]`` (rows and columns scaled as the solver
scales them); when ``Q`` is not in its range the inputs do not hold the loads (status
``unbalanced``: a free motion, a singular pose or too few inputs; :class:`kinprop.Status` and
its one message table, :func:`kinprop.engine.status.message`).

**Reactions.** The rows of a cut joint depend on the poses of its bodies ``i`` and ``j``
through ``d = P_j - P_i`` (``P_i`` moved along ``z''_i`` by a T-D joint's own coordinate)
and the frames' virtual rotations; their partials with respect to the bodies' twists are
``Z_i = [-Phi_d , Phi_d x P_i + Phi_wi]`` and ``Z_j = [Phi_d , -Phi_d x P_j + Phi_wj]`` (the
rows the kernel chains with ``T_t`` into ``Phi_q``, from the same basic-constraint rows), so
the constraint wrench on body ``i`` is ``Z_i^T lambda`` and on ``j`` ``Z_j^T lambda``. A tree
joint has no multipliers: the wrench it transmits onto its child body is minus the sum of
every other wrench (applied, element, cut-joint) on the subtree beyond it (Newton-Euler
recursion from the leaves); it includes the input effort and coupling torques along the
joint's free directions. Every joint's wrench on its body ``i`` is minus the one on ``j``.

**Redundancy.** When ``[Phi_q^T  E_D^T]`` has a null space (self-stress states: redundant
constraints or inputs) the multipliers are not unique. Each null vector is a set of reactions
in equilibrium with no load; a reported component that any of them changes is *undetermined*
(NaN, and named); the others are the same for every solution and are reported.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from kinprop.constraints.basic import DISTANCE, ROWS, basic_rows
from kinprop.engine.motion import _Frames, cross3, motion_state, spatial_cross
from kinprop.engine.status import Status, message
from kinprop.joints.composite import TD_CODE
from kinprop.kinematics.tables import (
    B_KIND,
    B_ON_J,
    J_BODY_I,
    J_BODY_J,
    J_CODE,
    J_NQ,
    J_QCOL,
    K_BASIC0,
    K_BASIC1,
    K_JOINT,
    K_ROW0,
    T_CHILD,
    T_JOINT,
    T_PARENT,
    T_REVERSED,
)
from kinprop.model.elements import Element, TorsionSpring
from kinprop.spatial import Array

if TYPE_CHECKING:
    from kinprop.engine.engine import Engine, State

#: relative singular value below which a direction of [Phi_q^T E_D^T] counts as null
RANK_RTOL = 1e-10
#: relative size above which a self-stress state changes a component (undetermined)
UNDETERMINED_RTOL = 1e-7
OK, UNBALANCED, NOT_ASSEMBLED = Status.OK, Status.UNBALANCED, Status.NOT_ASSEMBLED
#: scaled residual norm above which a state is not an assembly (its loads would mean nothing)
ASSEMBLED_TOL = 1e-6


@dataclass(frozen=True)
class ElementLaw:
    """A two-point force element: ends ``s_i`` on ``body_i``, ``s_j`` on ``body_j`` (body
    frames); force (positive: pushing the ends apart) ``f = f0 + k (L0 - L)`` at length ``L``
    (a damper at rest: ``k = f0 = 0``)."""

    body_i: int
    body_j: int
    s_i: Array
    s_j: Array
    k: float
    L0: float
    f0: float


@dataclass(frozen=True)
class TorsionLaw:
    """A torsion spring on a tree joint's angle (layout column ``col``, about the joint's
    ``z''``): torque ``T = T0 + k (theta0 - q)`` (per radian) turning ``body_j`` towards
    increasing ``q``, and ``body_i`` the other way (a couple pair ``+-T z''``)."""

    joint: int
    body_i: int
    body_j: int
    col: int
    k: float
    theta0: float
    T0: float


#: a force element's law
Law = ElementLaw | TorsionLaw


@dataclass(frozen=True)
class StaticsState:
    """Loads of one assembled state (solver units: the model's length and force units; the
    efforts of angular coordinates are torques, force x length per radian)."""

    #: ``ok``, ``unbalanced`` or ``not_assembled`` (:class:`kinprop.Status`)
    status: Status
    message: str
    #: multipliers of every row (NaN where undetermined is not tracked: use the reactions)
    lam: Array
    #: driven layout columns and the effort at each (NaN: undetermined)
    driven: tuple[int, ...]
    efforts: Array
    #: (nj, 2, 6) wrench each joint applies to its body i (``[:, 0]``) and body j (``[:, 1]``),
    #: ``[F ; M_O]`` about the global origin, global axes (NaN: undetermined)
    wrench: Array
    #: (nj, 2, 6) force and moment about the joint's point on each body, in joint frame i's
    #: axes (NaN where undetermined)
    local: Array
    #: (nj, 2, 6) the same in global axes (NaN where undetermined)
    at_point: Array
    #: (nj, 2, 6) True where that component is not determined by the loads (self-stress)
    undetermined: Array
    #: (nb, 6) applied wrench on each body (loads and elements), about the origin
    applied: Array
    #: element forces (positive: pushing the ends apart; a torsion spring's torque) and lengths
    #: (a torsion spring's angle, radians), by element
    element_force: Array
    element_length: Array
    #: (ne, 2, 3) element end points (global)
    element_ends: Array
    #: (nj,) axial force of the rod of every joint with a distance row (distance,
    #: revolute-spherical, translational-distance: ``-2 lambda |d|``), tension positive; NaN
    #: for the other joints and where undetermined
    member: Array
    #: self-stress basis: reactions (nj, 2, 6) of each null vector, and their count
    self_stress: Array
    r: Array
    A: Array
    P: Array
    R: Array
    #: ``||Phi||`` of the state (scaled as the solver's test, :attr:`kinprop.Solution.residual`)
    residual: float = 0.0

    @property
    def ok(self) -> bool:
        return self.status is OK

    def joint_point(self, j: int, side: int) -> Array:
        """Where the joint acts on its body ``side`` (the hardpoint ``P_i``/``P_j``)."""
        return self.P[j, side]


def _cut_rows(engine: Engine, fr_P: Array, fr_R: Array, Q: Array, L: Array, c: int) -> tuple[Array, ...]:
    """``(P_i, d, Phi_d, Phi_wi, Phi_wj)`` of cut joint ``c`` from the compiled basic-constraint
    rows (``P_i`` slid along ``z''_i`` by a T-D joint's own coordinate, ``d = P_j - P_i``)."""
    tb = engine.tables
    j = tb.cut[c, K_JOINT]
    Pi = fr_P[j, 0].copy()
    if tb.joint[j, J_CODE] == TD_CODE:
        Pi = Pi + fr_R[j, 0, :, 2] * Q[tb.joint[j, J_QCOL]]
    d = fr_P[j, 1] - Pi
    kinds = [tb.basic[b, B_KIND] for b in range(tb.cut[c, K_BASIC0], tb.cut[c, K_BASIC1])]
    m = sum(ROWS[k] for k in kinds)
    Phi, Pd, Wi, Wj, Pl = np.zeros(m), np.zeros((m, 3)), np.zeros((m, 3)), np.zeros((m, 3)), np.zeros(m)
    r = 0
    for b in range(tb.cut[c, K_BASIC0], tb.cut[c, K_BASIC1]):
        r += basic_rows(tb.basic[b, B_KIND], tb.basic[b, B_ON_J], tb.basic_axes[b], d, fr_R[j, 0], fr_R[j, 1],
                        L[j], r, Phi, Pd, Wi, Wj, Pl)  # fmt: skip
    return Pi, d, Pd, Wi, Wj


def _skew(p: Array) -> Array:
    """``S`` with ``a x p = a S`` for row vectors ``a``."""
    x, y, z = float(p[0]), float(p[1]), float(p[2])
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def cut_arms(Pi: Array, d: Array, Pd: Array, Wi: Array, Wj: Array) -> tuple[Array, Array]:
    """``(Z_i, Z_j)`` (m, 6): a cut joint's rows' partials with respect to the twists of its
    bodies (module docstring), from :func:`_cut_rows`."""
    return np.hstack([-Pd, Pd @ _skew(Pi) + Wi]), np.hstack([Pd, Wj - Pd @ _skew(Pi + d)])


def _cut_partials(engine: Engine, fr_P: Array, fr_R: Array, Q: Array, L: Array, c: int) -> tuple[Array, Array]:
    """``(Z_i, Z_j)`` (m, 6) of cut joint ``c`` (module docstring)."""
    return cut_arms(*_cut_rows(engine, fr_P, fr_R, Q, L, c))


def distance_rows(engine: Engine, P: Array, R: Array, Q: Array) -> list[tuple[int, int, float]]:
    """``(joint, row, |d|)`` of every cut joint's distance row (its rod's length now)."""
    tb = engine.tables
    out = []
    for c in range(tb.cut.shape[0]):
        j, r = tb.cut[c, K_JOINT], tb.cut[c, K_ROW0]
        Pi = P[j, 0] + (R[j, 0, :, 2] * Q[tb.joint[j, J_QCOL]] if tb.joint[j, J_CODE] == TD_CODE else 0.0)
        for b in range(tb.cut[c, K_BASIC0], tb.cut[c, K_BASIC1]):
            kind = tb.basic[b, B_KIND]
            if kind == DISTANCE:
                out.append((int(j), int(r), float(np.linalg.norm(P[j, 1] - Pi))))
            r += ROWS[kind]
    return out


def subtree_sums(engine: Engine, W: Array) -> Array:
    """``W_sub`` (..., nb, 6): each body's wrench plus those of every body below it in the tree."""
    tb = engine.tables
    Ws = np.array(W, dtype=float)
    for t in range(tb.tree.shape[0] - 1, -1, -1):
        Ws[..., tb.tree[t, T_PARENT], :] += Ws[..., tb.tree[t, T_CHILD], :]
    return Ws


def generalized_forces(engine: Engine, Tq: Array, W: Array) -> Array:
    """``Q`` (n_q,) of body wrenches ``W`` (nb, 6) about the origin: ``Q_t = T_t^T W_sub(t)``."""
    tb = engine.tables
    Ws = subtree_sums(engine, W)
    Qg = np.zeros(engine.n_coordinates)
    for t in range(tb.tree.shape[0]):
        j = tb.tree[t, T_JOINT]
        q0, nq = tb.joint[j, J_QCOL], tb.joint[j, J_NQ]
        if nq > 0:
            Qg[q0 : q0 + nq] = Tq[t, :, :nq].T @ Ws[tb.tree[t, T_CHILD]]
    return Qg


def element_state(
    laws: Sequence[Law], r: Array, A: Array, Q: Array | None = None, P: Array | None = None, R: Array | None = None
) -> tuple[Array, Array, Array, Array]:
    """Forces, lengths, end points (ne, 2, 3) of the elements and their wrenches (nb, 6); a
    torsion spring (its torque, its angle, its joint's points) needs the coordinates ``Q`` and
    the joint frames ``P``, ``R``."""
    f, lengths, ends = np.zeros(len(laws)), np.zeros(len(laws)), np.zeros((len(laws), 2, 3))
    W = np.zeros((r.shape[0], 6))
    for k, e in enumerate(laws):
        if isinstance(e, TorsionLaw):
            if Q is None or P is None or R is None:
                raise ValueError("a torsion spring needs the coordinates and the joint frames")
            q = float(Q[e.col])
            f[k], lengths[k], ends[k] = e.T0 + e.k * (e.theta0 - q), q, P[e.joint]
            M = f[k] * R[e.joint, 0, :, 2]
            W[e.body_j, 3:] += M
            W[e.body_i, 3:] -= M
            continue
        Pi, Pj = r[e.body_i] + A[e.body_i] @ e.s_i, r[e.body_j] + A[e.body_j] @ e.s_j
        d = Pj - Pi
        length = math.sqrt(float(d @ d))
        f[k], lengths[k], ends[k] = e.f0 + e.k * (e.L0 - length), length, (Pi, Pj)
        if f[k] != 0.0:
            if length == 0.0:
                raise ValueError("an element with a force has zero length: its direction is undefined")
            F = f[k] * d / length  # on body j, pushing it away from i
            W[e.body_j] += np.concatenate([F, cross3(Pj, F)])
            W[e.body_i] -= np.concatenate([F, cross3(Pi, F)])
    return f, lengths, ends, W


def element_laws(
    engine: Engine,
    elements: Sequence[Element],
    reference: State | None = None,
    torsion: Sequence[TorsionSpring] = (),
    angle_unit: float = 1.0,
) -> list[Law]:
    """The force laws of model elements, then of torsion springs; a ``preload`` is the force
    (torque) at the ``reference`` state's length (angle) (default: the engine's reference),
    ``free_length`` the length at zero force. ``angle_unit``: radians per unit of a torsion
    spring's ``free_angle`` (its stiffness is per that unit)."""
    laws: list[Law] = []
    r = A = None
    for e in elements:
        bi, bj = engine.body_index[e.body_i], engine.body_index[e.body_j]
        s_i, s_j = np.asarray(e.s_i, float), np.asarray(e.s_j, float)
        k = float(e.stiffness or 0.0) if e.has_spring else 0.0
        if not e.has_spring:
            laws.append(ElementLaw(bi, bj, s_i, s_j, 0.0, 0.0, 0.0))
        elif e.free_length is not None:
            laws.append(ElementLaw(bi, bj, s_i, s_j, k, float(e.free_length), 0.0))
        else:
            if r is None:
                st = reference if reference is not None else engine.reference
                if st is None:
                    raise ValueError("a preloaded element needs the reference state its preload is given at")
                r, A, _, _ = engine.poses(st)
            length = float(np.linalg.norm(r[bj] + A[bj] @ s_j - r[bi] - A[bi] @ s_i))
            laws.append(ElementLaw(bi, bj, s_i, s_j, k, length, float(e.preload or 0.0)))
    tb = engine.tables
    for t in torsion:
        j = engine.mechanism.joint_names.index(t.joint)
        if tb.joint[j, J_NQ] <= 0:
            raise ValueError(f"torsion spring {t.name!r}: joint {t.joint!r} is cut (it has no angle coordinate); "
                             "keep it in the tree (cut: false)")  # fmt: skip
        col = int(tb.joint[j, J_QCOL])
        if t.free_angle is not None:
            theta0, T0 = float(t.free_angle) * angle_unit, 0.0
        else:
            st = reference if reference is not None else engine.reference
            if st is None:
                raise ValueError("a preloaded torsion spring needs the reference state its preload is given at")
            theta0, T0 = float(st.Q[col]), float(t.preload or 0.0)
        laws.append(TorsionLaw(j, int(tb.joint[j, J_BODY_I]), int(tb.joint[j, J_BODY_J]), col,
                               float(t.stiffness) / angle_unit, theta0, T0))  # fmt: skip
    return laws


@dataclass(frozen=True)
class PointForces:
    """Applied loads as forces and couples at body points (global axes at the current pose):
    ``body`` (n,), ``P`` (n, 3) points, ``F`` (n, 3), ``M`` (n, 3); ``follows`` (n,) True when
    the components are fixed in the body's axes (they turn with it), False when global."""

    body: Array
    P: Array
    F: Array
    M: Array
    follows: Array
    #: wheel loads (None: every point is a material point): ``radius`` (n,) > 0 where the
    #: point is a wheel's contact point (the lowest point of the circle of that radius about
    #: ``centre`` (n, 3) in the plane normal to the unit spin ``axis`` (n, 3)), ``sae`` (n,)
    #: True where down is +z (the lowest point of the z-mirrored circle)
    radius: Array | None = None
    centre: Array | None = None
    axis: Array | None = None
    sae: Array | None = None

    @classmethod
    def empty(cls) -> PointForces:
        z = np.zeros((0, 3))
        return cls(np.zeros(0, np.int64), z, z, z, np.zeros(0, bool))

    def wrenches(self, nb: int) -> Array:
        """(nb, 6) ``[F ; M + P x F]`` summed by body."""
        W = np.zeros((nb, 6))
        for k in range(self.body.shape[0]):
            W[self.body[k]] += np.concatenate([self.F[k], self.M[k] + cross3(self.P[k], self.F[k])])
        return W


def _cross(a: Array, b: Array) -> Array:
    """Cross products on the last axis (broadcast; numpy's ``cross`` costs several times more
    on these small stacks)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def _velocity(T: Array, P: Array) -> Array:
    """(K, 3) velocity of the point now at ``P`` moving with twists ``T`` (K, 6)."""
    return T[:, :3] + _cross(T[:, 3:], P)


def load_rates(loads: PointForces, V: Array) -> Array:
    """(K, nb, 6) rates of the applied wrenches about the origin under body twists ``V``
    (K, nb, 6): a force at a material point P has ``dM_O = v_P x F + P x dF`` (``dF = omega x F``
    in body axes); a wheel load's contact point moves as :func:`contact_rate` says."""
    dW = np.zeros(V.shape)
    for k in range(loads.body.shape[0]):
        b, P, F, M = loads.body[k], loads.P[k], loads.F[k], loads.M[k]
        w = V[:, b, 3:]
        if loads.radius is not None and loads.radius[k] > 0.0:
            vP = contact_rate(loads, k, V[:, b])
        else:
            vP = _velocity(V[:, b], P)
        dF = _cross(w, F) if loads.follows[k] else np.zeros_like(w)
        dM = _cross(w, M) if loads.follows[k] else np.zeros_like(w)
        dW[:, b, :3] += dF
        dW[:, b, 3:] += dM + _cross(vP, F) + _cross(P, dF)
    return dW


def contact_rate(loads: PointForces, k: int, Vb: Array) -> Array:
    """(K, 3) velocity of wheel load ``k``'s contact point (the lowest point of the wheel circle
    ``centre + radius n``, ``n`` along ``-z`` projected onto the wheel plane; in SAE axes the
    lowest point of the z-mirrored circle) under the wheel body's twists ``Vb`` (K, 6)."""
    assert loads.radius is not None and loads.centre is not None and loads.axis is not None
    flip = np.array([1.0, 1.0, -1.0]) if loads.sae[k] else np.ones(3)
    c, a = loads.centre[k], loads.axis[k]
    vc, da = flip * _velocity(Vb, c), flip * _cross(Vb[:, 3:], a)
    a = flip * a
    g = np.array([0.0, 0.0, -1.0]) + a[2] * a
    ng = float(np.linalg.norm(g))
    n = g / ng
    dg = da[:, 2:3] * a + a[2] * da
    dn = (dg - (dg @ n)[:, None] * n) / ng
    return flip * (vc + loads.radius[k] * dn)


def element_rates(
    laws: Sequence[Law],
    held: Sequence[bool],
    r: Array,
    A: Array,
    V: Array,
    qdot: Array | None = None,
    frame_w: Array | None = None,
    R: Array | None = None,
    Q: Array | None = None,
) -> tuple[Array, Array, Array]:
    """``(dW (K, nb, 6), df (K, ne), dL (K, ne))``: rates of the elements' wrenches, forces
    and lengths under body twists ``V`` (K, nb, 6): ``df = -k dL`` (0 where ``held``: a force
    held at its preload), ``d(f u)`` with the direction's rate. A torsion spring needs the
    coordinates ``Q`` and their rates ``qdot`` (K, n_q), its joint frame i's angular velocity
    ``frame_w`` (K, nj, 3) and the frames ``R``: ``d(T z'') = dT z'' + T omega x z''``."""
    K = V.shape[0]
    dW, df, dL = np.zeros(V.shape), np.zeros((K, len(laws))), np.zeros((K, len(laws)))
    for k, e in enumerate(laws):
        if isinstance(e, TorsionLaw):
            if qdot is None or frame_w is None or R is None or Q is None:
                raise ValueError("a torsion spring's rates need the coordinates, their rates and the joint frames")
            a = R[e.joint, 0, :, 2]
            dL[:, k] = qdot[:, e.col]
            df[:, k] = 0.0 if held[k] else -e.k * dL[:, k]
            T = e.T0 + e.k * (e.theta0 - float(Q[e.col]))
            dM = df[:, k : k + 1] * a + T * _cross(frame_w[:, e.joint], a)
            dW[:, e.body_j, 3:] += dM
            dW[:, e.body_i, 3:] -= dM
            continue
        Pi, Pj = r[e.body_i] + A[e.body_i] @ e.s_i, r[e.body_j] + A[e.body_j] @ e.s_j
        d = Pj - Pi
        length = float(np.linalg.norm(d))
        if length == 0.0:
            continue
        u = d / length
        vi, vj = _velocity(V[:, e.body_i], Pi), _velocity(V[:, e.body_j], Pj)
        dd = vj - vi
        dL[:, k] = dd @ u
        du = (dd - dL[:, k : k + 1] * u) / length
        f = e.f0 + e.k * (e.L0 - length)
        df[:, k] = 0.0 if held[k] else -e.k * dL[:, k]
        dF = df[:, k : k + 1] * u + f * du
        Fv = f * u
        dW[:, e.body_j, :3] += dF
        dW[:, e.body_j, 3:] += _cross(vj, Fv) + _cross(Pj, dF)
        dW[:, e.body_i, :3] -= dF
        dW[:, e.body_i, 3:] -= _cross(vi, Fv) + _cross(Pi, dF)
    return dW, df, dL


def reduced_stiffness(
    engine: Engine, state: State, loads: PointForces, driven: Sequence[int], laws: Sequence[Law] = ()
) -> tuple[Array, Array, str]:
    """``(tau, K, message)`` (``message`` empty, or why there are none: the velocity analysis'
    ``singular`` message, and NaN efforts): the efforts at the ``driven`` columns and their exact derivatives
    ``K[k, l] = d tau_k / d q_l`` (the other driven coordinates held, the constraints
    re-solved): the tangent stiffness of the mechanism reduced to its inputs.

    By virtual work ``tau_k = -sum_b W_b . V_b^(k)`` (``V^(k)``: the twists for a unit rate of
    input k), so ``K[k, l] = -sum_b (dW_b/dq_l . V_b^(k) + W_b . dV_b^(k)/dq_l)``. The
    symmetric part of ``dV^(k)/dq_l`` is the bias acceleration of the velocity analysis
    (:mod:`kinprop.engine.motion`, Haug's ``gamma``: second order, analytic) polarised over
    ``e_k + e_l``; the antisymmetric part is half the twists' spatial cross product
    ``V^(l) x V^(k)``. Loads at material points; a wheel force's contact point moves as the
    lowest point of the wheel circle (:func:`contact_rate`)."""
    labels = engine.column_labels
    nd = len(driven)
    r, A, P, R = (np.array(x) for x in engine.poses(state))
    Q = state.Q
    W = loads.wrenches(r.shape[0]) + element_state(laws, r, A, Q, P, R)[3]
    body_i = engine.tables.joint[:, J_BODY_I]

    def rates(weights: dict[int, float]) -> dict[str, float]:
        return {labels[c]: weights.get(k, 0.0) for k, c in enumerate(driven)}

    Vk, qk, acc = [], [], {}
    for k in range(nd):
        ms = motion_state(engine, state, rates({k: 1.0}), {})
        if not ms.ok:
            return np.full(nd, np.nan), np.full((nd, nd), np.nan), ms.message
        Vk.append(ms.V)
        qk.append(ms.qdot)
        acc[k, k] = ms.dV
    for k in range(nd):
        for m in range(k + 1, nd):
            ms = motion_state(engine, state, rates({k: 1.0, m: 1.0}), {})
            acc[k, m] = 0.5 * (ms.dV - acc[k, k] - acc[m, m])
    tau = np.array([-float(np.sum(W * V)) for V in Vk])
    K = np.zeros((nd, nd))
    for m in range(nd):
        V = Vk[m][None]
        dW = load_rates(loads, V)[0] + element_rates(laws, [False] * len(laws), r, A, V, qk[m][None],
                                                     V[:, body_i, 3:], R, Q)[0][0]  # fmt: skip
        for k in range(nd):
            sym = acc[min(k, m), max(k, m)]
            anti = 0.5 * np.array([spatial_cross(Vk[m][b], Vk[k][b]) for b in range(r.shape[0])])
            K[k, m] = -float(np.sum(dW * Vk[k]) + np.sum(W * (sym + anti)))
    return tau, K, ""


def _reactions(engine: Engine, Zs: list[tuple[Array, Array]], lam: Array, W_applied: Array) -> Array:
    """Every joint's wrench (nj, 2, 6) on its bodies i and j, from the multipliers and the
    applied wrenches (module docstring)."""
    tb = engine.tables
    nj = tb.joint.shape[0]
    out = np.zeros((nj, 2, 6))
    W = np.array(W_applied, dtype=float)
    for c, (Zi, Zj) in enumerate(Zs):
        j, r0 = tb.cut[c, K_JOINT], tb.cut[c, K_ROW0]
        lc = lam[r0 : r0 + Zi.shape[0]]
        out[j, 0], out[j, 1] = Zi.T @ lc, Zj.T @ lc
        W[tb.joint[j, J_BODY_I]] += out[j, 0]
        W[tb.joint[j, J_BODY_J]] += out[j, 1]
    Ws = subtree_sums(engine, W)
    for t in range(tb.tree.shape[0]):
        j = tb.tree[t, T_JOINT]
        on_child = -Ws[tb.tree[t, T_CHILD]]
        child_side = 0 if tb.tree[t, T_REVERSED] else 1
        out[j, child_side], out[j, 1 - child_side] = on_child, -on_child
    return out


def _at_points(W: Array, P: Array) -> Array:
    """Joint wrenches (nj, 2, 6) as force and moment about the joint's point on each body, global axes."""
    return np.concatenate([W[..., :3], W[..., 3:] - _cross(P, W[..., :3])], axis=-1)


def _local(G: Array, R: Array) -> Array:
    """Joint wrenches at their points ``G`` (nj, 2, 6, :func:`_at_points`) in joint frame i's
    axes (the same frame for both sides)."""
    return np.einsum("jba,jstb->jsta", R[:, 0], G.reshape(*G.shape[:2], 2, 3)).reshape(G.shape)


def equilibrium_system(engine: Engine, Phi_q: Array, driven: Sequence[int]) -> tuple[Array, Array, Array]:
    """``(A_s, unscale, c_s)``: ``[Phi_q^T  E_D^T]`` with rows and columns scaled as the solver
    scales them; ``A_s (y / unscale) = b / c_s`` for ``[Phi_q^T  E_D^T] y = b``."""
    nq, nd = engine.n_coordinates, len(driven)
    rs, cs = engine.row_scale, engine.col_scale[:nq]
    E = np.zeros((nd, nq))
    E[np.arange(nd), list(driven)] = 1.0
    As = np.hstack([(Phi_q * rs[:, None] / cs[None, :]).T, E.T])  # unknowns [lambda / rs ; tau / cs_D]
    return As, np.concatenate([rs, cs[list(driven)] if nd else np.zeros(0)]), cs


def statics_state(
    engine: Engine,
    state: State,
    applied: Array,
    driven: Sequence[int] = (),
    laws: Sequence[Law] = (),
    frames: _Frames | None = None,
) -> StaticsState:
    """Multipliers, input efforts, joint reactions and element forces of the assembled
    ``state`` under body wrenches ``applied`` (nb, 6) about the origin, held by the efforts
    at the ``driven`` layout columns (module docstring); ``frames``: the kernel's evaluation
    of ``state`` when the caller has it."""
    fr = frames if frames is not None else _Frames(engine, state)
    st = fr.state
    tb = engine.tables
    m, nd = engine.n_rows, len(driven)
    f, lengths, ends, W_el = element_state(laws, fr.r, fr.A, fr.state.Q, fr.P, fr.R)
    W = np.asarray(applied, dtype=float) + W_el
    Qg = generalized_forces(engine, fr.Tq, W)
    As, unscale, cs = equilibrium_system(engine, fr.Phi_q, driven)
    b = -Qg / cs
    U, s, Vt = np.linalg.svd(As, full_matrices=True)
    smax = float(s[0]) if s.size and s[0] > 0 else 1.0
    rank = int(np.sum(s > RANK_RTOL * smax))
    xs = Vt[:rank].T @ ((U[:, :rank].T @ b) / s[:rank])
    null = Vt[rank:]
    resid = float(np.linalg.norm(As @ xs - b))
    Zs = [_cut_partials(engine, fr.P, fr.R, st.Q, st.L, c) for c in range(tb.cut.shape[0])]
    nj = tb.joint.shape[0]
    not_assembled = fr.residual > ASSEMBLED_TOL
    if not_assembled or (resid > 1e-8 * max(float(np.linalg.norm(b)), 1e-300) and resid > 0):
        nan = np.full((nj, 2, 6), np.nan)
        return StaticsState(
            NOT_ASSEMBLED if not_assembled else UNBALANCED,
            message(NOT_ASSEMBLED, residual=fr.residual) if not_assembled else
            message(UNBALANCED, mismatch=resid / float(np.linalg.norm(b))),
            np.full(m, np.nan), tuple(driven), np.full(nd, np.nan), nan, nan, nan, np.zeros((nj, 2, 6), bool), W,
            f, lengths, ends, np.full(nj, np.nan), np.zeros((0, nj, 2, 6)), fr.r, fr.A, fr.P, fr.R, fr.residual,
        )  # fmt: skip
    x = xs * unscale
    lam, tau = x[:m], x[m:]
    wrench = _reactions(engine, Zs, lam, W)
    stress = np.array([_reactions(engine, Zs, v * unscale, np.zeros_like(W)) for v in null]).reshape(-1, nj, 2, 6)
    # a component is undetermined when some self-stress state changes it
    Lsc = engine.length_scale or 1.0
    und, und_g = np.zeros((nj, 2, 6), bool), np.zeros((nj, 2, 6), bool)
    tau_und = np.zeros(nd, bool)
    rods = distance_rows(engine, fr.P, fr.R, st.Q)
    member = np.full(nj, np.nan)
    for j, row, length in rods:
        member[j] = -2.0 * lam[row] * length
    member_und = np.zeros(nj, bool)
    for k, v in enumerate(null):
        glob = _at_points(stress[k], fr.P)
        loc = _local(glob, fr.R)
        loc[..., 3:] /= Lsc
        glob[..., 3:] /= Lsc
        t = v[m:] * unscale[m:] / Lsc if nd else np.zeros(0)  # efforts: torque-like scale
        size = max(float(np.max(np.abs(loc))), float(np.max(np.abs(t))) if nd else 0.0)
        if size == 0.0:
            continue
        und |= np.abs(loc) > UNDETERMINED_RTOL * size
        und_g |= np.abs(glob) > UNDETERMINED_RTOL * size
        for j, row, length in rods:
            member_und[j] |= abs(2.0 * v[row] * unscale[row] * length) > UNDETERMINED_RTOL * size
        if nd:
            tau_und |= np.abs(t) > UNDETERMINED_RTOL * size
    wrench_out, at_point = wrench.copy(), _at_points(wrench, fr.P)
    local = _local(at_point, fr.R)
    local[und] = np.nan
    at_point[und_g] = np.nan
    wrench_out[und.any(axis=2)] = np.nan  # a side with an undetermined component: no global wrench
    tau = np.where(tau_und, np.nan, tau)
    member[member_und] = np.nan
    msg = message(OK, self_stress=null.shape[0], undetermined=int(und.sum()))
    return StaticsState(OK, msg, lam, tuple(driven), tau, wrench_out, local, at_point, und, W, f, lengths, ends, member,
                        stress,
                        fr.r, fr.A, fr.P, fr.R, fr.residual)  # fmt: skip


__all__ = [
    "ElementLaw",
    "Law",
    "PointForces",
    "StaticsState",
    "TorsionLaw",
    "contact_rate",
    "cut_arms",
    "distance_rows",
    "element_laws",
    "element_rates",
    "element_state",
    "equilibrium_system",
    "generalized_forces",
    "load_rates",
    "reduced_stiffness",
    "statics_state",
    "subtree_sums",
]
