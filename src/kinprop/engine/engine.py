"""The compiled engine: a mechanism's flat model, built once, with the by-address API.

``engine = kinprop.compile(model)`` derives the topology, variable layout, row blocks, flat
tables and Jacobian sparsity pattern once (Pinocchio's Model, MJX's flat model); it is
immutable and passed explicitly (no global cache). Per-call state — the design variables and
coordinates as arrays — lives in :class:`State` objects; every evaluation and solve runs the
one compiled implementation (:mod:`kinprop.kinematics.kernels`, :mod:`kinprop.solver.newton`).

Addresses (``L1.length``, ``J12.s_j``, ``J12.s_j[2]``, ``O2.q``, groups ``q s C l``) are
translated to columns once per distinct address and free set, so a by-name re-solve costs
what the kernel costs. Values are in solver units: lengths in the model's length unit,
angles in radians (the CLI and ``kinprop.propagate`` convert from the model's units).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from numbers import Real
from typing import Any

import numpy as np

from kinprop.constraints.coupling import N_COEF
from kinprop.engine.motion import MotionState, motion_state
from kinprop.engine.status import message, notes
from kinprop.engine.units import METRES_PER, UnitTable
from kinprop.errors import AddressError, ConvergenceError
from kinprop.jit import note_model, num_threads
from kinprop.kinematics import kernels
from kinprop.kinematics.layout import VariableLayout, build_layout, column_labels
from kinprop.kinematics.tables import RowBlock, Tables, build_tables, row_blocks
from kinprop.model.design import Design, as_coordinates, parse_address
from kinprop.model.mechanism import Mechanism
from kinprop.model.model import Model
from kinprop.solver import newton
from kinprop.solver.newton import STATUSES, Status
from kinprop.solver.plan import Plan, build_plan
from kinprop.spatial import Array, is_rotation
from kinprop.topology import Topology, build_topology

#: converged when the scaled residual < max(tol, ROUNDOFF * eps * (U L)^2): distance rows
#: d.d - l^2 carry round-off of about eps * L^2
ROUNDOFF = 16.0
#: a value beyond this multiple of the model's length scale is rejected as absurd (bounded work)
ABSURD = 1e6
#: branch keeping (kinprop.solver.newton.follow): jump test, trust radius of the predictor
#: (radians, or lengths over the model's length scale), smallest sub-step, sub-step cap
KAPPA, JUMP_ATOL, TRUST, MIN_STEP, MAX_SUBSTEPS = 0.5, 1e-9, 0.35, 1e-6, 200
#: at most this many Newton iterations per solve; a solve asked for tol <= POLISH_TOL takes one
#: more step after converging (kept when it lowers the residual: results to round-off)
MAX_ITER, POLISH_TOL = 10_000, 1e-8
#: floor of the optimality residual's tolerance (SI: metres, radians): its round-off
OPT_FLOOR = 1e-12
#: what a solve returns when the free set leaves freedom (docs/analysis/weights.md):
#: ``least-change`` the assembly closest to the start in the SI metric (the default), ``paper``
#: the end point of the paper's generalized-inverse iteration (Zou et al. 1997, eq. 5.2-5.3)
METHODS = ("least-change", "paper")
_FIELD_SIDE = {"s_i": 0, "s_j": 1, "C_i": 0, "C_j": 1}


@dataclass(frozen=True, eq=False)
class State:
    """Design variables and coordinates as arrays, optionally with a leading batch axis:
    ``Q`` (..., nq) coordinates (layout q columns), ``S`` (..., nj, 2, 3) s'_i/s'_j,
    ``C`` (..., nj, 2, 3, 3) C_i/C_j, ``L`` (..., nj + 5 nc) lengths, then each coupling's
    coefficients c0..c4."""

    Q: Array
    S: Array
    C: Array
    L: Array

    @property
    def batch(self) -> tuple[int, ...]:
        return self.Q.shape[:-1]

    def copy(self) -> State:
        return State(self.Q.copy(), self.S.copy(), self.C.copy(), self.L.copy())

    def __getitem__(self, k: Any) -> State:
        return State(self.Q[k], self.S[k], self.C[k], self.L[k])

    def writable(self) -> State:
        """The arrays as the kernels take them: writable and C-contiguous (copied only when not),
        so one compiled version of each kernel serves every call (numba compiles a separate
        one for read-only arrays)."""
        return State(*(a if a.flags.writeable and a.flags.c_contiguous else np.array(a)
                       for a in (self.Q, self.S, self.C, self.L)))  # fmt: skip

    def frozen(self) -> State:
        for a in (self.Q, self.S, self.C, self.L):
            a.setflags(write=False)
        return self


@dataclass(frozen=True)
class JointFrames:
    """Global joint frames of one joint: origins ``P_i``, ``P_j`` and orientations ``R_i``, ``R_j``."""

    P_i: Array
    R_i: Array
    P_j: Array
    R_j: Array


@dataclass(frozen=True)
class Kinematics:
    """Body poses and every joint's global frames, by name (for outputs, reports, plots)."""

    r: dict[str, Array]
    A: dict[str, Array]
    frames: dict[str, JointFrames]
    #: names of the spanning tree's joints (the others are cut)
    tree: frozenset[str] = frozenset()


@dataclass(frozen=True)
class Target:
    """Where an address lives in a :class:`State`."""

    address: str
    key: str  # the variable's key (``J.s_i`` of ``J.s_i[2]``)
    group: str
    joint: int
    side: int
    start: int  # first layout column
    size: int
    index: int | None


#: check rules of one-number changes (:meth:`Engine.apply`)
_BOUNDED, _POSITIVE, _ANY = 0, 1, 2


def _scalar_slot(t: Target) -> tuple[str, int, int] | None:
    """``(state array, flat index, rule)`` of a one-number address in a single state, or None
    (a vector, or an orientation: those go through ``Engine.set``)."""
    if t.group == "q" and (t.index is not None or t.size == 1):
        return "Q", t.start + (t.index or 0), _BOUNDED
    if t.group == "s" and t.index is not None:
        return "S", (2 * t.joint + t.side) * 3 + t.index, _BOUNDED
    if t.group == "coef" and t.index is not None:
        return "L", t.joint + t.index, _ANY
    if t.group == "l":
        return "L", t.joint, _POSITIVE
    return None


@dataclass(frozen=True, eq=False)
class Solution:
    """One solve's outcome; the model-level view (design, coordinates) is built on demand."""

    engine: Engine
    start: State
    state: State
    status: Status
    iterations: int
    residual: float
    #: the scaled ``||Phi||`` at the start and after every iteration
    residual_history: Array
    #: the free layout columns
    free: Array
    tol: float
    changes: Mapping[str, Array] = field(default_factory=dict)
    #: the tolerance asked for; ``tol`` is ``max(requested_tol, round-off floor)``
    requested_tol: float = 0.0
    #: fraction of the change followed (1 when converged), sub-steps taken, follow flags
    fraction: float = 1.0
    substeps: int = 1
    flags: int = 0
    #: optimality residual (SI: metres, radians; weighted): the length of the least-change
    #: correction at the returned point, 0 at the assembly closest to the start (and when the
    #: free set leaves no freedom); see docs/analysis/weights.md
    optimality: float = 0.0
    #: ``least-change`` or ``paper`` (:data:`METHODS`)
    method: str = "least-change"
    #: the iteration cap of one sub-step (0: not known)
    max_iter: int = 0

    @property
    def subdivided(self) -> bool:
        """The change was split into sub-steps to stay on the start's branch."""
        return bool(self.flags & newton.SUBDIVIDED)

    @property
    def notes(self) -> list[str]:
        """One line per thing a user should know about this solve (empty: nothing to say)."""
        return notes(self.status, self.flags, self.substeps)

    @property
    def converged(self) -> bool:
        return self.status is Status.CONVERGED

    @property
    def message(self) -> str:
        return message(self.status, self.iterations, self.residual, self.tol, self.requested_tol, self.fraction,
                       self.substeps, self.flags, self.optimality, self.max_iter)  # fmt: skip

    @cached_property
    def _unpacked(self) -> tuple[Design, Mapping[str, Array]]:
        return self.engine.unpack(self.state)

    @property
    def design(self) -> Design:
        return self._unpacked[0]

    @property
    def coordinates(self) -> Mapping[str, Array]:
        return self._unpacked[1]

    def value(self, address: str) -> Array:
        """Current value of an address (``O2.q``, ``L1.length``, ``J.s_i[1]``)."""
        return self.engine.get(self.state, address)

    @cached_property
    def jacobian(self) -> Array:
        """The full Jacobian ``Phi_x`` at the returned state (every column, not only the free ones)."""
        return self.engine.evaluate(self.state)[1]

    @cached_property
    def singular_values(self) -> Array:
        """Singular values of the free-column Jacobian at the returned state, largest first."""
        Jf = self.jacobian[:, self.free]
        return np.linalg.svd(Jf, compute_uv=False) if Jf.size else np.zeros(0)

    def raise_for_status(self) -> Solution:
        """This solution, or :class:`kinprop.errors.ConvergenceError` with its message when it
        did not converge."""
        if not self.converged:
            raise ConvergenceError(self.message)
        return self

    @property
    def rank(self) -> int:
        """Numerical rank of the free-column Jacobian (``s_k > RANK_RTOL * s_1``)."""
        sv = self.singular_values
        return int(np.sum(sv > newton.RANK_RTOL * sv[0])) if sv.size and sv[0] > 0 else 0

    def __repr__(self) -> str:
        return (f"<Solution {self.status.value}: {self.iterations} iterations, ||Phi|| = {self.residual:.3g}, "
                f"optimality {self.optimality:.3g}>")  # fmt: skip


@dataclass(frozen=True)
class BatchSolution:
    """Per-variant (or per-step) outcome of a batch, with :class:`Solution`'s field names:
    ``status_code`` indexes :class:`Status`; ``state`` has a leading batch axis."""

    state: State
    status_code: Array
    iterations: Array
    residual: Array
    fraction: Array | None = None
    flags: Array | None = None
    substeps: Array | None = None
    tol: float = 0.0
    requested_tol: float = 0.0
    #: per-variant optimality residual (:attr:`Solution.optimality`)
    optimality: Array | None = None
    #: the iteration cap of one sub-step (0: not known)
    max_iter: int = 0

    @property
    def converged(self) -> Array:
        return self.status_code == newton.CONVERGED

    def status(self, k: int) -> Status:
        return STATUSES[int(self.status_code[k])]

    def message(self, k: int) -> str:
        """Row ``k``'s outcome from the one message table (:func:`message`)."""
        return message(self.status(k), int(self.iterations[k]), float(self.residual[k]), self.tol, self.requested_tol,
                       1.0 if self.fraction is None else float(self.fraction[k]),
                       1 if self.substeps is None else int(self.substeps[k]),
                       0 if self.flags is None else int(self.flags[k]),
                       0.0 if self.optimality is None else float(self.optimality[k]), self.max_iter)  # fmt: skip

    def notes(self, k: int) -> list[str]:
        return notes(self.status(k), 0 if self.flags is None else int(self.flags[k]),
                     1 if self.substeps is None else int(self.substeps[k]))  # fmt: skip


class Engine:
    """A mechanism compiled once (see the module docstring); build it with :func:`compile`."""

    def __init__(self, mechanism: Mechanism, reference: Model | None = None) -> None:
        self.mechanism = mechanism
        self.topology: Topology = build_topology(mechanism)
        self.layout: VariableLayout = build_layout(mechanism, self.topology)
        self.row_blocks: tuple[RowBlock, ...] = row_blocks(mechanism, self.topology)
        self.n_rows = sum(b.rows.stop - b.rows.start for b in self.row_blocks)
        self.n_columns = self.layout.n
        self.n_coordinates = sum(v.size for v in self.layout.group("q"))
        note_model(self.n_coordinates)  # before the first kernel call: how kernels run may depend on it
        self.tables: Tables = build_tables(mechanism, self.topology, self.layout, self.row_blocks)
        self.nnz = int(kernels.count_entries(self.tables))
        self.joint_index = {j.name: k for k, j in enumerate(mechanism.joints)}
        #: slot of each coupling's c0 in the state's ``L`` (after the joints' lengths)
        self.coupling_slot = {c.name: len(mechanism.joints) + N_COEF * k for k, c in enumerate(mechanism.couplings)}
        self.body_index = {b.name: k for k, b in enumerate(mechanism.bodies)}
        #: which coordinate components are angles or Euler parameters, for every unit
        #: conversion (:mod:`kinprop.engine.units`), resolved once here
        self.unit_table: UnitTable = UnitTable.of(mechanism, self.topology)
        # first column of each column's variable (the Newton loop's ``need`` mask)
        self._variable_of = np.zeros(self.n_columns, dtype=np.int64)
        for v in self.layout.variables:
            self._variable_of[v.columns] = v.start
        self._plans: dict[tuple, Plan] = {}
        self._reference_signs: dict[tuple, int] = {}  # det sign at the reference, per plan (solve)
        self._targets: dict[str, Target] = {}
        self._free_cache: dict[tuple, Array] = {}
        self.model = reference
        self.reference: State | None = (
            self.pack(reference.design, reference.coordinates).frozen() if reference else None
        )
        #: characteristic length L of the compiled model (largest body position, s' or length; at
        #: least 1 m in the model's unit)
        self.length_scale = self._length_scale(self.reference) if reference else None

    def rebased(self, reference: Model) -> Engine:
        """This engine with another reference model of the same mechanism (a design study's base
        with its common changes): the compiled structure, tables and plans are shared, not
        rebuilt; only the reference state and what depends on it (length scale, branch data)
        are new."""
        if reference.mechanism is not self.mechanism and reference.mechanism != self.mechanism:
            raise ValueError("the reference model has another mechanism than the engine")
        new = object.__new__(Engine)
        new.__dict__.update(self.__dict__)
        for key in ("col_scale", "row_scale", "_reference_assembled", "unit", "si_scale", "_unit_metric"):
            new.__dict__.pop(key, None)
        if new.unit != self.unit:  # the plans hold the rows' SI scale
            new._plans = {}
        new._reference_signs = {}
        new.model = reference
        new.reference = new.pack(reference.design, reference.coordinates).frozen()
        new.length_scale = new._length_scale(new.reference)
        return new

    def __repr__(self) -> str:
        return (f"<Engine {self.mechanism.name!r}: {len(self.mechanism.bodies)} bodies, {len(self.mechanism.joints)} "
                f"joints, {self.n_rows} equations, {self.n_columns} variables>")  # fmt: skip

    # --- structure ---------------------------------------------------------------------------
    @cached_property
    def pattern(self) -> tuple[Array, Array]:
        """Row and column of every Jacobian entry the kernel emits (fixed order)."""
        st = self.default_state().writable()
        rows, cols = np.zeros(self.nnz, np.int64), np.zeros(self.nnz, np.int64)
        need = np.ones(self.n_columns, np.int8)
        k = kernels.evaluate(self.tables, st.Q, st.S, st.C, st.L, kernels.workspace(self.tables),
                             np.zeros(self.n_rows), np.zeros(self.nnz), need, rows, cols)  # fmt: skip
        if k != self.nnz:  # pragma: no cover - the count and the kernel's emission must agree
            raise AssertionError(f"the kernel emitted {k} Jacobian entries, the count says {self.nnz}")
        return rows, cols

    @cached_property
    def dense_pattern(self) -> tuple[Array, Array, Array]:
        """``(q, flat_q, flat)``: which Jacobian entries are in q columns, their flat index in
        the dense ``Phi_q`` (n_rows, n_q), and every entry's flat index in the dense ``Phi_x``
        (n_rows, n_columns) (duplicates add: ``np.bincount``)."""
        rows, cols = self.pattern
        q = cols < self.n_coordinates
        return q, rows[q] * self.n_coordinates + cols[q], rows * self.n_columns + cols

    @property
    def row_labels(self) -> list[str]:
        return [f"{b.joint}:{lab}" for b in self.row_blocks for lab in b.labels]

    @property
    def column_labels(self) -> list[str]:
        return column_labels(self.layout)

    def columns(self, selectors: Iterable[str] = ("q",), exclude: Iterable[str] = ()) -> Array:
        """Layout columns of groups (``q s C l``) and addresses, minus the ``exclude`` variable keys."""
        return self.layout.columns(list(selectors), exclude=set(exclude)).astype(np.int64)

    def free_columns(self, free: Iterable[str], changed: Iterable[str]) -> Array:
        """Columns of ``free`` minus what ``changed`` (addresses) sets: a changed design variable
        is never free as a whole; a changed coordinate component (``J.q[k]``) only itself, so a
        joint's other coordinates may follow (PAPER-NOTES 7)."""
        targets = [self.target(a) for a in changed]
        keys = {t.key for t in targets if t.group != "q" or t.index is None}
        cols = self.columns(free, keys)
        held = [t.start + t.index for t in targets if t.group == "q" and t.index is not None]
        return cols[~np.isin(cols, held)] if held else cols

    @staticmethod
    def _plan_key(free: Array, weights: Array | None) -> tuple[bytes, bytes | None]:
        return free.tobytes(), None if weights is None else np.asarray(weights, float).tobytes()

    def plan(self, free: Array, weights: Array | None = None) -> Plan:
        """The linear-solve plan of a free column set (computed once per set)."""
        key = self._plan_key(free, weights)
        plan = self._plans.get(key)
        if plan is None:
            rows, cols = self.pattern
            rotations = [v.start for v in self.layout.group("C")]
            plan = build_plan(self.n_rows, self.n_columns, rows, cols, free, self._variable_of, weights, self.row_scale,
                              np.array(rotations, dtype=np.int64))  # fmt: skip
            self._plans[key] = plan
        return plan

    def weights_for(self, free: Array, weights: Mapping[str, float] | None) -> Array | None:
        """Per-free-column weights ``w_k / si_k^2`` of the step's metric ``sum (si_k dx_k)^2 / w_k``
        (:attr:`si_scale`: changes measured in metres and radians, so that a model in mm and in m
        take the same step) from the user's ``{address or group: w}``; None: all ones."""
        full = self.metric_weights(weights) if weights else self._unit_metric
        return None if full is None else full[free]

    @cached_property
    def _unit_metric(self) -> Array | None:
        """:meth:`metric_weights` without user weights (None for a metre model), computed once."""
        return self.metric_weights(None)

    def metric_weights(self, weights: Mapping[str, float] | None = None) -> Array | None:
        """:meth:`weights_for` over every layout column (None: all ones, a metre model unweighted)."""
        full = np.ones(self.n_columns)
        for sel, val in (weights or {}).items():
            if not (isinstance(val, int | float) and np.isfinite(val) and val > 0):
                raise AddressError(f"weight for {sel!r} must be positive, found {val}")
            full[self.columns([sel])] = float(val)
        full /= self.si_scale**2
        return None if np.all(full == 1.0) else full

    @cached_property
    def si_scale(self) -> Array:
        """SI units per solver unit of every layout column: U (metres per model length unit) for
        lengths (s', link lengths, slides, a T-D joint's own coordinate), 1 for angles (radians),
        Euler parameters and orientations (rotation vectors); a coupling coefficient ``c_k``
        ``U_a / U_b^k`` (``q_a = c0 + c1 q_b + ...`` with U of a slide, 1 of an angle)."""
        U = self.unit
        si = np.ones(self.n_columns)
        for v in self.layout.variables:
            if v.group in ("s", "l"):
                si[v.columns] = U
            elif v.group == "q":
                jt = self.mechanism.joint(v.joint).jtype
                tree = v.joint in self._tree
                angular = set(jt.angle_indices) | (set(range(jt.euler.start, jt.euler.stop)) if jt.euler else set())
                for k in range(v.size):
                    if not (tree and k in angular):
                        si[v.start + k] = U
            elif v.group == "coef":
                cp = next(c for c in self.mechanism.couplings if c.name == v.joint)
                ua, ub = (1.0 if self.mechanism.joint(n).jtype.angle_indices else U for n in (cp.joint_a, cp.joint_b))
                si[v.columns] = ua / ub ** np.arange(v.size)
        return si

    # --- state -------------------------------------------------------------------------------
    def default_state(self) -> State:
        """Zero s', identity C, unit lengths, default coordinates (structure passes)."""
        nj = len(self.mechanism.joints)
        Q = np.zeros(self.n_coordinates)
        for v in self.layout.group("q"):
            jt = self.mechanism.joint(v.joint).jtype
            Q[v.columns] = jt.default_coordinates() if v.size == jt.n_coordinates else jt.default_cut_coordinates()
        L = np.ones(nj + N_COEF * len(self.mechanism.couplings))
        return State(Q, np.zeros((nj, 2, 3)), np.tile(np.eye(3), (nj, 2, 1, 1)), L)

    def pack(self, design: Design, coordinates: Mapping[str, Array]) -> State:
        """A :class:`State` from a design and coordinates (missing coordinates: defaults)."""
        st = self.default_state()
        for k, j in enumerate(self.mechanism.joints):
            st.S[k, 0], st.S[k, 1] = design.value(j.name, "s_i"), design.value(j.name, "s_j")
            st.C[k, 0], st.C[k, 1] = design.value(j.name, "C_i"), design.value(j.name, "C_j")
            st.L[k] = float(design[f"{j.name}.length"]) if f"{j.name}.length" in design else 0.0
        for c in self.mechanism.couplings:
            st.L[self.coupling_slot[c.name] : self.coupling_slot[c.name] + N_COEF] = design[f"{c.name}.coef"]
        for v in self.layout.group("q"):
            val = coordinates.get(v.joint)
            if val is not None:
                st.Q[v.columns] = val
        return st

    def state_of(self, model: Model) -> State:
        return self.pack(model.design, model.coordinates)

    def stack(self, states: Sequence[State]) -> State:
        """Stack single states along a new leading batch axis."""
        return State(*(np.stack([getattr(s, a) for s in states]) for a in "QSCL"))

    def unpack(self, state: State) -> tuple[Design, Mapping[str, Array]]:
        """``(Design, coordinates)`` of a single state."""
        vals: dict[str, object] = {}
        coords: dict[str, Array] = {}
        for v in self.layout.variables:
            j = self.coupling_slot[v.joint] if v.group == "coef" else self.joint_index[v.joint]
            if v.group == "q":
                coords[v.joint] = state.Q[v.columns].copy()
            elif v.group == "s":
                vals[v.key] = state.S[j, _FIELD_SIDE[v.field]].copy()
            elif v.group == "C":
                vals[v.key] = state.C[j, _FIELD_SIDE[v.field]].copy()
            elif v.group == "coef":
                vals[v.key] = state.L[j : j + N_COEF].copy()
            else:
                vals[v.key] = float(state.L[j])
        return Design(vals), as_coordinates(coords)

    def model_of(self, state: State, like: Model) -> Model:
        """``like`` (units, source) with the design and coordinates of ``state``."""
        design, coords = self.unpack(state)
        return like.with_state(design, coords)

    def target(self, address: str) -> Target:
        """Where ``address`` lives in a state (parsed once per distinct address)."""
        t = self._targets.get(address)
        if t is None:
            addr = parse_address(address)
            if addr.key not in self.layout:
                known = ", ".join(v.key for v in self.layout.variables)
                raise AddressError(f"{address!r} is not a design variable or coordinate of this model; known: {known}")
            v = self.layout[addr.key]
            if addr.index is not None and addr.index >= (9 if v.group == "C" else v.size):
                raise AddressError(f"{address!r}: index out of range for a variable of size {v.size}")
            # ``joint``: the joint's index; for a coupling's coefficients, the slot of c0 in ``L``
            j = self.coupling_slot[v.joint] if v.group == "coef" else self.joint_index[v.joint]
            t = Target(address, v.key, v.group, j, _FIELD_SIDE.get(v.field, 0), v.start, v.size, addr.index)
            self._targets[address] = t
        return t

    def get(self, state: State, address: str) -> Array:
        t = self.target(address)
        if t.group == "q":
            full = state.Q[..., t.start : t.start + t.size]
        elif t.group == "s":
            full = state.S[..., t.joint, t.side, :]
        elif t.group == "C":
            full = state.C[..., t.joint, t.side, :, :].reshape(*state.batch, 9)
        elif t.group == "coef":
            full = state.L[..., t.joint : t.joint + N_COEF]
        else:
            full = state.L[..., t.joint, None]
        return full.copy() if t.index is None else full[..., t.index].copy()

    def set(self, state: State, address: str, value: Any) -> None:
        """Overwrite one address in ``state`` (in place), checking size, finiteness and kind."""
        t = self.target(address)
        val = np.asarray(value, dtype=float)
        if t.index is not None:
            if val.size != 1:
                raise AddressError(f"{address!r}: expected one number for component {t.index}, found {val.size}")
            val = val.reshape(())
        elif t.group == "C":
            if val.size != 9:
                raise AddressError(f"{address!r}: expected a 3x3 rotation matrix (9 numbers), found {val.size}")
            val = val.reshape(3, 3)
        elif val.size != t.size:
            raise AddressError(f"{address!r}: expected {t.size} numbers, found {val.size}")
        if not np.all(np.isfinite(val)):
            raise AddressError(f"{address!r}: value must be finite")
        bound = ABSURD * max(1.0, self.length_scale or 1.0)
        if t.group not in ("C", "coef") and np.max(np.abs(val)) > bound:
            raise AddressError(
                f"{address!r}: {float(np.max(np.abs(val))):.3g} is beyond {ABSURD:g} times the model's length scale "
                f"(L = {self.length_scale or 1.0:.3g}; the limit is {bound:.3g}); no mechanism assembles there"
            )
        if t.group == "q":
            state.Q[t.start + (t.index or 0) : t.start + (t.index or 0) + (1 if t.index is not None else t.size)] = val
        elif t.group == "s":
            if t.index is None:
                state.S[t.joint, t.side] = val
            else:
                state.S[t.joint, t.side, t.index] = val
        elif t.group == "C":
            C = state.C[t.joint, t.side].copy()
            if t.index is None:
                C = val
            else:
                C.flat[t.index] = val
            if not is_rotation(C):
                raise AddressError(f"{address!r}: not a proper rotation matrix (C^T C = I, det C = +1)")
            state.C[t.joint, t.side] = C
        elif t.group == "coef":
            state.L[t.joint + (t.index or 0) : t.joint + (t.index or 0) + (1 if t.index is not None else N_COEF)] = val
        else:
            length = float(val.reshape(()))
            if not length > 0:
                raise AddressError(f"{address!r}: a length must be positive, found {length:g}")
            state.L[t.joint] = length

    # --- evaluation --------------------------------------------------------------------------
    def _as_state(self, state: State | Design, coordinates: Mapping[str, Array] | None) -> State:
        return state if isinstance(state, State) else self.pack(state, coordinates or {})

    def evaluate(
        self, state: State | Design, coordinates: Mapping[str, Array] | None = None, jacobian: bool = True
    ) -> tuple[Array, Array | None]:
        """``(Phi, Phi_x)`` of a single state (or design and coordinates), the Jacobian dense
        over every layout column."""
        state = self._as_state(state, coordinates).writable()
        Phi, vals = np.zeros(self.n_rows), np.zeros(self.nnz)
        need = np.full(self.n_columns, int(jacobian), np.int8)
        dummy = np.zeros(0, np.int64)
        kernels.evaluate(self.tables, state.Q, state.S, state.C, state.L, kernels.workspace(self.tables), Phi, vals,
                         need, dummy, dummy)  # fmt: skip
        if not jacobian:
            return Phi, None
        J = np.zeros((self.n_rows, self.n_columns))
        rows, cols = self.pattern
        np.add.at(J, (rows, cols), vals)
        return Phi, J

    def residual(self, state: State | Design, coordinates: Mapping[str, Array] | None = None) -> Array:
        return self.evaluate(state, coordinates, jacobian=False)[0]

    def poses(self, state: State) -> tuple[Array, Array, Array, Array]:
        """Body positions ``r`` (nb, 3), orientations ``A`` (nb, 3, 3) and joint frames ``P``
        (nj, 2, 3), ``R`` (nj, 2, 3, 3) (global origins and axes of frames i and j) of a single state."""
        ws, state = kernels.workspace(self.tables), state.writable()
        kernels.forward_kinematics(self.tables, state.Q, state.S, state.C, ws)
        return ws[kernels.W_BODY_R], ws[kernels.W_BODY_A], ws[kernels.W_FRAME_P], ws[kernels.W_FRAME_R]

    def kinematics(self, design: Design | State, coordinates: Mapping[str, Array] | None = None) -> Kinematics:
        """Body poses and joint frames by name, of a state or of ``(design, coordinates)``."""
        st = design if isinstance(design, State) else self.pack(design, coordinates or {})
        r, A, P, R = self.poses(st)
        names = self.mechanism.body_names
        frames = {j.name: JointFrames(P[k, 0], R[k, 0], P[k, 1], R[k, 1]) for k, j in enumerate(self.mechanism.joints)}
        return Kinematics(dict(zip(names, r, strict=True)), dict(zip(names, A, strict=True)), frames,
                          frozenset(self.topology.tree_joints))  # fmt: skip

    def retract(self, state: State, dx: Array) -> State:
        """``state (+) dx`` for a step over every layout column (additive for q, s', l;
        ``C <- exp(tilde(dxi')) C``), as a new state."""
        st = state.copy()
        cols = np.flatnonzero(np.asarray(dx)).astype(np.int64)
        dxc = np.ascontiguousarray(np.asarray(dx, float)[cols])
        kernels.retract(self.tables, cols, dxc, st.Q, st.S, st.C, st.L, kernels.workspace(self.tables))
        return st

    def _length_scale(self, state: State) -> float:
        r = self.poses(state)[0]
        # at least one metre (in the model's unit): the scale, and with it the branch tests and the
        # round-off floor, do not depend on the unit a small mechanism is written in
        vals = [1.0 / self.unit, float(np.max(np.linalg.norm(r, axis=1), initial=0.0))]
        for k, j in enumerate(self.mechanism.joints):
            for side, fld in ((0, "s_i"), (1, "s_j")):
                if fld in j.fields:
                    vals.append(float(np.linalg.norm(state.S[k, side])))
            if "length" in j.fields:
                vals.append(abs(float(state.L[k])))
        return max(vals)

    # --- scaling and settings ----------------------------------------------------------------
    @cached_property
    def unit(self) -> float:
        """Metres per model length unit (1 for a bare mechanism)."""
        return METRES_PER[self.model.units.get("length", "m")] if self.model is not None else 1.0

    @cached_property
    def row_scale(self) -> Array:
        """Per-row scale of the residual the stopping test reads: length rows (spherical, dot-2)
        times U, distance rows (length^2) times U^2, dot-1 and normalisation rows 1, with U the
        metres per model length unit. Models in mm and in m meet the same accuracy; for metre
        models the residual is the paper's. A coupling row is in the unit of its driven joint's
        coordinate: U for a slide, 1 for an angle."""
        U = self.unit
        per_kind = {"spherical": U, "dot2": U, "distance": U * U}
        slides = {c.name for c in self.mechanism.couplings if not self.mechanism.joint(c.joint_a).jtype.angle_indices}
        return np.array([U if b.kind == "coupling" and b.joint in slides else per_kind.get(lab.split("[")[0], 1.0)
                         for b in self.row_blocks for lab in b.labels])  # fmt: skip

    @cached_property
    def col_scale(self) -> Array:
        """Per-column scale of the branch-jump metric: lengths / L (L the model's length scale),
        angles, Euler parameters and orientations 1."""
        L = self.length_scale or 1.0
        scale = np.ones(self.n_columns)
        for v in self.layout.variables:
            if v.group in ("s", "l"):
                scale[v.columns] = 1.0 / L
            elif v.group == "q":
                jt = self.mechanism.joint(v.joint).jtype
                tree = v.joint in self._tree
                angular = set(jt.angle_indices) | (set(range(jt.euler.start, jt.euler.stop)) if jt.euler else set())
                for k in range(v.size):
                    if not (tree and k in angular):
                        scale[v.start + k] = 1.0 / L
        return scale

    @cached_property
    def _reference_assembled(self) -> bool:
        """Whether the compiled model's state is an assembly (at the default tolerance)."""
        r = self.residual(self.reference) * self.row_scale
        return bool(np.linalg.norm(r) < max(1e-10, self.roundoff_floor()))

    @cached_property
    def _tree(self) -> frozenset[str]:
        return frozenset(self.topology.tree_joints)

    def roundoff_floor(self, state: State | None = None) -> float:
        """``ROUNDOFF * eps * (U L)^2``: below this the scaled residual is round-off (distance
        rows carry ~eps L^2); L the compiled model's length scale (a design change never
        loosens it: an absurd length must not make a non-assembly converge)."""
        L = self._length_scale(state) if state is not None and self.length_scale is None else self.length_scale or 1.0
        return ROUNDOFF * float(np.finfo(float).eps) * (self.unit * L) ** 2

    def settings(self, tol: float = 1e-10, max_iter: int = 50, *, branch: bool = True, divergence: float = 1e6,
                 state: State | None = None, method: str = "least-change") -> newton.Settings:  # fmt: skip
        """The compiled loops' settings (caps: :data:`MAX_SUBSTEPS` sub-steps per change, the
        smallest sub-step :data:`MIN_STEP` of the change). ``method``: :data:`METHODS`; the
        optimality residual's tolerance is ``max(tol, OPT_FLOOR)`` (SI units)."""
        if not (np.isfinite(tol) and tol > 0):
            raise ValueError(f"tolerance must be a positive number, found {tol}")
        if not (isinstance(max_iter, int | np.integer) and 0 <= max_iter <= MAX_ITER):
            raise ValueError(f"max_iter must be an integer in 0..{MAX_ITER}, found {max_iter}")
        if method not in METHODS:
            raise ValueError(f"method must be one of {', '.join(METHODS)}, found {method!r}")
        target = max(tol, self.roundoff_floor(state))
        return newton.Settings(target, int(max_iter), divergence, KAPPA, JUMP_ATOL, TRUST, MIN_STEP if branch else 1.0,
                               MAX_SUBSTEPS if branch else 1, bool(tol <= POLISH_TOL), bool(branch),
                               method == "least-change", max(tol, OPT_FLOOR))  # fmt: skip

    # --- solving -----------------------------------------------------------------------------
    def solve(
        self,
        start: State,
        free: Sequence[str] | Array = ("q",),
        *,
        target: State | None = None,
        exclude: Iterable[str] = (),
        weights: Mapping[str, float] | None = None,
        tol: float = 1e-10,
        max_iter: int = 50,
        branch: bool = True,
        changes: Mapping[str, Array] | None = None,
        assembled: bool | None = None,
        method: str = "least-change",
    ) -> Solution:
        """Solve from ``start`` (copied) moving only the ``free`` columns (groups/addresses or an
        array of columns, minus the ``exclude`` variable keys) for the design of ``target``
        (default: ``start``'s own). With ``branch`` (the default) the change is followed on the
        start's branch (:func:`kinprop.solver.newton.follow`); ``branch=False`` is the paper's
        plain Newton. ``assembled``: whether ``start`` is an assembly (None: find out).

        When the free set leaves freedom the result is the assembly closest to ``start`` in the
        metric ``sum (si_k dx_k)^2 / w_k`` (:meth:`weights_for`), its optimality residual in
        ``Solution.optimality``; ``method="paper"``: the end point of the paper's iteration."""
        cols = free if isinstance(free, np.ndarray) else self.columns(free, exclude)
        if assembled is None and start is self.reference:
            assembled = self._reference_assembled
        w = self.weights_for(cols, weights)
        plan = self.plan(cols, w)
        cfg = self.settings(tol, max_iter, branch=branch, state=start, method=method)
        st = start.copy()
        goal = (target if target is not None else start).writable()
        hist = np.zeros(2 * max_iter + 2)
        # the det sign of the free Jacobian at the compiled model's assembled state, per plan:
        # computed by the first solve from it, then reused (one evaluation and factorisation less)
        ref_key = self._plan_key(cols, w) if start is self.reference and assembled else None
        sign0 = self._reference_signs.get(ref_key, newton.UNKNOWN_SIGN) if ref_key else newton.UNKNOWN_SIGN
        code, it, frac, subs, norm, flags, hlen, sign_start, _, opt = newton.follow_one(
            self.tables, plan, self.nnz, st.Q, st.S, st.C, st.L, goal.Q, goal.S, goal.C, goal.L,
            -1 if assembled is None else int(assembled), self.row_scale, self.col_scale, cfg, hist,
            sign0)  # fmt: skip
        if flags & newton.FLIPPED and not flags & newton.SUBDIVIDED:  # plain Newton landed on a turned cut joint
            code, frac = newton.INFEASIBLE, 0.0
        if ref_key is not None and sign_start != newton.UNKNOWN_SIGN and not flags & newton.FROM_ESTIMATES:
            self._reference_signs[ref_key] = int(sign_start)
        return Solution(self, start, st, STATUSES[code], int(it), float(norm), hist[: min(hlen, hist.size)], cols,
                        cfg.tol, dict(changes or {}), tol, float(frac), int(subs), int(flags), float(opt),
                        method, int(cfg.max_iter))  # fmt: skip

    def apply(self, start: State, changes: Mapping[str, Any]) -> tuple[State, dict[str, Array], set[str]]:
        """A copy of ``start`` with ``changes`` (address -> value) written; returns it, the
        changes as arrays, and the changed variable keys (never free). Single numbers for
        one-number addresses (``L3.length``, ``J.s_i[2]``, ``O2.q``) are checked and written
        together (as :meth:`set` checks them: finite, within the length bound, lengths
        positive); everything else goes through :meth:`set`."""
        st = start.copy()
        done: dict[str, Array] = {}
        keys: set[str] = set()
        pending: list[tuple[str, float, tuple[str, int, int]]] = []
        for address, value in changes.items():
            t = self.target(address)
            keys.add(t.key)
            slot = _scalar_slot(t) if isinstance(value, Real) else None
            if slot is not None:
                pending.append((address, float(value), slot))
                continue
            self._set_scalars(st, pending, done)  # before this change: changes apply in their order
            pending = []
            self.set(st, address, value)
            done[address] = np.asarray(value, dtype=float)
        self._set_scalars(st, pending, done)
        return st, done, keys

    def set_batch(self, states: State, address: str, values: Array) -> Array:
        """Write one number per state of a C-contiguous batch (leading axis, as :meth:`stack`
        builds it) to the one-number ``address``; returns the rows that took it: the others
        (not finite, beyond the length bound, a length not positive: :meth:`set`'s checks) are
        left as they were."""
        t = self.target(address)
        slot = _scalar_slot(t)
        if slot is None:
            raise AddressError(f"{address!r}: not a one-number address (give a component, e.g. {t.key}[0])")
        name, flat, rule = slot
        vals = np.asarray(values, dtype=float).reshape(-1)
        bound = ABSURD * max(1.0, self.length_scale or 1.0)
        ok = np.isfinite(vals) & ((rule == _ANY) | (np.abs(vals) <= bound)) & ((rule != _POSITIVE) | (vals > 0))
        arr = getattr(states, name)
        view = arr.reshape(vals.size, -1)
        if not np.shares_memory(view, arr):
            raise ValueError("set_batch needs a C-contiguous batch of states")
        view[ok, flat] = vals[ok]
        return ok

    def _set_scalars(self, state: State, scalars: list[tuple[str, float, tuple[str, int, int]]],
                     done: dict[str, Array]) -> None:  # fmt: skip
        """Write one-number changes ``(address, value, slot)`` after checking them all at once
        (into ``done`` too); a bad one is reported by :meth:`set` with its own message. Below
        three, :meth:`set` each (the arrays cost ~8 us: more than two calls of ``set``)."""
        if len(scalars) < 3:
            for address, value, _ in scalars:
                self.set(state, address, value)
        else:
            vals = np.array([v for _, v, _ in scalars])
            flat, rule = (np.array(x, dtype=np.int64) for x in zip(*(s[1:] for _, _, s in scalars), strict=True))
            where = np.array([s[0] for _, _, s in scalars])
            bound = ABSURD * max(1.0, self.length_scale or 1.0)
            ok = np.isfinite(vals) & ((rule == _ANY) | (np.abs(vals) <= bound)) & ((rule != _POSITIVE) | (vals > 0))
            if not ok.all():
                address, value, _ = scalars[int(np.argmin(ok))]
                self.set(state, address, value)  # raises, naming the address and the rule
            for name in "QSL":
                sel = where == name
                if sel.any():
                    getattr(state, name).reshape(-1)[flat[sel]] = vals[sel]
        done.update((a, np.asarray(v)) for a, v, _ in scalars)

    def propagate(
        self,
        changes: Mapping[str, Any] | None = None,
        free: Sequence[str] = ("q",),
        *,
        start: State | Solution | None = None,
        weights: Mapping[str, float] | None = None,
        tol: float = 1e-10,
        max_iter: int = 50,
        branch: bool = True,
        method: str = "least-change",
    ) -> Solution:
        """Apply ``changes`` by address to ``start`` (default: the compiled model's state) and
        re-assemble moving only ``free`` (groups ``q s C l`` and/or addresses), on the start's
        branch; the changed variables are never free (PAPER-NOTES 7). With freedom left, the
        assembly closest to the changed start (``method="paper"``: the paper's iteration's end
        point; :meth:`solve`)."""
        base = start.state if isinstance(start, Solution) else start if start is not None else self.reference
        if base is None:
            raise ValueError("this engine was compiled from a Mechanism: pass start=engine.pack(design, coordinates)")
        assembled = start.converged if isinstance(start, Solution) else self._reference_assembled if start is None \
            else None  # fmt: skip
        goal, done, _ = self.apply(base, changes or {})
        key = (tuple(free), tuple(done))
        cols = self._free_cache.get(key)
        if cols is None:
            cols = self._free_cache[key] = self.free_columns(free, done)
        return self.solve(base, cols, target=goal, weights=weights, tol=tol, max_iter=max_iter, branch=branch,
                          changes=done, assembled=assembled, method=method)  # fmt: skip

    def solve_batch(
        self,
        targets: State,
        free: Sequence[str] | Array = ("q",),
        *,
        start: State | None = None,
        exclude: Iterable[str] = (),
        tol: float = 1e-10,
        max_iter: int = 50,
        branch: bool = True,
        threads: bool | None = None,
        method: str = "least-change",
    ) -> BatchSolution:
        """Follow every variant of a batched state (leading axis) from ``start`` (default: the
        compiled model's state) to its own design, each on the start's branch; ``threads``
        splits the batch over numba's threads (default: for batches of 256 and more)."""
        base = start if start is not None else self.reference
        if base is None:
            raise ValueError("this engine was compiled from a Mechanism: pass start=engine.pack(design, coordinates)")
        cols = free if isinstance(free, np.ndarray) else self.columns(free, exclude)
        plan = self.plan(cols, self.weights_for(cols, None))
        cfg = self.settings(tol, max_iter, branch=branch, state=base, method=method)
        targets = targets.writable()
        N = targets.Q.shape[0]
        shared = base.Q.ndim == 1  # one start for every variant: copied into each by the kernel
        starts = State(*(getattr(base, a)[None] for a in "QSCL")) if shared else base
        starts = starts.writable()
        st = State(*(np.empty_like(getattr(targets, a)) for a in "QSCL"))
        out = np.zeros((N, 7))
        # whether the start is assembled: known here for one start, else each variant's own test
        assembled = int(np.linalg.norm(self.residual(base) * self.row_scale) < cfg.tol) if shared else -1
        args = (self.tables, plan, self.nnz, starts.Q, starts.S, starts.C, starts.L, targets.Q, targets.S, targets.C,
                targets.L, st.Q, st.S, st.C, st.L, assembled, self.row_scale, self.col_scale, cfg, out)  # fmt: skip
        if (N >= 256 if threads is None else threads) and N > 1:
            _batch_in_threads(args, N)
        else:
            newton.follow_batch(*args)
        return BatchSolution(st, out[:, 0].astype(np.int64), out[:, 1].astype(np.int64), out[:, 4], out[:, 2],
                             out[:, 5].astype(np.int64), out[:, 3].astype(np.int64), cfg.tol, tol,
                             out[:, 6], int(cfg.max_iter))  # fmt: skip

    def solve_sequence(
        self,
        start: State,
        addresses: Sequence[str],
        values: Array,
        free: Sequence[str] | Array = ("q",),
        *,
        tol: float = 1e-10,
        max_iter: int = 50,
        branch: bool = True,
        method: str = "least-change",
    ) -> tuple[Array, BatchSolution]:
        """Drive the coordinate ``addresses`` through the rows of ``values``, each step followed
        from the last good one on the start's branch (a failed step is recorded and the next
        restarts from the last good step). Returns the coordinates of every step (NaN rows where
        a step failed) and the per-step outcome, whose ``state`` is every step's state (free
        design variables move too; NaN where a step failed)."""
        targets = [self.target(a) for a in addresses]
        if any(t.group != "q" for t in targets):
            raise AddressError("a sequence drives coordinates (JOINT.q or JOINT.q[k])")
        set_cols = np.array([t.start + (t.index or 0) for t in targets], np.int64)
        cols = free if isinstance(free, np.ndarray) else self.columns(free, {t.key for t in targets})
        plan = self.plan(cols, self.weights_for(cols, None))
        cfg = self.settings(tol, max_iter, branch=branch, state=start, method=method)
        st = start.copy()
        values = np.ascontiguousarray(np.reshape(values, (len(values), len(addresses))), dtype=float)
        n = values.shape[0]
        steps = State(*(np.zeros((n, *getattr(st, a).shape)) for a in "QSCL"))
        out = np.zeros((n, 7))
        newton.follow_sequence(self.tables, plan, self.nnz, st.Q, st.S, st.C, st.L, set_cols, values, self.row_scale,
                               self.col_scale, cfg, steps.Q, steps.S, steps.C, steps.L, out)  # fmt: skip
        return steps.Q, BatchSolution(steps, out[:, 0].astype(np.int64), out[:, 1].astype(np.int64), out[:, 4],
                                      out[:, 2], out[:, 5].astype(np.int64), out[:, 3].astype(np.int64), cfg.tol,
                                      tol, out[:, 6], int(cfg.max_iter))  # fmt: skip

    # --- motion: velocities and accelerations (kinprop.engine.motion) ------------------------
    def motion(
        self, state: State, rates: Mapping[str, Any], accelerations: Mapping[str, Any] | None = None
    ) -> MotionState:
        """Every coordinate's rate (and acceleration) and every body's twist of an assembled
        ``state`` from the driven coordinates' ``rates`` (``{"O2.q": 1.0}``, solver units);
        status ``singular`` (NaN rates) when they do not determine the motion."""
        return motion_state(self, state, rates, accelerations)


def _batch_in_threads(args: tuple, N: int) -> None:
    """:func:`kinprop.solver.newton.follow_batch` over contiguous chunks of the variants on a
    pool of threads (the kernel releases the GIL): one chunk per thread at least, up to 16 per
    thread of 64 variants or more, handed out one at a time, so a thread that finishes early
    takes the next and a core slowed by other work does not hold up the batch. Views of the
    batch arrays along their leading axis keep one compiled signature of the kernel."""
    from concurrent.futures import ThreadPoolExecutor

    nth = num_threads()
    chunks = max(min(nth, N), min(16 * nth, N // 64))
    bounds = [(c * N // chunks, (c + 1) * N // chunks) for c in range(chunks)]
    # sliced per chunk: the starts (args 3-6) unless one is shared, targets and ends (7-14), out
    sliced = [k for k in range(3, 15) if k >= 7 or args[3].shape[0] > 1] + [len(args) - 1]

    def run(b: tuple[int, int]) -> None:
        part = list(args)
        for k in sliced:
            part[k] = args[k][b[0] : b[1]]
        newton.follow_batch(*part)

    with ThreadPoolExecutor(max_workers=nth) as pool:
        list(pool.map(run, bounds))


def compile(model: Model | Mechanism) -> Engine:
    """Compile a model (or a bare mechanism) into an :class:`Engine`.

    From a :class:`Model`, the engine also holds the model's design and coordinates as its
    reference state, the default start of :meth:`Engine.propagate`.
    """
    if isinstance(model, Model):
        return Engine(model.mechanism, model)
    return Engine(model)


__all__ = ["METHODS", "BatchSolution", "Engine", "JointFrames", "Kinematics", "Solution", "State", "Status", "compile"]
