"""A suspension's first-order geometry: gains with wheel travel, front- and side-view instant
centres and swing arms, roll-centre height, anti-dive / anti-lift / anti-squat, half-track
and contact-patch changes, motion ratios and the wheel rate (docs/analysis/suspension.md has
every definition with its reference and sign).

Everything comes from one velocity analysis of the assembled state
(:mod:`kinprop.engine.motion`): the wheel's motion in bump is the one-degree-of-freedom
motion with the travel input driven (the first declared input, or the mechanism's only
degree of freedom when it declares none) and every other declared input held (a rack, a
steering input; a translational-distance joint's own rack coordinate too). "Wheel travel"
``z`` is the wheel centre's vertical displacement; a gain is
``(d quantity / dt) / (dz / dt)`` along that motion: exact, no differencing.

A view's instant centre (front view: the plane x = x_E, side view: y = y_E, E the contact
point) is the pole of the wheel body's motion relative to the fixed body in that plane: the
point X of the plane whose velocity ``v_O + w x X`` is normal to it, so every point F of the
plane moves across the line F-X (Milliken's construction, exact in 3D: a force at E reaches the
spring through E's path, virtual work). For a screw of zero pitch X is where the screw axis
pierces the plane; a screw of large pitch (a MacPherson with large bump steer) moves it
far from there. Written homogeneously so that a centre at infinity gives finite line
directions: ``X = H / s`` with ``s = n.w / |w|`` (the side view: ``H = (v_Oz + w_x y_E,
w_y y_E, w_z y_E - v_Ox) / |w|``), and the line from F towards it has direction
``H - s F``. Centres at infinity are reported as NaN coordinates and an infinite swing-arm
length; roll-centre height and the anti percentages stay finite.

The formulas are compiled (:mod:`kinprop.engine.firstorder`, the one implementation): a
:class:`FirstOrderProgram` holds one wheel's points, parameters and elements as its tables and
evaluates them over a whole batch of states in one call (a sweep's steps, a study's variants).
Design derivatives (:meth:`FirstOrderProgram.derivatives`) are exact too: the velocity state's
derivatives along a state direction come from :func:`kinprop.engine.motion.motion_derivatives`
(analytic second-order terms), the points move with their bodies (and with their own ``s'``
when they are joint frames, or an element's end when it is a design variable), and the
formulas, analytic in all of these, are differentiated in forward mode by a complex step (dual
numbers; no subtractive difference).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from kinprop.analysis.program import ProgramBuilder
from kinprop.engine import Engine, State
from kinprop.engine import firstorder as compiled
from kinprop.engine import outputs as compiled_outputs
from kinprop.engine.motion import SOLVED, MotionState, _velocity_plan, cross3, motion_derivatives, motion_state
from kinprop.errors import AddressError
from kinprop.kinematics.kernels import W_BODY_A, W_BODY_R, W_FRAME_P
from kinprop.kinematics.tables import J_COL_S_I, J_NQ, J_QCOL, K_JOINT
from kinprop.model import Model
from kinprop.spatial import Array

GAIN_METRICS = ("camber_gain", "bump_steer", "caster_gain")
CENTRE_METRICS = ("fvic_y", "fvic_z", "fvsa_length", "svic_x", "svic_z", "svsa_length", "roll_centre_height")
ANTI_METRICS = ("anti_dive", "anti_lift", "anti_squat")
GROUND_METRICS = ("half_track_change", "contact_patch_dx", "half_track_gain", "contact_patch_dx_gain")
#: motion ratios are ``motion_ratio:ELEMENT``
MOTION_RATIO = "motion_ratio"
FIRST_ORDER = GAIN_METRICS + CENTRE_METRICS + ANTI_METRICS + GROUND_METRICS + ("wheel_rate",)


def travel_rates(engine: Engine, model: Model, travel_input: str | None, state: State) -> dict[str, float]:
    """The driven rates of the bump motion (module docstring): the travel input at unit rate,
    every other declared input held, and a cut joint's own coordinate (a translational-distance
    joint's rack, which ``inputs:`` cannot name) held when the motion would otherwise have
    more than one degree of freedom."""
    inputs = [a if "." in a else f"{a}.q" for a in model.mechanism.inputs]
    nq = engine.n_coordinates
    tb = engine.tables
    cut = tb.cut[:, K_JOINT]
    racks = tb.joint[cut[tb.joint[cut, J_NQ] > 0], J_QCOL].tolist()

    def null(cols: list[int]) -> Array:
        J = engine.evaluate(state)[1][:, :nq] * engine.row_scale[:, None] / engine.col_scale[None, :nq]
        E = np.zeros((len(cols), nq))
        E[np.arange(len(cols)), cols] = 1.0
        M = np.vstack([J, E])
        _, s, Vt = np.linalg.svd(M)
        return Vt[int(np.sum(s > 1e-10 * s[0])) :]

    if travel_input is not None or inputs:
        drive = (travel_input if "." in travel_input else f"{travel_input}.q") if travel_input else inputs[0]
        held = [a for a in inputs if a != drive]
        if racks:
            driven = [int(c) for c in engine.columns([drive, *held])]
            if null(driven).shape[0] > 0:  # underdetermined: hold the racks too
                held += [engine.column_labels[c] for c in racks if c not in driven]
    else:  # the mechanism's only degree of freedom (racks held): drive its largest coordinate
        free = null(racks)
        if free.shape[0] != 1:
            raise AddressError(
                f"the wheel's motion has {free.shape[0]} degrees of freedom: declare the travel input "
                "first in 'inputs:' (and the others, e.g. a rack, after it)"
            )
        col = int(np.argmax(np.abs(free[0])))
        drive, held = engine.column_labels[col], [engine.column_labels[c] for c in racks]
    return {drive: 1.0} | {a: 0.0 for a in held}


def travel_motion(
    engine: Engine, model: Model, travel_input: str | None = None, state: State | None = None
) -> MotionState:
    """The velocity state of the bump motion (module docstring) at the model's state (``state``:
    already packed)."""
    st = state if state is not None else engine.state_of(model)
    return engine.motion(st, travel_rates(engine, model, travel_input, st))


#: complex step of the exact derivatives (:meth:`FirstOrderProgram.derivatives`): the metric
#: formulas are analytic in their inputs, so ``Im f(x + i h dx) / h`` is ``f'(x) dx`` with a
#: truncation error of order h^2 (1e-60 relative), far below round-off: forward-mode dual numbers
COMPLEX_STEP = 1e-30

#: the formulas' Python source: run on complex arrays for the complex step (module docstring)
_FORMULAS = getattr(compiled.wheel_first_order, "py_func", compiled.wheel_first_order)
_POSITIONS = getattr(compiled.point_positions, "py_func", compiled.point_positions)


class _Builder(ProgramBuilder):
    """Point slots of a first-order program: the output program's (wheel points by the lookup
    rules of :mod:`kinprop.analysis.metrics`), plus the elements' body-frame ends."""

    def element_point(self, element: str, side: str, body: str, xyz: Array) -> int:
        b = self.engine.body_index[body]
        return self._slot(("element", element, side), compiled_outputs.PK_BODY, b, 0, xyz)


@dataclass(frozen=True)
class FirstOrderProgram:
    """One wheel's first-order metrics as the tables of :mod:`kinprop.engine.firstorder`,
    evaluated over any number of states by its compiled kernel; :meth:`derivatives`: their exact
    design derivatives at one state."""

    engine: Engine
    model: Model
    wheel: str
    #: the metrics the wheel supports (:func:`first_order_names`) and their columns in a row
    names: tuple[str, ...]
    columns: Array
    points: Array
    xyz: Array
    wheels: Array
    params: Array
    elements: Array
    stiffness: Array
    travel_input: str | None = None

    def rates(self, state: State) -> dict[str, float]:
        """The bump motion's driven rates at ``state`` (:func:`travel_rates`)."""
        return travel_rates(self.engine, self.model, self.travel_input, state)

    def point_xyz(self, ends: Array | None = None) -> Array:
        """``(M, np, 3)``: the point table's coordinates, with the elements' body-frame ends
        ``ends`` (M, ne, 2, 3) of each of M states written into their slots (None: the model's,
        M = 1)."""
        if ends is None:
            return self.xyz[None]
        ends = np.asarray(ends, dtype=float).reshape(-1, self.elements.shape[0], 2, 3)
        xyz = np.repeat(self.xyz[None], ends.shape[0], axis=0)
        for e in range(self.elements.shape[0]):
            for side in (0, 1):
                xyz[:, self.elements[e, side]] = ends[:, e, side]
        return xyz

    def evaluate(self, states: State, ok: Array | None = None, ends: Array | None = None) -> Array:
        """``(N, len(names))``: the metrics at each state of a batch (leading axis; one state:
        ``(len(names),)``), NaN where not ``ok`` or where the bump motion is singular: one
        compiled call (a state whose velocity blocks are not square and regular is answered by
        the SVD path of :func:`kinprop.engine.motion.motion_state`). ``ends`` (N, ne, 2, 3):
        each state's own element ends in their bodies' frames (element points varied by a
        study; no body moves with them), else the model's."""
        st = states.writable()
        single = st.Q.ndim == 1
        if single:
            st = State(st.Q[None], st.S[None], st.C[None], st.L[None])
        n, eng = st.Q.shape[0], self.engine
        xyz = self.point_xyz(ends)
        if xyz.shape[0] not in (1, n):
            raise ValueError(f"ends for {xyz.shape[0]} states, given {n} states")
        mask = np.ones(n, dtype=np.bool_) if ok is None else np.ascontiguousarray(ok, dtype=np.bool_)
        out = np.full((n, 1, compiled.N_FIRST + self.elements.shape[0]), np.nan)
        status = np.full(n, -1, np.int64)
        first = np.flatnonzero(mask)
        if first.size:
            rates = self.rates(st[int(first[0])])
            cols, vals, plan, need, buf = _velocity_plan(eng, rates)
            rate = np.zeros(eng.n_coordinates)
            rate[cols] = vals
            rows, pcols = eng.pattern
            if buf is not None:
                compiled.batch_first_order(eng.tables, plan, st.Q, st.S, st.C, st.L, mask, rate, need, rows, pcols,
                                           eng.row_scale, self.points, xyz, self.wheels, self.params,
                                           self.elements, self.stiffness, out, status)  # fmt: skip
            for i in first[status[first] != SOLVED]:  # the SVD path decides (singular: NaN)
                ms = motion_state(eng, st[int(i)], rates)
                if ms.ok:
                    pts, body_of = self._positions(ms, xyz[int(i) if xyz.shape[0] > 1 else 0])
                    _FORMULAS(self.wheels[0], self.params[0], pts, body_of, ms.V, self.elements, self.stiffness,
                              out[i, 0])  # fmt: skip
        values = out[:, 0, self.columns]
        return values[0] if single else values

    def values(self, state: State) -> dict[str, float]:
        """``{metric: value}`` at one state."""
        return dict(zip(self.names, (float(v) for v in self.evaluate(state)), strict=True))

    def _positions(self, ms: MotionState, xyz: Array | None = None) -> tuple[Array, Array]:
        ws: list[Any] = [None] * (max(W_BODY_R, W_BODY_A, W_FRAME_P) + 1)
        ws[W_BODY_R], ws[W_BODY_A], ws[W_FRAME_P] = ms.r, ms.A, ms.P
        pts, body_of = np.zeros((self.points.shape[0], 3)), np.zeros(self.points.shape[0], np.int64)
        _POSITIONS(self.engine.tables, ws, self.points, self.xyz if xyz is None else xyz, pts, body_of)
        return pts, body_of

    def derivatives(self, state: State, directions: Array, elements: Array | None = None) -> dict[str, Array]:
        """Exact derivatives of the metrics along each column ``dx`` of ``directions``
        (``(n_columns, k)``, solver units; the state moves along ``retract(x, eps dx)``, the
        wheel's travel rate held): the velocity state's derivatives from
        :func:`kinprop.engine.motion.motion_derivatives` (analytic), the points' from the bodies'
        pose changes (and a joint frame's own ``s'``), and the formulas in forward mode by a
        complex step (:data:`COMPLEX_STEP`). ``elements`` (ne, 2, 3, k): the body-frame moves of
        the elements' ends along each direction (element points as design variables). NaN
        where a metric is undefined or infinite."""
        eng = self.engine
        X = np.asarray(directions, dtype=float).reshape(eng.n_columns, -1)
        md = motion_derivatives(eng, state, self.rates(state), X)
        ms, k = md.motion, X.shape[1]
        out = {n: np.full(k, np.nan) for n in self.names}
        if not ms.ok:
            return out
        pts, body_of = self._positions(ms)
        tb, h = eng.tables, COMPLEX_STEP
        frame_cols: dict[int, Array] = {}  # a joint frame slot: the columns of its own s'
        for slot in range(self.points.shape[0]):
            kind, a, side = (int(x) for x in self.points[slot])
            if kind == compiled_outputs.PK_FRAME and tb.joint[a, J_COL_S_I + side] >= 0:
                c0 = int(tb.joint[a, J_COL_S_I + side])
                frame_cols[slot] = np.arange(c0, c0 + 3)
        ends = {int(self.elements[e, s]): (e, s) for e in range(self.elements.shape[0]) for s in (0, 1)}
        row = np.zeros(compiled.N_FIRST + self.elements.shape[0], dtype=complex)
        for i in range(k):
            P = md.pose[i]
            d = np.zeros_like(pts)
            for slot in range(pts.shape[0]):
                b = int(body_of[slot])
                if b < 0:
                    continue
                d[slot] = P[b, :3] + cross3(P[b, 3:], pts[slot])
                if slot in frame_cols:
                    d[slot] += ms.A[b] @ X[frame_cols[slot], i]
                if elements is not None and slot in ends:
                    e, s = ends[slot]
                    d[slot] += ms.A[b] @ elements[e, s, :, i]
            _FORMULAS(self.wheels[0], self.params[0], pts + 1j * h * d, body_of, ms.V + 1j * h * md.V[i],
                      self.elements, self.stiffness, row)  # fmt: skip
            for n, c in zip(self.names, self.columns, strict=True):
                v = row[c]
                out[n][i] = np.imag(v) / h if np.isfinite(np.real(v)) else math.nan
        return out


def first_order_program(
    model: Model,
    engine: Engine,
    wheel: str,
    radius: float | None,
    reference_contact: Array | tuple[str, str] | None,
    *,
    reference: Model | None = None,
    wheels: Any = None,
    travel_input: str | None = None,
) -> FirstOrderProgram:
    """The :class:`FirstOrderProgram` of ``wheel``: its points by the lookup rules of
    :mod:`kinprop.analysis.metrics` (``reference``, ``wheels`` as there), ``radius`` the loaded
    radius (None: no contact patch), ``reference_contact`` a global position or a fixed body's
    named point ``(body, name)`` (None: no half-track / contact-patch changes)."""
    b = _Builder(model, engine, reference, wheels)
    row, _ = b.wheel(wheel)
    w = b._wheels[row]
    ref = -1
    if isinstance(reference_contact, tuple):
        ref = b.body_point(*reference_contact)
    elif reference_contact is not None:
        ref = b.constant(f"contact:{wheel}", reference_contact)
    veh = model.vehicle
    axle = compiled.AXLE_NONE if veh is None else compiled.AXLE_FRONT if veh.axle == "front" else compiled.AXLE_REAR
    inboard = 0 if veh is None else (veh.brakes == "inboard") + 2 * (veh.drive == "inboard")
    wheels_t = np.array([[engine.body_index[wheel], w[compiled_outputs.WH_CENTRE], w[compiled_outputs.WH_SPIN],
                          w[compiled_outputs.WH_UPPER], w[compiled_outputs.WH_LOWER], w[compiled_outputs.WH_ORDER],
                          ref, axle, inboard]], dtype=np.int64)  # fmt: skip
    lever = math.nan if veh is None else veh.wheelbase / veh.cg_height * 100.0
    params = np.array([[math.nan if radius is None else radius, lever, math.nan if veh is None else veh.brake_front,
                        math.nan if veh is None else veh.drive_front]])  # fmt: skip
    ends = [[b.element_point(e.name, s, body, np.asarray(x, float)) for s, body, x in
             (("i", e.body_i, e.s_i), ("j", e.body_j, e.s_j))] for e in model.elements]  # fmt: skip
    stiffness = np.array([float(e.stiffness or 0.0) if e.has_spring else math.nan for e in model.elements])
    names = first_order_names(model, radius is not None, w[compiled_outputs.WH_UPPER] >= 0, ref >= 0)
    codes = {c: k for k, c in enumerate(compiled.FIRST_CODES)}
    codes |= {f"{MOTION_RATIO}:{e.name}": compiled.N_FIRST + k for k, e in enumerate(model.elements)}
    prog = b.build()
    return FirstOrderProgram(engine, model, wheel, tuple(names), np.array([codes[n] for n in names], np.int64),
                             prog.points, prog.xyz, wheels_t, params, np.array(ends, np.int64).reshape(-1, 2),
                             stiffness.reshape(-1), travel_input)  # fmt: skip


def first_order_names(model: Model, contact: bool, steer: bool, reference: bool) -> list[str]:
    """First-order metrics a wheel supports: the gains always, caster gain with a steering axis,
    the ground and centre metrics with a contact patch (changes with a reference), the anti
    metrics of the vehicle's axle, the elements' motion ratios and the springs' wheel rate."""
    out = ["camber_gain", "bump_steer"] + (["caster_gain"] if steer else [])
    if contact:
        out += (["half_track_change", "contact_patch_dx"] if reference else []) + [
            "half_track_gain",
            "contact_patch_dx_gain",
        ]
        out += list(CENTRE_METRICS)
        if model.vehicle is not None:
            out += ["anti_dive", "anti_lift"] if model.vehicle.axle == "front" else ["anti_lift", "anti_squat"]
    out += [f"{MOTION_RATIO}:{e.name}" for e in model.elements]
    if any(e.has_spring for e in model.elements):
        out.append("wheel_rate")
    return out


def first_order_unit(metric: str, units: dict[str, str] | None = None) -> str:
    """Unit of a first-order metric in the model's units."""
    u = units or {}
    length, angle = u.get("length", "m"), u.get("angle", "rad")
    if metric in GAIN_METRICS:
        return f"{angle}/{length}"
    if metric in ANTI_METRICS:
        return "%"
    if metric == "wheel_rate":
        return f"{u.get('force', 'force')}/{length}"
    if metric in ("half_track_gain", "contact_patch_dx_gain") or metric.startswith(f"{MOTION_RATIO}:"):
        return ""
    return length


__all__ = [
    "COMPLEX_STEP",
    "FIRST_ORDER",
    "FirstOrderProgram",
    "first_order_names",
    "first_order_program",
    "first_order_unit",
    "travel_motion",
    "travel_rates",
]
