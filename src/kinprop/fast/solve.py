"""Fast evaluation and Newton solves over compiled mechanisms (single, batched, sequences).

Every function here agrees with the reference (:meth:`Assembly.evaluate`,
:func:`kinprop.propagation.propagate`) to rounding; ``tests/fast`` checks it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from kinprop.fast import kernels as kn
from kinprop.fast.compiled import STATUS, Compiled, State, compile_model, pack, unpack
from kinprop.model.design import Design
from kinprop.model.model import Model
from kinprop.propagation.propagate import Propagation
from kinprop.spatial import Array


@dataclass
class BatchResult:
    """Per-variant solver outcome; ``state`` holds the solved arrays, ``x`` its coordinates."""

    status: Array  # int: 0 converged, 1 not converged, 2 diverged, 3 no free variables
    iterations: Array
    residual: Array
    state: State

    @property
    def x(self) -> Array:
        return self.state.Q

    @property
    def converged(self) -> Array:
        return self.status == kn.CONVERGED

    def message(self, k: int) -> str:
        st, it = STATUS[int(self.status[k])], int(self.iterations[k])
        return f"{st} after {it} iterations: ||Phi|| = {self.residual[k]:.3g}"


def evaluate(comp: Compiled, state: State) -> tuple[Array, Array]:
    """``(Phi, J)`` with shapes (N, m) and (N, m, n): the dense Jacobian over every layout column."""
    N = state.size
    Phi = np.zeros((N, comp.m))
    J = np.zeros((N, comp.m, comp.n))
    kn.evaluate_dense(comp.tables, comp.rows, comp.cols, state.Q, state.S, state.C, state.L, Phi, J)
    return Phi, J


def body_poses(comp: Compiled, state: State) -> tuple[Array, Array]:
    """Global body positions (N, nb, 3) and orientations (N, nb, 3, 3), bodies in mechanism order."""
    nb = comp.fixed.shape[0]
    r = np.zeros((state.size, nb, 3))
    A = np.zeros((state.size, nb, 3, 3))
    kn.poses_batch(comp.tables, state.Q, state.S, state.C, state.L, comp.m, r, A)
    return r, A


def _as_state(
    comp: Compiled,
    designs: State | Design | Sequence[Design],
    coords: Mapping[str, Array] | Sequence[Mapping[str, Array]] | None,
) -> State:
    if isinstance(designs, State):
        return designs
    return pack(comp, designs, coords if coords is not None else {})


class BoundSolver:
    """A compiled mechanism bound to a free set and stopping rule (shared by the solvers)."""

    def __init__(
        self,
        comp: Compiled,
        free: Sequence[str] | Array = ("q",),
        exclude: set[str] | frozenset[str] = frozenset(),
        tol: float = 1e-10,
        max_iter: int = 50,
        divergence: float = 1e6,
    ) -> None:
        self.comp = comp
        cols = np.asarray(free) if isinstance(free, np.ndarray) else comp.free_columns(free, exclude)
        self.free = np.ascontiguousarray(cols, dtype=np.int64)
        self.tol, self.max_iter, self.divergence = float(tol), int(max_iter), float(divergence)
        self._args = (comp.tables, comp.colinfo, comp.rows, comp.cols, comp.m, comp.n, self.free)


class Solver(BoundSolver):
    """A Newton solver bound to a compiled mechanism and a free set (minimal per-call overhead)."""

    def solve_one(self, Q: Array, S: Array, C: Array, L: Array) -> tuple[int, int, float]:
        """Solve one variant in place (arrays without the batch axis); ``(status, iterations, residual)``."""
        return kn.newton(*self._args, Q, S, C, L, self.tol, self.max_iter, self.divergence)

    def solve(self, state: State, copy: bool = True, parallel: bool = False) -> BatchResult:
        """Solve every variant of ``state`` (each with its own convergence).

        ``parallel``: split the batch over numba's threads (``NUMBA_NUM_THREADS``).
        """
        st = state.copy() if copy else state
        N = st.size
        status = np.zeros(N, dtype=np.int64)
        iters = np.zeros(N, dtype=np.int64)
        res = np.zeros(N)
        kernel = kn.newton_batch_parallel if parallel else kn.newton_batch
        kernel(*self._args, st.Q, st.S, st.C, st.L, self.tol, self.max_iter, self.divergence, status, iters, res)
        return BatchResult(status, iters, res, st)

    def sequence(self, state: State, column: int, values: Array, k: int = 0) -> tuple[Array, BatchResult]:
        """Set layout q ``column`` to each value in turn, solving each step from the previous one.

        Returns the coordinates after every step (len(values), nq) and the per-step outcome.
        """
        st = state.take(slice(k, k + 1)).copy()
        values = np.ascontiguousarray(values, dtype=float)
        S_ = values.shape[0]
        Qout = np.zeros((S_, self.comp.nq))
        status = np.zeros(S_, dtype=np.int64)
        iters = np.zeros(S_, dtype=np.int64)
        res = np.zeros(S_)
        kn.newton_sequence(*self._args, st.Q[0], st.S[0], st.C[0], st.L[0], self.tol, self.max_iter, self.divergence,
                          int(column), values, Qout, status, iters, res)  # fmt: skip
        return Qout, BatchResult(status, iters, res, st)


def solve_batch(
    comp: Compiled,
    designs: State | Design | Sequence[Design],
    coords: Mapping[str, Array] | Sequence[Mapping[str, Array]] | None = None,
    free: Sequence[str] = ("q",),
    tol: float = 1e-10,
    max_iter: int = 50,
    exclude: set[str] | frozenset[str] = frozenset(),
    parallel: bool = False,
) -> BatchResult:
    """Batched generalized-inverse Newton over N variants; per-variant convergence.

    ``designs`` is a :class:`State` or one/many :class:`Design` (with ``coords``); ``free``
    groups or addresses minus the ``exclude`` keys (e.g. the changed variables).
    """
    return Solver(comp, free, exclude, tol, max_iter).solve(_as_state(comp, designs, coords), parallel=parallel)


def propagate_fast(
    model: Model,
    changes: Mapping[str, object] | None = None,
    free: Sequence[str] = ("q",),
    *,
    tol: float = 1e-10,
    max_iter: int = 50,
) -> Propagation:
    """:func:`kinprop.propagate` on the compiled path (same step, same result to rounding).

    Returns the reference's :class:`~kinprop.propagation.Propagation`; its
    ``result.residual_history`` holds the initial and final norms only (the kernel keeps no
    history), rank and singular values are those of the free Jacobian at the result.
    """
    from kinprop.propagation.propagate import apply_changes, roundoff_floor
    from kinprop.solver.newton import RANK_RTOL, SolveResult

    start, normalised, changed = apply_changes(model, dict(changes or {}))
    comp = compile_model(model.mechanism)
    tol = max(tol, roundoff_floor(start))  # the reference's stopping rule (SolveOptions.target)
    solver = Solver(comp, free, exclude=changed, tol=tol, max_iter=max_iter)
    st = pack(comp, start.design, start.coordinates)
    Phi0 = evaluate(comp, st)[0][0]
    res = solver.solve(st, copy=False)
    design, coords = unpack(comp, res.state)
    _, J = evaluate(comp, res.state)
    Jf = J[0][:, solver.free]
    sv = np.linalg.svd(Jf, compute_uv=False) if Jf.size else np.zeros(0)
    rank = int(np.sum(sv > RANK_RTOL * sv[0])) if sv.size and sv[0] > 0 else 0
    status, it, norm = int(res.status[0]), int(res.iterations[0]), float(res.residual[0])
    converged = status == kn.CONVERGED
    if converged:
        message = f"converged in {it} iterations: ||Phi|| = {norm:.3g} < {tol:g}"
    elif status == kn.NO_FREE:
        message = "no free variables: nothing can move to satisfy the constraints"
    elif status == kn.DIVERGED:
        message = f"diverged at iteration {it}: ||Phi|| = {norm:.3g}"
    else:
        message = f"not converged after {it} iterations: ||Phi|| = {norm:.3g} >= {tol:g}"
    result = SolveResult(converged, it, norm, [float(np.linalg.norm(Phi0)), norm], rank, int(solver.free.size),
                         comp.m, sv, message, (design, coords))  # fmt: skip
    return Propagation(model, start.with_state(design, coords), result, normalised, tuple(free))
