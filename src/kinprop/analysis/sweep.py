"""Sweeps: drive joint coordinates over a range, each step re-assembled from the previous one.

A drive ``JOINT=START:STOP:STEPS`` sets the coordinate to ``STEPS + 1`` evenly spaced
values from START to STOP (both included), ``JOINT=v1,v2,...`` to the listed values and
``JOINT=@FILE.csv[:COLUMN]`` to a CSV column, in the model's units (degrees when the file says
``angle: deg`` and the coordinate is an angle; lists and columns of angles are unwrapped).
Several drives move together (lockstep) and must have the same number of values. Step k is
a design propagation (section 5) from the last successful step with the driven coordinates
set (never free) and the ``free`` variables moving, followed on that step's assembly branch
(:func:`kinprop.solver.newton.follow`: a step too large to follow safely is subdivided; a
step that cannot be followed, e.g. past a toggle, fails and the next step restarts from the
last good one); step 0 goes from the model's state (assembled first from its estimates when
it is not) to the start values, with the ``--set`` changes, the same way. With
``continuation`` a failed step is diagnosed (the constraints in conflict are named).

Step 0 is one engine solve (:meth:`kinprop.Engine.propagate`); the later steps run in the
engine's compiled sequence (:meth:`kinprop.Engine.solve_sequence`), in chunks of
:data:`SEQUENCE_CHUNK` steps. Each step gives one row: ``step``, the drive values, ``status``
(:class:`kinprop.Status`: ``converged``, ``infeasible``, ``not_converged``, ...),
``iterations``, ``residual`` (the scaled ``||Phi||``, docs/units.md), ``sv_ratio`` (unit-independent
smallest/largest singular value of the free-variable Jacobian,
:mod:`kinprop.propagation.conditioning`; ``near_singular`` when below ``SINGULAR_RTOL``),
every joint coordinate, the outputs (named points ``point:BODY.NAME[x]``, suspension metrics, or any name
:func:`kinprop.analysis.outputs.evaluate_outputs` accepts) and ``message`` — every value in the
model's declared units (metric angles in the angle unit, docs/units.md). A failed step is
recorded with NaN values and its reason, and the sweep goes on from the last good state.

Rows are handed to a sink as they are computed: CSV appended and flushed row by row, Parquet
in row groups (:class:`ParquetSink`); the sink is closed (Parquet footer written) even when
the sweep is interrupted, so every finished row is kept.
"""

from __future__ import annotations

import csv
import math
import os
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from html import escape
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from kinprop.analysis.drives import ROLL, STEER, DrivenOutputs, augment, expand_driven, is_drive, is_driven, wheel_for
from kinprop.analysis.metrics import metric_names
from kinprop.analysis.outputs import evaluate_outputs, expand_outputs, output_function, program_batch
from kinprop.analysis.units import derivative_scale, unit_of
from kinprop.engine import Engine, Solution, State, Status
from kinprop.engine import compile as compile_engine
from kinprop.engine.units import changes_to_internal, check_units, degrees, from_solver_units, to_solver_units
from kinprop.errors import AddressError
from kinprop.model import Model
from kinprop.propagation.conditioning import SINGULAR_RTOL, conditioning
from kinprop.propagation.continuation import continuation_of
from kinprop.propagation.hardpoints import free_addresses
from kinprop.propagation.propagate import solve_changes
from kinprop.spatial import Array

if TYPE_CHECKING:
    from matplotlib.figure import Figure

_DRIVE = re.compile(r"^(?P<joint>[^\s=\[\].]+)(\.q)?(\[(?P<index>\d+)\])?=(?P<range>.+)$")

#: the most steps one sweep may take (each is a Newton solve and a row of results)
MAX_STEPS = 10_000_000
#: rows a sweep result's notebook table shows
SUMMARY_ROWS = 8
#: steps per call of the engine's compiled sequence (rows reach the sink after each)
SEQUENCE_CHUNK = 64
#: columns before the coordinates and outputs
META = ("step", "status", "iterations", "residual", "sv_ratio", "near_singular")


@dataclass(frozen=True)
class Drive:
    """One driven coordinate: ``joint``'s coordinate ``index`` over ``values`` (model units)."""

    joint: str
    index: int
    values: Array
    angle: bool = False
    #: coordinates the joint has (for the label)
    size: int = 1
    #: the column's name when not the coordinate's (a drive of kinprop.analysis.drives: ``travel``)
    name: str = ""

    @property
    def label(self) -> str:
        if self.name:
            return self.name
        return f"{self.joint}.q" if self.size == 1 else f"{self.joint}.q[{self.index}]"

    @property
    def address(self) -> str:
        return f"{self.joint}.q[{self.index}]"


def _coordinate_info(asm: Engine, model: Model, joint: str) -> tuple[int, tuple[int, ...]]:
    """(number of coordinates, indices that are angles in model units) of a joint."""
    if joint not in model.mechanism.joint_names:
        raise AddressError(f"--drive: unknown joint {joint!r}; joints are {', '.join(model.mechanism.joint_names)}")
    key = f"{joint}.q"
    if key not in asm.layout:
        raise AddressError(f"--drive: joint {joint!r} has no coordinates to drive")
    size = asm.layout[key].size
    tree = joint in asm.topology.tree_joints
    angles = model.mechanism.joint(joint).jtype.angle_indices if tree else ()
    return size, tuple(angles) if degrees(model) else ()


def _drive_values(text: str, spec: str) -> Array:
    """The values of a drive: ``START:STOP:STEPS``, a list ``v1,v2,...`` or a CSV column
    ``@FILE.csv`` (first column) / ``@FILE.csv:COLUMN`` (by header name or 0-based index)."""
    if spec.startswith("@"):
        path, _, col = spec[1:].partition(":")
        try:
            with open(path, newline="", encoding="utf-8") as f:
                rows = [r for r in csv.reader(f) if r and any(c.strip() for c in r)]
        except OSError as exc:
            raise AddressError(f"--drive {text!r}: cannot read {path!r}: {exc.strerror or exc}") from None
        if not rows:
            raise AddressError(f"--drive {text!r}: {path!r} has no rows")
        header = [c.strip() for c in rows[0]]
        has_header = any(not _is_number(c) for c in header)
        if col == "":
            k = 0
        elif col in header and has_header:
            k = header.index(col)
        elif col.isdigit():
            k = int(col)
        else:
            raise AddressError(f"--drive {text!r}: no column {col!r} in {path!r}; columns: {', '.join(header)}")
        body = rows[1:] if has_header else rows
        values = []
        for n, r in enumerate(body, start=2 if has_header else 1):
            if k >= len(r) or not _is_number(r[k]):
                raise AddressError(f"--drive {text!r}: {path!r} line {n}, column {k}: expected a number")
            values.append(float(r[k]))
        out = np.array(values)
    elif ":" in spec:
        parts = spec.split(":")
        if len(parts) != 3:
            raise AddressError(f"--drive {text!r}: expected START:STOP:STEPS, found {spec!r}")
        try:
            start, stop, steps = float(parts[0]), float(parts[1]), int(parts[2])
        except ValueError:
            raise AddressError(f"--drive {text!r}: START and STOP must be numbers and STEPS an integer") from None
        if steps < 1:
            raise AddressError(f"--drive {text!r}: STEPS must be >= 1")
        if steps > MAX_STEPS:
            raise AddressError(f"--drive {text!r}: {steps:,} steps; the limit is {MAX_STEPS:,}")
        out = np.linspace(start, stop, steps + 1)
    else:
        try:
            out = np.array([float(v) for v in spec.replace(";", ",").split(",") if v.strip()])
        except ValueError:
            raise AddressError(f"--drive {text!r}: expected START:STOP:STEPS, a list v1,v2,... or @FILE.csv") from None
    if out.size == 0 or out.size > MAX_STEPS + 1 or not np.all(np.isfinite(out)):
        raise AddressError(f"--drive {text!r}: expected 1..{MAX_STEPS + 1} finite values, found {out.size}")
    return out


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def parse_drive(model: Model, text: str, engine: Engine | None = None) -> Drive:
    """``JOINT=VALUES`` (also ``JOINT[k]=...``, ``JOINT.q[k]=...``) -> :class:`Drive`; VALUES
    is ``START:STOP:STEPS``, a list ``v1,v2,...`` or a CSV column ``@FILE.csv[:COLUMN]``, in
    the model's units. Angles in a list or a CSV column are unwrapped along the sequence (a
    jump of more than half a turn between neighbours is taken the short way)."""
    name, eq, spec = text.strip().partition("=")
    if eq and is_drive(name.strip()):  # wheel travel or body roll (kinprop.analysis.drives)
        if name.strip() != ROLL:
            wheel_for(model, name.strip())
        deg = name.strip().startswith((ROLL, STEER)) and degrees(model)
        return Drive(name.strip(), 0, _drive_values(text, spec.strip()), deg, 1, name.strip())
    m = _DRIVE.match(text.strip())
    if not m:
        raise AddressError(
            f"--drive {text!r}: expected JOINT=START:STOP:STEPS (e.g. O2=0:360:360), travel=, roll=, steer:WHEEL="
        )
    joint = m.group("joint")
    size, angles = _coordinate_info(engine if engine is not None else compile_engine(model.mechanism), model, joint)
    index = int(m.group("index") or 0)
    if m.group("index") is None and size != 1:
        raise AddressError(f"--drive {text!r}: joint {joint!r} has {size} coordinates; say which, e.g. {joint}[0]=...")
    if index >= size:
        raise AddressError(f"--drive {text!r}: joint {joint!r} has {size} coordinate(s), index {index} is out of range")
    spec = m.group("range").strip()
    values = _drive_values(text, spec)
    angle = index in angles
    if ":" not in spec or spec.startswith("@"):
        is_angle = angle or (index in _angle_indices(model, joint))
        if is_angle:
            values = np.unwrap(values, period=360.0 if angle else 2 * math.pi)
    return Drive(joint, index, values, angle, size)


def _angle_indices(model: Model, joint: str) -> tuple[int, ...]:
    """Indices of a tree joint's angular coordinates, whatever the model's angle unit."""
    return tuple(model.mechanism.joint(joint).jtype.angle_indices)


def coordinate_columns(model: Model, engine: Engine | None = None) -> list[tuple[str, str, int, bool]]:
    """``(column, joint, index, is_angle_in_degrees)`` for every coordinate of the layout."""
    asm = engine if engine is not None else compile_engine(model.mechanism)
    out = []
    for v in asm.layout.group("q"):
        _, angles = _coordinate_info(asm, model, v.joint)
        for k in range(v.size):
            out.append((v.key if v.size == 1 else f"{v.key}[{k}]", v.joint, k, k in angles))
    return out


def _each_output(
    model: Model, names: list[str], expanded: list[str], scale: Array, engine: Any, note: str
) -> dict[str, Any]:
    """The outputs one by one (NaN for those that fail here), and a message naming the failures."""
    values: dict[str, Any] = {}
    failed = []
    wanted = set(expanded)
    for name in names:
        for e in expand_outputs(model, [name]):
            if e not in wanted:
                continue
            try:
                v = evaluate_outputs(model, [e], units="solver", engine=engine)[e]
                values[e] = float(v) * float(scale[expanded.index(e)])
            except Exception as exc:
                failed.append(f"{e}: {exc}")
    values["message"] = f"{note}; outputs: {'; '.join(failed)}" if failed else note
    return values


def default_outputs(model: Model) -> list[str]:
    """Named points of every body, plus the suspension metrics of wheel bodies if any."""
    names = [f"point:{b.name}.{p}" for b in model.mechanism.bodies for p, _ in b.points]
    try:
        return names + metric_names(model)
    except Exception:  # a model without wheels, or metrics unavailable: points only
        return names


class Sink(Protocol):
    def write(self, row: Mapping[str, Any]) -> None: ...
    def close(self) -> None: ...


def header_labels(model: Model, columns: Sequence[str], engine: Engine | None = None) -> dict[str, str]:
    """CSV header of each column: ``NAME [unit]`` for a quantity in the model's units
    (``O2.q [deg]``, ``point:crank.tip[x] [m]``, ``metric:upright.camber [deg]``), the bare name
    for the rest (``step``, ``status``, Euler parameters, ...); docs/units.md."""
    out = {}
    for c in columns:
        u = "" if c in (*META, "message") else unit_of(model, c, engine)
        out[c] = f"{c} [{u}]" if u else c
    return out


class CsvSink:
    """Append rows to a CSV file, flushing after each row; ``labels`` maps a column to its
    header text (default: the column name)."""

    def __init__(self, path: str | Path, columns: Sequence[str], labels: Mapping[str, str] | None = None):
        self.path = Path(path)
        self.columns = list(columns)
        self._fh = self.path.open("w", newline="")
        self._w = csv.DictWriter(self._fh, fieldnames=self.columns, lineterminator="\n")
        self._w.writerow({c: (labels or {}).get(c, c) for c in self.columns})
        self._fh.flush()

    def write(self, row: Mapping[str, Any]) -> None:
        self._w.writerow({k: ("" if isinstance(v, float) and math.isnan(v) else v) for k, v in row.items()})
        self._fh.flush()

    def close(self) -> None:
        if not self._fh.closed:
            self._fh.close()


class ParquetSink:
    """Write rows to a Parquet file in row groups of ``row_group_size`` (pyarrow ParquetWriter)."""

    def __init__(self, path: str | Path, columns: Sequence[str], text_columns: Sequence[str], row_group_size: int = 32):
        import pyarrow as pa
        import pyarrow.parquet as pq

        self._pa = pa
        self.path = Path(path)
        #: rows go to a hidden partial file, renamed onto ``path`` when closed (also on an
        #: interrupt): ``path`` is always a complete Parquet file with its footer, or absent
        self.partial = self.path.with_name(f".{self.path.name}.partial")
        ints = {"step", "iterations"}
        fields = []
        for c in columns:
            t = (
                pa.string()
                if c in text_columns
                else pa.int64()
                if c in ints
                else pa.bool_()
                if c == "near_singular"
                else pa.float64()
            )
            fields.append(pa.field(c, t))
        self.schema = pa.schema(fields)
        self.row_group_size = max(1, int(row_group_size))
        self._rows: list[Mapping[str, Any]] = []
        #: (file size before, rows) of the group being written: an interrupt can land after
        #: ``write_table`` returned and before the rows are dropped; the file has then grown
        #: past the mark and those rows are not written again (no duplicate, none lost)
        self._mark: tuple[int, int] | None = None
        self._file = pa.OSFile(str(self.partial), "wb")
        self._writer = pq.ParquetWriter(self._file, self.schema)

    def write(self, row: Mapping[str, Any]) -> None:
        self._rows.append(dict(row))
        if len(self._rows) >= self.row_group_size:
            self.flush()

    def _settle(self) -> None:
        """Drop the rows of a group the file already holds (see ``_mark``)."""
        if self._mark is not None:
            size, n = self._mark
            if self._file.tell() > size:
                del self._rows[:n]
            self._mark = None

    def flush(self) -> None:
        self._settle()
        if self._rows:
            table = self._pa.Table.from_pylist(self._rows, schema=self.schema)
            self._mark = (self._file.tell(), len(self._rows))
            self._writer.write_table(table)
            self._settle()

    def close(self) -> None:
        if self._writer is not None:
            try:
                self.flush()
            finally:
                self._writer.close()
                self._writer = None
                self._file.close()
                os.replace(self.partial, self.path)


def open_sink(
    path: str | Path,
    columns: Sequence[str],
    text_columns: Sequence[str] = ("status", "message"),
    labels: Mapping[str, str] | None = None,
) -> Sink:
    """A sink for ``path`` by its suffix: ``.csv`` (header ``labels``, e.g. with units) or
    ``.parquet`` / ``.pq`` (the plain column names)."""
    suffix = Path(path).suffix.lower()
    if suffix == ".csv":
        return CsvSink(path, columns, labels)
    if suffix in (".parquet", ".pq"):
        return ParquetSink(path, columns, text_columns)
    raise ValueError(f"output {str(path)!r}: expected a .csv or .parquet file")


@dataclass
class SweepResult:
    """The sweep's rows as a DataFrame (``frame``), with counts."""

    frame: Any  # pandas.DataFrame
    drives: tuple[Drive, ...]
    outputs: list[str] = field(default_factory=list)
    last: Model | None = None

    @property
    def n_steps(self) -> int:
        return len(self.frame)

    @property
    def n_failed(self) -> int:
        return int((self.frame["status"] != "converged").sum()) if len(self.frame) else 0

    @property
    def ok(self) -> bool:
        return self.n_failed == 0

    def _summary(self) -> str:
        units = self.frame.attrs.get("units", {})
        drives = ", ".join(
            f"{d.label} {d.values[0]:g}..{d.values[-1]:g} {units.get('angle' if d.angle else 'length', '')}".rstrip()
            for d in self.drives
        )
        return f"{self.n_steps} steps ({self.n_failed} failed) driving {drives}; {len(self.frame.columns)} columns"

    def __repr__(self) -> str:
        """One line: steps, failures, drives and their range; the rows are ``frame``."""
        return f"<SweepResult: {self._summary()}>"

    def _repr_html_(self) -> str:
        head = self.frame.head(SUMMARY_ROWS).to_html(max_cols=12, float_format=lambda x: f"{x:.6g}")
        return f"<p><b>SweepResult</b>: {escape(self._summary())}</p>{head}"


def sweep(
    model: Model,
    drives: Sequence[Drive] | Sequence[str],
    *,
    changes: Mapping[str, object] | None = None,
    free: Sequence[str] = ("q",),
    outputs: Sequence[str] | None = None,
    tol: float = 1e-10,
    max_iter: int = 50,
    output: str | Path | Sink | None = None,
    on_step: Callable[[int, int, Mapping[str, Any]], None] | None = None,
    continuation: bool = False,
    units: str = "model",
) -> SweepResult:
    """Drive coordinates over their ranges; one row per step (see the module docstring).

    Drive values (strings and :class:`Drive` objects) and the rows are in the model's units;
    ``units`` is the unit of ``changes``: ``"model"`` (default) or ``"solver"`` (radians).

    ``drives``: :class:`Drive` objects or ``JOINT=START:STOP:STEPS`` strings. ``outputs``:
    names for :func:`kinprop.analysis.outputs.evaluate_outputs` (default
    :func:`default_outputs`). ``output``: a ``.csv`` / ``.parquet`` path or a :class:`Sink`;
    it receives each row as it is computed and is closed at the end, also on an exception
    (KeyboardInterrupt). ``on_step(k, n, row)`` is called after
    each row (progress). Step 0 goes from the model's (assembled) estimates to the start values;
    later steps run in the engine's compiled sequence. Every step follows its change on the
    last good step's branch; with ``continuation`` a failed step's message is its diagnosis
    (:func:`kinprop.propagation.continuation.diagnose`).
    """
    import pandas as pd

    # drives in the designer's terms (wheel travel, steer, roll) need no engine to parse; with one
    # the augmented model's engine is the sweep's only compile (a roll drive also compiles the model)
    texts = [d for d in drives if isinstance(d, str)]
    by_output = [d.partition("=")[0].strip() for d in texts if is_drive(d.partition("=")[0].strip())]
    by_output += [d.joint for d in drives if not isinstance(d, str) and is_drive(d.joint)]
    user, drv = model, None
    if by_output:  # joints of their own, solved with the mechanism
        drv = augment(model, by_output)
        engine = drv.engine
    else:
        engine = compile_engine(model)
    dr = tuple(parse_drive(model, d, engine) if isinstance(d, str) else d for d in drives)
    if not dr:
        raise AddressError("a sweep needs at least one --drive")
    hidden: frozenset[str] = frozenset()
    user_engine = engine
    if drv is not None:
        released = {r.split(".")[0] for d in by_output for r in drv.released[d]}
        both = [d.joint for d in dr if d.joint in released]
        if both:
            raise AddressError(f"--drive: {both[0]} moves the wheel that {by_output[0]} drives; drive one of them")
        model, free, hidden = drv.model, drv.free(free, by_output), drv.joints
        # outputs: on the model's own engine when the drive needed it (roll), else on the augmented
        # engine with its drive joints following (the model's motions and statics unchanged)
        if drv.base_engine is None:
            user = drv.follower()
        else:
            user_engine = drv.base_engine
        dr = tuple(e for d in dr for e in (_drive_joints(drv, d) if is_drive(d.joint) else [d]))
    on_base = drv is not None and drv.base_engine is not None  # outputs from drv.base_of per step
    n = {d.values.size for d in dr}
    if len(n) != 1:
        raise AddressError(f"--drive: all drives move together and need the same number of values, found {sorted(n)}")
    n_steps = n.pop()
    seen = [d.address for d in dr]
    if len(set(seen)) != len(seen):
        raise AddressError("--drive: a coordinate is driven twice")
    if any(c.startswith(tuple(f"{d.joint}.q" for d in dr)) for c in (changes or {})):
        raise AddressError("--set: a driven coordinate cannot also be set")
    names = list(default_outputs(model) if outputs is None else outputs)
    changes = changes_to_internal(model, changes or {}, engine) if check_units(units) else dict(changes or {})
    # outputs are evaluated on the user's model (without drive joints) at each step's state
    base, base_engine = (drv.base, drv.base_engine) if drv is not None else (user, user_engine)
    driven = expand_driven(base, [n for n in names if is_driven(n)], base_engine)
    names = [n for n in names if not is_driven(n)]
    at = DrivenOutputs(base, driven, free=free, tol=tol, max_iter=max_iter, engine=base_engine) if driven else None
    fout, expanded = output_function(user, names, engine=user_engine)
    coord_cols = [c for c in coordinate_columns(model, engine) if c[1] not in hidden]
    drive_cols = [d.label for d in dr]
    # unit factors, once (kinprop.engine.units' conversions are linear): model -> solver for the drives,
    # solver -> model for the coordinate columns
    to_solver = [float(to_solver_units(model, d.address, [1.0], engine)[0]) for d in dr]
    to_model = {col: float(from_solver_units(model, col, [1.0], engine)[0]) for col, *_ in coord_cols}
    # an output naming a coordinate is already a column (in model units, not radians)
    taken = {c for c, *_ in coord_cols} | set(drive_cols)
    keep = [i for i, e in enumerate(expanded) if e not in taken]
    expanded = [expanded[i] for i in keep]
    out_scale = np.array([derivative_scale(model, e, engine) for e in expanded])  # metric angles: the angle unit
    driven_scale = {n: derivative_scale(model, n, engine) for n in driven}
    columns = list(dict.fromkeys(["step", *drive_cols, *META[1:], *(c for c, *_ in coord_cols), *expanded, *driven,
                                  "message"]))  # fmt: skip
    rows: list[dict[str, Any]] = []
    sink = (
        open_sink(output, columns, labels=header_labels(model, columns, engine))
        if isinstance(output, (str, Path))
        else output
    )
    free_set = free_addresses(engine, free)
    drive_values = np.column_stack([d.values * (f if d.angle else 1.0) for d, f in zip(dr, to_solver, strict=True)])

    program = fout.program  # type: ignore[attr-defined]
    qcol = {col: engine.layout[f"{joint}.q"].start + idx for col, joint, idx, _ in coord_cols}
    last: list[State] = []  # the last converged step's state (its model is built once, at the end)

    def outputs_of(states: State, ok: Array) -> Array | None:
        """Every step's outputs in one compiled call (None: one of them fails at some step)."""
        try:
            return None if on_base else program_batch(program, user if drv is not None else model, states, ok)
        except Exception:  # one output that cannot be evaluated there: never blank the others
            return None

    def emit(k: int, status: Status, iterations: int, residual: float, message: str, state: State | None,
             values: Array | None) -> None:  # fmt: skip
        row: dict[str, Any] = dict.fromkeys(columns, float("nan"))
        row.update({"step": k, **{d.label: float(d.values[k]) for d in dr}})
        converged = status is Status.CONVERGED and state is not None
        ratio = float("nan")
        if converged:
            _, J = engine.evaluate(state)
            ratio = conditioning(engine.row_blocks, J[:, cols]) if cols.size else float("nan")
        row.update(
            {
                "status": status.value,
                "iterations": int(iterations),
                "residual": float(residual),
                "sv_ratio": ratio,
                "near_singular": bool(converged and ratio < SINGULAR_RTOL),
                "message": message,
            }
        )
        if converged:
            last[:] = [state]
            for col, _, _, deg in coord_cols:
                if col in drive_cols:
                    continue  # the driven value exactly as given (not degrees -> radians -> degrees)
                val = float(state.Q[qcol[col]])
                row[col] = val * to_model[col] if deg else val
            # with a drive joint: the outputs of the user's model (no drive joints) at this state
            view = drv.base_of(engine, state) if on_base else engine.model_of(state, user if drv else model)
            if values is not None:
                row.update(zip(expanded, (float(values[i]) * s for i, s in zip(keep, out_scale, strict=True)),
                               strict=True))  # fmt: skip
            else:
                try:
                    got = fout(view)
                    row.update(zip(expanded, (float(got[i]) * s for i, s in zip(keep, out_scale, strict=True)),
                                   strict=True))  # fmt: skip
                except Exception:  # one output that cannot be evaluated here: never blank the others
                    row.update(_each_output(view, names, expanded, out_scale, user_engine, message))
            if at is not None:  # outputs at a drive position: from this step, one engine solve each
                own = drv.base_of(engine, state) if drv is not None else view
                row.update({n: float(v[0]) * driven_scale[n] for n, v in at.values([own]).items()})
        rows.append(row)
        if sink is not None:
            sink.write(row)
        if on_step is not None:
            on_step(k, n_steps, row)

    try:
        # step 0: from the model's state (assembled first when it is not) to the start values
        first = dict(changes or {}) | {d.address: float(v) for d, v in zip(dr, drive_values[0], strict=True)}
        sol = solve_changes(engine, model, first, free, tol=tol, max_iter=max_iter, units="solver")
        cols = sol.free if sol.free.size else engine.free_columns(free_set, [d.address for d in dr])
        note = _diagnosis(model, sol, free) if continuation and not sol.converged else "; ".join(sol.notes)
        one = State(*(getattr(sol.state, a)[None] for a in "QSCL"))
        values0 = outputs_of(one, np.ones(1, bool)) if sol.converged else None
        emit(0, sol.status, sol.iterations, sol.residual, note or sol.message, sol.state if sol.converged else None,
             None if values0 is None else values0[0])  # fmt: skip
        start = sol.state if sol.converged else engine.state_of(model)
        addresses = [d.address for d in dr]
        # later steps: the engine's compiled sequence, each from the last good step on its branch,
        # in chunks so that finished rows reach the sink (and survive an interrupt)
        for k0 in range(1, n_steps, SEQUENCE_CHUNK):
            k1 = min(n_steps, k0 + SEQUENCE_CHUNK)
            _, seq = engine.solve_sequence(start, addresses, drive_values[k0:k1], cols, tol=tol, max_iter=max_iter)
            values = outputs_of(seq.state, seq.converged)
            for i in range(k1 - k0):
                st = seq.state[i]
                status = seq.status(i)
                if status is Status.CONVERGED:
                    start = st.copy()
                    note = "; ".join(seq.notes(i))
                elif continuation:  # the failed step once more from the last good one, to diagnose it
                    step = {a: float(v) for a, v in zip(addresses, drive_values[k0 + i], strict=True)}
                    failed = engine.propagate(step, cols, start=start, tol=tol, max_iter=max_iter)
                    note = _diagnosis(model, failed, free) if not failed.converged else ""
                else:
                    note = ""
                emit(k0 + i, status, seq.iterations[i], seq.residual[i], note or seq.message(i),
                     st if status is Status.CONVERGED else None, None if values is None else values[i])  # fmt: skip
    finally:
        if sink is not None:
            sink.close()
    frame = pd.DataFrame(rows, columns=columns)
    frame.attrs["units"] = dict(model.units)
    frame.attrs["drives"] = drive_cols
    frame.attrs["angle_columns"] = [c for c, _, _, deg in coord_cols if deg]
    #: the unit of every quantity column (docs/units.md), as the CSV header states it
    frame.attrs["column_units"] = {
        c: u for c in columns if c not in (*META, "message") and (u := unit_of(model, c, engine))
    }
    good = user
    if last:
        good = engine.model_of(last[0], model) if drv is None else drv.base_of(engine, last[0])
    return SweepResult(frame, dr, expanded + driven, good)


def _drive_joints(drv, d: Drive) -> list[Drive]:
    """A drive of :mod:`kinprop.analysis.drives` as the coordinates of its joints (``travel`` of
    an axle: one per wheel, labelled ``travel:WHEEL``)."""
    addrs = drv.addresses[d.joint]
    if len(addrs) == 1:
        return [Drive(addrs[0].split(".")[0], 0, d.values, d.angle, 1, d.name)]
    wheels = [a.split(".")[0].removesuffix("_travel") for a in addrs]
    return [Drive(a.split(".")[0], 0, d.values, d.angle, 1, f"travel:{w}") for a, w in zip(addrs, wheels, strict=True)]


def _diagnosis(model: Model, sol: Solution, free: Sequence[str]) -> str:
    """``continuation: ...``: the diagnosis of a failed step (no further solve:
    :func:`kinprop.propagation.continuation.diagnose`)."""
    return f"continuation: {continuation_of(model, sol, free).message}"


def plot_sweep(
    result: SweepResult, path: str | Path | None = None, columns: Sequence[str] | None = None, title: str | None = None
) -> Figure:
    """Plot the swept coordinates and outputs against the first drive (matplotlib, lazy); returns
    the :class:`matplotlib.figure.Figure` (a notebook shows it), saved to ``path`` when given.

    One panel for the coordinates that move, one per output group (points, metrics, other),
    stacked; failed steps are marked with red crosses on the x axis. Built without pyplot:
    no backend is switched and no figure is left open.
    """
    from matplotlib.figure import Figure

    df = result.frame
    x = result.drives[0].label
    drive_cols = {d.label for d in result.drives}
    skip = set(META) | drive_cols | {"message"}
    cand = [c for c in (columns or df.columns) if c not in skip]
    moving = [c for c in cand if df[c].notna().any() and float(np.nanmax(df[c]) - np.nanmin(df[c])) > 1e-12]
    groups: dict[str, list[str]] = {}
    for c in moving:
        g = (
            "points"
            if c.startswith(("point:", "hardpoint:"))
            else "metrics"
            if c.startswith("metric:")
            else "coordinates"
            if ".q" in c
            else "outputs"
        )
        groups.setdefault(g, []).append(c)
    if not groups:
        groups = {"coordinates": []}
    unit = result.frame.attrs.get("units", {})
    fig = Figure(figsize=(7.5, 2.8 * len(groups) + 0.6))
    axes = fig.subplots(len(groups), 1, sharex=True, squeeze=False)
    failed = df["status"] != "converged"
    for ax, (g, cols) in zip(axes[:, 0], groups.items(), strict=True):
        for c in cols:
            ax.plot(df[x], df[c], label=c, lw=1.4)
        if failed.any():
            y0 = ax.get_ylim()[0]
            ax.plot(df.loc[failed, x], np.full(int(failed.sum()), y0), "x", color="red", label="failed step")
        angles = set(df.attrs.get("angle_columns", ()))
        n_ang = sum(c in angles for c in cols)
        coord_unit = unit.get("angle", "") if n_ang == len(cols) else unit.get("length", "") if n_ang == 0 else "mixed"
        ylabel = {
            "coordinates": f"coordinate [{coord_unit}]",
            "points": f"position [{unit.get('length', '')}]",
        }
        ax.set_ylabel(ylabel.get(g, g))
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="best", ncol=2)
    axes[-1, 0].set_xlabel(f"{x} [{unit.get('angle', '') if result.drives[0].angle else unit.get('length', '')}]")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    if path is not None:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=110)
    return fig


__all__ = ["CsvSink", "Drive", "ParquetSink", "SweepResult", "open_sink", "parse_drive", "plot_sweep", "sweep"]
