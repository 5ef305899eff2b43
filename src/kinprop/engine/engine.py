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
from typing import Any

import numpy as np

from kinprop.errors import AddressError
from kinprop.jit import get_num_threads
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

#: converged when ||Phi|| < max(tol, ROUNDOFF * eps * L^2): distance rows d.d - l^2 carry
#: round-off of about eps * L^2, which exceeds 1e-10 for metre-sized mechanisms in mm
ROUNDOFF = 16.0
_FIELD_SIDE = {"s_i": 0, "s_j": 1, "C_i": 0, "C_j": 1}


@dataclass(frozen=True, eq=False)
class State:
    """Design variables and coordinates as arrays, optionally with a leading batch axis:
    ``Q`` (..., nq) coordinates (layout q columns), ``S`` (..., nj, 2, 3) s'_i/s'_j,
    ``C`` (..., nj, 2, 3, 3) C_i/C_j, ``L`` (..., nj) lengths."""

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


@dataclass(frozen=True, eq=False)
class Solution:
    """One solve's outcome; the model-level view (design, coordinates) is built on demand."""

    engine: Engine
    start: State
    state: State
    status: Status
    iterations: int
    residual: float
    history: Array
    free: Array
    tol: float
    changes: Mapping[str, Array] = field(default_factory=dict)
    #: the tolerance asked for; ``tol`` is ``max(requested_tol, round-off floor)``
    requested_tol: float = 0.0

    @property
    def converged(self) -> bool:
        return self.status is Status.CONVERGED

    @property
    def message(self) -> str:
        bound = (
            f"{self.tol:.3g} (round-off floor at this model's length scale; tol {self.requested_tol:g})"
            if self.tol > self.requested_tol
            else f"{self.tol:g}"
        )
        if self.status is Status.CONVERGED:
            return f"converged in {self.iterations} iterations: ||Phi|| = {self.residual:.3g} < {bound}"
        if self.status is Status.NO_FREE:
            return "no free variables: nothing can move to satisfy the constraints"
        if self.status is Status.DIVERGED:
            return f"diverged at iteration {self.iterations}: ||Phi|| = {self.residual:.3g}"
        return f"not converged after {self.iterations} iterations: ||Phi|| = {self.residual:.3g} >= {bound}"

    @cached_property
    def design(self) -> Design:
        return self.engine.unpack(self.state)[0]

    @cached_property
    def coordinates(self) -> Mapping[str, Array]:
        return self.engine.unpack(self.state)[1]

    def value(self, address: str) -> Array:
        """Current value of an address (``O2.q``, ``L1.length``, ``J.s_i[1]``)."""
        return self.engine.get(self.state, address)

    def __repr__(self) -> str:
        return f"<Solution {self.status.value}: {self.iterations} iterations, ||Phi|| = {self.residual:.3g}>"


@dataclass(frozen=True)
class BatchSolution:
    """Per-variant outcome of a batch: status codes index :class:`Status`."""

    state: State
    status_code: Array
    iterations: Array
    residual: Array

    @property
    def converged(self) -> Array:
        return self.status_code == newton.CONVERGED

    def status(self, k: int) -> Status:
        return STATUSES[int(self.status_code[k])]


class Engine:
    """A mechanism compiled once (see the module docstring); build it with :func:`compile`."""

    def __init__(self, mechanism: Mechanism, reference: Model | None = None) -> None:
        self.mechanism = mechanism
        self.topology: Topology = build_topology(mechanism)
        self.layout: VariableLayout = build_layout(mechanism, self.topology)
        self.row_blocks: tuple[RowBlock, ...] = row_blocks(mechanism, self.topology)
        self.n_rows = sum(b.rows.stop - b.rows.start for b in self.row_blocks)
        self.n_columns = self.layout.n
        self.tables: Tables = build_tables(mechanism, self.topology, self.layout, self.row_blocks)
        self.nnz = int(kernels.count_entries(self.tables))
        self.joint_index = {j.name: k for k, j in enumerate(mechanism.joints)}
        self.body_index = {b.name: k for k, b in enumerate(mechanism.bodies)}
        self.n_coordinates = sum(v.size for v in self.layout.group("q"))
        # first column of each column's variable (the Newton loop's ``need`` mask)
        self._variable_of = np.zeros(self.n_columns, dtype=np.int64)
        for v in self.layout.variables:
            self._variable_of[v.columns] = v.start
        self._plans: dict[tuple, Plan] = {}
        self._targets: dict[str, Target] = {}
        self._free_cache: dict[tuple, Array] = {}
        self.model = reference
        self.reference: State | None = (
            self.pack(reference.design, reference.coordinates).frozen() if reference else None
        )
        #: characteristic length L of the compiled model (largest body position, s' or length, >= 1)
        self.length_scale = self._length_scale(self.reference) if reference else None

    def __repr__(self) -> str:
        return (f"<Engine {self.mechanism.name!r}: {len(self.mechanism.bodies)} bodies, {len(self.mechanism.joints)} "
                f"joints, {self.n_rows} equations, {self.n_columns} variables>")  # fmt: skip

    # --- structure ---------------------------------------------------------------------------
    @cached_property
    def pattern(self) -> tuple[Array, Array]:
        """Row and column of every Jacobian entry the kernel emits (fixed order)."""
        st = self.default_state()
        rows, cols = np.zeros(self.nnz, np.int64), np.zeros(self.nnz, np.int64)
        need = np.ones(self.n_columns, np.int8)
        k = kernels.evaluate(self.tables, st.Q, st.S, st.C, st.L, kernels.workspace(self.tables),
                             np.zeros(self.n_rows), np.zeros(self.nnz), need, rows, cols, True)  # fmt: skip
        if k != self.nnz:  # pragma: no cover - the count and the kernel's emission must agree
            raise AssertionError(f"the kernel emitted {k} Jacobian entries, the count says {self.nnz}")
        return rows, cols

    @property
    def row_labels(self) -> list[str]:
        return [f"{b.joint}:{lab}" for b in self.row_blocks for lab in b.labels]

    @property
    def column_labels(self) -> list[str]:
        return column_labels(self.layout)

    def columns(self, selectors: Iterable[str] = ("q",), exclude: Iterable[str] = ()) -> Array:
        """Layout columns of groups (``q s C l``) and addresses, minus the ``exclude`` variable keys."""
        return self.layout.columns(list(selectors), exclude=set(exclude)).astype(np.int64)

    def plan(self, free: Array, weights: Array | None = None) -> Plan:
        """The linear-solve plan of a free column set (computed once per set)."""
        key = (free.tobytes(), None if weights is None else np.asarray(weights, float).tobytes())
        plan = self._plans.get(key)
        if plan is None:
            rows, cols = self.pattern
            plan = build_plan(self.n_rows, self.n_columns, rows, cols, free, self._variable_of, weights)
            self._plans[key] = plan
        return plan

    def weights_for(self, free: Array, weights: Mapping[str, float] | None) -> Array | None:
        """Per-free-column weights of a weighted min-norm step from ``{address or group: w}``."""
        if not weights:
            return None
        full = np.ones(self.n_columns)
        for sel, val in weights.items():
            if not (isinstance(val, int | float) and np.isfinite(val) and val > 0):
                raise AddressError(f"weight for {sel!r} must be positive, found {val}")
            full[self.columns([sel])] = float(val)
        return full[free]

    # --- state -------------------------------------------------------------------------------
    def default_state(self) -> State:
        """Zero s', identity C, unit lengths, default coordinates (structure passes)."""
        nj = len(self.mechanism.joints)
        Q = np.zeros(self.n_coordinates)
        for v in self.layout.group("q"):
            jt = self.mechanism.joint(v.joint).jtype
            Q[v.columns] = jt.default_coordinates() if v.size == jt.n_coordinates else jt.default_cut_coordinates()
        return State(Q, np.zeros((nj, 2, 3)), np.tile(np.eye(3), (nj, 2, 1, 1)), np.ones(nj))

    def pack(self, design: Design, coordinates: Mapping[str, Array]) -> State:
        """A :class:`State` from a design and coordinates (missing coordinates: defaults)."""
        st = self.default_state()
        for k, j in enumerate(self.mechanism.joints):
            st.S[k, 0], st.S[k, 1] = design.value(j.name, "s_i"), design.value(j.name, "s_j")
            st.C[k, 0], st.C[k, 1] = design.value(j.name, "C_i"), design.value(j.name, "C_j")
            st.L[k] = float(design[f"{j.name}.length"]) if f"{j.name}.length" in design else 0.0
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
            j = self.joint_index[v.joint]
            if v.group == "q":
                coords[v.joint] = state.Q[v.columns].copy()
            elif v.group == "s":
                vals[v.key] = state.S[j, _FIELD_SIDE[v.field]].copy()
            elif v.group == "C":
                vals[v.key] = state.C[j, _FIELD_SIDE[v.field]].copy()
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
            t = Target(address, v.key, v.group, self.joint_index[v.joint], _FIELD_SIDE.get(v.field, 0), v.start, v.size,
                       addr.index)  # fmt: skip
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
        state = self._as_state(state, coordinates)
        Phi, vals = np.zeros(self.n_rows), np.zeros(self.nnz)
        need = np.full(self.n_columns, int(jacobian), np.int8)
        dummy = np.zeros(0, np.int64)
        kernels.evaluate(self.tables, state.Q, state.S, state.C, state.L, kernels.workspace(self.tables), Phi, vals,
                         need, dummy, dummy, False)  # fmt: skip
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
        r, A, P, R, _, _ = kernels.workspace(self.tables)
        kernels.forward_kinematics(self.tables, state.Q, state.S, state.C, r, A, P, R)
        return r, A, P, R

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
        kernels.retract(self.tables, cols, np.ascontiguousarray(np.asarray(dx, float)[cols]), st.Q, st.S, st.C, st.L)
        return st

    def _length_scale(self, state: State) -> float:
        r = self.poses(state)[0]
        vals = [1.0, float(np.max(np.linalg.norm(r, axis=1), initial=0.0))]
        for k, j in enumerate(self.mechanism.joints):
            for side, fld in ((0, "s_i"), (1, "s_j")):
                if fld in j.fields:
                    vals.append(float(np.linalg.norm(state.S[k, side])))
            if "length" in j.fields:
                vals.append(abs(float(state.L[k])))
        return max(vals)

    def _floor(self, state: State | None) -> float:
        """The stopping floor: at the compiled model's length scale (a design change does not
        loosen it: an absurd length must not make a non-assembly "converge"), else the state's."""
        return self.roundoff_floor(None if self.length_scale is not None else state)

    def roundoff_floor(self, state: State | None = None) -> float:
        """``ROUNDOFF * eps * L^2``: below this ||Phi|| is round-off (about 1e-13 for the paper's
        metre-scale examples, 1e-8 for a vehicle suspension in mm)."""
        L = self._length_scale(state) if state is not None or self.length_scale is None else self.length_scale
        return ROUNDOFF * float(np.finfo(float).eps) * L**2

    # --- solving -----------------------------------------------------------------------------
    def solve(
        self,
        start: State,
        free: Sequence[str] | Array = ("q",),
        *,
        exclude: Iterable[str] = (),
        weights: Mapping[str, float] | None = None,
        tol: float = 1e-10,
        max_iter: int = 50,
        divergence: float = 1e6,
        changes: Mapping[str, Array] | None = None,
    ) -> Solution:
        """Newton from ``start`` (copied) moving only the ``free`` columns (groups/addresses or
        an array of columns), minus the ``exclude`` variable keys."""
        cols = free if isinstance(free, np.ndarray) else self.columns(free, exclude)
        plan = self.plan(cols, self.weights_for(cols, weights))
        st = start.copy()
        hist = np.zeros(max_iter + 1)
        target = max(tol, self._floor(start))
        code, it, norm = newton.solve_one(self.tables, plan, self.nnz, st.Q, st.S, st.C, st.L, target, max_iter,
                                          divergence, hist)  # fmt: skip
        return Solution(self, start, st, STATUSES[code], it, float(norm), hist[: it + 1], cols, target,
                        dict(changes or {}), tol)  # fmt: skip

    def apply(self, start: State, changes: Mapping[str, Any]) -> tuple[State, dict[str, Array], set[str]]:
        """A copy of ``start`` with ``changes`` (address -> value) written; returns it, the
        changes as arrays, and the changed variable keys (never free)."""
        st = start.copy()
        done: dict[str, Array] = {}
        keys: set[str] = set()
        for address, value in changes.items():
            self.set(st, address, value)
            done[address] = np.asarray(value, dtype=float)
            keys.add(self.target(address).key)
        return st, done, keys

    def propagate(
        self,
        changes: Mapping[str, Any] | None = None,
        free: Sequence[str] = ("q",),
        *,
        start: State | Solution | None = None,
        weights: Mapping[str, float] | None = None,
        tol: float = 1e-10,
        max_iter: int = 50,
    ) -> Solution:
        """Apply ``changes`` by address to ``start`` (default: the compiled model's state) and
        re-assemble moving only ``free`` (groups ``q s C l`` and/or addresses); the changed
        variables are never free (PAPER-NOTES 7)."""
        base = start.state if isinstance(start, Solution) else start if start is not None else self.reference
        if base is None:
            raise ValueError("this engine was compiled from a Mechanism: pass start=engine.pack(design, coordinates)")
        st, done, keys = self.apply(base, changes or {})
        key = (tuple(free), frozenset(keys))
        cols = self._free_cache.get(key) if weights is None else None
        if cols is None:
            cols = self.columns(free, keys)
            if weights is None:
                self._free_cache[key] = cols
        return self.solve(st, cols, weights=weights, tol=tol, max_iter=max_iter, changes=done)

    def solve_batch(
        self,
        states: State,
        free: Sequence[str] | Array = ("q",),
        *,
        exclude: Iterable[str] = (),
        tol: float = 1e-10,
        max_iter: int = 50,
        divergence: float = 1e6,
        threads: bool | None = None,
    ) -> BatchSolution:
        """Solve every variant of a batched state (leading axis) on its own; ``threads`` splits
        the batch over numba's threads (default: for batches of 256 and more)."""
        cols = free if isinstance(free, np.ndarray) else self.columns(free, exclude)
        plan = self.plan(cols)
        st = states.copy()
        N = st.Q.shape[0]
        status, iters, res = np.zeros(N, np.int64), np.zeros(N, np.int64), np.zeros(N)
        target = max(tol, self._floor(st[0] if N else None))
        threaded = N >= 256 if threads is None else threads
        args = (self.tables, plan, self.nnz, st.Q, st.S, st.C, st.L, target, max_iter, divergence, status, iters, res)
        if threaded:
            newton.solve_batch_threaded(*args, max(1, min(get_num_threads(), N)))
        else:
            newton.solve_batch(*args)
        return BatchSolution(st, status, iters, res)

    def solve_sequence(
        self,
        start: State,
        addresses: Sequence[str],
        values: Array,
        free: Sequence[str] = ("q",),
        *,
        tol: float = 1e-10,
        max_iter: int = 50,
        divergence: float = 1e6,
    ) -> tuple[Array, BatchSolution]:
        """Set the coordinate ``addresses`` to each row of ``values`` in turn, solving each step
        from the previous one; returns the coordinates of every step and the per-step outcome."""
        set_cols = np.array([self.target(a).start + (self.target(a).index or 0) for a in addresses], np.int64)
        if any(self.target(a).group != "q" for a in addresses):
            raise AddressError("a sequence drives coordinates (JOINT.q or JOINT.q[k])")
        keys = {parse_address(a).key for a in addresses}
        cols = self.columns(free, keys)
        plan = self.plan(cols)
        st = start.copy()
        values = np.ascontiguousarray(np.reshape(values, (len(values), len(addresses))), dtype=float)
        n = values.shape[0]
        Qout = np.zeros((n, self.n_coordinates))
        status, iters, res = np.zeros(n, np.int64), np.zeros(n, np.int64), np.zeros(n)
        target = max(tol, self._floor(start))
        newton.solve_sequence(self.tables, plan, self.nnz, st.Q, st.S, st.C, st.L, target, max_iter, divergence,
                              set_cols, values, Qout, status, iters, res)  # fmt: skip
        return Qout, BatchSolution(st, status, iters, res)


def compile(model: Model | Mechanism) -> Engine:
    """Compile a model (or a bare mechanism) into an :class:`Engine`.

    From a :class:`Model`, the engine also holds the model's design and coordinates as its
    reference state, the default start of :meth:`Engine.propagate`.
    """
    if isinstance(model, Model):
        return Engine(model.mechanism, model)
    return Engine(model)


__all__ = ["BatchSolution", "Engine", "JointFrames", "Kinematics", "Solution", "State", "Status", "compile"]
