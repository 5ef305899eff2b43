"""What the ``kinprop`` commands and the workbench's HTTP API (:mod:`kinprop.serve`) share:
the propagation, sensitivity and sweep drivers behind ``propagate``, ``sensitivity`` and
``sweep``, and the JSON / CSV each answers with (``check``, ``propagate``, ``sensitivity``,
``sweep``; the before/after CSV). The CLI prints them, the HTTP API returns them.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from kinprop.analysis.drives import driven_sensitivity, expand_driven, is_driven
from kinprop.analysis.mobility import MobilityReport, row_names
from kinprop.analysis.outputs import expand_outputs
from kinprop.analysis.points import hardpoint_table
from kinprop.analysis.sensitivity import derivative_method, design_sensitivity, output_sensitivity_matrix
from kinprop.analysis.sweep import Drive, coordinate_columns, default_outputs, parse_drive
from kinprop.analysis.units import derivative_scale, unit_of
from kinprop.engine import Engine, Solution
from kinprop.engine import compile as compile_engine
from kinprop.engine.units import changes_to_internal
from kinprop.errors import AddressError
from kinprop.io.arguments import parse_assignments
from kinprop.io.results import comparison_rows, coordinates_json, design_json, point_rows, propagation_json
from kinprop.io.writer import csv_text
from kinprop.model import Model
from kinprop.propagation import Propagation
from kinprop.propagation.continuation import ContinuationResult, continuation_of
from kinprop.propagation.element_points import apply_element_changes, is_element_address
from kinprop.propagation.hardpoints import free_weights, global_columns, is_global
from kinprop.propagation.propagate import propagation_of, solve_changes

# --- kinprop check ---------------------------------------------------------------------------

#: ||Phi|| below which the configuration counts as assembled (the rank is then reliable)
ASSEMBLED_TOL = 1e-8


def joint_rows(asm: Engine) -> dict[str, list[str]]:
    """Constraint-row labels of Phi per joint (cut-joint rows, Euler normalisation rows)."""
    labels = row_names(asm)
    rows: dict[str, list[str]] = {}
    for blk in asm.row_blocks:
        rows.setdefault(blk.joint, []).extend(labels[blk.rows])
    return rows


def check_json(model: Model, rep: MobilityReport, evaluated_at: str) -> dict[str, Any]:
    """The report as one JSON object (see ``kinprop check --help``)."""
    mech = model.mechanism
    asm = compile_engine(mech)
    topo = asm.topology
    tree = set(topo.tree_joints)
    rows = joint_rows(asm)
    at_body: dict[str, list[str]] = {b.name: [] for b in mech.bodies}
    for j in mech.joints:
        at_body[j.body_i].append(j.name)
        at_body[j.body_j].append(j.name)
    hardpoints = hardpoint_table(model, asm)
    return {
        "model": model.source,
        "name": mech.name,
        "units": dict(model.units),
        "hardpoints": hardpoints if any(r["group"] == "wheel" for r in hardpoints) else [],  # a suspension's
        "bodies": [
            {
                "name": b.name,
                "fixed": b.fixed,
                "joints": at_body[b.name],
                "points": [p for p, _ in b.points],
            }
            for b in mech.bodies
        ],
        "joints": [
            {
                "name": j.name,
                "type": j.jtype.name,
                "bodies": [j.body_i, j.body_j],
                "role": "tree" if j.name in tree else "cut",
                "n_coordinates": j.jtype.n_coordinates if j.name in tree else j.jtype.n_cut_coordinates,
                "rows": rows.get(j.name, []),
            }
            for j in mech.joints
        ],
        "couplings": [
            {"name": c.name, "joints": [c.joint_a, c.joint_b], "rows": rows.get(c.name, [])} for c in mech.couplings
        ],
        "tree_joints": list(topo.tree_joints),
        "cut_joints": list(topo.cut_joints),
        "loops": [
            {
                "cut_joint": lp.cut_joint,
                "bodies": [lp.body_i, lp.body_j],
                "junction": lp.junction,
                "case": lp.case,
                "path_i": list(lp.path_i),
                "path_j": list(lp.path_j),
            }
            for lp in topo.loops
        ],
        "n_coordinates": rep.n_coordinates,
        "n_constraints": rep.n_constraints,
        "rank": rep.rank,
        "gruebler": rep.gruebler,
        "mobility": rep.mobility,
        "redundant": rep.redundant,
        "redundant_joints": rep.redundant_joints,
        "dependent": rep.dependent,
        "singular_values": rep.singular_values,
        "rtol": rep.rtol,
        "residual": rep.residual,
        "assembled": rep.residual < ASSEMBLED_TOL,
        "evaluated_at": evaluated_at,
    }


# --- kinprop propagate -----------------------------------------------------------------------


def solve_propagation(
    model: Model,
    changes: Mapping[str, object],
    free: Sequence[str],
    *,
    tol: float,
    max_iter: int,
    weights: Mapping[str, float] | None,
    continuation: bool | None,
    on_fallback: Callable[[Propagation], None] | None = None,
    method: str = "least-change",
) -> tuple[Propagation, ContinuationResult | None, bool]:
    """One engine solve of the change, on the start's branch; its diagnosis when it failed
    (``continuation`` None or True) or always (True). No second solve: the diagnosis is a
    function of the solution (:func:`kinprop.propagation.continuation.diagnose`).

    Returns ``(prop, res, newton_ran)``: the propagation to report (a failed one is the
    solver's record), the continuation view when asked for (else None) and True.
    ``on_fallback(prop)`` is called when the solve failed and the diagnosis follows.
    """
    engine = compile_engine(model)
    sol = solve_changes(engine, model, changes, free, tol=tol, max_iter=max_iter, weights=weights, units="solver",
                        method=method)  # fmt: skip
    prop = propagation_of(engine, model, sol, free)
    if continuation is False or (continuation is None and (sol.converged or not changes)):
        return prop, None, True
    if not sol.converged and on_fallback is not None:
        on_fallback(prop)
    res = continuation_of(model, sol, free)
    return (res.propagation if res.converged else prop), res, True


def continuation_json(res: ContinuationResult) -> dict[str, Any]:
    return {
        "status": res.status.value,
        "fraction": res.fraction,
        "message": res.message,
        "conflict": [{"row": r, "weight": w} for r, w in res.conflict],
        "residual_rows": [{"row": r, "value": v} for r, v in res.residual_rows],
        "singularity_ratio": res.singularity_ratio,
        "substeps": res.substeps,
        "last_feasible": {"coordinates": coordinates_json(res.after), "design": design_json(res.after)},
    }


def propagate_json(prop: Propagation, res: ContinuationResult | None = None, newton_ran: bool = True) -> dict[str, Any]:
    """What ``kinprop propagate --json`` prints for :func:`solve_propagation`'s result: the
    propagation's JSON (its ``status`` the solution's, :class:`kinprop.Status`), and when the
    change failed, a ``continuation`` object with the diagnosis."""
    obj = propagation_json(prop)
    if res is None or res.converged:
        return obj
    obj["continuation"] = continuation_json(res)
    return obj


def comparison_csv(prop: Propagation) -> str:
    """Before/after rows (:func:`comparison_rows`, then hardpoints and named points) as CSV text:
    shortest round-trip numbers, ``\\n`` line endings (no pandas needed)."""
    return csv_text(["variable", "unit", "before", "after", "change", "role"], comparison_rows(prop) + point_rows(prop))


# --- kinprop sensitivity ---------------------------------------------------------------------


def _per(model, name: str, engine=None) -> str:
    """The unit of a design column: a C column is per angle of body-frame rotation."""
    if ".C_" in name:
        return model.units.get("angle", "rad")
    return unit_of(model, name, engine)


def with_element_sets(model: Model, given: Mapping[str, Any]) -> tuple[Model, dict[str, Any]]:
    """``--set element:E.point_i=x,y,z`` (:mod:`kinprop.propagation.element_points`): the model
    with those element points moved (global, at its assembly; no body moves), and the other
    changes."""
    if not any(is_element_address(a) for a in given):
        return model, dict(given)
    engine = compile_engine(model)
    return apply_element_changes(model, engine, engine.reference, given)


class Sensitivities(NamedTuple):
    """d(rows)/d(columns) in the model's units, with the unit of every row and column."""

    matrix: np.ndarray
    rows: list[str]
    columns: list[str]
    units_of: list[str]
    units_wrt: list[str]
    #: how each row was differentiated (``kinprop.analysis.sensitivity.derivative_method``;
    #: None: the free variables' implicit-function response, analytic)
    methods: list[str] | None = None


def _solver_matrix(
    assembled: Model, wrt: Sequence[str], of: Sequence[str] | None, free: Sequence[str], weights: Any
) -> tuple[np.ndarray, list[str], list[str]]:
    if any(is_element_address(w) for w in wrt) and not (of and not any(is_driven(o) for o in of)):
        raise AddressError("--wrt element:...: an element point moves no body (the free variables do not respond "
                           "to it); name outputs with --of (motion_ratio:E, wheel_rate, force:E), none at a drive "
                           "position")  # fmt: skip
    if of and any(is_driven(o) for o in of):  # outputs at a drive position (analysis/drives.py)
        names = expand_driven(assembled, of)
        plain = [o for o in names if not is_driven(o)]
        Dd, rows_d, columns = driven_sensitivity(assembled, [o for o in names if is_driven(o)], wrt, free, weights)
        parts = dict(zip(rows_d, Dd, strict=True))
        if plain:
            Dp, rows_p, cols_p, _ = output_sensitivity_matrix(assembled, plain, wrt, free, weights, units="solver")
            at = [cols_p.index(c) for c in columns]
            parts |= {r: np.asarray(Dp)[k, at] for k, r in enumerate(rows_p)}
        return np.array([parts[o] for o in names]).reshape(len(names), len(columns)), names, list(columns)
    if of:
        matrix, rows, columns, _ = output_sensitivity_matrix(assembled, of, wrt, free, weights, units="solver")
        return np.asarray(matrix), list(rows), list(columns)
    sens = design_sensitivity(assembled, wrt, free, weights, units="solver")
    return np.asarray(sens.matrix), list(sens.rows), list(sens.columns)


def sensitivities(
    assembled: Model,
    wrt: Sequence[str],
    of: Sequence[str] | None,
    free: Sequence[str],
    weights: Mapping[str, float] | None,
) -> Sensitivities:
    """d(outputs)/d(wrt) at an assembled model (without ``of``: of the free variables), in the
    model's units (docs/units.md); ``hardpoint:J[.i|.j][c]`` columns are per global length unit
    (:func:`kinprop.propagation.hardpoints.global_columns`)."""
    engine = compile_engine(assembled)
    design, combos = global_columns(engine, engine.reference, wrt)
    matrix, rows, columns = _solver_matrix(assembled, design, of, free, free_weights(engine, weights))
    if combos:
        index = {c: k for k, c in enumerate(columns)}
        plain = {
            engine.column_labels[int(c)]
            for c in engine.columns([w for w in wrt if not is_global(w) and not is_element_address(w)])
        }
        keep = [c for c in columns if c in plain or is_element_address(c)]
        extra = list(combos)
        cols = [matrix[:, index[c]] for c in keep] + [
            sum(coef * matrix[:, index[c]] for c, coef in combos[label].items()) for label in extra
        ]
        matrix, columns = np.column_stack(cols) if cols else np.zeros((len(rows), 0)), keep + extra
    # in the model's units: d(out)/d(in) * scale(out) / scale(in)
    so = np.array([derivative_scale(assembled, str(name), engine) for name in rows])
    si = np.array([derivative_scale(assembled, str(name), engine) for name in columns])
    matrix = matrix * so[:, None] / si[None, :]
    units_of = [unit_of(assembled, str(name), engine) for name in rows]
    units_wrt = [_per(assembled, str(name), engine) for name in columns]
    # an output at a drive position is differentiated as its output is (analysis/drives.py)
    methods = [derivative_method(assembled, str(n).partition("@")[0].removeprefix("slope:")) for n in rows] if of \
        else None  # fmt: skip
    return Sensitivities(matrix, rows, columns, units_of, units_wrt, methods)


def sensitivity_json(
    model: str, sens: Sensitivities, free: Sequence[str], weights: Mapping[str, float] | None, assembly: Solution
) -> dict[str, Any]:
    """What ``kinprop sensitivity --json`` prints (``assembly``: the assembly solved first)."""
    r = assembly
    return {
        "model": model,
        "of": [str(i) for i in sens.rows],
        "wrt": [str(c) for c in sens.columns],
        "matrix": np.asarray(sens.matrix).tolist(),
        "units": {"of": sens.units_of, "wrt": sens.units_wrt, "matrix": "unit of the row per unit of the column"},
        "method": dict(zip(map(str, sens.rows), sens.methods, strict=True)) if sens.methods else None,
        "free": list(free),
        "weights": dict(weights) if weights else {},
        "assembly": {
            "status": r.status,
            "message": r.message,
            "initial_residual": r.residual_history[0],
            "residual": r.residual,
            "iterations": r.iterations,
        },
    }


# --- kinprop sweep ---------------------------------------------------------------------------

#: sweep columns that are counts, flags or text
_NO_UNIT = {"step", "status", "iterations", "residual", "sv_ratio", "near_singular", "message"}


def _records(frame) -> list[dict]:
    """Rows as JSON-ready dicts (NaN -> null)."""
    return [
        {k: (None if isinstance(v, float) and v != v else v) for k, v in row.items()}
        for row in frame.to_dict("records")
    ]


def label_units(res, base=None) -> None:
    """The unit of every value column (model units, docs/units.md) into the frames' attrs."""
    units = {c: unit_of(res.last, c) for c in res.frame.columns if c not in _NO_UNIT}
    for r in (res, base):
        if r is not None:
            r.frame.attrs["column_units"] = units


def sweep_json(res, base, output: Path | None = None, plot: Path | None = None, x: str | None = None) -> dict:
    """What ``kinprop sweep --json`` prints: counts, failed steps and every row (and the
    baseline's rows when ``base`` is given), with the unit of every column; ``x`` the abscissa
    of the curves (``--x``; default the first drive)."""
    if "column_units" not in res.frame.attrs:
        label_units(res, base)
    df = res.frame
    ok = df["status"] == "converged"
    obj = {
        "steps": len(df),
        "converged": int(ok.sum()),
        "failed": [int(k) for k in df.loc[~ok, "step"]],
        "drives": [d.label for d in res.drives],
        "x": x or res.drives[0].label,
        "outputs": list(res.outputs),
        "output_file": None if output is None else str(output),
        "plot_file": None if plot is None else str(plot),
        "rows": _records(df),
        "units": {c: u for c, u in df.attrs.get("column_units", {}).items() if u},
    }
    if base is not None:
        obj["baseline_rows"] = _records(base.frame)
    return obj


def check_x(model: Model, drives: Sequence[Drive], outputs: Sequence[str] | None, x: str) -> None:
    """``--x`` (the abscissa of a sweep's curves) names a column the sweep will have: a drive,
    a coordinate or an output; raises ValueError listing the columns."""
    names = list(default_outputs(model) if outputs is None else outputs)
    columns = [d.label for d in drives] + [c for c, *_ in coordinate_columns(model)] + expand_outputs(model, names)
    if x not in columns:
        raise ValueError(f"--x {x!r}: not a column of this sweep; columns: {', '.join(dict.fromkeys(columns))}")


def sweep_inputs(
    m: Model, drive: Sequence[str], set_: Sequence[str], baseline: bool = False
) -> tuple[list[Drive], dict[str, np.ndarray]]:
    """The parsed ``--drive`` and ``--set`` options (``--set`` in model units, converted)."""
    given = parse_assignments("--set", list(set_))
    if baseline and not given:
        raise ValueError("--baseline compares with the design before the --set changes: give at least one --set")
    return [parse_drive(m, d) for d in drive], changes_to_internal(m, given)


__all__ = [
    "ASSEMBLED_TOL",
    "Sensitivities",
    "check_json",
    "check_x",
    "comparison_csv",
    "continuation_json",
    "joint_rows",
    "label_units",
    "propagate_json",
    "sensitivities",
    "sensitivity_json",
    "solve_propagation",
    "sweep_inputs",
    "sweep_json",
]
