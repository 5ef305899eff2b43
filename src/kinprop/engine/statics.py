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

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from kinprop.engine import statics_kernels as sk
from kinprop.engine.motion import _Frames, motion_state, spatial_cross
from kinprop.engine.status import Status, message
from kinprop.kinematics.tables import (
    J_BODY_I,
    J_BODY_J,
    J_NQ,
    J_QCOL,
)
from kinprop.model.elements import Element, TorsionSpring
from kinprop.spatial import Array

if TYPE_CHECKING:
    from kinprop.engine.engine import Engine, State

#: relative singular value below which a direction of [Phi_q^T E_D^T] counts as null
RANK_RTOL = sk.RANK_RTOL
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


def law_table(laws: Sequence[Law]) -> tuple[Array, Array]:
    """The element laws as the compiled loops' tables ``(li, lf)``
    (:mod:`kinprop.engine.statics_kernels`)."""
    li, lf = np.zeros((len(laws), 5), np.int64), np.zeros((len(laws), 9))
    for k, e in enumerate(laws):
        if isinstance(e, TorsionLaw):
            li[k] = (1, e.body_i, e.body_j, e.joint, e.col)
            lf[k, 6:] = (e.k, e.theta0, e.T0)
        else:
            li[k] = (0, e.body_i, e.body_j, -1, -1)
            lf[k] = (*e.s_i, *e.s_j, e.k, e.L0, e.f0)
    return li, lf


def _tables(laws: Sequence[Law] | tuple[Array, Array]) -> tuple[Array, Array]:
    """``(li, lf)`` of laws given as laws or already as tables."""
    if isinstance(laws, tuple) and len(laws) == 2 and isinstance(laws[0], np.ndarray):
        return laws
    return law_table(laws)  # type: ignore[arg-type]


def _cut_partials(engine: Engine, fr_P: Array, fr_R: Array, Q: Array, L: Array, c: int) -> tuple[Array, Array]:
    """``(Z_i, Z_j)`` (m, 6) of cut joint ``c`` (module docstring)."""
    ct = sk.cut_terms(engine.tables, fr_P, fr_R, Q, L)
    m = ct[7][c]
    return ct[5][c, :m], ct[6][c, :m]


def distance_rows(engine: Engine, P: Array, R: Array, Q: Array) -> list[tuple[int, int, float]]:
    """``(joint, row, |d|)`` of every cut joint's distance row (its rod's length now)."""
    rod_row, rod_len = sk.cut_terms(engine.tables, P, R, Q, np.zeros(engine.tables.joint.shape[0]))[8:]
    return [(int(j), int(rod_row[j]), float(rod_len[j])) for j in np.flatnonzero(rod_row >= 0)]


def subtree_sums(engine: Engine, W: Array) -> Array:
    """``W_sub`` (nb, 6) or (K, nb, 6): each body's wrench plus those of every body below it in the tree."""
    W = np.asarray(W, dtype=float)
    return sk.subtree_sums(engine.tables, W) if W.ndim == 2 else sk.subtree_sums_k(engine.tables, W)


def generalized_forces(engine: Engine, Tq: Array, W: Array) -> Array:
    """``Q`` (n_q,) of body wrenches ``W`` (nb, 6) about the origin: ``Q_t = T_t^T W_sub(t)``."""
    return sk.generalized_forces(engine.tables, Tq, np.asarray(W, dtype=float), engine.n_coordinates)


def element_state(
    laws: Sequence[Law] | tuple[Array, Array],
    r: Array,
    A: Array,
    Q: Array | None = None,
    P: Array | None = None,
    R: Array | None = None,
) -> tuple[Array, Array, Array, Array]:
    """Forces, lengths, end points (ne, 2, 3) of the elements and their wrenches (nb, 6); a
    torsion spring (its torque, its angle, its joint's points) needs the coordinates ``Q`` and
    the joint frames ``P``, ``R``."""
    li, lf = _tables(laws)
    if Q is None or P is None or R is None:
        if li[:, 0].any():
            raise ValueError("a torsion spring needs the coordinates and the joint frames")
        Q, P, R = np.zeros(0), np.zeros((0, 2, 3)), np.zeros((0, 2, 3, 3))
    return sk.element_forces(li, lf, r, A, Q, P, R, r.shape[0])


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
        return sk.point_wrenches(self.body, self.P, self.F, self.M, nb)

    def arrays(self) -> tuple[Array, ...]:
        """``(body, P, F, M, follows, radius, centre, axis, sae)`` for the compiled loops (a
        radius of 0: a material point)."""
        n = self.body.shape[0]
        if self.radius is None or self.centre is None or self.axis is None or self.sae is None:
            z = np.zeros((n, 3))
            return self.body, self.P, self.F, self.M, self.follows, np.zeros(n), z, z, np.zeros(n, bool)
        return self.body, self.P, self.F, self.M, self.follows, self.radius, self.centre, self.axis, self.sae


def load_rates(loads: PointForces, V: Array) -> Array:
    """(K, nb, 6) rates of the applied wrenches about the origin under body twists ``V``
    (K, nb, 6): a force at a material point P has ``dM_O = v_P x F + P x dF`` (``dF = omega x F``
    in body axes); a wheel load's contact point moves as the lowest point of the wheel circle
    (:func:`kinprop.engine.statics_kernels.contact_rate`)."""
    return sk.load_rates(*loads.arrays(), np.ascontiguousarray(V, dtype=float))


def element_rates(
    laws: Sequence[Law] | tuple[Array, Array],
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
    li, lf = _tables(laws)
    V = np.ascontiguousarray(V, dtype=float)
    if qdot is None or frame_w is None or R is None or Q is None:
        if li[:, 0].any():
            raise ValueError("a torsion spring's rates need the coordinates, their rates and the joint frames")
        K = V.shape[0]
        qdot, frame_w, R, Q = np.zeros((K, 0)), np.zeros((K, 0, 3)), np.zeros((0, 2, 3, 3)), np.zeros(0)
    h = np.array(held, dtype=bool).reshape(-1) if len(held) else np.zeros(li.shape[0], bool)
    return sk.element_rates(li, lf, h, r, A, V, np.ascontiguousarray(qdot, dtype=float),
                            np.ascontiguousarray(frame_w, dtype=float), R, Q)  # fmt: skip


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


@dataclass(frozen=True)
class _Terms:
    """What the statics of a state computed on the way that their rates reuse: the applied
    wrenches with the elements', the cut joints' rows
    (:func:`kinprop.engine.statics_kernels.cut_terms`), the reactions before any NaN, the
    scaled system's SVD and rank and its scales."""

    W: Array
    cut: tuple[Array, ...]
    wrench: Array
    U: Array
    s: Array
    Vt: Array
    rank: int
    unscale: Array
    cs: Array


def _statics(
    engine: Engine, fr: _Frames, applied: Array, driven: Sequence[int], laws: tuple[Array, Array]
) -> tuple[StaticsState, _Terms | None]:
    """:func:`statics_state` on the kernel's evaluation ``fr``, with the terms its rates reuse
    (None when the state is not balanced)."""
    st = fr.state
    tb = engine.tables
    m, nd, nj = engine.n_rows, len(driven), tb.joint.shape[0]
    nq = engine.n_coordinates
    dr = np.asarray(driven, dtype=np.int64).reshape(nd)
    (W, f, lengths, ends, unscale, U, s, Vt, rank, resid, bn, lam, tau, wrench, at_point, local, member,
     ct) = sk.statics_core(tb, fr.r, fr.A, fr.P, fr.R, fr.Tq, st.Q, st.L, fr.Phi_q, engine.row_scale,
                           engine.col_scale[:nq], dr, *laws, np.asarray(applied, dtype=float))  # fmt: skip
    not_assembled = fr.residual > ASSEMBLED_TOL
    if not_assembled or (resid > 1e-8 * max(bn, 1e-300) and resid > 0):
        nan = np.full((nj, 2, 6), np.nan)
        return StaticsState(
            NOT_ASSEMBLED if not_assembled else UNBALANCED,
            message(NOT_ASSEMBLED, residual=fr.residual) if not_assembled else message(UNBALANCED, mismatch=resid / bn),
            np.full(m, np.nan), tuple(driven), np.full(nd, np.nan), nan, nan, nan, np.zeros((nj, 2, 6), bool), W,
            f, lengths, ends, np.full(nj, np.nan), np.zeros((0, nj, 2, 6)), fr.r, fr.A, fr.P, fr.R, fr.residual,
        ), None  # fmt: skip
    null = Vt[rank:]
    und = np.zeros((nj, 2, 6), bool)
    stress = np.zeros((0, nj, 2, 6))
    if null.shape[0]:  # self-stress: a component is undetermined when some null vector changes it
        Zi, Zj, mrows, rod_row, rod_len = ct[5:]
        rods = np.flatnonzero(rod_row >= 0)
        zero = np.zeros_like(W)
        stress = np.array([sk.reactions(tb, Zi, Zj, mrows, v * unscale, zero) for v in null]).reshape(-1, nj, 2, 6)
        Lsc = engine.length_scale or 1.0
        und_g = np.zeros((nj, 2, 6), bool)
        tau_und, member_und = np.zeros(nd, bool), np.zeros(nj, bool)
        for k, v in enumerate(null):
            glob, loc = sk.at_points(stress[k], fr.P, fr.R)
            loc[..., 3:] /= Lsc
            glob[..., 3:] /= Lsc
            t = v[m:] * unscale[m:] / Lsc if nd else np.zeros(0)  # efforts: torque-like scale
            size = max(float(np.max(np.abs(loc))), float(np.max(np.abs(t))) if nd else 0.0)
            if size == 0.0:
                continue
            und |= np.abs(loc) > UNDETERMINED_RTOL * size
            und_g |= np.abs(glob) > UNDETERMINED_RTOL * size
            member_und[rods] |= np.abs(2.0 * v[rod_row[rods]] * unscale[rod_row[rods]] * rod_len[rods]) > (
                UNDETERMINED_RTOL * size
            )
            if nd:
                tau_und |= np.abs(t) > UNDETERMINED_RTOL * size
        wrench_out = wrench.copy()
        local[und] = np.nan
        at_point[und_g] = np.nan
        wrench_out[und.any(axis=2)] = np.nan  # a side with an undetermined component: no global wrench
        tau = np.where(tau_und, np.nan, tau)
        member[member_und] = np.nan
    else:
        wrench_out = wrench
    msg = message(OK, self_stress=null.shape[0], undetermined=int(und.sum()))
    ss = StaticsState(OK, msg, lam, tuple(driven), tau, wrench_out, local, at_point, und, W, f, lengths, ends, member,
                      stress, fr.r, fr.A, fr.P, fr.R, fr.residual)  # fmt: skip
    return ss, _Terms(W, ct, wrench, U, s, Vt, rank, unscale, engine.col_scale[:nq])


def statics_state(
    engine: Engine,
    state: State,
    applied: Array,
    driven: Sequence[int] = (),
    laws: Sequence[Law] | tuple[Array, Array] = (),
    frames: _Frames | None = None,
) -> StaticsState:
    """Multipliers, input efforts, joint reactions and element forces of the assembled
    ``state`` under body wrenches ``applied`` (nb, 6) about the origin, held by the efforts
    at the ``driven`` layout columns (module docstring); ``frames``: the kernel's evaluation
    of ``state`` when the caller has it; ``laws`` as laws or as their tables (:func:`law_table`)."""
    fr = frames if frames is not None else _Frames(engine, state)
    return _statics(engine, fr, applied, driven, _tables(laws))[0]


__all__ = [
    "ElementLaw",
    "Law",
    "PointForces",
    "StaticsState",
    "TorsionLaw",
    "distance_rows",
    "element_laws",
    "element_rates",
    "element_state",
    "generalized_forces",
    "law_table",
    "load_rates",
    "reduced_stiffness",
    "statics_state",
    "subtree_sums",
]
