"""Named outputs of a model at its current state: one place that evaluates them.

Output names (all scalars once expanded; a vector name without a component expands into
its components, e.g. ``point:wheel.wheel_centre`` into ``...[x]``, ``...[y]``, ``...[z]``):

* coordinates: ``J01.q`` (one coordinate), ``J32.q[1]``; angles in radians;
* design variables: ``RS.s_i[2]``, ``RS.s_i`` (three), ``RS.length``;
* named points (``Body.points``, body frame) in global coordinates:
  ``point:BODY.NAME[x|y|z]``;
* joint hardpoints, the global origin of the joint frame on the joint's first (``i``) or
  second (``j``) body: ``hardpoint:JOINT.i[x]``, ``hardpoint:JOINT.j[z]``;
* a body's pose, the global origin of its frame and its orientation as yaw, pitch and roll
  (ISO 8855 order, intrinsic z-y'-x''; angles in the model's angle unit): ``body:BODY`` (six
  components) or ``body:BODY[x|y|z|roll|pitch|yaw]``;
* the distance between two points (e.g. a spring's length), each ``BODY.NAME`` (a named
  point) or ``hardpoint:JOINT.i|j``: ``distance:chassis.spring_chassis,lca.spring_lca``;
* suspension metrics of a wheel body (:mod:`kinprop.analysis.metrics`):
  ``metric:WHEEL.camber`` (``camber`` alone when the model has one wheel); angles in degrees.

Lengths are in the model's length unit. Points, distances, variables and position-level
metrics are evaluated by one compiled kernel from one forward-kinematics pass over the spanning
tree (:func:`output_program`, :mod:`kinprop.engine.outputs`), for one state or a whole batch;
the model is not re-assembled here.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping, Sequence

import numpy as np

from kinprop.analysis.context import BODY, HARD, POINT, POSE, OutputContext, pivot_point
from kinprop.analysis.metrics import (
    METRIC_NEEDS,
    WheelSpec,
    is_first_order,
    metric_names,
    resolve_metric,
    wheel_first_order,
    wheel_first_order_derivatives,
    wheel_first_order_program,
)
from kinprop.analysis.program import OutputProgram, ProgramBuilder
from kinprop.analysis.statics import is_load_output, load_value
from kinprop.analysis.units import derivative_scale
from kinprop.engine import Engine, State
from kinprop.engine import compile as compile_engine
from kinprop.engine.units import check_units
from kinprop.errors import AddressError
from kinprop.model import Model
from kinprop.model.design import Address, parse_address
from kinprop.propagation.element_points import with_element_ends
from kinprop.spatial import Array

AXES = {"x": 0, "y": 1, "z": 2, "0": 0, "1": 1, "2": 2}
_XYZ = "xyz"

_POINT, _HARD = POINT, HARD
_DIST = re.compile(r"^distance:(?P<a>[^,\s]+),(?P<b>[^,\s]+)$")


def _distance_ends(name: str) -> tuple[str, str]:
    """The two point specs of ``distance:A,B`` (``BODY.NAME`` means ``point:BODY.NAME``)."""
    m = _DIST.match(name)
    if not m:
        raise AddressError(f"bad output {name!r}: expected distance:BODY.NAME,BODY.NAME (or hardpoint:JOINT.i|j ends)")
    return tuple(x if x.startswith(("point:", "hardpoint:")) else f"point:{x}" for x in (m["a"], m["b"]))  # type: ignore[return-value]


def _vector_name(base: str, n: int, letters: bool) -> list[str]:
    return [f"{base}[{_XYZ[k] if letters else k}]" for k in range(n)]


def expand_outputs(model: Model, names: Sequence[str], engine: Engine | None = None) -> list[str]:
    """Scalar output names: vector names are expanded into their components (validated);
    ``engine``: compiled from the model's mechanism (None: compiled here, once)."""
    engine = engine if engine is not None else compile_engine(model.mechanism)
    out: list[str] = []
    for name in names:
        name = name.strip()
        if is_load_output(name):
            load_value(model, name, {}, engine)  # the joint, element, input and load case exist
            out.append(name)
        elif name.startswith("body:"):
            m = BODY.match(name)
            if not m or (m["c"] is not None and m["c"] not in POSE):
                raise AddressError(f"bad output {name!r}: expected body:BODY or body:BODY[{'|'.join(POSE)}]")
            if m["body"] not in model.mechanism.body_names:
                raise AddressError(
                    f"output {name!r}: unknown body {m['body']!r}; bodies are {', '.join(model.mechanism.body_names)}"
                )
            out += [name] if m["c"] is not None else [f"{name}[{c}]" for c in POSE]
        elif name.startswith("distance:"):
            ctx = OutputContext.of(model, engine=engine)
            for end in _distance_ends(name):
                ctx.point(end)  # both ends exist
            out.append(name)
        elif name.startswith(("point:", "hardpoint:")):
            m = _POINT.match(name) or _HARD.match(name)
            if not m:
                raise AddressError(
                    f"bad output {name!r}: expected point:BODY.NAME[x|y|z] or hardpoint:JOINT.i|j[x|y|z]"
                )
            _check_point(model, name, m)
            out += [name] if m.group("c") is not None else _vector_name(name, 3, True)
        elif name.startswith("metric:") or "." not in name:
            resolve_metric(model, name)  # a wheel body and a known metric
            out.append(name)
        else:
            addr = _parse_variable(engine, name)
            size = engine.layout[addr.key].size
            out += [name] if addr.index is not None or size == 1 else _vector_name(name, size, False)
    return out


def _check_point(model: Model, name: str, m: re.Match[str]) -> None:
    """The body and its named point (or the joint) of a point output exist."""
    mech = model.mechanism
    if name.startswith("point:"):
        body, point = m.group("body"), m.group("name")
        if body not in mech.body_names:
            raise AddressError(f"output {name!r}: unknown body {body!r}; bodies are {', '.join(mech.body_names)}")
        known = [p for p, _ in mech.body(body).points]
        if point not in known:
            raise AddressError(
                f"output {name!r}: body {body!r} has no named point {point!r}; its points: {', '.join(known) or 'none'}"
            )
    elif m.group("joint") not in mech.joint_names:
        raise AddressError(
            f"output {name!r}: unknown joint {m.group('joint')!r}; joints are {', '.join(mech.joint_names)}"
        )
    elif m.group("side") not in ("i", "j"):
        try:
            pivot_point(model, m.group("joint"), m.group("side"))  # a pivot of the joint
        except AddressError as exc:
            raise AddressError(f"bad output {name!r}: {exc.args[0]}") from None


def _parse_variable(engine: Engine, name: str) -> Address:
    try:
        addr = parse_address(name)
    except AddressError:
        raise AddressError(
            f"bad output {name!r}: expected a coordinate (J.q[k]), a design variable (J.s_i[k], J.length), "
            "point:BODY.NAME[x], hardpoint:JOINT.i[x], body:BODY[x|roll], distance:A,B or a metric "
            "(metric:WHEEL.camber)"
        ) from None
    if addr.field in ("C_i", "C_j"):
        raise AddressError(f"output {name!r}: orientations are not scalar outputs; use points or metrics")
    layout = engine.layout
    if addr.key not in layout:
        known = ", ".join(v.key for v in layout.variables if v.group != "C")
        raise AddressError(f"output {name!r} is not a variable of this model; known: {known}")
    if addr.index is not None and addr.index >= layout[addr.key].size:
        raise AddressError(f"output {name!r}: index out of range for a variable of size {layout[addr.key].size}")
    return addr


def output_program(
    model: Model,
    names: Sequence[str],
    *,
    reference: Model | None = None,
    wheels: Mapping[str, WheelSpec] | None = None,
    engine: Engine | None = None,
) -> OutputProgram:
    """The expanded outputs as a compiled :class:`~kinprop.analysis.program.OutputProgram`:
    every point, distance, variable and position-level metric evaluated by the kernel of
    :mod:`kinprop.engine.outputs`; first-order metrics and loads are rows the program leaves
    to :func:`evaluate_outputs` (NaN). Raises :class:`AddressError` for unknown names and for a
    metric the wheel cannot give (naming what it needs)."""
    eng = engine if engine is not None else compile_engine(model.mechanism)
    b = ProgramBuilder(model, eng, reference, wheels)
    for name in expand_outputs(model, names, eng):
        if is_load_output(name) or name.startswith("body:"):
            b.add_other(name)
        elif name.startswith("distance:"):
            b.add_distance(name, *_distance_ends(name))
        elif name.startswith("point:") and (m := _POINT.match(name)):
            b.add_point(name, f"point:{m.group('body')}.{m.group('name')}", AXES[m.group("c")])
        elif name.startswith("hardpoint:") and (m := _HARD.match(name)):
            b.add_point(name, f"hardpoint:{m.group('joint')}.{m.group('side')}", AXES[m.group("c")])
        elif name.startswith("metric:") or "." not in name:
            wheel, metric = resolve_metric(model, name)
            if is_first_order(metric):
                b.add_other(name)
                continue
            _, given = b.wheel(wheel)
            if metric not in given:
                needs = METRIC_NEEDS.get(metric, "more named points").replace("WHEEL", wheel)
                raise AddressError(f"output {name!r}: metric {metric!r} of wheel {wheel!r} needs {needs}; "
                                   f"this model gives: {', '.join(given)}")  # fmt: skip
            b.add_metric(name, wheel, metric)
        else:
            _parse_variable(eng, name)
            b.add_variable(name, name)
    return b.build()


def _other(ctx: OutputContext, name: str, cache: dict[str, dict[str, float]]) -> float:
    """An output the program leaves to Python: a load, a body's pose, or a first-order metric
    (one velocity analysis per wheel and state, :func:`~kinprop.analysis.metrics.wheel_first_order`)."""
    if is_load_output(name):
        return load_value(ctx.model, name, cache, ctx.engine, ctx.reference)
    if name.startswith("body:"):
        m = BODY.match(name)
        return float(ctx.body_pose(m["body"])[POSE.index(m["c"])])  # type: ignore[index]
    wheel, metric = resolve_metric(ctx.model, name)
    key = f"{wheel}\x00first"
    if key not in cache:
        cache[key] = wheel_first_order(ctx, wheel)
    values = cache[key]
    if metric not in values:
        needs = METRIC_NEEDS.get(metric, "more named points").replace("WHEEL", wheel)
        raise AddressError(f"output {name!r}: metric {metric!r} of wheel {wheel!r} needs {needs}; "
                           f"this model gives: {', '.join(values)}")  # fmt: skip
    return float(values[metric])


def program_values(
    program: OutputProgram, model: Model, reference: Model | None = None, wheels: Mapping[str, WheelSpec] | None = None
) -> Array:
    """Every output of ``program`` at the model's state (solver units): the compiled ones in one
    kernel call, the others (first-order metrics, loads) from one shared context."""
    eng = program.engine
    values = program.evaluate(eng.state_of(model))
    others = np.flatnonzero(~program.compiled)
    if others.size:
        ctx = OutputContext.of(model, reference, wheels, eng)
        cache: dict[str, dict[str, float]] = {}
        for k in others:
            values[k] = _other(ctx, program.names[k], cache)
    return values


def program_batch(
    program: OutputProgram,
    model: Model,
    states: State,
    ok: Array | None = None,
    reference: Model | None = None,
    wheels: Mapping[str, WheelSpec] | None = None,
    ends: Array | None = None,
) -> Array:
    """Every output of ``program`` at each state of a batch (N, no; solver units; NaN where not
    ``ok``): the compiled ones in one kernel call, the others per state (``model``: units and
    structure of the states). ``ends`` (N, ne, 2, 3): each state's own element ends in their
    bodies' frames (a study's element-point factors), else the model's."""
    values = program.evaluate(states, ok)
    others = np.flatnonzero(~program.compiled)
    eng = program.engine
    first: dict[str, list[tuple[int, str]]] = {}  # per wheel: (output, metric), one compiled batch each
    for k in others:
        found = first_order_of(model, program.names[k])
        if found is not None:
            first.setdefault(found[0], []).append((int(k), found[1]))
    for wheel, outs in first.items():
        fo = wheel_first_order_program(model, eng, wheel, reference, wheels)
        got = fo.evaluate(states, ok, ends)
        for k, metric in outs:
            if metric not in fo.names:
                needs = METRIC_NEEDS.get(metric, "more named points").replace("WHEEL", wheel)
                raise AddressError(f"output {program.names[k]!r}: metric {metric!r} of wheel {wheel!r} needs "
                                   f"{needs}; this model gives: {', '.join(fo.names)}")  # fmt: skip
            values[:, k] = got[:, fo.names.index(metric)]
    others = np.array([k for k in others if first_order_of(model, program.names[k]) is None], dtype=np.int64)
    if others.size:
        for i in range(values.shape[0]) if ok is None else np.flatnonzero(ok):
            at = eng.model_of(states[i], model)
            ctx = OutputContext.of(at if ends is None else with_element_ends(at, ends[i]), reference, wheels, eng)
            cache: dict[str, dict[str, float]] = {}
            for k in others:
                values[i, k] = _other(ctx, program.names[k], cache)
    return values


def first_order_of(model: Model, name: str) -> tuple[str, str] | None:
    """``(wheel, metric)`` of an expanded output name that is a first-order metric (a gain, a
    centre, anti, a motion ratio, the wheel rate; :mod:`kinprop.analysis.firstorder`), else None."""
    if is_load_output(name) or name.startswith(("distance:", "point:", "hardpoint:")):
        return None
    if name.startswith("metric:") or "." not in name:
        wheel, metric = resolve_metric(model, name)
        return (wheel, metric) if is_first_order(metric) else None
    return None


def first_order_derivatives(
    model: Model,
    names: Sequence[str],
    directions: Array,
    *,
    reference: Model | None = None,
    wheels: Mapping[str, WheelSpec] | None = None,
    engine: Engine | None = None,
    elements: Array | None = None,
) -> dict[int, Array]:
    """Exact derivatives of the first-order metrics among the expanded outputs ``names`` along
    each column of ``directions`` (state directions, solver units), keyed by their index in
    ``names`` (values as :func:`evaluate_outputs` with ``units="solver"`` gives them):
    :func:`kinprop.analysis.metrics.wheel_first_order_derivatives`, once per wheel;
    ``elements`` (ne, 2, 3, k): the element ends' body-frame moves along each column."""
    eng = engine if engine is not None else compile_engine(model.mechanism)
    ctx = OutputContext.of(model, reference, wheels, eng)
    per_wheel: dict[str, dict[str, Array]] = {}
    out: dict[int, Array] = {}
    for i, name in enumerate(names):
        found = first_order_of(model, name)
        if found is None:
            continue
        wheel, metric = found
        if wheel not in per_wheel:
            per_wheel[wheel] = wheel_first_order_derivatives(ctx, wheel, directions, elements=elements)
        out[i] = per_wheel[wheel][metric]
    return out


def evaluate_outputs(
    model: Model,
    names: Sequence[str],
    *,
    reference: Model | None = None,
    wheels: Mapping[str, WheelSpec] | None = None,
    units: str = "model",
    engine: Engine | None = None,
) -> dict[str, float]:
    """Values of the named outputs at the model's current state, keyed by expanded name
    (a scalar name is its own key), in the model's units (docs/units.md: joint angles and
    angle metrics in the model's angle unit); ``units="solver"``: joint angles in radians and
    metrics in the degrees they are computed in.

    ``reference`` (same mechanism) sets the reference configuration of the wheel-centre
    displacement metrics; without it the fixed-body point ``wheel_centre_ref`` is used.
    ``wheels`` gives per-wheel metric parameters (:class:`~kinprop.analysis.metrics.WheelSpec`).
    Raises :class:`AddressError` for unknown names.
    """
    to_model = check_units(units)
    eng = engine if engine is not None else compile_engine(model.mechanism)
    program = output_program(model, names, reference=reference, wheels=wheels, engine=eng)
    got = program_values(program, model, reference, wheels)
    values = dict(zip(program.names, (float(v) for v in got), strict=True))
    if to_model:
        values = {n: v * derivative_scale(model, n, eng) for n, v in values.items()}
    return values


def output_function(
    model: Model,
    names: Sequence[str],
    *,
    reference: Model | None = None,
    wheels: Mapping[str, WheelSpec] | None = None,
    engine: Engine | None = None,
) -> tuple[Callable[[Model], Array], list[str]]:
    """``(f, expanded)``: ``f(model) -> array`` of the expanded outputs (``f.program``: the
    :class:`~kinprop.analysis.program.OutputProgram`, for batches of states).

    Checked once, here: every output is evaluated at ``model`` (whether an output exists
    does not depend on the pose), so one that the model cannot give (a metric without the
    points it needs) raises :class:`AddressError` naming it and what is missing, before any
    solve, instead of a blank column later.
    """
    eng = engine if engine is not None else compile_engine(model.mechanism)
    program = output_program(model, names, reference=reference, wheels=wheels, engine=eng)

    def f(m: Model) -> Array:
        return program_values(program, m, reference, wheels)

    f.program = program  # type: ignore[attr-defined]
    f(model)
    return f, list(program.names)


def output_names(model: Model, engine: Engine | None = None) -> list[str]:
    """Every scalar output the model defines: coordinates, design variables (not C), named
    points, joint hardpoints and the suspension metrics of its wheel bodies."""
    mech = model.mechanism
    layout = (engine if engine is not None else compile_engine(mech)).layout
    names: list[str] = []
    for v in layout.variables:
        if v.group == "C":
            continue
        names += [v.key] if v.size == 1 else [f"{v.key}[{k}]" for k in range(v.size)]
    for b in mech.bodies:
        for p, _ in b.points:
            names += _vector_name(f"point:{b.name}.{p}", 3, True)
    for j in mech.joints:
        for side in "ij":
            names += _vector_name(f"hardpoint:{j.name}.{side}", 3, True)
    names += metric_names(model, first_order=True)
    return names


__all__ = [
    "OutputContext",
    "evaluate_outputs",
    "expand_outputs",
    "output_function",
    "output_names",
    "output_program",
    "program_batch",
    "program_values",
]
