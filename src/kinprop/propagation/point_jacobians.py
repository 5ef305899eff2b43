"""Analytic Jacobians of global points with respect to every state column, from the engine.

A body-fixed point ``P = r_b + A_b s`` is differentiated by the compiled kernel itself: the
mechanism is compiled once more with one *probe* per point — a cut ``spherical-point`` joint
from the fixed body (``s_i = 0``) to body ``b`` at ``s_j = s`` — whose three constraint rows
are ``P - r_fixed`` (Table 1's spherical partials through the tree's B, M, N transforms). The
probes add no variables, so the probe engine's columns are the model's; their rows are
``dP/dx`` over every column (q, s', xi', l): the chain rule through the kinematics, analytic.

A joint hardpoint ``P = r_b + A_b s'_J`` also depends on the design variable ``s'_J`` itself:
its column block gets ``+A_b`` on top of the probe's rows (the probe's own ``s`` is not a
column). Checked against central differences in tests/propagation/test_targets.py.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from kinprop.engine import Engine, State
from kinprop.engine import compile as compile_engine
from kinprop.errors import AddressError
from kinprop.model.mechanism import Joint, Mechanism
from kinprop.spatial import Array


@dataclass(frozen=True)
class PointSpec:
    """A body-fixed point: a named point (``s`` constant) or a joint hardpoint (``joint``,
    ``side``: ``s`` is that joint's current ``s'``)."""

    body: str
    s: tuple[float, float, float] | None = None
    joint: str | None = None
    side: int = 0


class PointJacobians:
    """``dP/dx`` of a fixed list of points (module docstring); build once per engine and list."""

    def __init__(self, engine: Engine, points: Sequence[PointSpec]) -> None:
        mech = engine.mechanism
        fixed = next(b.name for b in mech.bodies if b.fixed)
        # a point on a fixed body needs no probe: only its own s' column moves it
        self._moving = [k for k, p in enumerate(points) if not mech.body(p.body).fixed]
        probes = tuple(
            Joint(f"__probe{k}", "spherical-point", fixed, points[k].body, frozenset(), cut=True) for k in self._moving
        )
        self.engine = engine
        self.points = tuple(points)
        probed = Mechanism(mech.bodies, mech.joints + probes, mech.name, couplings=mech.couplings, edits=mech.edits)
        self.probe = compile_engine(probed)
        if self.probe.column_labels != engine.column_labels:  # pragma: no cover - probes add no columns
            raise AddressError("internal: probe joints changed the variable layout")
        blocks = {b.joint: b.rows for b in self.probe.row_blocks}
        self.rows = {k: blocks[j.name] for k, j in zip(self._moving, probes, strict=True)}
        self.nj = len(mech.joints)
        self._fixed = self.probe.poses(self.probe.default_state())[0][self.probe.body_index[fixed]]
        keys = [None if p.joint is None else f"{p.joint}.{'s_i' if p.side == 0 else 's_j'}" for p in points]
        self._s_cols = [engine.columns([k]) if k is not None and k in engine.layout else None for k in keys]

    def _state(self, state: State) -> State:
        """The probe engine's state: the model's, plus each probe's ``s_j``."""
        nj, npb = self.nj, len(self._moving)
        S = np.concatenate([state.S, np.zeros((npb, 2, 3))])
        C = np.concatenate([state.C, np.tile(np.eye(3), (npb, 2, 1, 1))])
        L = np.concatenate([state.L[:nj], np.zeros(npb), state.L[nj:]])  # lengths, probes, coupling coefficients
        for n, k in enumerate(self._moving):
            S[nj + n, 1] = self._s(state, self.points[k])
        return State(state.Q, S, C, L)

    def _s(self, state: State, p: PointSpec) -> Array:
        return np.asarray(p.s, float) if p.joint is None else state.S[self.engine.joint_index[p.joint], p.side]

    def evaluate(self, state: State, columns: Array) -> tuple[Array, Array]:
        """Points ``(n, 3)`` and ``dP/dx`` ``(n, 3, len(columns))`` at ``state``."""
        st = self._state(state)
        Phi, J = self.probe.evaluate(st)
        cols = np.asarray(columns, np.int64)
        r, A, _, _ = self.probe.poses(st)
        P = np.zeros((len(self.points), 3))
        G = np.zeros((len(self.points), 3, cols.size))
        for k, p in enumerate(self.points):
            rows = self.rows.get(k)
            if rows is None:  # fixed body
                b = self.probe.body_index[p.body]
                P[k] = r[b] + A[b] @ self._s(state, p)
            else:  # Phi = P_j - P_i with the fixed body (s_i = 0) on side i
                P[k] = Phi[rows] + self._fixed
                G[k] = J[rows][:, cols]
            if self._s_cols[k] is not None:
                Ab = A[self.probe.body_index[p.body]]
                for c_local, c in enumerate(self._s_cols[k]):
                    hit = np.flatnonzero(cols == c)
                    if hit.size:
                        G[k][:, hit[0]] += Ab[:, c_local]
        return P, G


__all__ = ["PointJacobians", "PointSpec"]
