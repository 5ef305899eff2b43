"""Design propagation (section 5): overwrite design variables, re-assemble over a free set.

A propagation starts from the model's state exactly as it is; only the changed variables are
overwritten, and they are never free (PAPER-NOTES 7). It runs on the compiled engine
(:func:`kinprop.compile`); pass ``engine=`` to reuse one across calls.

Units (docs/units.md): :func:`propagate` and :func:`assemble` take changes in the model's
declared units (``units="model"``, the default: degrees in a degree model) or in solver units
(``units="solver"``: the model's length unit and radians). A :class:`Propagation` reports
``changes``, ``coordinates`` and ``joint_values`` in the model's units; the raw solver arrays are
``solver_changes``, ``solver_joint_values`` and the models ``before``/``after`` themselves (a
:class:`~kinprop.model.Model` stores solver units).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from functools import cached_property
from html import escape
from typing import Any

import numpy as np

from kinprop.engine import Engine, Solution, State, compile
from kinprop.engine.units import (
    address_unit,
    changes_to_internal,
    changes_to_model_units,
    check_units,
    from_solver_units,
    joint_values_to_model_units,
    radians_per_angle,
)
from kinprop.errors import AddressError, SingularityWarning
from kinprop.model.model import Model
from kinprop.propagation.conditioning import SINGULAR_RTOL, conditioning
from kinprop.propagation.element_points import apply_element_changes, is_element_address
from kinprop.propagation.hardpoints import free_addresses, free_weights, pivot_updates, resolve_changes
from kinprop.propagation.poses import body_poses, joint_values
from kinprop.spatial import Array, log_so3


def warn_if_singular(ratio: float, rtol: float = SINGULAR_RTOL, stacklevel: int = 3) -> None:
    """Issue a :class:`SingularityWarning` when a solved configuration is near singular:
    unit-independent ``s_r / s_1`` of the free-variable Jacobian below ``rtol``
    (:mod:`kinprop.propagation.conditioning`; docs/analysis/mobility.md)."""
    if ratio < rtol:
        warnings.warn(
            f"near-singular configuration (toggle): smallest/largest singular value of the (scaled) free-variable "
            f"Jacobian = {ratio:.3g} < {rtol:g}; small design changes may move the free variables a lot or "
            "leave no assembly",
            SingularityWarning,
            stacklevel=stacklevel,
        )


def engine_for(model: Model, engine: Engine | None = None) -> Engine:
    """``engine`` when given (it must be compiled from the same mechanism), else a new one."""
    if engine is None:
        return compile(model)
    if engine.mechanism is not model.mechanism and engine.mechanism != model.mechanism:
        raise ValueError("the engine was compiled from another mechanism")
    return engine


@dataclass(frozen=True)
class Propagation:
    """Before and after of one re-assembly: the model-level view of the engine's one solution
    record, ``result`` (a :class:`kinprop.engine.Solution`: ``status``, ``message``,
    ``iterations``, ``residual``, ``residual_history``, ``optimality``, ``fraction``, ``rank``).

    ``changes``, ``coordinates`` and ``joint_values`` are in the model's declared units
    (``units``); ``solver_changes``, ``solver_joint_values`` and ``before``/``after`` (models
    store solver units) are in solver units: the model's length unit and radians."""

    before: Model
    after: Model
    #: the engine's solution this propagation reads (the one result record)
    result: Solution
    #: the free set as given (groups and addresses)
    free: tuple[str, ...]
    #: unit-independent s_r / s_1 of the free-variable Jacobian at the solution (NaN if not converged)
    singularity_ratio: float = float("nan")

    @property
    def engine(self) -> Engine:
        """The compiled engine the solution came from."""
        return self.result.engine

    @property
    def converged(self) -> bool:
        return self.result.converged

    @property
    def solver_changes(self) -> Mapping[str, Array]:
        """The values set, by address, in solver units (radians); ``changes``: the model's units."""
        return self.result.changes

    @property
    def notes(self) -> list[str]:
        """One line per thing to know: the change was subdivided to stay on the branch, the
        assembly may be another branch than the estimates, the result is near a singularity."""
        out = list(self.result.notes)
        if self.singularity_ratio < SINGULAR_RTOL:
            out.append(f"near-singular configuration (toggle): singularity measure {self.singularity_ratio:.3g}")
        return out

    @cached_property
    def bodies(self) -> dict[str, dict[str, Array]]:
        """Every body's global pose after the propagation: ``{BODY: {"R": (3, 3), "t": (3,)}}``."""
        return body_poses(self.engine, self.engine.state_of(self.after))

    @property
    def units(self) -> dict[str, str]:
        """The model's declared units, the units of ``changes``, ``coordinates`` and ``joint_values``."""
        return {"length": self.before.units.get("length", "m"), "angle": self.before.units.get("angle", "rad")}

    @cached_property
    def changes(self) -> dict[str, Array]:
        """The values set, by address, in the model's units (degrees in a degree model)."""
        return changes_to_model_units(self.before, self.solver_changes, self.engine)

    @cached_property
    def coordinates(self) -> dict[str, Array]:
        """Every joint's coordinates after the propagation, in the model's units."""
        return {j: from_solver_units(self.after, f"{j}.q", q, self.engine) for j, q in self.after.coordinates.items()}

    @cached_property
    def solver_joint_values(self) -> dict[str, dict[str, float | Array]]:
        """Every joint's relative value after the propagation, cut joints included
        (:mod:`kinprop.propagation.poses`), in solver units: radians, the model's length unit."""
        return joint_values(self.engine, self.engine.state_of(self.after))

    @cached_property
    def joint_values(self) -> dict[str, dict[str, float | Array]]:
        """:attr:`solver_joint_values` in the model's units (angles, rotation vectors in
        ``units["angle"]``; Euler parameters have no unit)."""
        return joint_values_to_model_units(self.after, self.solver_joint_values)

    def changed_variables(self, atol: float = 0.0) -> list[str]:
        """Layout keys whose value differs between before and after."""
        eng = self.engine
        a, b = eng.state_of(self.before), eng.state_of(self.after)
        return [v.key for v in eng.layout.variables if np.max(np.abs(eng.get(a, v.key) - eng.get(b, v.key))) > atol]

    def __repr__(self) -> str:
        """A compact summary (status, the set and most-moved variables, model units)."""
        return summary_text(self)

    def _repr_html_(self) -> str:
        return summary_html(self)


def variable_rows(prop: Propagation) -> list[dict[str, Any]]:
    """One row per variable: before and after values, their unit, role, max change.

    Values in the model's units (docs/units.md); ``C`` variables report the rotation angle of
    after relative to before, in the model's angle unit.
    """
    asm = prop.engine
    st_before, st_after = asm.state_of(prop.before), asm.state_of(prop.after)
    changed = set(prop.changed_variables())
    set_keys = {k.split("[")[0] for k in prop.solver_changes}
    model = prop.before
    angle = model.units.get("angle", "rad")
    rows: list[dict[str, Any]] = []
    for v in asm.layout.variables:
        role = "set" if v.key in set_keys else ("moved" if v.key in changed else "")
        if v.group == "C":
            Cb, Ca = prop.before.design[v.key], prop.after.design[v.key]
            ang = 0.0 if np.array_equal(Ca, Cb) else float(np.linalg.norm(log_so3(Ca @ Cb.T)))
            ang /= radians_per_angle(model)
            rows.append(
                {"variable": v.key, "unit": angle, "before": [0.0], "after": [ang], "change": ang, "role": role}
            )
            continue
        b = from_solver_units(model, v.key, asm.get(st_before, v.key), asm)
        a = from_solver_units(model, v.key, asm.get(st_after, v.key), asm)
        unit = address_unit(model, v.key, asm)
        change = float(np.max(np.abs(a - b))) if a.size else 0.0
        rows.append(
            {"variable": v.key, "unit": unit, "before": b.tolist(), "after": a.tolist(), "change": change, "role": role}
        )
    return rows


#: moved variables listed by a summary before it says "... and N more"
SUMMARY_ROWS = 8


#: a shown number this small against the largest of its row or column is round-off, shown as 0
ROUND_OFF = 1e-10
#: ... and so is one below this, in the model's units (1e-12 m, mm, rad or deg)
ROUND_OFF_ABS = 1e-12


def shown(value: float, scale: float = 0.0, digits: int = 6) -> str:
    """``value`` for a table or a summary: ``digits`` significant digits, round-off (below
    :data:`ROUND_OFF` times ``scale``, the largest magnitude beside it, or :data:`ROUND_OFF_ABS`)
    as ``0`` and never ``-0``; NaN as an empty string. Files keep the full values."""
    if value != value:
        return ""
    if abs(value) <= max(ROUND_OFF_ABS, ROUND_OFF * abs(scale)):
        value = 0.0
    text = f"{value:.{digits}g}"
    return "0" if text == "-0" else text


def _short(values: list[float], unit: str = "") -> str:
    """``[a, b, c]`` (one value: ``a``); a vector with mixed units (``m,m,m,,,,`` of a free
    joint) carries each component's unit, ``[0.01 m, 0, 0.4 m, 1, 0, 0, 0]``."""
    scale = max((abs(x) for x in values if x == x), default=0.0)
    units = unit.split(",") if "," in unit else [""] * len(values)
    text = ", ".join(f"{shown(x, scale)} {u}".rstrip() for x, u in zip(values, units, strict=True))
    return text if len(values) == 1 else f"[{text}]"


def unit_text(unit: str) -> str:
    """A unit for a ``unit`` column: mixed units of a vector per component (``[m, m, m, -, -, -, -]``)."""
    return f"[{', '.join(u or '-' for u in unit.split(','))}]" if "," in unit else unit


def summary_text(prop: Propagation) -> str:
    """A compact ``repr`` of a propagation for a notebook or a REPL (a few lines, not a dump):
    status, iterations, ``||Phi||``, the changes and the variables that moved most."""
    r = prop.result
    name = prop.before.mechanism.name
    rows = [row for row in variable_rows(prop) if row["role"]]
    rows.sort(key=lambda row: (row["role"] != "set", -row["change"]))
    lines = [
        f"<Propagation of {name!r}: {r.status} in {r.iterations} iterations, ||Phi|| = {r.residual:.3g};"
        f" free: {' '.join(prop.free)}>"
    ]
    for row in rows[:SUMMARY_ROWS]:
        u = row["unit"]
        before, after = (_short(row[k], u) for k in ("before", "after"))
        unit = f" {u}" if u and "," not in u else ""  # mixed units: on each component
        lines.append(f"  {row['role']:>5} {row['variable']}: {before} -> {after}{unit}")
    if len(rows) > SUMMARY_ROWS:
        lines.append(f"  ... and {len(rows) - SUMMARY_ROWS} more moved variables (prop.changed_variables())")
    return "\n".join(lines)


def summary_html(prop: Propagation) -> str:
    """``_repr_html_`` of a propagation: the status line and a before/after table of the set
    and moved variables (every one; values escaped)."""
    r = prop.result
    head = (
        f"<p><b>Propagation</b> of {escape(prop.before.mechanism.name)}: {escape(r.status)} in {r.iterations} "
        f"iterations, ||Phi|| = {r.residual:.3g}; free: {escape(' '.join(prop.free))}</p>"
    )
    cells = "".join(
        "<tr>"
        + "".join(
            f"<td>{escape(str(x))}</td>"
            for x in (row["role"], row["variable"], unit_text(row["unit"]), _short(row["before"]), _short(row["after"]))
        )
        + f"<td>{row['change']:.3g}</td></tr>"
        for row in variable_rows(prop)
        if row["role"]
    )
    header = "".join(f"<th>{h}</th>" for h in ("role", "variable", "unit", "before", "after", "max |change|"))
    return f"{head}<table><thead><tr>{header}</tr></thead><tbody>{cells}</tbody></table>"


def propagation_of(engine: Engine, model: Model, sol: Solution, free: Sequence[str]) -> Propagation:
    """The :class:`Propagation` view (before = ``model``) of an engine solution, with the
    singularity measure of its free Jacobian (NaN unless converged; a warning below
    :data:`SINGULAR_RTOL`)."""
    ratio = conditioning(engine.row_blocks, sol.jacobian[:, sol.free]) if sol.converged and sol.free.size else \
        float("nan")  # fmt: skip
    if np.isfinite(ratio):
        warn_if_singular(ratio, stacklevel=4)
    after = model.with_state(sol.design, sol.coordinates)
    return Propagation(model, after, sol, tuple(free), ratio)


#: a changed coordinate whose first-order motion leaves this relative residual is not independent
DEPENDENT_RTOL = 1e-6


def check_coordinates_movable(engine: Engine, start: State, changes: Mapping[str, object], free: Sequence[str]) -> None:
    """Refuse a changed coordinate that cannot move while the held declared inputs stay (the
    other coordinates free, group ``q``): the free columns cannot absorb its motion to first
    order, ``J_c e`` is not in the range of ``J_free`` (least squares, relative residual above
    :data:`DEPENDENT_RTOL`). Without this the solver would grind through its sub-steps and
    report conflicting rows; the message names the held coordinates and how to free them."""
    targets = [(a, engine.target(a)) for a in changes if "." in a]
    moved = [(a, t) for a, t in targets if t.group == "q"]
    if not moved or "q" not in free:  # only the declared inputs' hold is diagnosed here
        return
    free_cols = engine.free_columns(free, list(changes))
    labels = engine.column_labels
    qcols = [k for k, lab in enumerate(labels) if lab.split("[")[0].endswith(".q")]  # inputs too
    changed_cols = {t.start + k for _, t in moved for k in ([t.index] if t.index is not None else range(t.size))}
    held = [c for c in qcols if c not in changed_cols and c not in set(free_cols.tolist())]
    if not held:
        return
    _, J = engine.evaluate(start)
    Jf = J[:, free_cols]
    for address, t in moved:
        cols = [t.start + k for k in ([t.index] if t.index is not None else range(t.size))]
        for c in cols:
            b = J[:, c]
            nb = float(np.linalg.norm(b))
            if nb == 0.0:
                continue
            y = np.linalg.lstsq(Jf, b, rcond=None)[0] if Jf.size else np.zeros(0)
            r = float(np.linalg.norm(b - Jf @ y)) if Jf.size else nb
            if r > DEPENDENT_RTOL * nb:
                names = list(dict.fromkeys(labels[h].split(".q")[0].split("[")[0] for h in held))
                which = ", ".join(names)
                raise AddressError(
                    f"{address}: not independent while {which} {'is' if len(names) == 1 else 'are'} held: the "
                    f"mechanism cannot move it with {'that coordinate' if len(names) == 1 else 'those'} fixed; "
                    f"free it (--free q --free {names[0]}.q; Python: free=['q', '{names[0]}.q']) or set "
                    f"{names[0]}.q instead"
                )


def hold(model: Model, joints: Sequence[str], where: str = "--hold") -> Model:
    """``model`` with ``joints`` (``J`` or ``J.q[k]``) held like its declared inputs: added to
    ``mechanism.inputs``, so the group ``q`` leaves them where they are and ``--free J.q``
    frees them again. For a model without ``inputs:`` (an imported MJCF), this holds two
    joints without listing every other one as free. Raises :class:`AddressError` naming
    ``where`` for an unknown joint or one that has no coordinates of its own (a cut joint)."""
    if not joints:
        return model
    mech = model.mechanism
    tree = compile(mech).topology.tree_joints
    for name in joints:
        joint = name.split(".q")[0].split("[")[0]
        if joint not in mech.joint_names:
            raise AddressError(f"{where} {name!r}: unknown joint; joints are {', '.join(mech.joint_names)}")
        if joint not in tree or mech.joint(joint).jtype.n_coordinates == 0:
            raise AddressError(
                f"{where} {name!r}: {joint} has no coordinates of its own to hold (a cut or fixed joint); "
                "hold a joint of the spanning tree"
            )
    inputs = tuple(dict.fromkeys([*mech.inputs, *joints]))
    return replace(model, mechanism=replace(mech, inputs=inputs))


def apply_changes(
    model: Model, changes: Mapping[str, object], engine: Engine | None = None
) -> tuple[Model, dict[str, Array], set[str]]:
    """Overwrite design variables / coordinates by address; returns the model, the changes as
    arrays and the set of changed variable keys."""
    eng = engine_for(model, engine)
    st, done, keys = eng.apply(eng.state_of(model), changes)
    return eng.model_of(st, model), done, keys


def propagate(
    model: Model,
    changes: Mapping[str, object] | None = None,
    free: Sequence[str] = ("q",),
    *,
    tol: float = 1e-10,
    max_iter: int = 50,
    weights: Mapping[str, float] | None = None,
    engine: Engine | None = None,
    branch: bool = True,
    units: str = "model",
    method: str = "least-change",
) -> Propagation:
    """Apply ``changes`` (address -> value, in the model's units; ``units="solver"``: radians)
    and re-assemble, moving only ``free`` variables, on the start's assembly branch (``branch=False``: the paper's plain
    Newton, which may land on another branch; docs/analysis/continuation.md).

    ``free`` holds groups (``q``, ``s``, ``C``, ``l``) and/or addresses (``J.s_i``, ``J.q``,
    ``J.s_i[2]``, and ``hardpoint:J[.i|.j]`` / ``axis:J[.i|.j]`` for those design variables).
    ``changes`` may use global addresses ``hardpoint:J.i=x,y,z``, ``hardpoint:J``, ``axis:J``
    (:mod:`kinprop.propagation.hardpoints`), converted exactly at the model's current assembly,
    and element points ``element:E.point_i=x,y,z`` (:mod:`kinprop.propagation.element_points`:
    the model's element moves, no body does).
    ``weights`` maps addresses or groups to positive weights of a weighted
    minimum-norm step (a larger weight lets a variable move more). When the free set leaves
    freedom the result is the assembly closest to the changed start, changes measured in metres
    and radians and scaled by ``weights`` (docs/analysis/weights.md); ``method="paper"``: the end
    point of the paper's generalized-inverse iteration (with ``tol=1e-3``, its tables).
    """
    eng = engine_for(model, engine)
    changed = model
    if changes and any(is_element_address(a) for a in changes):  # element points: the model's, no body moves
        changed, changes = apply_element_changes(model, eng, eng.state_of(model), changes)
    sol = solve_changes(eng, model, changes, free, tol=tol, max_iter=max_iter, weights=weights, branch=branch,
                        units=units, method=method)  # fmt: skip
    prop = propagation_of(eng, model, sol, free)
    if changed is not model:
        prop = replace(prop, after=replace(prop.after, elements=changed.elements))
    moved_pivots = pivot_updates(eng, changes or {})
    if moved_pivots:  # the result carries its moved pivots (fixed-body points, not variables)
        prop = replace(prop, after=with_points(prop.after, moved_pivots))
    return prop


def solve_changes(
    engine: Engine,
    model: Model,
    changes: Mapping[str, object] | None,
    free: Sequence[str] = ("q",),
    *,
    tol: float = 1e-10,
    max_iter: int = 50,
    weights: Mapping[str, float] | None = None,
    branch: bool = True,
    units: str = "model",
    method: str = "least-change",
) -> Solution:
    """The engine solution of :func:`propagate` (its arguments; ``engine`` compiled from the
    model's mechanism): changes converted to solver units and global addresses resolved at the
    model's assembly, then one :meth:`Engine.propagate`."""
    eng = engine
    start = eng.reference if eng.model is model else eng.state_of(model)
    changes = changes_to_internal(model, changes or {}, eng) if check_units(units) else dict(changes or {})
    changes = resolve_changes(eng, start, changes)
    check_coordinates_movable(eng, start, changes, free_addresses(eng, free))
    return eng.propagate(
        changes,
        free_addresses(eng, free),
        start=start,
        weights=free_weights(eng, weights),
        tol=tol,
        max_iter=max_iter,
        branch=branch,
        method=method,
    )


def with_points(model: Model, points: Mapping[str, Mapping[str, Array]]) -> Model:
    """``model`` with named points (body frame) of some bodies replaced or added."""
    mech = model.mechanism
    bodies = []
    for b in mech.bodies:
        new = points.get(b.name)
        if new:
            pts = dict(b.points)
            pts.update({k: tuple(float(x) for x in v) for k, v in new.items()})
            b = replace(b, points=tuple(pts.items()))
        bodies.append(b)
    return replace(model, mechanism=replace(mech, bodies=tuple(bodies)))


def assemble(
    model: Model,
    free: Sequence[str] = ("q",),
    *,
    tol: float = 1e-10,
    max_iter: int = 50,
    engine: Engine | None = None,
    branch: bool = True,
    method: str = "least-change",
) -> Propagation:
    """Solve for an assembled configuration from the model's estimates (no design change): a
    Newton homotopy from the estimates, so the assembly found is the one they point at. It takes
    no values; the result reports model units like :func:`propagate`'s. With freedom left: the
    assembly closest to the estimates (``method="paper"``: the paper's iteration's end point)."""
    return propagate(model, {}, free, tol=tol, max_iter=max_iter, engine=engine, branch=branch, units="solver",
                     method=method)  # fmt: skip


def roundoff_floor(model: Model, engine: Engine | None = None) -> float:
    """The round-off floor of ||Phi|| at a model's length scale (:meth:`Engine.roundoff_floor`)."""
    eng = engine_for(model, engine)
    return eng.roundoff_floor(eng.state_of(model))
