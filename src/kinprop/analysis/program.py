"""Output programs: named outputs translated once into the flat tables of
:mod:`kinprop.engine.outputs`, then evaluated over any number of states by its compiled kernel
(no Python per state).

:class:`ProgramBuilder` adds one row per scalar output — a coordinate or design variable, a
component of a point (``point:BODY.NAME``, ``hardpoint:JOINT.i|j``, a pivot ``hardpoint:JOINT.NAME``),
a distance between two points, a position-level metric of a wheel (docs/analysis/suspension.md)
— or a row left to the caller (first-order metrics and loads, evaluated from a velocity or a
static analysis: NaN here). Each point is stored once however many outputs use it, and each
wheel once (its centre, spin-axis point, steering axis, contact patch and reference centre by
the lookup rules of :mod:`kinprop.analysis.metrics`). :mod:`kinprop.analysis.outputs` parses
output names into these rows.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from kinprop.analysis.context import OutputContext, WheelSpec, find_point, locate_point, pivot_point
from kinprop.engine import Engine, State
from kinprop.engine import outputs as compiled
from kinprop.errors import AddressError
from kinprop.model import Model
from kinprop.model.joint_points import steering_joints
from kinprop.spatial import Array

_SIDES = {"i": 0, "j": 1}


@dataclass(frozen=True)
class OutputProgram:
    """Scalar outputs as the tables of :mod:`kinprop.engine.outputs` (module docstring)."""

    engine: Engine
    names: tuple[str, ...]
    points: Array
    xyz: Array
    wheels: Array
    outputs: Array

    @property
    def compiled(self) -> Array:
        """Per output: evaluated by the kernel (False: left to the caller, NaN in :meth:`evaluate`)."""
        return self.outputs[:, compiled.OT_KIND] != compiled.OK_NONE

    def evaluate(self, states: State, ok: Array | None = None) -> Array:
        """The outputs (solver units: radians, metric angles in degrees) of one state (no,) or
        of a batch (N, no); rows where ``ok`` is False are NaN."""
        st = states.writable()
        single = st.Q.ndim == 1
        if single:
            st = State(st.Q[None], st.S[None], st.C[None], st.L[None])
        n = st.Q.shape[0]
        mask = np.ones(n, dtype=np.bool_) if ok is None else np.ascontiguousarray(ok, dtype=np.bool_)
        out = np.empty((n, self.outputs.shape[0]))
        compiled.batch_outputs(self.engine.tables, st.Q, st.S, st.C, st.L, mask, self.points, self.xyz, self.wheels,
                               self.outputs, out)  # fmt: skip
        return out[0] if single else out


class ProgramBuilder:
    """Rows of an :class:`OutputProgram` for one model (its mechanism's engine); ``reference``
    and ``wheels`` as in :func:`kinprop.analysis.outputs.evaluate_outputs`."""

    def __init__(
        self,
        model: Model,
        engine: Engine,
        reference: Model | None = None,
        wheels: Mapping[str, WheelSpec] | None = None,
    ) -> None:
        self.model, self.engine, self.reference, self.specs = model, engine, reference, wheels or {}
        self._points: list[tuple[int, int, int]] = []
        self._xyz: list[Array] = []
        self._slots: dict[tuple, int] = {}
        self._wheels: list[list[int]] = []
        self._wheel_rows: dict[str, tuple[int, tuple[str, ...]]] = {}
        self.names: list[str] = []
        self.rows: list[tuple[int, int, int, int]] = []

    # --- points -------------------------------------------------------------------------------
    def _slot(self, key: tuple, kind: int, a: int, b: int, xyz: Array) -> int:
        if key not in self._slots:
            self._slots[key] = len(self._points)
            self._points.append((kind, a, b))
            self._xyz.append(np.asarray(xyz, dtype=float))
        return self._slots[key]

    def body_point(self, body: str, name: str) -> int:
        """Slot of the named point ``name`` of ``body`` (a joint's point follows the joint)."""
        source = locate_point(self.model, body, name)
        if source[0] == "joint":
            return self.hardpoint(source[1], source[2])  # type: ignore[arg-type]
        b = self.engine.body_index[body]
        return self._slot(("body", body, name), compiled.PK_BODY, b, 0, source[2])

    def hardpoint(self, joint: str, side: str) -> int:
        """Slot of ``joint``'s frame origin on side ``i``/``j``, or of its pivot ``side``."""
        mech = self.model.mechanism
        if joint not in mech.joint_names:
            raise AddressError(f"unknown joint {joint!r}; joints are {', '.join(mech.joint_names)}")
        if side not in _SIDES:
            return self.body_point(*pivot_point(self.model, joint, side))
        j = self.engine.joint_index[joint]
        return self._slot(("frame", joint, side), compiled.PK_FRAME, j, _SIDES[side], np.zeros(3))

    def constant(self, key: str, xyz: Array) -> int:
        """Slot of a fixed global point."""
        return self._slot(("const", key), compiled.PK_CONST, 0, 0, xyz)

    def point(self, spec: str) -> int:
        """Slot of a ``point:BODY.NAME`` or ``hardpoint:JOINT.i|j`` spec."""
        kind, _, rest = spec.partition(":")
        head, _, name = rest.partition(".")
        if kind == "point" and name:
            return self.body_point(head, name)
        if kind == "hardpoint" and name:
            return self.hardpoint(head, name)
        raise AddressError(f"{spec!r} is not a point: expected point:BODY.NAME or hardpoint:JOINT.i|j")

    # --- wheels -------------------------------------------------------------------------------
    def wheel(self, wheel: str) -> tuple[int, tuple[str, ...]]:
        """``(row, metrics)``: the wheel's row in the wheels table and the position-level metrics
        its points give (lookup rules of :mod:`kinprop.analysis.metrics`)."""
        if wheel in self._wheel_rows:
            return self._wheel_rows[wheel]
        spec = self.specs.get(wheel)
        row = [self.body_point(wheel, "wheel_centre"), self.body_point(wheel, "spin_axis"), -1, -1, 0, -1, -1]
        metrics = ["camber", "toe"]
        found = [find_point(self.model, wheel, n) for n in ("kingpin_upper", "kingpin_lower")]
        pair = steering_joints(self.model.mechanism, wheel)
        if spec is not None and spec.steering_axis is not None:
            row[2], row[3] = (self.point(s) for s in spec.steering_axis)
        elif found[0] is not None and found[1] is not None:
            row[2], row[3] = (self.body_point(*f) for f in found)  # type: ignore[misc]
        elif pair is not None:  # the higher of the two joints' points is the upper one, per state
            row[2], row[3], row[4] = self.hardpoint(*pair[0]), self.hardpoint(*pair[1]), 1
        if row[2] >= 0:
            metrics += ["caster", "kpi"]
            if "contact_patch" in dict(self.model.mechanism.body(wheel).points):
                row[5] = self.body_point(wheel, "contact_patch")
                metrics += ["scrub_radius", "trail"]
        if self.reference is not None:
            centre = OutputContext.of(self.reference, engine=self.engine).body_point(wheel, "wheel_centre")
            row[6] = self.constant(f"reference:{wheel}", centre)
        else:
            ref = find_point(self.model, wheel, "wheel_centre_ref", on_wheel=False)
            if ref is not None:
                row[6] = self.body_point(*ref)
        if row[6] >= 0:
            metrics += ["wheel_centre_dx", "wheel_centre_dy", "wheel_centre_dz"]
        self._wheels.append(row)
        self._wheel_rows[wheel] = (len(self._wheels) - 1, tuple(metrics))
        return self._wheel_rows[wheel]

    # --- rows ---------------------------------------------------------------------------------
    def _add(self, name: str, kind: int, a: int = 0, b: int = 0, c: int = 0) -> None:
        self.names.append(name)
        self.rows.append((kind, a, b, c))

    def add_point(self, name: str, spec: str, component: int) -> None:
        self._add(name, compiled.OK_POINT, self.point(spec), component)

    def add_distance(self, name: str, a: str, b: str) -> None:
        self._add(name, compiled.OK_DISTANCE, self.point(a), self.point(b))

    def add_metric(self, name: str, wheel: str, metric: str) -> None:
        """A position-level metric of ``wheel`` (the caller checks that the wheel gives it)."""
        row, _ = self.wheel(wheel)
        self._add(name, compiled.OK_METRIC, row, compiled.METRIC_CODES.index(metric))

    def add_variable(self, name: str, address: str) -> None:
        """A coordinate or a scalar design variable (one component of ``address``)."""
        t = self.engine.target(address)
        k = t.index or 0
        if t.group == "q":
            self._add(name, compiled.OK_Q, t.start + k)
        elif t.group == "s":
            self._add(name, compiled.OK_S, t.joint, t.side, k)
        elif t.group in ("l", "coef"):
            self._add(name, compiled.OK_L, t.joint + (k if t.group == "coef" else 0))
        else:
            raise AddressError(f"output {name!r}: orientations are not scalar outputs; use points or metrics")

    def add_other(self, name: str) -> None:
        """An output the caller evaluates itself (NaN in the program)."""
        self._add(name, compiled.OK_NONE)

    def build(self) -> OutputProgram:
        def table(rows: list, width: int) -> Array:
            return np.array(rows, dtype=np.int64).reshape(len(rows), width)

        xyz = np.array(self._xyz, dtype=float).reshape(len(self._xyz), 3)
        return OutputProgram(self.engine, tuple(self.names), table(self._points, 3), xyz, table(self._wheels, 7),
                             table(self.rows, 4))  # fmt: skip


__all__ = ["OutputProgram", "ProgramBuilder"]
