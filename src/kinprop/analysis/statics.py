"""Loads of an assembled model, by name, in the model's units: ``kp.statics(model, loads)``.

The engine does the work (:mod:`kinprop.engine.statics`: ``Phi_q^T lambda + Q + E_D^T tau =
0`` on the kernel's Jacobian, tree-joint reactions by the Newton-Euler recursion from the
leaves); this module turns the model's loads (:mod:`kinprop.model.loads`) into body wrenches
and the engine's arrays into a record by joint, element and input.

Sign conventions and units (force unit ``F`` = the model's ``units.force``, length ``L``):

* **reaction** of a joint on a body: the force (``F``) and moment (``F L``, about the joint's
  point on that body: its hardpoint ``P_i`` on body i, ``P_j`` on body j) the joint applies to
  that body; the two sides are equal and opposite (moments too when ``P_i = P_j``). Global
  axes, and joint frame i's axes (``local``). A tree joint's reaction includes the input
  effort and coupling torques along its free directions.
* **member force** of a joint with a rod (distance joint, revolute-spherical link,
  translational-distance tie rod: tie rods, push rods, links): the rod's axial force,
  **tension positive** (``F``), ``-2 lambda |d|`` of its distance row.
* **element force** of a spring or damper: **positive pushing the ends apart** (compression
  of a coil spring; the ``preload`` convention), ``f = k (L0 - L)`` from ``free_length``
  ``L0``, or ``preload + k (L_model - L)`` with ``L_model`` the length in the given model; a
  damper carries no force at rest.
* **torsion spring** on a revolute joint's angle (``type: torsion``, an anti-roll bar's
  twist): its torque ``T = k (free_angle - q)`` or ``preload + k (q_model - q)`` (``F L``;
  ``k`` per the model's angle unit), positive turning body j towards increasing ``q``; its
  "length" is the joint angle (the model's angle unit).
* **effort** at a declared input: the generalised force the input applies to its coordinate
  to hold the pose, positive along increasing ``q``: a torque (``F L``) for an angle whatever
  the angle unit, a force for a slide. By virtual work ``effort = -sum F_k . dP_k/dq``.
* **undetermined**: the components a redundant mechanism's loads do not determine
  (``JOINT.fx`` ... ``JOINT.mz`` in joint frame i, on body j), reported NaN.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from kinprop.analysis.metrics import _radius, contact_point, wheel_bodies
from kinprop.engine import Engine
from kinprop.engine import compile as compile_engine
from kinprop.engine.motion import motion_state
from kinprop.engine.statics import (
    Law,
    PointForces,
    StaticsState,
    TorsionLaw,
    distance_rows,
    element_laws,
    element_state,
    reduced_stiffness,
    statics_state,
)
from kinprop.engine.statics_rates import StaticsRates, statics_rates
from kinprop.engine.status import Status
from kinprop.engine.units import address_scale, radians_per_angle
from kinprop.errors import AddressError
from kinprop.model import Model
from kinprop.model.loads import LoadCase, PointLoad
from kinprop.propagation.sensitivity import design_sensitivity
from kinprop.spatial import Array

COMPONENTS = ("fx", "fy", "fz", "mx", "my", "mz")


@dataclass(frozen=True)
class JointReaction:
    """One joint's reaction on its two bodies (module docstring), model units; NaN: undetermined."""

    joint: str
    bodies: tuple[str, str]
    #: the joint's point on body i and on body j (global)
    points: tuple[Array, Array]
    #: force and moment (about that body's point) on body i / body j, global axes
    force: tuple[Array, Array]
    moment: tuple[Array, Array]
    #: the same in joint frame i's axes: (2, 6) [fx fy fz mx my mz] on body i / body j
    local: Array
    #: undetermined components of the reaction on body j (joint frame i): ``fx`` ... ``mz``
    undetermined: tuple[str, ...] = ()

    @property
    def magnitude(self) -> float:
        """``|F|`` of the force on body j (NaN when undetermined)."""
        return float(np.linalg.norm(self.force[1]))


@dataclass(frozen=True)
class Statics:
    """Loads of one assembled model under one load case (module docstring)."""

    model: Model
    engine: Engine
    state: StaticsState
    case: str | None
    reactions: Mapping[str, JointReaction]
    #: distance joints' axial forces, tension positive
    member_forces: Mapping[str, float]
    #: elements' forces (positive pushing apart) and lengths
    element_forces: Mapping[str, float]
    element_lengths: Mapping[str, float]
    #: the inputs' efforts: ``{"O2.q": torque}`` (``JOINT.q[k]`` for a multi-coordinate joint)
    efforts: Mapping[str, float]
    #: ``JOINT.fx`` ... of every undetermined reaction component (on body j, joint frame i)
    undetermined: tuple[str, ...]

    @property
    def status(self) -> Status:
        """:class:`kinprop.Status`: ``ok``, ``unbalanced`` or ``not_assembled`` (docs/results.md)."""
        return self.state.status

    @property
    def residual(self) -> float:
        """``||Phi||`` of the pose, scaled as the solver's test (:attr:`kinprop.Solution.residual`)."""
        return self.state.residual

    @property
    def ok(self) -> bool:
        return self.state.ok

    @property
    def message(self) -> str:
        return self.state.message

    @property
    def units(self) -> dict[str, str]:
        F, L = self.model.units.get("force", "force"), self.model.units.get("length", "m")
        return {"force": F, "moment": f"{F} {L}", "length": L}

    def value(self, name: str) -> float:
        """A load output: ``reaction:JOINT.fx|fy|fz|mx|my|mz|f`` (global axes, on body j,
        moment about its point; ``f`` the magnitude), ``reaction:JOINT.local.fx`` ... (joint
        frame i), ``force:NAME`` (a distance joint's tension or an element's force),
        ``effort:JOINT`` (``effort:JOINT.q[k]``)."""
        kind, _, rest = name.partition(":")
        if kind == "reaction":
            joint, _, comp = rest.partition(".")
            if joint not in self.reactions:
                raise AddressError(f"{name!r}: unknown joint {joint!r}; joints: {', '.join(self.reactions)}")
            r = self.reactions[joint]
            local = comp.startswith("local.")
            comp = comp[len("local.") :] if local else comp
            if comp == "f":
                return float(np.linalg.norm(r.local[1, :3] if local else r.force[1]))
            if comp not in COMPONENTS:
                raise AddressError(f"{name!r}: expected a component {', '.join(COMPONENTS)} or f")
            k = COMPONENTS.index(comp)
            if local:
                return float(r.local[1, k])
            return float((r.force[1] if k < 3 else r.moment[1])[k % 3])
        if kind == "force":
            if rest in self.member_forces:
                return self.member_forces[rest]
            if rest in self.element_forces:
                return self.element_forces[rest]
            raise AddressError(
                f"{name!r}: not a distance joint or an element; members: {', '.join(self.member_forces) or 'none'}; "
                f"elements: {', '.join(self.element_forces) or 'none'}"
            )
        if kind == "effort":
            key = rest if "." in rest else f"{rest}.q"
            if key not in self.efforts:
                raise AddressError(f"{name!r}: not a held input; inputs: {', '.join(self.efforts) or 'none'}")
            return self.efforts[key]
        raise AddressError(f"{name!r}: a load output is reaction:JOINT.COMPONENT, force:NAME or effort:JOINT")

    def names(self, local: bool = False) -> list[str]:
        """Every load output :meth:`value` answers (``local``: with the joint-frame components)."""
        out = [f"reaction:{j}.{c}" for j in self.reactions for c in (*COMPONENTS, "f")]
        if local:
            out += [f"reaction:{j}.local.{c}" for j in self.reactions for c in (*COMPONENTS, "f")]
        out += [f"force:{n}" for n in (*self.member_forces, *self.element_forces)]
        return out + [f"effort:{a}" for a in self.efforts]

    def __repr__(self) -> str:
        u = self.units
        lines = [
            f"<Statics {self.case or '(no case)'}: {self.status}; forces in {u['force']}, moments in {u['moment']}>"
        ]
        for a, v in self.efforts.items():
            lines.append(f"  effort {a}: {v:.6g}")
        for j, r in self.reactions.items():
            lines.append(f"  {j} on {r.bodies[1]}: F = {np.array2string(r.force[1], precision=5)}")
        for n, v in {**self.member_forces, **self.element_forces}.items():
            lines.append(f"  force {n}: {v:.6g}")
        return "\n".join(lines)


def _angle_unit(model: Model) -> float:
    """Radians per unit of the model's angles."""
    return radians_per_angle(model)


def model_laws(model: Model, engine: Engine, reference: Any, at_pose: bool = False) -> tuple[list[Law], list[bool]]:
    """The force laws of the model's elements and torsion springs (preloads at the state
    ``reference``) and, per law, whether its force is held at its preload whatever the pose
    (``at_pose``: the preload is at the analysed pose itself, so a change of the pose moves the
    free length with it)."""
    laws = element_laws(engine, model.elements, reference, model.torsion_springs, _angle_unit(model))
    held = [at_pose and e.has_spring and e.free_length is None for e in model.elements]
    held += [at_pose and t.free_angle is None for t in model.torsion_springs]
    return laws, held


def input_columns(engine: Engine, inputs: Sequence[str]) -> tuple[list[int], list[str]]:
    """Layout q columns and their addresses of driven inputs (``JOINT`` or ``JOINT.q[k]``)."""
    cols, names = [], []
    labels = engine.column_labels
    for a in inputs:
        t = engine.target(a if "." in a else f"{a}.q")
        if t.group != "q":
            raise AddressError(f"input {a!r}: an input is a joint coordinate (JOINT or JOINT.q[k])")
        idx = [t.start + t.index] if t.index is not None else list(range(t.start, t.start + t.size))
        for c in idx:
            cols.append(c)
            names.append(labels[c] if len(idx) > 1 or t.index is not None else f"{a.split('.')[0]}.q")
    return cols, names


def _point(model: Model, body: str, point: str | Sequence[float]) -> Array:
    """Body-frame coordinates of a named point or of given coordinates."""
    if isinstance(point, str):
        pts = dict(model.mechanism.body(body).points)
        if point not in pts:
            raise AddressError(f"body {body!r} has no named point {point!r}; its points: {', '.join(pts) or 'none'}")
        return np.asarray(pts[point], dtype=float)
    return np.asarray(point, dtype=float)


def applied_points(model: Model, engine: Engine, r: Array, A: Array, case: LoadCase | None) -> PointForces:
    """The loads of a case as forces and couples at body points, global axes at poses ``r``, ``A``."""
    body, Ps, Fs, Ms, follows = [], [], [], [], []
    wheel_of: list[tuple[float, Array, Array, bool]] = []  # (radius, centre, unit axis, SAE) or radius 0
    if case is None:
        return PointForces.empty()
    names = set(model.mechanism.body_names)

    def add(b_name: str, P: Array, F: Array, M: Array, turns: bool = False) -> None:
        if b_name not in names:
            raise AddressError(f"unknown body {b_name!r}; bodies are {', '.join(model.mechanism.body_names)}")
        body.append(engine.body_index[b_name])
        Ps.append(P), Fs.append(F), Ms.append(M), follows.append(turns)
        if len(wheel_of) < len(body):
            wheel_of.append((0.0, np.zeros(3), np.zeros(3), False))

    for ld in case.forces:
        b = engine.body_index.get(ld.body, -1)
        if b < 0:
            raise AddressError(f"unknown body {ld.body!r}; bodies are {', '.join(model.mechanism.body_names)}")
        P = r[b] + A[b] @ _point(model, ld.body, ld.point)
        F, M = np.asarray(ld.force, float), np.asarray(ld.moment, float)
        if ld.axes == "body":
            F, M = A[b] @ F, A[b] @ M
        add(ld.body, P, F, M, ld.axes == "body")
    sae = model.units.get("axes") == "SAE"
    for wheel, force in case.wheels.items():
        if wheel not in wheel_bodies(model):
            raise AddressError(f"wheel force on {wheel!r}: not a wheel body (named points 'wheel_centre' and "
                               f"'spin_axis'); wheels: {', '.join(wheel_bodies(model)) or 'none'}")  # fmt: skip
        radius = _radius(model, wheel)
        if radius is None:
            raise AddressError(f"wheel force on {wheel!r}: the wheel has no 'contact_patch' point (its loaded radius)")
        b = engine.body_index[wheel]
        centre = r[b] + A[b] @ _point(model, wheel, "wheel_centre")
        axis = r[b] + A[b] @ _point(model, wheel, "spin_axis") - centre
        F = np.asarray(force, float) * (np.array([1.0, -1.0, -1.0]) if sae else 1.0)
        wheel_of.append((float(radius), centre, axis / np.linalg.norm(axis), sae))
        if sae:  # down is +z: the lowest point of the wheel circle in the z-mirrored axes, mirrored back
            flip = np.array([1.0, 1.0, -1.0])
            add(wheel, flip * contact_point(flip * centre, flip * axis, radius), F, np.zeros(3))
        else:
            add(wheel, contact_point(centre, axis, radius), F, np.zeros(3))
    if case.gravity is not None:
        g = np.asarray(case.gravity, float)
        for m in model.loads.masses if model.loads is not None else ():
            b = engine.body_index[m.body]
            add(m.body, r[b] + A[b] @ _point(model, m.body, m.cm), m.weight * g, np.zeros(3))

    def stack(x: list) -> Array:
        return np.array(x, dtype=float).reshape(-1, 3)

    return PointForces(np.array(body, np.int64), stack(Ps), stack(Fs), stack(Ms), np.array(follows, bool),
                       np.array([w[0] for w in wheel_of]), stack([w[1] for w in wheel_of]),
                       stack([w[2] for w in wheel_of]), np.array([w[3] for w in wheel_of], bool))  # fmt: skip


def applied_wrenches(model: Model, engine: Engine, r: Array, A: Array, case: LoadCase | None) -> Array:
    """(nb, 6) wrenches ``[F ; M_O]`` about the global origin of a load case at poses ``r``, ``A``."""
    return applied_points(model, engine, r, A, case).wrenches(r.shape[0])


def _case(model: Model, loads: Any) -> LoadCase | None:
    if loads is None or isinstance(loads, LoadCase):
        return loads
    if isinstance(loads, str):
        if model.loads is None:
            raise KeyError(f"load case {loads!r}: the model has no 'loads:' section")
        return model.loads.case(loads)
    if isinstance(loads, PointLoad):
        return LoadCase("loads", (loads,))
    return LoadCase("loads", tuple(loads))


def statics(
    model: Model,
    loads: str | LoadCase | PointLoad | Sequence[PointLoad] | None = None,
    *,
    inputs: Sequence[str] | None = None,
    engine: Engine | None = None,
    reference: Model | None = None,
) -> Statics:
    """Reactions, member and element forces and input efforts of the assembled ``model`` under
    ``loads`` (a load case name of the model's ``loads:``, a :class:`LoadCase`, point loads, or
    None: the elements only), held by ``inputs`` (default: the model's declared inputs).
    A preloaded element's ``preload`` is its force at ``reference``'s pose (default: this
    model's own pose: give ``free_length`` for springs analysed over a sweep). Status
    ``unbalanced`` (NaN) when the constraints and inputs cannot hold the loads."""
    eng = engine or compile_engine(model)
    st = eng.state_of(model)
    case = _case(model, loads)
    r, A, _, _ = eng.poses(st)
    W = applied_wrenches(model, eng, r, A, case)
    cols, names = input_columns(eng, model.mechanism.inputs if inputs is None else inputs)
    laws, _ = model_laws(model, eng, st if reference is None else eng.state_of(reference), reference is None)
    ss = statics_state(eng, st, W, cols, laws)
    mech = model.mechanism
    reactions = {}
    undetermined: list[str] = []
    for k, j in enumerate(mech.joints):
        F = (ss.at_point[k, 0, :3], ss.at_point[k, 1, :3])
        M = (ss.at_point[k, 0, 3:], ss.at_point[k, 1, 3:])
        und = tuple(c for n, c in enumerate(COMPONENTS) if ss.undetermined[k, 1, n] or ss.undetermined[k, 0, n])
        undetermined += [f"{j.name}.{c}" for c in und]
        reactions[j.name] = JointReaction(j.name, (j.body_i, j.body_j), (ss.P[k, 0], ss.P[k, 1]), F, M,  # type: ignore[arg-type]
                                          ss.local[k], und)  # fmt: skip
    members = {}
    rods = {j for j, _, _ in distance_rows(eng, ss.P, ss.R, st.Q)}
    for k, j in enumerate(mech.joints):
        if k in rods:  # a cut joint with a rod: its distance row's multiplier
            members[j.name] = float(ss.member[k])
        elif j.jtype.name == "distance":  # a distance joint in the tree: the force along its line
            u = ss.P[k, 1] - ss.P[k, 0]
            members[j.name] = float(-ss.at_point[k, 1, :3] @ u / np.linalg.norm(u))
    named = [*model.elements, *model.torsion_springs]
    angle = _angle_unit(model)
    ef = {e.name: float(ss.element_force[k]) for k, e in enumerate(named)}
    el = {e.name: float(ss.element_length[k]) / (angle if e.kind == "torsion" else 1.0) for k, e in enumerate(named)}
    efforts = {n: float(ss.efforts[k]) for k, n in enumerate(names)}
    return Statics(model, eng, ss, case.name if case else None, reactions, members, ef, el, efforts,
                   tuple(undetermined))  # fmt: skip


# --- design derivatives ------------------------------------------------------------------------
def _rate(s: Statics, rates: StaticsRates, name: str) -> Array:
    """(K,) rate of the load output ``name`` (no ``@CASE``) along the directions of ``rates``."""
    s.value(name)  # the output exists (AddressError naming what does otherwise)
    kind, _, rest = name.partition(":")
    mech = s.model.mechanism
    if kind == "reaction":
        joint, _, comp = rest.partition(".")
        k = mech.joint_names.index(joint)
        local = comp.startswith("local.")
        comp = comp[len("local.") :] if local else comp
        arr, now = (rates.local, s.state.local) if local else (rates.at_point, s.state.at_point)
        if comp == "f":
            F = now[k, 1, :3]
            return arr[:, k, 1, :3] @ F / float(np.linalg.norm(F))
        return arr[:, k, 1, COMPONENTS.index(comp)]
    if kind == "force":
        if rest in s.element_forces:
            return rates.element_force[:, list(s.element_forces).index(rest)]
        k = mech.joint_names.index(rest)
        if not np.isnan(s.state.member[k]):  # a cut joint's rod
            return rates.member[:, k]
        # a distance joint in the tree: -F_j . u / |u|
        u = s.state.P[k, 1] - s.state.P[k, 0]
        du = rates.point_rates[:, k, 1] - rates.point_rates[:, k, 0]
        n = float(np.linalg.norm(u))
        F = s.state.at_point[k, 1, :3]
        return -(rates.at_point[:, k, 1, :3] @ u + du @ F - (du @ u) * (F @ u) / n**2) / n
    key = rest if "." in rest else f"{rest}.q"
    return rates.efforts[:, list(s.efforts).index(key)]


def load_derivatives(
    model: Model,
    names: Sequence[str],
    directions: Array,
    *,
    engine: Engine | None = None,
    reference: Model | None = None,
    inputs: Sequence[str] | None = None,
    loads: str | LoadCase | PointLoad | Sequence[PointLoad] | None = None,
) -> Array:
    """(len(names), K): exact rates of the load outputs ``NAME[@CASE]`` (with ``loads``: every
    name under those loads, as :func:`statics` takes them) along ``directions``
    (K, n_columns), state directions tangent to the constraints (e.g. a design column plus the
    coordinates' response, :func:`kinprop.analysis.sensitivity.output_sensitivity`), in solver
    units, by the direct method of :mod:`kinprop.engine.statics_rates`. Preloads as
    :func:`statics` takes them: at ``reference``'s pose, else at the model's own pose (then the
    element's force stays its preload); held by ``inputs`` (default: the declared ones)."""
    eng = engine or compile_engine(model)
    st = eng.state_of(model)
    X = np.atleast_2d(np.asarray(directions, dtype=float))
    out = np.zeros((len(names), X.shape[0]))
    r, A, _, _ = eng.poses(st)
    r, A = np.array(r), np.array(A)
    cols, _ = input_columns(eng, model.mechanism.inputs if inputs is None else inputs)
    laws, held = model_laws(model, eng, st if reference is None else eng.state_of(reference), reference is None)
    by_case: dict[str, list[int]] = {}
    for i, n in enumerate(names):
        by_case.setdefault(n.partition("@")[2], []).append(i)
    for case_name, rows in by_case.items():
        case = _case(model, loads if loads is not None else case_name or None)
        s = statics(model, case, inputs=inputs, engine=eng, reference=reference)
        rates = statics_rates(eng, st, applied_points(model, eng, r, A, case), X, cols, laws, held)
        for i in rows:
            out[i] = _rate(s, rates, names[i].partition("@")[0])
    return out


# --- static equilibrium and wheel rate --------------------------------------------------------
#: Newton on the reduced equilibrium: converged when |tau| < EQ_TOL * (force scale x length scale)
EQ_TOL, EQ_MAX_ITER, EQ_TRUST = 1e-12, 50, 0.35
#: relative singular value of the weighted stiffness below which a direction is neutral
EQ_RCOND = 1e-10


@dataclass(frozen=True)
class Equilibrium:
    """The pose at which the released inputs need no effort: ``status`` (:class:`kinprop.Status`)
    ``converged``, ``not_converged`` or ``infeasible`` (no equilibrium step could be taken: the
    loads are not held, or the position solve could not follow a step on the branch);
    ``stiffness`` the reduced tangent stiffness ``d tau / d q`` there (solver units: per radian
    for an angle), ``stable`` when its symmetric part is positive definite."""

    status: Status
    message: str
    model: Model
    statics: Statics
    iterations: int
    released: tuple[str, ...]
    stiffness: Array
    stable: bool

    @property
    def converged(self) -> bool:
        return self.status is Status.CONVERGED


def _tau_scale(pf: PointForces, laws: Sequence[Any], model: Model, eng: Engine, st: Any) -> float:
    L = eng.length_scale or eng._length_scale(st)
    r, A, P, R = (np.array(x) for x in eng.poses(st))
    f = np.abs(element_state(laws, r, A, st.Q, P, R)[0])
    arm = np.array([1.0 if isinstance(e, TorsionLaw) else L for e in laws])
    return float(np.abs(pf.F).sum() * L + float(f @ arm) + np.abs(pf.M).sum()) or 1.0


def equilibrium(
    model: Model,
    loads: str | LoadCase | PointLoad | Sequence[PointLoad] | None = None,
    *,
    release: Sequence[str] | None = None,
    tol: float = EQ_TOL,
    max_iter: int = EQ_MAX_ITER,
    engine: Engine | None = None,
    weights: Mapping[str, float] | None = None,
) -> Equilibrium:
    r"""The static equilibrium of the spring-supported ``model`` under ``loads`` with the
    ``release``\ d inputs (default: the declared inputs) free: Newton on ``tau(q_D) = 0`` with
    the exact tangent stiffness (:func:`kinprop.engine.statics.reduced_stiffness`), each step
    re-assembled on the start's branch (``Engine.propagate``), steps limited to a trust radius.
    Least change, as in propagation: each step is the minimum-norm solution of ``K dq = -tau``
    in the propagation's metric ``sum (si_k dq_k)^2 / w_k`` (changes in metres and radians,
    ``weights`` by address as ``propagate`` takes them), so where the loads leave the pose
    undetermined (a neutral direction, ``K`` singular) the released inputs move as little as
    the metric allows. Preloads are taken at the given model's pose."""
    eng = engine or compile_engine(model)
    st0 = eng.state_of(model)
    case = _case(model, loads)
    names = list(model.mechanism.inputs if release is None else release)
    cols, addresses = input_columns(eng, names)
    labels = eng.column_labels
    laws, _ = model_laws(model, eng, st0)
    w = eng.weights_for(np.array(cols, np.int64), weights)
    w_half = np.sqrt(w) if w is not None else np.ones(len(cols))
    st, status, message, K, it = st0, Status.NOT_CONVERGED, "", np.zeros((len(cols), len(cols))), 0
    for it in range(1, max_iter + 1):
        r, A, _, _ = eng.poses(st)
        pf = applied_points(model, eng, np.array(r), np.array(A), case)
        tau, K, msg = reduced_stiffness(eng, st, pf, cols, laws)
        if msg:
            status, message = Status.INFEASIBLE, msg
            break
        if float(np.max(np.abs(tau), initial=0.0)) <= tol * _tau_scale(pf, laws, model, eng, st):
            status, message = Status.CONVERGED, f"converged in {it - 1} step(s)"
            break
        dq = -w_half * np.linalg.lstsq(K * w_half[None, :], tau, rcond=EQ_RCOND)[0]
        size = float(np.max(np.abs(dq * eng.col_scale[cols])))
        if size > EQ_TRUST:
            dq *= EQ_TRUST / size
        sol = eng.propagate({labels[c]: float(st.Q[c] + dq[k]) for k, c in enumerate(cols)}, free=["q"], start=st,
                            tol=1e-13)  # fmt: skip
        if not sol.converged:
            status, message = Status.INFEASIBLE, f"the equilibrium step could not be followed: {sol.message}"
            break
        st = sol.state
    else:
        message = (f"not converged after {max_iter} iterations: the released inputs' efforts are not below {tol:g} "
                   "of the load scale")  # fmt: skip
    at = eng.model_of(st, model)
    s = statics(at, case, inputs=names, engine=eng, reference=model)
    stable = bool(np.all(np.linalg.eigvalsh(0.5 * (K + K.T)) > 0)) if K.size else True
    return Equilibrium(status, message, at, s, it, tuple(addresses), K, stable)


def equilibrium_sensitivity(
    eq: Equilibrium,
    wrt: Sequence[str],
    loads: str | LoadCase | PointLoad | Sequence[PointLoad] | None = None,
    *,
    reference: Model | None = None,
    engine: Engine | None = None,
) -> tuple[Array, list[str], list[str]]:
    """``(D, released, columns)``: exact derivatives of the equilibrium's released inputs with
    respect to the design columns ``wrt``, in the model's units. At equilibrium ``tau(q_D, p) =
    0``, so ``dq_D/dp = -K^-1 dtau/dp``: ``K`` the reduced tangent stiffness
    (:func:`equilibrium`) and ``dtau/dp`` the efforts' design derivatives with the inputs held
    (:func:`kinprop.engine.statics_rates.statics_rates` along ``e_p + dq/dp``, the other
    coordinates' response by the implicit-function theorem). ``loads`` as the equilibrium
    took them; preloads at ``reference``'s pose (the model the equilibrium started from;
    default: the equilibrium's own)."""
    model = eq.model
    eng = engine or compile_engine(model)
    st = eng.state_of(model)
    cols, names = input_columns(eng, list(eq.released))
    labels = eng.column_labels
    held = [labels[c] for c in range(eng.n_coordinates) if c not in cols]
    sens = design_sensitivity(model, wrt, held, engine=eng, units="solver")
    X = np.zeros((sens.wrt_columns.size, eng.n_columns))
    X[np.arange(sens.wrt_columns.size), sens.wrt_columns] = 1.0
    X[:, sens.free_columns] = sens.matrix.T
    r, A, _, _ = eng.poses(st)
    pf = applied_points(model, eng, np.array(r), np.array(A), _case(model, loads))
    laws, _ = model_laws(model, eng, st if reference is None else eng.state_of(reference))
    dtau = statics_rates(eng, st, pf, X, cols, laws).efforts  # (K, nd)
    D = -np.linalg.solve(eq.stiffness, dtau.T)
    so = np.array([address_scale(model, n, eng) for n in names])
    si = np.array([address_scale(model, c, eng) for c in sens.columns])
    return D * so[:, None] / si[None, :], list(names), list(sens.columns)


def wheel_rate(
    model: Model,
    wheel: str | None = None,
    loads: str | LoadCase | PointLoad | Sequence[PointLoad] | None = None,
    *,
    inputs: Sequence[str] | None = None,
    engine: Engine | None = None,
) -> float:
    """Wheel rate (force per length): the derivative of the vertical force at the wheel centre
    that holds the mechanism against its springs (and ``loads``) with respect to the wheel
    centre's vertical travel, ``K_w = dF_z/dz``, exact: with ``F_z = tau / z'`` (``tau`` the
    effort of the single input, ``z' = dz/dq``), ``K_w = (tau' z' - tau z'') / z'^3`` from the
    reduced stiffness ``tau'`` and the velocity analysis' ``z''``. Vertical is +z (ISO 8855;
    -z in a model declared in SAE axes). Milliken & Milliken, *Race Car Vehicle Dynamics*,
    ch. 16 (wheel rate; here at the wheel centre, the tyre excluded)."""
    eng = engine or compile_engine(model)
    st = eng.state_of(model)
    wheels = wheel_bodies(model)
    if wheel is None:
        if len(wheels) != 1:
            raise AddressError(f"wheel_rate: name the wheel; wheel bodies: {', '.join(wheels) or 'none'}")
        wheel = wheels[0]
    if wheel not in wheels:
        raise AddressError(f"wheel_rate: {wheel!r} is not a wheel body; wheels: {', '.join(wheels) or 'none'}")
    cols, _ = input_columns(eng, model.mechanism.inputs if inputs is None else inputs)
    if len(cols) != 1:
        raise ValueError(f"wheel_rate needs exactly one input coordinate (the wheel travel), found {len(cols)}")
    r, A, _, _ = eng.poses(st)
    r, A = np.array(r), np.array(A)
    pf = applied_points(model, eng, r, A, _case(model, loads))
    tau, K, msg = reduced_stiffness(eng, st, pf, cols, model_laws(model, eng, st)[0])
    if msg:
        return float("nan")
    ms = motion_state(eng, st, {eng.column_labels[cols[0]]: 1.0}, {})
    b = eng.body_index[wheel]
    centre = r[b] + A[b] @ _point(model, wheel, "wheel_centre")
    up = np.array([0.0, 0.0, -1.0 if model.units.get("axes") == "SAE" else 1.0])
    z1, z2 = float(up @ ms.point_velocity(b, centre)), float(up @ ms.point_acceleration(b, centre))
    return float((K[0, 0] * z1 - tau[0] * z2) / z1**3)


# --- loads as outputs of sweeps, studies and evaluate_outputs ----------------------------------
LOAD_PREFIXES = ("reaction:", "force:", "effort:")


def is_load_output(name: str) -> bool:
    """``reaction:...``, ``force:...``, ``effort:...`` (optionally ``@CASE``)."""
    return name.startswith(LOAD_PREFIXES)


def load_output_unit(model: Model, name: str) -> str:
    """Force unit, or force x length for a moment or an angular input's effort."""
    F, L = model.units.get("force", "force"), model.units.get("length", "m")
    base = name.partition("@")[0]
    if base.startswith("reaction:") and base.rsplit(".", 1)[-1] in ("mx", "my", "mz"):
        return f"{F} {L}"
    if base.startswith("force:") and base[len("force:") :] in {t.name for t in model.torsion_springs}:
        return f"{F} {L}"  # a torsion spring's torque
    if base.startswith("effort:"):
        joint = base[len("effort:") :].split(".")[0]
        if joint in model.mechanism.joint_names and model.mechanism.joint(joint).jtype.angle_indices:
            return f"{F} {L}"
    return F


def load_value(
    model: Model,
    name: str,
    cache: dict[str, dict[str, Any]],
    engine: Engine | None = None,
    reference: Model | None = None,
) -> float:
    """A load output ``NAME[@CASE]`` at the model's state (``CASE`` a load case of its
    ``loads:``; without it the elements only); ``cache`` keeps one statics per case and state."""
    base, _, case = name.partition("@")
    key = f"\x00statics@{case}"
    if not case and key not in cache and base.startswith("force:"):
        # an element's force depends on the pose only: any load case's statics at this state has it
        known = next((v for k, v in cache.items() if k.startswith("\x00statics@")), None)
        if known is not None and base[len("force:") :] in known[""].element_forces:
            return known[""].element_forces[base[len("force:") :]]
    if key not in cache:  # one statics per case and state; each value read from it when asked
        cache[key] = {"": statics(model, case or None, engine=engine, reference=reference)}
    values = cache[key]
    if base not in values:
        values[base] = values[""].value(base)  # raises AddressError naming what is known
    return values[base]


__all__ = [
    "COMPONENTS",
    "LOAD_PREFIXES",
    "Equilibrium",
    "JointReaction",
    "Statics",
    "applied_wrenches",
    "equilibrium",
    "equilibrium_sensitivity",
    "input_columns",
    "is_load_output",
    "load_derivatives",
    "load_output_unit",
    "load_value",
    "statics",
    "wheel_rate",
]
