"""Targets in the designer's terms: parse target specs, build configurations, solve, report.

A target spec (CLI ``--target``, Python ``propagate_targets(model, [...])``)::

    [slope:]OUTPUT[@CONDITION[&CONDITION...]]=VALUE[UNIT][:WEIGHT]

* ``OUTPUT``: any scalar output of :mod:`kinprop.analysis.outputs` (``metric:camber``,
  ``camber``, ``point:upright.wheel_centre[z]``, ``hardpoint:UBJ.j[x]``, ``distance:A,B``,
  ``O4.q``, ``P.q[2]``, ``L1.length``) or a joint's relative value ``joint:JOINT.NAME``
  (``joint:UBJ.euler[1]``, ``joint:B.displacement``; :mod:`kinprop.propagation.poses`).
* ``CONDITION`` puts the target in a configuration of its own; conditions hold exactly:
  ``JOINT.q=V`` / ``JOINT.q[k]=V`` holds a coordinate (not free there);
  a drive — ``travel=V`` / ``travel:WHEEL=V`` (or ``metric:WHEEL.wheel_centre_dz=V``), ``roll=V``,
  ``steer:WHEEL=V`` — holds the drive joint of :mod:`kinprop.analysis.drives` at V (the joints
  ``sweep --drive`` and ``camber@travel=50`` use; the input it releases moves); any other
  ``OUTPUT=V`` is a condition row of its own. Targets with the same conditions share a configuration; a
  target without conditions lives in the base configuration (every coordinate free).
* ``slope:OUTPUT@COND=A..B=V``: the slope ``(OUTPUT(B) - OUTPUT(A)) / (B - A)`` over a single
  condition's range (e.g. bump steer ``slope:toe@travel=-50..50=0``), unit output per condition.
* ``VALUE``: a number with an optional unit: ``deg``/``rad`` for angles, ``mm``/``cm``/``m``/``in``
  for lengths, ``deg/m``-style for slopes. Without a unit: the model's units (metric, coordinate
  and joint angles in its angle unit, lengths in its length unit).
* ``WEIGHT`` (default 1) multiplies the target's residual in the least-squares compromise when
  targets conflict (a miss of 1/WEIGHT units counts as one).
* ``OUTPUT<=VALUE`` / ``OUTPUT>=VALUE``: a bound, not a value: met while it holds (it does not
  pull the design then), driven onto its limit when violated, reported ``met`` or in conflict.
* Loads (``reaction:UBJ.f``, ``force:TR``, ``effort:LCA``, :mod:`kinprop.analysis.statics`)
  name their load case after ``@`` (``reaction:UBJ.f@braking_1g<=8kN``; ``@*``: one target per
  load case of the model, e.g. "the upper ball joint's force at most 8 kN over the load
  cases"); further ``@``-conditions put them in a configuration as any other output. Values in
  the model's force unit, or ``N``/``kN``/``lbf`` when the model's force unit is one of those;
  their derivatives are exact (the differentiated equilibrium along the configuration's
  tangent, :func:`kinprop.analysis.statics.load_derivatives`), preloads at the starting model's
  pose.

:func:`propagate_targets` solves by :func:`kinprop.engine.targets.solve_targets` (the
minimum-(weighted-)norm change of the ``free`` design variables: ``hardpoint:J[.i|.j]``,
``axis:J``, ``J.s_i``, ``J.length``, groups ``s C l``). Output Jacobians are analytic for
points, hardpoints, distances, coordinates, design variables and the camber, toe, caster, KPI
and wheel-centre metrics (:func:`_config_jacobian`); the first-order metrics (gains, centres,
roll-centre height, anti, motion ratios, wheel rate) are exact
(:func:`kinprop.analysis.outputs.first_order_derivatives`); a slope's row is the difference of
its two configurations' rows (exact when they are); scrub radius, trail and joint values use
central differences of the output map; a configuration with a load output takes every row's
rate along its tangent (:attr:`Configuration.rates`).
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from html import escape
from typing import Any

import numpy as np

from kinprop.analysis.context import HARD, POINT, find_point, pivot_point
from kinprop.analysis.drives import (
    ROLL,
    TRAVEL,
    _number,
    augment,
    base_view,
    condition_value,
    drive_condition,
    is_drive,
)
from kinprop.analysis.firstorder import GAIN_METRICS
from kinprop.analysis.metrics import (
    ANGLE_METRICS,
    METRIC_ALIASES,
    is_first_order,
    metric_unit,
    resolve_metric,
    wheel_bodies,
)
from kinprop.analysis.outputs import (
    _distance_ends,
    expand_outputs,
    first_order_derivatives,
    first_order_of,
    output_function,
)
from kinprop.analysis.statics import is_load_output, load_derivatives, load_output_unit, load_value
from kinprop.engine import Engine, State, Status
from kinprop.engine import compile as compile_engine
from kinprop.engine.targets import (
    FD_STEP,
    Configuration,
    ExternalDesign,
    Row,
    TargetResult,
    output_jacobian,
    solve_targets,
)
from kinprop.engine.units import METRES_PER, RADIANS_PER, changes_to_internal, check_units, degrees
from kinprop.errors import AddressError
from kinprop.model import Model
from kinprop.model.design import parse_address
from kinprop.model.joint_points import steering_joints
from kinprop.propagation.element_points import (
    apply_element_changes,
    element_directions,
    element_ends,
    element_labels,
    element_point,
    is_element_address,
    with_element_ends,
)
from kinprop.propagation.hardpoints import body_rotation, free_tie, free_weights, resolve_changes
from kinprop.propagation.point_jacobians import PointJacobians, PointSpec
from kinprop.propagation.poses import joint_values
from kinprop.propagation.propagate import Propagation, engine_for, propagation_of
from kinprop.spatial import Array

#: force units a load target's value may be written in (when the model's force unit is one of them)
NEWTONS_PER = {"N": 1.0, "kN": 1000.0, "lbf": 4.4482216152605}
_JOINT_OUT = re.compile(r"^joint:(?P<joint>[^.\s]+)\.(?P<name>[a-z_0-9]+)(\[(?P<k>\d)\])?$")


@dataclass(frozen=True)
class Condition:
    output: str  # scalar output name, a coordinate address when ``held``, or a drive when ``drive``
    value: float  # internal units (a drive's: solver units, a length or radians)
    held: bool
    #: ``output`` is a drive of :mod:`kinprop.analysis.drives` (``travel:WHEEL``, ``roll``,
    #: ``steer:WHEEL``): its drive joint is held at ``value``
    drive: bool = False


@dataclass(frozen=True)
class TargetSpec:
    """A parsed target (internal units: metric angles deg, coordinate angles rad, lengths model unit)."""

    text: str
    output: str
    value: float
    conditions: tuple[Condition, ...] = ()
    #: for a slope: the two condition sets and the range
    slope: tuple[tuple[Condition, ...], tuple[Condition, ...], float] | None = None
    weight: float = 1.0
    unit: str = ""
    #: ``""`` a value; ``"<="`` / ``">="`` a bound
    bound: str = ""


def _kind(model: Model, output: str) -> str:
    """``deg`` (metric angle, degrees), ``rad`` (coordinate/joint angle, radians), ``length``,
    ``gain`` (a first-order angle gain, degrees per length unit), ``force``, ``moment`` (a load
    output in force x length), ``none``."""
    if is_drive(output):
        return "length" if output.startswith(TRAVEL) else "rad"
    if is_load_output(output):
        F = model.units.get("force", "force")
        return "force" if load_output_unit(model, output) == F else "moment"
    if output.startswith("joint:"):
        m = _JOINT_OUT.match(output)
        name = m["name"] if m else ""
        return "rad" if "angle" in name else "none" if name in ("euler", "rotation_vector") else "length"
    if output.startswith(("point:", "hardpoint:", "distance:")):
        return "length"
    if output.startswith("metric:") or "." not in output:
        _, metric = resolve_metric(model, output)
        if is_first_order(metric):
            length = model.units.get("length", "m")
            return "gain" if metric in GAIN_METRICS else "length" if metric_unit(metric, length) == length else "none"
        return "deg" if METRIC_ALIASES.get(metric, metric) in ANGLE_METRICS else "length"
    addr = parse_address(output)
    if addr.field == "q":
        idx = model.mechanism.joint(addr.joint).jtype.angle_indices
        return "rad" if (addr.index or 0) in idx else "length"
    return "length"


def _unit_factor(model: Model, kind: str, unit: str, where: str) -> float:
    """Factor from ``unit`` to the internal unit of ``kind`` (no unit: the display unit), from
    the one table of factors (:mod:`kinprop.engine.units`)."""
    length_unit = model.units.get("length", "m")
    angle = unit or model.units.get("angle", "rad")
    if kind in ("deg", "gain") and angle in RADIANS_PER and (kind == "deg" or not unit):
        return RADIANS_PER[angle] / RADIANS_PER["deg"]  # internal: degrees (metrics are computed in degrees)
    if kind == "rad" and angle in RADIANS_PER:
        return RADIANS_PER[angle]
    if kind == "length" and (not unit or (unit in METRES_PER and length_unit in METRES_PER)):
        return METRES_PER[unit] / METRES_PER[length_unit] if unit else 1.0
    if kind not in ("deg", "rad", "gain", "length") and not unit:
        return 1.0
    force = model.units.get("force", "")
    if kind == "force" and (unit == force or (unit in NEWTONS_PER and force in NEWTONS_PER)):
        return NEWTONS_PER[unit] / NEWTONS_PER[force] if unit != force else 1.0
    raise AddressError(f"{where}: unit {unit!r} does not fit this output ({kind}; model length unit {length_unit})")


def _travel(model: Model, where: str) -> str:
    wheels = wheel_bodies(model)
    if len(wheels) != 1:
        raise AddressError(f"{where}: 'travel' needs exactly one wheel body, found {len(wheels)}; "
                           "write metric:WHEEL.wheel_centre_dz=V")  # fmt: skip
    return f"metric:{wheels[0]}.wheel_centre_dz"


def _metric_name(model: Model, name: str) -> str:
    """``metric:NAME`` (one wheel) -> ``metric:WHEEL.NAME``; other names unchanged."""
    if name.startswith("metric:") and "." not in name:
        wheel, metric = resolve_metric(model, name[len("metric:") :])
        return f"metric:{wheel}.{metric}"
    if "." not in name and name not in ("travel",) and (":" not in name or name.startswith("motion_ratio:")):
        wheel, metric = resolve_metric(model, name)
        return f"metric:{wheel}.{metric}"
    return name


def _condition(model: Model, text: str, where: str, value_text: str | None = None) -> Condition:
    name, _, val = text.partition("=")
    name, val = name.strip(), value_text if value_text is not None else val
    if not name or not val.strip():
        raise AddressError(f"{where}: condition {text!r}: expected NAME=VALUE (e.g. travel=50mm, O2.q=40)")
    try:
        drive = drive_condition(model, name)
    except AddressError as exc:
        raise AddressError(f"{where}: {exc}") from None
    if drive is not None:  # a drive joint held at the value (kinprop.analysis.drives)
        wheels = wheel_bodies(model)
        drive = f"{TRAVEL}:{wheels[0]}" if drive == TRAVEL and len(wheels) == 1 else drive
        kind = "length" if drive.startswith(TRAVEL) else "angle"
        return Condition(drive, condition_value(model, kind, val, where), True, drive=True)
    name = _metric_name(model, name)
    kind = _kind(model, name)
    v, unit = _number(val, where)
    v *= _unit_factor(model, kind, unit, where)
    held = False
    if not name.startswith(("metric:", "point:", "hardpoint:", "distance:", "joint:")) and "." in name:
        addr = parse_address(name)
        held = addr.field == "q"
    return Condition(name, v, held)


def parse_target(model: Model, text: str, engine: Engine | None = None) -> TargetSpec:
    """Parse one target spec (module docstring); raises :class:`AddressError` with the spec."""
    where = f"--target {text!r}"
    body, sep, value = text.rpartition("=")
    bound = body[-1] + "=" if body.endswith(("<", ">")) else ""
    body = body[:-1] if bound else body
    if not sep or not body:
        raise AddressError(f"{where}: expected OUTPUT[@CONDITION]=VALUE (e.g. metric:camber@travel=50mm=-1.5deg)")
    weight = 1.0
    if ":" in value:
        value, _, w = value.partition(":")
        try:
            weight = float(w)
        except ValueError:
            raise AddressError(f"{where}: weight {w!r} is not a number") from None
        if not weight > 0:
            raise AddressError(f"{where}: weight must be positive, found {weight:g}")
    out, _, conds = body.partition("@")
    is_slope = out.startswith("slope:")
    out = out[len("slope:") :] if is_slope else out
    out = out.strip()
    out = _travel(model, where) if out == "travel" else _metric_name(model, out)
    if is_load_output(out) and conds:  # a load output's first @ names its load case
        case, _, conds = conds.partition("&") if "=" not in conds.partition("&")[0] else ("", "", conds)
        if case.strip():
            case = case.strip()
            cases = model.loads.cases if model.loads is not None else {}
            if case != "*" and case not in cases:
                raise AddressError(f"{where}: unknown load case {case!r}; load cases: {', '.join(cases) or 'none'}"
                                   " (or * for every one)")  # fmt: skip
            out = f"{out}@{case}"
    if not out.startswith("joint:") and not out.endswith("@*"):
        names = expand_outputs(model, [out], engine)
        if names != [out]:
            raise AddressError(f"{where}: {out!r} is not a scalar output; name a component, e.g. {names[0]}")
    kind = _kind(model, out)
    v, unit = _number(value, where)
    parts = [c for c in conds.split("&") if c.strip()] if conds else []
    if any("=" not in c for c in parts):
        raise AddressError(
            f"{where}: expected OUTPUT@CONDITION=VALUE with CONDITION as NAME=VALUE (target value missing?)"
        )
    if is_slope:
        if len(parts) != 1 or ".." not in parts[0]:
            raise AddressError(f"{where}: a slope needs one condition range, e.g. slope:toe@travel=-50..50=0")
        name, _, rng = parts[0].partition("=")
        a_text, _, b_text = rng.partition("..")
        a_unit, b_unit = _number(a_text, where)[1], _number(b_text, where)[1]
        if b_unit and not a_unit:  # "-50..50mm": the unit written once, at the end, is both ends'
            a_text += b_unit
        ca, cb = _condition(model, name, where, a_text), _condition(model, name, where, b_text)
        if ca.value == cb.value:
            raise AddressError(f"{where}: the slope's range is empty")
        num_unit, _, den_unit = unit.partition("/")
        v *= _unit_factor(model, kind, num_unit, where)
        v /= _unit_factor(model, _kind(model, ca.output), den_unit, where)
        return TargetSpec(text, out, v, (), ((ca,), (cb,), cb.value - ca.value), weight=weight, bound=bound)
    v *= _unit_factor(model, kind, unit, where)
    return TargetSpec(text, out, v, tuple(_condition(model, c, where) for c in parts), weight=weight, bound=bound)


def _every_case(model: Model, spec: TargetSpec) -> list[TargetSpec]:
    """A load target over ``@*`` as one target per load case of the model (its text naming the
    case); any other target as it is."""
    if not spec.output.endswith("@*"):
        return [spec]
    cases = list(model.loads.cases) if model.loads is not None else []
    if not cases:
        raise AddressError(f"--target {spec.text!r}: @* means every load case, and this model has none")
    base = spec.output[:-2]
    return [replace(spec, text=spec.text.replace("@*", f"@{c}", 1), output=f"{base}@{c}") for c in cases]


def _joint_output(engine: Engine, name: str) -> Callable[[State], float]:
    m = _JOINT_OUT.match(name)
    if not m or m["joint"] not in engine.joint_index:
        raise AddressError(f"output {name!r}: expected joint:JOINT.VALUE with a joint of this model")
    probe = joint_values(engine, engine.reference if engine.reference is not None else engine.default_state())
    vals = probe[m["joint"]]
    if m["name"] not in vals:
        raise AddressError(f"output {name!r}: joint {m['joint']!r} has values {', '.join(vals)}")
    k = int(m["k"]) if m["k"] is not None else None
    if k is None and np.ndim(vals[m["name"]]) > 0:
        raise AddressError(f"output {name!r} is a vector; name a component, e.g. {name}[0]")

    def f(st: State) -> float:
        v = joint_values(engine, st)[m["joint"]][m["name"]]
        return float(v if k is None else np.asarray(v)[k])

    return f


def _config_outputs(model: Model, engine: Engine, names: list[str]) -> Callable[[State], Array]:
    """One configuration's output map ``state -> values`` of ``names`` (loads with their
    preloads at ``model``'s pose)."""
    std = [n for n in names if not n.startswith("joint:") and not is_load_output(n)]
    jf = {n: _joint_output(engine, n) for n in names if n.startswith("joint:")}
    f, _ = output_function(model, std, engine=engine) if std else (None, [])
    pos = {n: i for i, n in enumerate(std)}

    def outputs(st: State) -> Array:
        at = engine.model_of(st, model)
        vals = f(at) if f is not None else np.zeros(0)
        cache: dict[str, dict[str, float]] = {}
        return np.array([vals[pos[n]] if n in pos else load_value(at, n, cache, engine, model) if is_load_output(n)
                         else jf[n](st) for n in names])  # fmt: skip

    return outputs


_DEG = 1.0 / RADIANS_PER["deg"]  # metrics are computed in degrees
_XYZ = {"x": 0, "y": 1, "z": 2, "0": 0, "1": 1, "2": 2}


def _point_spec(model: Model, engine: Engine, spec: str) -> PointSpec:
    """A ``point:BODY.NAME`` / ``hardpoint:JOINT.i|j`` spec (no component) as a :class:`PointSpec`."""
    m = POINT.match(spec)
    if m:
        body = model.mechanism.body(m["body"])
        ref = body.joint_point(m["name"])
        if ref is not None:  # a joint's point: as the hardpoint (it follows the joint's s')
            spec = f"hardpoint:{ref[0]}.{ref[1]}"
        else:
            return PointSpec(m["body"], tuple(float(x) for x in dict(body.points)[m["name"]]))
    m = HARD.match(spec)
    if m is not None and m["side"] not in ("i", "j"):  # a pivot: a fixed body's point
        body, name = pivot_point(model, m["joint"], m["side"])
        return PointSpec(body, tuple(float(x) for x in dict(model.mechanism.body(body).points)[name]))
    j = model.mechanism.joint(m["joint"])  # type: ignore[index]
    side = 0 if m["side"] == "i" else 1  # type: ignore[index]
    return PointSpec(j.body_i if side == 0 else j.body_j, joint=j.name, side=side)


def _steering_specs(model: Model, engine: Engine, wheel: str) -> tuple[PointSpec, PointSpec, bool] | None:
    """``(upper, lower, by height)``: the wheel's steering-axis points by the lookup rule of
    :class:`kinprop.analysis.program.ProgramBuilder` (declared ``kingpin_upper``/``kingpin_lower``,
    else the steering joints, the higher one upper at each state), or None."""
    found = [find_point(model, wheel, n) for n in ("kingpin_upper", "kingpin_lower")]
    if found[0] is not None and found[1] is not None:
        return (*(_point_spec(model, engine, f"point:{b}.{n}") for b, n in found), False)  # type: ignore[misc, return-value]
    pair = steering_joints(model.mechanism, wheel)
    if pair is None:
        return None
    a, b = (_point_spec(model, engine, f"hardpoint:{j}.{side}") for j, side in pair)
    return a, b, True


def _analytic_rows(model: Model, engine: Engine, names: list[str]) -> tuple[list[PointSpec], dict[str, Callable]]:
    """Point specs and, per output name with an analytic derivative, ``row(P, G, cols) -> dy/dx``
    from the points ``P`` (n, 3) and their Jacobians ``G`` (n, 3, ncols)."""
    specs: list[PointSpec] = []

    def idx(spec: PointSpec) -> int:
        if spec not in specs:
            specs.append(spec)
        return specs.index(spec)

    rows: dict[str, Callable] = {}
    for name in names:
        if name.startswith(("point:", "hardpoint:")):
            m = POINT.match(name) or HARD.match(name)
            base = name[: name.index("[")] if m and m["c"] is not None else None
            if base is None:
                continue
            k, c = idx(_point_spec(model, engine, base)), _XYZ[m["c"]]  # type: ignore[index]
            rows[name] = lambda P, G, cols, k=k, c=c: G[k, c]
        elif name.startswith("distance:"):
            a, b = (idx(_point_spec(model, engine, e)) for e in _distance_ends(name))

            def dist(P, G, cols, a=a, b=b):
                d = P[a] - P[b]
                return (d / np.linalg.norm(d)) @ (G[a] - G[b])

            rows[name] = dist
        elif name.startswith("metric:"):
            wheel, metric = resolve_metric(model, name)
            centre = idx(_point_spec(model, engine, f"point:{wheel}.wheel_centre"))
            spin = idx(_point_spec(model, engine, f"point:{wheel}.spin_axis"))
            if metric == "camber":

                def camber(P, G, cols, c=centre, s=spin):
                    a = P[s] - P[c]
                    n = np.linalg.norm(a)
                    u = a / n
                    du = ((np.eye(3) - np.outer(u, u)) / n) @ (G[s] - G[c])
                    return -_DEG * du[2] / math.sqrt(max(1.0 - u[2] ** 2, 1e-300))

                rows[name] = camber
            elif metric == "toe":

                def toe(P, G, cols, c=centre, s=spin):
                    a, da = P[s] - P[c], G[s] - G[c]
                    sy = 1.0 if a[1] >= 0 else -1.0
                    return _DEG * (abs(a[1]) * da[0] - a[0] * sy * da[1]) / (a[0] ** 2 + a[1] ** 2)

                rows[name] = toe
            elif metric in ("caster", "kpi") and (axis := _steering_specs(model, engine, wheel)) is not None:
                up, lo = (idx(a) for a in axis[:2])

                def steer(P, G, cols, c=centre, s=spin, up=up, lo=lo, order=axis[2], kpi=metric == "kpi"):
                    if order and P[up][2] < P[lo][2]:  # the higher joint is the upper one (ProgramBuilder)
                        up, lo = lo, up
                    k, dk = P[up] - P[lo], G[up] - G[lo]
                    if not kpi:  # atan2(-k_x, k_z)
                        return _DEG * (k[0] * dk[2] - k[2] * dk[0]) / (k[0] ** 2 + k[2] ** 2)
                    side = 1.0 if P[s][1] - P[c][1] >= 0 else -1.0  # atan2(-side k_y, k_z)
                    return _DEG * side * (k[1] * dk[2] - k[2] * dk[1]) / (k[1] ** 2 + k[2] ** 2)

                rows[name] = steer
            elif metric in ("wheel_centre_dx", "wheel_centre_dy", "wheel_centre_dz"):
                k = "xyz".index(metric[-1])
                rows[name] = lambda P, G, cols, c=centre, k=k: G[c, k]
        elif not name.startswith("joint:"):
            addr = parse_address(name)
            if addr.field in ("C_i", "C_j") or addr.key not in engine.layout:
                continue
            col = engine.layout[addr.key].start + (addr.index or 0)
            rows[name] = lambda P, G, cols, col=col: (np.asarray(cols) == col).astype(float)
    return specs, rows


def _config_jacobian(model: Model, engine: Engine, names: list[str]) -> Callable[[State, Array], Array]:
    """``(state, cols) -> d outputs / d x``: analytic rows (:func:`_analytic_rows`, the kernel's
    partials via :class:`PointJacobians`), exact rows of the first-order metrics
    (:func:`kinprop.analysis.outputs.first_order_derivatives` along each column), central
    differences of the output map for the rest."""
    specs, rows = _analytic_rows(model, engine, names)
    pj = PointJacobians(engine, specs) if specs else None
    first = [n for n in names if n not in rows and not n.startswith("joint:") and first_order_of(model, n) is not None]
    fd_names = [n for n in names if n not in rows and n not in first]
    f_fd = _config_outputs(model, engine, fd_names) if fd_names else None

    def jacobian(st: State, cols: Array) -> Array:
        cols = np.asarray(cols, np.int64)
        P, G = pj.evaluate(st, cols) if pj is not None else (np.zeros((0, 3)), np.zeros((0, 3, cols.size)))
        fd = output_jacobian(engine, f_fd, st, cols) if f_fd is not None else None
        exact: dict[int, Array] = {}
        if first:
            directions = np.zeros((engine.n_columns, cols.size))
            directions[cols, np.arange(cols.size)] = 1.0
            exact = first_order_derivatives(engine.model_of(st, model), first, directions, engine=engine)
        out = np.zeros((len(names), cols.size))
        for r, n in enumerate(names):
            if n in rows:
                out[r] = rows[n](P, G, cols)
            elif n in first:
                out[r] = exact[first.index(n)]
            else:
                out[r] = fd[fd_names.index(n)]  # type: ignore[index]
        return out

    return jacobian


def _config_rates(model: Model, engine: Engine, names: list[str]) -> Callable[[State, Array], Array]:
    """``(state, X) -> (len(names), K)``: every output's rate along the tangent directions ``X``
    (K, n_columns): the load outputs' exact ones (the differentiated equilibrium,
    :func:`~kinprop.analysis.statics.load_derivatives`, preloads at ``model``'s pose), the
    others' :func:`_config_jacobian` rows over the columns ``X`` moves."""
    loads = [n for n in names if is_load_output(n)]
    rest = [n for n in names if not is_load_output(n)]
    jac = _config_jacobian(model, engine, rest) if rest else None

    def rates(st: State, X: Array) -> Array:
        out = np.zeros((len(names), X.shape[0]))
        if not X.shape[0]:
            return out
        at = engine.model_of(st, model)
        D = load_derivatives(at, loads, X, engine=engine, reference=model)
        for i, n in enumerate(loads):
            out[names.index(n)] = D[i]
        if jac is not None:
            cols = np.flatnonzero(np.any(X != 0.0, axis=0))
            G = jac(st, cols) @ X[:, cols].T
            for i, n in enumerate(rest):
                out[names.index(n)] = G[i]
        return out

    return rates


@dataclass(frozen=True)
class TargetPropagation:
    """The outcome of :func:`propagate_targets`: the solver's :class:`TargetResult`, the specs,
    and models before/after per configuration. ``propagation`` is the base configuration's
    (the first configuration's when every target has conditions) before/after record, with
    body poses and joint values. A configuration with a drive condition is solved on a model
    with drive joints (:mod:`kinprop.analysis.drives`; ``result.engines[k]``); ``base_state``
    views its states on :attr:`engine`, the model's own."""

    model: Model
    specs: tuple[TargetSpec, ...]
    result: TargetResult
    engine: Engine = field(repr=False)
    configuration_names: tuple[str, ...] = ()
    #: the model with the element points the targets moved (``--free element:...``; None: none)
    designed: Model | None = field(default=None, repr=False)
    #: per configuration: its engine's state -> :attr:`engine`'s (empty: the same engine)
    views: tuple[Callable[[State], State], ...] = field(default=(), repr=False)

    def base_state(self, k: int, state: State) -> State:
        """Configuration ``k``'s ``state`` as a state of :attr:`engine` (the drive joints dropped)."""
        return self.views[k](state) if self.views else state

    @property
    def converged(self) -> bool:
        return self.result.converged

    @property
    def status(self) -> Status:
        """The solve's :class:`kinprop.Status` (``converged`` also for a compromise)."""
        return self.result.status

    @property
    def targets_status(self) -> str:
        """``met``, ``compromise`` or, when not converged, the status."""
        return self.result.targets_status

    @property
    def met(self) -> bool:
        return self.result.met

    def before_model(self, k: int = 0) -> Model:
        return self.engine.model_of(self.base_state(k, self.result.before[k]), self.model)

    def after_model(self, k: int = 0) -> Model:
        return self.engine.model_of(self.base_state(k, self.result.after[k]), self.designed or self.model)

    @cached_property
    def propagation(self) -> Propagation:
        """The model before and the changed design re-assembled at the model's own coordinates
        (only coordinates free), with body poses and joint values."""
        orig, new = self.engine.state_of(self.model), self.base_state(0, self.result.after[0])
        sol = self.engine.solve(State(orig.Q.copy(), new.S.copy(), new.C.copy(), new.L.copy()), ("q",))
        prop = propagation_of(self.engine, self.model, sol, ("q",))
        if self.designed is None:
            return prop
        return replace(prop, after=with_element_ends(prop.after, element_ends(self.designed)))

    @property
    def after(self) -> Model:
        """The changed design, re-assembled at the model's own coordinates."""
        return self.propagation.after

    def unit(self, spec: TargetSpec) -> str:
        """The display unit of a target's values (a slope: per model length unit)."""
        length = self.model.units.get("length", "")
        angle = self.model.units.get("angle", "rad")
        force = self.model.units.get("force", "")
        names = {"deg": angle, "rad": angle, "length": length, "none": "", "gain": f"{angle}/{length}",
                 "force": force, "moment": f"{force} {length}"}  # fmt: skip
        u = names[_kind(self.model, spec.output)]
        metric = spec.output.startswith("metric:") or "." not in spec.output
        if _kind(self.model, spec.output) == "none" and spec.slope is None and metric:
            u = metric_unit(resolve_metric(self.model, spec.output)[1], length, angle, self.model.units.get("force"))
        if spec.slope is not None:
            if u == "deg" and _kind(self.model, spec.output) == "rad":
                u = "rad"
            return f"{u or '1'}/{names[_kind(self.model, spec.slope[0][0].output)] or '1'}"
        return u

    def table(self) -> list[dict[str, Any]]:
        """One row per target: spec, output, wanted, before, achieved, miss, in the model's
        units (angles in its angle unit, lengths in its length unit; slopes per length unit)."""
        rows = []
        deg = degrees(self.model)
        for spec, t in zip(self.specs, self.result.targets, strict=True):
            k, kind = 1.0, _kind(self.model, spec.output)
            if kind == "rad" and deg and spec.slope is None:
                k = 1.0 / RADIANS_PER["deg"]
            elif kind in ("deg", "gain") and not deg:  # a metric angle (degrees inside) in a radian model
                k = RADIANS_PER["deg"]
            if spec.slope is not None and _kind(self.model, spec.slope[0][0].output) == "rad":
                k *= RADIANS_PER[self.model.units.get("angle", "rad")]  # per radian inside: per model angle unit
            row = {"target": spec.text, "output": spec.output, "unit": self.unit(spec)}
            rows.append(row | {n: t[n] * k for n in ("value", "before", "achieved", "miss")})
        return rows

    @property
    def design_change(self) -> dict[str, Array]:
        return self.result.design_change

    def __repr__(self) -> str:
        """One line per target (wanted, achieved, unit), not the configurations' arrays."""
        changed = ", ".join(self.design_change) or "nothing"
        n = f"{len(self.specs)} targets, {len(self.configuration_names)} configurations"
        lines = [f"<TargetPropagation of {self.model.mechanism.name!r}: {self.targets_status}; {n}, changed {changed}>"]
        for row in self.table()[:8]:
            lines.append(f"  {row['target']}: wanted {row['value']:.6g}, achieved {row['achieved']:.6g} {row['unit']}")
        return "\n".join(line.rstrip() for line in lines)

    def _repr_html_(self) -> str:
        head = "".join(f"<th>{h}</th>" for h in ("target", "unit", "wanted", "before", "achieved", "miss"))
        body = "".join(
            f"<tr><td>{escape(r['target'])}</td><td>{escape(r['unit'])}</td>"
            + "".join(f"<td>{r[k]:.6g}</td>" for k in ("value", "before", "achieved", "miss"))
            + "</tr>"
            for r in self.table()
        )
        return (f"<p><b>TargetPropagation</b> of {escape(self.model.mechanism.name)}: {escape(self.targets_status)}</p>"
                f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>")  # fmt: skip

    def joint_positions(self, k: int = 0) -> dict[str, tuple[Array, Array]]:
        """Global joint origins ``J.i``/``J.j`` -> (before, after) in configuration ``k``
        (both designs solved there: where the joints actually sit, model length unit)."""
        _, _, P0, _ = self.engine.poses(self.base_state(k, self.result.before[k]))
        _, _, P1, _ = self.engine.poses(self.base_state(k, self.result.after[k]))
        return {f"{j.name}.{'ij'[s]}": (P0[n, s].copy(), P1[n, s].copy())
                for n, j in enumerate(self.engine.mechanism.joints) for s in (0, 1)}  # fmt: skip

    def design_position_moves(self) -> dict[str, tuple[Array, Array]]:
        """The moved hardpoints at the design position (:attr:`propagation`: the model's own
        coordinates, before and after the change), global (before, after), model length unit:
        the joints whose attachment ``s'`` changed, nothing else. A joint whose two sides meet
        is listed once by its name, else by side (``J.i``, ``J.j``)."""
        eng, prop = self.engine, self.propagation
        changed = {(k[:-4], "ij".index(k[-1])) for k in self.result.design_change if k.endswith((".s_i", ".s_j"))}
        _, _, P0, _ = eng.poses(eng.state_of(prop.before))
        _, _, P1, _ = eng.poses(eng.state_of(prop.after))
        tiny = 1e-9 * max(1.0, eng.length_scale or 1.0)
        out: dict[str, tuple[Array, Array]] = {}
        for n, j in enumerate(eng.mechanism.joints):
            moved = [s for s in (0, 1) if (j.name, s) in changed and np.linalg.norm(P1[n, s] - P0[n, s]) > tiny]
            if not moved:
                continue
            one = all(np.linalg.norm(P[n, 0] - P[n, 1]) <= tiny for P in (P0, P1))
            for s in (0,) if one else moved:
                out[j.name if one else f"{j.name}.{'ij'[s]}"] = (P0[n, s].copy(), P1[n, s].copy())
        return out

    def hardpoint_moves(self) -> dict[str, Array]:
        """Global displacement of every changed joint attachment (``J.i``/``J.j`` -> [dx, dy, dz],
        model length unit): ``A (s'_after - s'_before)`` with the body's orientation ``A`` at the
        design position (the model's own coordinates, where the designer moves the point)."""
        st = self.engine.state_of(self.model)
        out: dict[str, Array] = {}
        for key, d in self.result.design_change.items():
            joint, _, fld = key.partition(".")
            if fld not in ("s_i", "s_j"):
                continue
            k, side = self.engine.joint_index[joint], 0 if fld == "s_i" else 1
            out[f"{joint}.{'ij'[side]}"] = body_rotation(self.engine, st, k, side) @ d
        return out


def propagate_targets(
    model: Model,
    targets: Sequence[str | TargetSpec],
    free: Sequence[str],
    *,
    changes: Mapping[str, object] | None = None,
    weights: Mapping[str, float] | None = None,
    coordinates: Sequence[str] = ("q",),
    engine: Engine | None = None,
    tol: float = 1e-9,
    target_tol: float = 1e-6,
    max_iter: int = 60,
    analytic: bool = True,
    units: str = "model",
) -> TargetPropagation:
    """Find the minimum-(weighted-)norm change of the ``free`` design variables that meets the
    ``targets`` (specs, module docstring) with every configuration assembled.

    ``changes`` (addresses, global hardpoints too) are applied first, at the model's assembly;
    they are in the model's units (``units="model"``, degrees in a degree model) or in solver
    units (``units="solver"``: radians). Target values carry their own unit (module docstring).
    ``weights``: ``{address or group: w}``, a larger weight lets a variable move more.
    ``analytic``: analytic output Jacobians where available (False: central differences of the
    output map for every output; :mod:`kinprop.engine.targets`). ``free`` may name element points
    (``element:E.point_i``, ``element:E.point_i[z]``: global, at the model's assembly,
    :mod:`kinprop.propagation.element_points`): they move no body, only the element-dependent
    outputs (motion ratios, wheel rate: exact derivatives; element forces: central
    differences), and the result's :attr:`TargetPropagation.after` carries them.
    """
    eng = engine_for(model, engine)
    start = eng.state_of(model)
    loose = [str(f) for f in free if is_element_address(str(f))]
    free = [f for f in free if not is_element_address(str(f))]
    try:
        labels, moves = element_directions(model, eng, start, loose) if loose else ([], None)
    except AddressError as exc:
        raise AddressError(f"--free {exc}") from None
    for a in changes or {}:
        if is_element_address(a) and set(element_labels(model, a)) & set(labels):
            raise AddressError(f"--set {a}: the element point is also free (--free element:...)")
    if changes and any(is_element_address(a) for a in changes):  # element points: the model's, no body moves
        model, changes = apply_element_changes(model, eng, start, changes)
    ext_weights = {k: float(v) for k, v in (weights or {}).items() if is_element_address(k)}
    weights = {k: v for k, v in (weights or {}).items() if not is_element_address(k)}
    changes = changes_to_internal(model, changes or {}, eng) if check_units(units) else dict(changes or {})
    st, _, _ = eng.apply(start, resolve_changes(eng, start, changes))
    specs = tuple(e for t in targets for e in _every_case(model, t if isinstance(t, TargetSpec) else
                                                           parse_target(model, t, eng)))  # fmt: skip
    if not specs:
        raise AddressError("no targets given")
    # configurations keyed by their conditions
    keys: dict[tuple, int] = {}
    conds: list[tuple[Condition, ...]] = []
    outs: list[list[str]] = []

    def config(cs: tuple[Condition, ...]) -> int:
        key = tuple(sorted((c.output, c.value) for c in cs))
        if key not in keys:
            keys[key] = len(conds)
            conds.append(cs)
            outs.append([c.output for c in cs if not c.held])
        return keys[key]

    def slot(k: int, name: str) -> int:
        if name not in outs[k]:
            outs[k].append(name)
        return outs[k].index(name)

    for s in specs:
        if s.slope is None:
            config(s.conditions)
        else:
            config(s.slope[0])
            config(s.slope[1])
    rows: list[Row] = []
    for k, cs in enumerate(conds):
        for c in cs:
            if not c.held:
                rows.append(Row(f"{c.output}={c.value:g}", c.value, ((k, slot(k, c.output), 1.0),), hard=True))
    for s in specs:
        if s.slope is None:
            k = config(s.conditions)
            rows.append(Row(s.text, s.value, ((k, slot(k, s.output), 1.0),), scale=1.0 / s.weight, bound=s.bound))
        else:
            ka, kb = config(s.slope[0]), config(s.slope[1])
            span = s.slope[2]
            terms = ((ka, slot(ka, s.output), -1.0 / span), (kb, slot(kb, s.output), 1.0 / span))
            rows.append(Row(s.text, s.value, terms, scale=1.0 / s.weight, bound=s.bound))
    names = tuple(" & ".join(_label(model, c) for c in cs) or "base" for cs in conds)
    drives = _drive_engines(model, eng, st, conds, coordinates)

    def build(m: Model) -> list[Configuration]:
        cfgs = []
        for k, cs in enumerate(conds):
            cfg = Configuration(
                names[k],
                _config_outputs(m, eng, outs[k]),
                {c.output: [c.value] for c in cs if c.held},
                _config_jacobian(m, eng, outs[k]) if analytic and not any(map(is_load_output, outs[k])) else None,
                # loads have no partials off the constraint manifold: their rates, also without analytic
                _config_rates(m, eng, outs[k]) if any(map(is_load_output, outs[k])) else None,
            )
            cfgs.append(cfg if drives[k] is None else drives[k].lift(cfg, cs))  # type: ignore[union-attr]
        return cfgs

    external = _element_design(model, eng, start, labels, moves, outs, build, ext_weights) if labels else None
    if external is not None and any(d is not None for d in drives):  # its partials on the base engine's states
        base_partials = external.partials
        views = [(lambda x: x) if d is None else d.view for d in drives]
        external = replace(external, partials=lambda k, state, e: base_partials(k, views[k](state), e))
    opts = {"tol": tol, "target_tol": target_tol, "max_iter": max_iter}
    addresses, tie = free_tie(eng, st, free)
    res = solve_targets(eng, st, build(model) if external is None else [], rows, addresses, coordinates=coordinates,
                        weights=free_weights(eng, weights), external=external, tie=tie, **opts)  # fmt: skip
    designed = None
    if external is not None and res.external is not None:
        designed = _element_model(model, eng, start, labels, res.external)
    return TargetPropagation(model, specs, res, eng, names, designed,
                             tuple((lambda x: x) if d is None else d.view for d in drives))  # fmt: skip


def _label(model: Model, c: Condition) -> str:
    """A condition as a configuration's name: ``travel:W=50``, ``roll=2`` (model units), ``J.q=V``."""
    v = c.value
    if c.drive and _kind(model, c.output) == "rad":
        v /= RADIANS_PER[model.units.get("angle", "rad")]
    return f"{c.output}={v:g}"


@dataclass(frozen=True)
class _DriveEngine:
    """The engine of the configurations that hold drives (:mod:`kinprop.analysis.drives`, the
    drive joints of ``sweep --drive`` and ``camber@travel=50``): the augmented model's engine,
    its start, and the view of its states on the base engine, where the outputs are evaluated."""

    driven: Any  # kinprop.analysis.drives.Driven
    engine: Engine
    start: State
    view: Callable[[State], State]
    columns: Array  # base column -> augmented column
    coordinates: tuple[str, ...]

    def lift(self, cfg: Configuration, conditions: Sequence[Condition]) -> Configuration:
        """``cfg`` (outputs on the base engine) as a configuration of the augmented engine: its
        drives held at their values, the inputs they release and the other drive joints free."""
        view, cols = self.view, self.columns
        inv = np.full(self.engine.n_columns, -1, np.int64)
        inv[cols] = np.arange(cols.size)
        held = {k: v for k, v in cfg.held.items()}
        drives = [c.output for c in conditions if c.drive]
        for c in conditions:
            if c.drive:
                del held[c.output]
                held |= {a: [c.value] for a in self.driven.addresses[c.output]}
        jac, rates, outputs = cfg.jacobian, cfg.rates, cfg.outputs

        def jacobian(st: State, columns: Array) -> Array:
            b = inv[np.asarray(columns, np.int64)]
            ok = b >= 0
            G0 = jac(view(st), b[ok])  # type: ignore[misc]
            G = np.zeros((G0.shape[0], b.size))
            G[:, ok] = G0
            return G

        return Configuration(
            cfg.name,
            lambda st: outputs(view(st)),
            held,
            jacobian if jac is not None else None,
            (lambda st, X: rates(view(st), X[:, cols])) if rates is not None else None,  # type: ignore[misc]
            self.engine,
            self.start,
            self.driven.free(self.coordinates, drives),
        )


def _drive_engines(model: Model, engine: Engine, start: State, conds: Sequence[Sequence[Condition]],
                   coordinates: Sequence[str]) -> list[_DriveEngine | None]:  # fmt: skip
    """Per configuration, the drive engine it is solved by (None: the base engine). The roll
    drive and the travel drives both set the wheels' heights, so configurations with a roll
    condition share one augmented model (roll, and steer drives) and all the others another
    (travel and steer drives; none: the base engine)."""
    family = [ROLL in {c.output for c in cs if c.drive} for cs in conds]
    drives = [any(c.drive for c in cs) for cs in conds]
    for cs in conds:
        ds = {c.output for c in cs if c.drive}
        if ROLL in ds and any(d.startswith(TRAVEL) for d in ds):
            raise AddressError("--target: a roll and a travel condition in one configuration are not supported "
                               "(both set the wheels' heights)")  # fmt: skip
    at = engine.model_of(start, model)
    out: list[_DriveEngine | None] = [None] * len(conds)
    for fam in (False, True):
        ks = [k for k, f in enumerate(family) if f == fam and drives[k]]
        ds = list(dict.fromkeys(c.output for k in ks for c in conds[k] if c.drive))
        if not ds:
            continue
        drv = augment(at, ds, engine)
        eng = compile_engine(drv.model)
        view, cols = base_view(engine, eng)
        one = _DriveEngine(drv, eng, eng.state_of(drv.model), view, cols, tuple(coordinates))
        for k in ks:
            out[k] = one
    return out


def _element_model(model: Model, engine: Engine, start: State, labels: Sequence[str], values: Array) -> Model:
    """``model`` with the element-point components ``labels`` at ``values`` (global, at ``start``)."""
    return apply_element_changes(model, engine, start, dict(zip(labels, np.asarray(values, float), strict=True)))[0]


def _element_design(
    model: Model,
    engine: Engine,
    start: State,
    labels: list[str],
    moves: Array,
    outs: list[list[str]],
    build: Callable[[Model], list[Configuration]],
    weights: Mapping[str, float],
) -> ExternalDesign:
    """Element points as free target variables (:class:`kinprop.engine.targets.ExternalDesign`):
    one global component each (``labels``, at ``start``'s assembly, body-frame moves ``moves``);
    the first-order metrics' partials exact (:func:`first_order_derivatives` along the ends'
    moves alone), a load output's by a central difference of its configuration's output map with
    the point moved; every other output does not depend on them (0)."""
    e0 = np.array([float(element_point(model, engine, start, lab)[0]) for lab in labels])
    h = FD_STEP * max(1.0, engine.length_scale or 1.0)
    none = np.zeros((engine.n_columns, len(labels)))

    def partials(k: int, st: State, e: Array) -> Array:
        m, names = _element_model(model, engine, start, labels, e), outs[k]
        D = np.zeros((len(names), len(labels)))
        first = [i for i, n in enumerate(names) if not n.startswith("joint:") and first_order_of(m, n) is not None]
        if first:
            exact = first_order_derivatives(engine.model_of(st, m), [names[i] for i in first], none, engine=engine,
                                            elements=moves)  # fmt: skip
            for j, i in enumerate(first):
                D[i] = exact[j]
        loads = [i for i, n in enumerate(names) if is_load_output(n)]
        for c in range(len(labels)) if loads else ():
            step = np.zeros(len(labels))
            step[c] = h
            f = [_config_outputs(_element_model(model, engine, start, labels, e + s), engine,
                                 [names[i] for i in loads])(st) for s in (step, -step)]  # fmt: skip
            D[loads, c] = (f[0] - f[1]) / (2.0 * h)
        return D

    def weight(lab: str) -> float:  # an address's weight covers its components
        return next((float(v) for a, v in weights.items() if lab in (a, *element_labels(model, a))), 1.0)

    w = np.array([weight(lab) for lab in labels])
    return ExternalDesign(tuple(labels), e0, lambda e: build(_element_model(model, engine, start, labels, e)),
                          partials, w)  # fmt: skip


__all__ = ["TargetPropagation", "TargetSpec", "parse_target", "propagate_targets"]
