"""Design studies: a design of experiments of propagations, local or on a Dask cluster.

A study varies scalar design variables (``RS.s_i[2]``, ``coupler.length``, ``crank.q``) over
ranges — a full grid, a Latin hypercube (``scipy.stats.qmc``) or plain Monte Carlo — or over
a given plan, and re-assembles every variant from the model's state with the varied
variables (and ``sets``) overwritten and never free, like :func:`kinprop.propagate`.

Per variant it records the inputs, ``converged``, ``status``, ``iterations``, ``residual``,
every coordinate (layout labels ``J01.q``, ``J32.q[1]``), every named point
(``point:BODY.NAME[x]``) and the outputs of :func:`kinprop.analysis.outputs.evaluate_outputs`
(by default the suspension metrics of wheel bodies, if any).

Variants run in chunks (:data:`CHUNK_SIZE` locally; about four per worker on a cluster). A
chunk is one batch: the plan written into a stack of states column by column
(:meth:`kinprop.Engine.set_batch`), one :meth:`kinprop.Engine.solve_batch`, and one compiled
evaluation of every point and position-level output over the converged variants
(:func:`study_program`, :mod:`kinprop.engine.outputs`); only first-order metrics and loads
are evaluated per variant. Locally each part is written in a second thread while the next
chunk is solved; with a ``scheduler`` address the chunks go to a Dask distributed cluster,
whose workers write their parts themselves when they see the study's directory. With
``collect=False`` a study returns :class:`StudyTotals` and holds one chunk of rows at a
time. Finished chunks are
streamed to the output as one Parquet file per chunk in a directory
(``results.parquet/part-000012.parquet``), each written to a temporary name and renamed
atomically, next to a ``_study.json`` manifest. A killed study therefore never leaves a
half-written or footer-less file (a single ``ParquetWriter`` would lose every row group if
the process died before closing it), chunks can finish in any order (Dask), and ``resume``
computes only the chunks whose part is missing. ``pandas.read_parquet`` reads the directory
as one table.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from kinprop.analysis.drives import DrivenOutputs, expand_driven, is_driven
from kinprop.analysis.metrics import metric_names
from kinprop.analysis.outputs import expand_outputs, output_program, program_batch
from kinprop.analysis.program import OutputProgram
from kinprop.analysis.units import derivative_scale
from kinprop.engine import Engine, State, Status
from kinprop.engine import compile as compile_engine
from kinprop.engine.status import STATUSES
from kinprop.engine.units import changes_to_internal, check_units
from kinprop.errors import AddressError
from kinprop.kinematics.layout import column_labels
from kinprop.model import Design, Model
from kinprop.model.design import as_coordinates, parse_address
from kinprop.propagation.element_points import (
    apply_element_changes,
    element_factors,
    factor_ends,
    is_element_address,
    with_element_ends,
)
from kinprop.propagation.propagate import apply_changes
from kinprop.spatial import Array

if TYPE_CHECKING:  # pandas (the data extra) is imported where a frame is built
    import pandas as pd

METHODS = ("grid", "lhs", "mc")
MANIFEST = "_study.json"
#: the most variants one study may plan (a grid grows as samples**factors): 10^7 rows of results
#: are already gigabytes; a larger plan is refused up front with its count
MAX_VARIANTS = 10_000_000
#: variants per chunk (one batch solve, one Parquet part): large enough that a chunk's fixed
#: costs (the calls into the kernels, the frame, the part's file) are small beside its solves
CHUNK_SIZE = 4096


@dataclass(frozen=True)
class Factor:
    """A scalar design variable varied over ``[low, high]``."""

    address: str
    low: float
    high: float


def parse_vary(text: str) -> Factor:
    """``ADDRESS=LOW:HIGH`` -> :class:`Factor` (raises :class:`AddressError`)."""
    addr, sep, rng = text.partition("=")
    lo, sep2, hi = rng.partition(":")
    try:
        if not sep or not sep2:
            raise ValueError
        low, high = float(lo), float(hi)
    except ValueError:
        raise AddressError(f"--vary {text!r}: expected ADDRESS=LOW:HIGH (e.g. RS.s_i[2]=-0.40:-0.38)") from None
    if not (np.isfinite(low) and np.isfinite(high)) or high < low:
        raise AddressError(f"--vary {text!r}: need finite LOW <= HIGH")
    return Factor(addr.strip(), low, high)


def sample_plan(factors: Sequence[Factor], method: str = "lhs", samples: int = 100, seed: int | None = 0) -> Array:
    """The (N, F) matrix of factor values: ``grid`` (``samples`` levels per factor, N = samples^F),
    ``lhs`` (Latin hypercube, N = samples) or ``mc`` (uniform, N = samples)."""
    F = len(factors)
    if method not in METHODS:
        raise AddressError(f"method {method!r}: expected one of {', '.join(METHODS)}")
    if F == 0 or samples < 1:
        raise AddressError("a study needs at least one --vary factor and --samples >= 1")
    count = samples**F if method == "grid" else samples  # exact (Python int): no overflow
    if count > MAX_VARIANTS:
        plan = f"{samples}^{F} = {count:.3g}" if method == "grid" else f"{count:.3g}"
        raise AddressError(
            f"--method {method} with --samples {samples} plans {plan} variants; the limit is {MAX_VARIANTS:,}: "
            f"lower --samples" + (" (levels per factor)" if method == "grid" else "")
        )
    lo = np.array([f.low for f in factors])
    hi = np.array([f.high for f in factors])
    if method == "grid":
        levels = [
            np.linspace(a, b, samples) if samples > 1 else np.array([(a + b) / 2]) for a, b in zip(lo, hi, strict=True)
        ]
        return np.array(list(itertools.product(*levels)), dtype=float).reshape(-1, F)
    if method == "lhs":
        from scipy.stats import qmc

        u = qmc.LatinHypercube(d=F, seed=seed).random(samples)
    else:
        u = np.random.default_rng(seed).uniform(size=(samples, F))
    return lo + u * (hi - lo)


@dataclass
class StudySpec:
    """Everything that defines a study's rows (stored in the manifest, checked on resume)."""

    addresses: list[str]
    free: list[str] = field(default_factory=lambda: ["q"])
    sets: dict[str, list[float]] = field(default_factory=dict)
    outputs: list[str] | None = None
    tol: float = 1e-10
    max_iter: int = 50
    chunk_size: int = CHUNK_SIZE
    method: str = "plan"
    samples: int = 0
    seed: int | None = None
    plan_hash: str = ""
    model_hash: str = ""
    #: "auto" (compiled batched Newton when the mechanism compiles), "fast" or "reference"
    engine: str = "auto"
    #: column -> factor from solver units (radians; metric angles: degrees) to the stored units; a
    #: factor's plan values are in the stored units and divided by it before solving
    #: (:func:`model_unit_scale`: the model's units)
    scale: dict[str, float] = field(default_factory=dict)
    #: the factors as the user gave them when ``addresses`` were derived from them (global
    #: hardpoints ``hardpoint:J.i[z]`` -> the ``s'`` components they set); stored as columns too
    factors: list[str] | None = None
    #: element-point factors (``element:spring.point_i[z]``): ``{address: [element, side, d, p_c]}``
    #: (:func:`kinprop.propagation.element_points.element_factors`, at the model's assembly); they
    #: move no body, only the element-dependent outputs (motion ratios, wheel rate, loads)
    elements: dict[str, list[float]] = field(default_factory=dict)


# --- model transport (Design holds read-only mapping proxies, which do not pickle) ---------------


def _model_payload(model: Model) -> dict[str, Any]:
    return {
        "mechanism": model.mechanism,
        "design": {k: np.array(v) for k, v in model.design.items()},
        "coordinates": {k: np.array(v) for k, v in model.coordinates.items()},
        "units": dict(model.units),
        "elements": model.elements,
        "vehicle": model.vehicle,
        "loads": model.loads,
        "torsion_springs": model.torsion_springs,
    }


def _model_from_payload(p: Mapping[str, Any]) -> Model:
    return Model(p["mechanism"], Design(p["design"]), as_coordinates(p["coordinates"]), p["units"],
                 elements=p.get("elements", ()), vehicle=p.get("vehicle"), loads=p.get("loads"),
                 torsion_springs=p.get("torsion_springs", ()))  # fmt: skip


def _model_hash(model: Model) -> str:
    """A content hash of the model that is the same in every process (for ``resume``).

    Built from plain, ordered data: names, types, connectivity, the sorted design fields of
    each joint, fixed poses, named points, units, then the design and coordinate arrays by
    address. (``repr(mechanism)`` is not stable: it shows frozensets, whose order changes with
    each process's string hashing.)"""
    mech = model.mechanism
    structure = {
        "name": mech.name,
        "units": sorted(model.units.items()),
        "bodies": [
            [b.name, b.fixed, list(b.position), [list(r) for r in b.orientation], [[k, list(p)] for k, p in b.points]]
            for b in mech.bodies
        ],
        "joints": [[j.name, j.type, j.body_i, j.body_j, sorted(j.fields), j.cut] for j in mech.joints],
    }
    h = hashlib.sha256(json.dumps(structure, sort_keys=True).encode())
    for k in sorted(model.design):
        h.update(k.encode() + np.ascontiguousarray(model.design[k], dtype=float).tobytes())
    for k in sorted(model.coordinates):
        h.update(k.encode() + np.ascontiguousarray(model.coordinates[k], dtype=float).tobytes())
    return h.hexdigest()[:16]


# --- one chunk ----------------------------------------------------------------------------------


def _default_outputs(model: Model) -> list[str]:
    try:
        return list(metric_names(model))
    except Exception:  # a model without wheel bodies
        return []


def _pandas():
    import pandas

    return pandas


def model_unit_scale(
    model: Model, addresses: Sequence[str], outputs: Sequence[str] | None = None, engine: Engine | None = None
) -> dict[str, float]:
    """Column -> factor from solver units to the model's units, for the varied ``addresses``,
    every coordinate column and the metric ``outputs`` (default: the wheel metrics): ``180/pi``
    for angles of a degree model, ``pi/180`` for metric angles of a radian model; columns
    already in the model's units are left out."""
    engine = engine if engine is not None else compile_engine(model.mechanism)
    labels = column_labels(engine.layout)
    names = list(outputs) if outputs is not None else _default_outputs(model)
    qlabels = [lab for lab in labels if parse_address(lab).field == "q"]
    cols = [*addresses, *qlabels, *(expand_driven(model, names, engine) if names else [])]
    scale = {c: derivative_scale(model, c, engine) for c in dict.fromkeys(cols)}
    return {k: v for k, v in scale.items() if v != 1.0}


#: a Dask worker's engine and output program of the study it last ran chunks of (compiled once
#: per worker process, not once per chunk)
_WORKER: dict[str, tuple[Engine, OutputProgram]] = {}


def evaluate_payload(payload: Mapping[str, Any], spec: StudySpec, values: Array, start: int,
                     part: tuple[str, int] | None = None,
                     given: tuple[Sequence[str], Array] | None = None) -> pd.DataFrame | StudyTotals:  # fmt: skip
    """:func:`evaluate_chunk` on a Dask worker: the model travels as a payload; the worker compiles
    it on its first chunk of the study and keeps the engine for the next ones. Each chunk runs on
    the worker's thread alone (no numba threads): a cluster's parallelism is its workers.

    ``part``: ``(directory, index)`` of the chunk's Parquet part. When the worker sees the
    study's directory (its manifest, for this plan: a shared or the same file system) it writes
    the part itself (with ``given``: the factors as given, this chunk's rows) and returns only
    the chunk's :class:`StudyTotals`; otherwise it returns the rows."""
    key = json.dumps([spec.model_hash, spec.sets, spec.outputs], sort_keys=True)
    if key not in _WORKER:
        eng = compile_engine(_model_from_payload(payload))
        _WORKER.clear()
        _WORKER[key] = (eng, study_program(eng, spec))
    eng, program = _WORKER[key]
    frame = evaluate_chunk(eng, spec, values, start, program, threads=False)
    if part is None or not _is_study_of(Path(part[0]), spec):
        return frame
    _with_given(frame, given)
    _write_part(Path(part[0]), part[1], frame)
    totals = StudyTotals()
    totals.add(frame)
    return totals


def _is_study_of(directory: Path, spec: StudySpec) -> bool:
    try:
        return json.loads((directory / MANIFEST).read_text()).get("plan_hash") == spec.plan_hash
    except (OSError, ValueError):
        return False


def _with_given(frame: pd.DataFrame, given: tuple[Sequence[str], Array] | None) -> None:
    """Insert the factors as given (rows of the frame's variants, or the chunk's own rows)
    beside the variant column."""
    if given is None:
        return
    vals = np.asarray(given[1], dtype=float)
    if len(vals) != len(frame):
        vals = vals[frame["variant"].to_numpy()]
    for k, name in enumerate(given[0]):
        if name not in frame:  # an element point is a factor of the plan itself
            frame.insert(1 + k, name, vals[:, k])


def study_program(eng: Engine, spec: StudySpec) -> OutputProgram:
    """The study's outputs as one compiled program: every named point (``point:BODY.NAME[x]``),
    then the requested outputs (default: the wheel metrics) not already among them."""
    model = eng.model
    points = [f"point:{b.name}.{p}" for b in model.mechanism.bodies for p, _ in b.points]
    names = spec.outputs if spec.outputs is not None else _default_outputs(model)
    taken = set(expand_outputs(model, points, eng)) if points else set()
    names = [x for x in names if not is_driven(x)]  # outputs at a drive position: solved apart (evaluate_chunk)
    extra = [x for x in expand_outputs(model, names, eng) if x not in taken] if names else []
    return output_program(model, [*points, *extra], engine=eng)


def evaluate_chunk(eng: Engine, spec: StudySpec, values: Array, start: int, program: OutputProgram | None = None,
                   threads: bool | None = None) -> pd.DataFrame:  # fmt: skip
    """Rows of variants ``start .. start + len(values) - 1`` with the study's engine (compiled
    once from the base model: ``eng.model``) and its outputs (:func:`study_program`, built here
    when not given): the plan written into one batch of states, one :meth:`Engine.solve_batch`,
    one compiled evaluation of the outputs over the converged variants; ``threads`` as in
    :meth:`Engine.solve_batch`."""
    model = eng.model
    program = program if program is not None else study_program(eng, spec)
    labels = column_labels(eng.layout)
    nq = sum(v.size for v in eng.layout.variables if v.group == "q")
    n = values.shape[0]
    rows: dict[str, Any] = {"variant": np.arange(start, start + n, dtype=np.int64)}
    for k, a in enumerate(spec.addresses):
        rows[a] = values[:, k]
    # the plan is in the stored units (e.g. degrees); the solver takes solver units (radians)
    solver_values = values / np.array([spec.scale.get(a, 1.0) for a in spec.addresses])[None, :]
    base = eng.reference
    if spec.sets:
        base, _, _ = eng.apply(base, spec.sets)
    st = State(*(np.repeat(getattr(base, a)[None], n, axis=0) for a in "QSCL"))
    ok = np.ones(n, dtype=bool)
    # an orientation varied as all nine components (a pivot's joint frame) is set as one matrix
    whole_c = _whole_rotations(eng, spec.addresses)
    in_c = {k for cols in whole_c.values() for k in cols}
    for k, a in enumerate(spec.addresses):
        if k not in in_c and a not in spec.elements:
            ok &= eng.set_batch(st, a, solver_values[:, k])
    for key, cols in whole_c.items():
        for i in np.flatnonzero(ok):
            try:
                eng.set(st[i], key, solver_values[i, cols].reshape(3, 3))
            except AddressError:
                ok[i] = False
    changed = {parse_address(a).key for a in spec.addresses if a not in spec.elements}
    changed |= {parse_address(a).key for a in spec.sets}
    res = eng.solve_batch(st, tuple(spec.free), exclude=changed, tol=spec.tol, max_iter=spec.max_iter,
                          threads=threads)  # fmt: skip
    conv = res.converged & ok
    status = np.array([s.value for s in STATUSES], dtype=object)[res.status_code]
    status[~ok] = Status.INVALID.value
    Q = res.state.Q.copy()
    Q[~conv] = np.nan
    rows["converged"] = conv
    rows["status"] = status
    rows["iterations"] = res.iterations.copy()
    rows["residual"] = res.residual.copy()
    for c in range(nq):
        if labels[c] not in rows:
            rows[labels[c]] = Q[:, c] * spec.scale.get(labels[c], 1.0)
    # element points: each variant's own element ends (no body moves; the solve ignores them)
    ends = factor_ends(model, spec.elements, spec.addresses, solver_values) if spec.elements else None
    outs = program_batch(program, model, res.state, conv, ends=ends)
    for k, key in enumerate(program.names):
        rows[key] = outs[:, k] * spec.scale.get(key, 1.0)
    driven = [x for x in expand_driven(model, spec.outputs or [], eng) if is_driven(x)]
    if driven:  # every converged variant at each drive position: one batched engine solve each
        done = np.flatnonzero(conv)
        at = DrivenOutputs(model, driven, free=spec.free, tol=spec.tol, max_iter=spec.max_iter, engine=eng)
        variants = [model.with_state(*eng.unpack(res.state[i])) for i in done]
        if ends is not None:
            variants = [with_element_ends(m, ends[i]) for m, i in zip(variants, done, strict=True)]
        vals = at.values(variants) if done.size else {}
        for key in driven:
            rows[key] = np.full(n, np.nan)
            if done.size:
                rows[key][done] = vals[key] * spec.scale.get(key, 1.0)
    import pandas as pd

    return pd.DataFrame(rows)


# --- the study ----------------------------------------------------------------------------------


def _write_part(directory: Path, index: int, frame: pd.DataFrame) -> None:
    """One chunk's Parquet part, written under a temporary name and renamed (atomic). Dictionary
    encoding only for the status column: the numeric columns rarely repeat, and trying it on
    them took 60 % of the write (3.9 -> 1.6 us per variant)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    final = directory / f"part-{index:06d}.parquet"
    tmp = directory / f".part-{index:06d}.parquet.tmp"
    pq.write_table(pa.Table.from_pandas(frame, preserve_index=False), tmp, use_dictionary=["status"])
    os.replace(tmp, final)


@dataclass
class StudyTotals:
    """What :func:`run_study` with ``collect=False`` returns instead of the rows: the number of
    variants and of failed ones, and per numeric column the count, minimum, sum and maximum
    over the converged variants (accumulated chunk by chunk: memory does not grow with the study)."""

    variants: int = 0
    failed: int = 0
    columns: dict[str, list[float]] = field(default_factory=dict)

    def add(self, frame: pd.DataFrame) -> None:
        ok = frame["converged"].to_numpy(dtype=bool)
        self.variants += len(frame)
        self.failed += int((~ok).sum())
        for c in frame.columns:
            if c in ("variant", "converged", "status") or frame[c].dtype.kind not in "fiu":
                continue
            x = frame[c].to_numpy(dtype=float)[ok]
            x = x[np.isfinite(x)]
            t = self.columns.setdefault(c, [0, math.inf, 0.0, -math.inf])
            if x.size:
                t[0] += x.size
                t[1], t[2], t[3] = min(t[1], float(x.min())), t[2] + float(x.sum()), max(t[3], float(x.max()))

    def merge(self, other: StudyTotals) -> None:
        """Add another chunk's totals."""
        self.variants += other.variants
        self.failed += other.failed
        for c, (n, lo, total, hi) in other.columns.items():
            t = self.columns.setdefault(c, [0, math.inf, 0.0, -math.inf])
            t[0], t[1], t[2], t[3] = t[0] + n, min(t[1], lo), t[2] + total, max(t[3], hi)

    def summary(self, column: str) -> tuple[float, float, float] | None:
        """``(min, mean, max)`` of a column over the converged variants (None: no values)."""
        t = self.columns.get(column)
        return None if t is None or not t[0] else (t[1], t[2] / t[0], t[3])


def _done_chunks(directory: Path) -> set[int]:
    return {int(p.stem.split("-")[1]) for p in directory.glob("part-*.parquet")}


def read_study(path: str | Path) -> pd.DataFrame:
    """All finished rows of a study directory, ordered by variant."""
    parts = sorted(Path(path).glob("part-*.parquet"))
    if not parts:
        return _pandas().DataFrame()
    pd = _pandas()
    return pd.concat([pd.read_parquet(p) for p in parts], ignore_index=True).sort_values("variant", ignore_index=True)


def _whole_rotations(eng: Engine, addresses: Sequence[str]) -> dict[str, list[int]]:
    """``{J.C_i: plan columns of its components 0..8}`` for orientations whose nine components
    are all in ``addresses`` (a global pivot factor's plan, :func:`kinprop.propagation.hardpoints.global_plan`)."""
    found: dict[str, dict[int, int]] = {}
    for k, a in enumerate(addresses):
        if is_element_address(a):
            continue
        addr = parse_address(a)
        if addr.index is not None and addr.key in eng.layout and eng.layout[addr.key].group == "C":
            found.setdefault(addr.key, {})[addr.index] = k
    return {key: [cols[c] for c in range(9)] for key, cols in found.items() if set(cols) == set(range(9))}


def run_study(
    model: Model,
    factors: Sequence[Factor] | None = None,
    *,
    method: str = "lhs",
    samples: int = 100,
    seed: int | None = 0,
    plan: Array | None = None,
    addresses: Sequence[str] | None = None,
    free: Sequence[str] = ("q",),
    sets: Mapping[str, object] | None = None,
    outputs: Sequence[str] | None = None,
    tol: float = 1e-10,
    max_iter: int = 50,
    chunk_size: int | None = None,
    output: str | Path | None = None,
    resume: bool = False,
    scheduler: str | None = None,
    progress: bool = False,
    on_chunk: Callable[[int], None] | None = None,
    engine: str = "auto",
    scale: Mapping[str, float] | None = None,
    units: str = "model",
    compiled: Engine | None = None,
    given: tuple[Sequence[str], Array] | None = None,
    collect: bool = True,
) -> pd.DataFrame | StudyTotals:
    """Run a design study and return one row per variant (see the module docstring); with
    ``collect=False`` (and an ``output`` directory) return only the :class:`StudyTotals`,
    holding no more than one chunk of rows at a time.

    Either ``factors`` (sampled by ``method``/``samples``/``seed``) or an explicit ``plan``
    (N, F) with its ``addresses``. ``sets`` are changes applied to every variant. With
    ``output`` the chunks are streamed to that directory; ``resume`` keeps the finished ones
    (the manifest must match). ``scheduler``: a Dask scheduler address (``tcp://host:8786``)
    or a ``distributed.Client``. ``on_chunk(index)`` is called after each chunk is stored.
    ``engine``: ``"auto"`` (compiled when possible), ``"fast"`` or ``"reference"`` (numpy).
    ``units="model"`` (the default): the plan, ``factors`` and ``sets`` are in the model's units
    and every stored input, coordinate and metric is too (:func:`model_unit_scale`);
    ``units="solver"``: ``sets`` and the plan in solver units, rows as computed (radians, metric
    angles in degrees). ``scale`` (column -> factor from solver units to the stored units)
    overrides the default of ``units``. ``compiled``: the engine of ``model``'s mechanism, when
    the caller has one (else the study compiles once). ``given``: with a ``plan`` derived from factors
    sampled by ``method``/``samples``/``seed`` (global hardpoints), those factors' addresses
    and values (N, k): stored beside the plan's columns in every part, and in the manifest
    with the method and seed that sampled them.
    Raises :class:`AddressError` / :class:`ValueError` for invalid input.
    """
    model_units = check_units(units)
    eng0 = compiled.rebased(model) if compiled is not None else compile_engine(model)
    if sets and any(is_element_address(a) for a in sets):  # the model's element points, no body moves
        model, sets = apply_element_changes(model, eng0, eng0.state_of(model), sets)
        eng0 = eng0.rebased(model)
    if model_units:
        sets = changes_to_internal(model, sets or {}, eng0)
    if plan is None:
        factors = list(factors or [])
        values = sample_plan(factors, method, samples, seed)
        addrs = [f.address for f in factors]
    else:
        values = np.atleast_2d(np.asarray(plan, dtype=float))
        addrs = list(addresses or [])
        if values.shape[1] != len(addrs):
            raise AddressError(f"plan has {values.shape[1]} columns for {len(addrs)} addresses")
        if given is None:
            method, samples, seed = "plan", values.shape[0], None
    if chunk_size is not None and chunk_size < 1:
        raise AddressError("--chunk-size must be >= 1")
    if engine not in ("auto", "fast", "reference"):
        raise AddressError(f"engine {engine!r}: expected auto, fast or reference")
    # validate every address once (component, group, existence) with the reference code path
    lay = eng0.layout
    try:
        elements = element_factors(model, eng0, eng0.state_of(model), [a for a in addrs if is_element_address(a)])
    except AddressError as exc:
        raise AddressError(f"--vary {exc}") from None
    addrs = [a.strip() if is_element_address(a) else a for a in addrs]
    for a in addrs:
        if a in elements:
            continue
        addr = parse_address(a)
        if addr.key in lay and lay[addr.key].group == "C" and addr.key not in _whole_rotations(eng0, addrs):
            raise AddressError(f"--vary {a!r}: orientations cannot be varied component by component")
        if addr.key in lay and lay[addr.key].size > 1 and addr.index is None:
            raise AddressError(f"--vary {a!r}: give a component, e.g. {a}[0]")
    base, _, _ = apply_changes(model, dict(sets or {}), eng0)
    if len(values):
        whole = _whole_rotations(eng0, addrs)
        first = {a: values[0, k] for k, a in enumerate(addrs)
                 if a not in elements and parse_address(a).key not in whole}  # fmt: skip
        first.update({key: values[0, cols].reshape(3, 3) for key, cols in whole.items()})
        apply_changes(base, first, eng0)
    if outputs:  # unknown output names fail here, before any directory is created
        expand_driven(base, list(outputs), eng0)
    if scale is None and model_units:
        scale = model_unit_scale(model, addrs, outputs, eng0)
    if not collect and output is None:
        raise AddressError("collect=False needs an output directory")
    client, own_client = _connect(scheduler)  # before creating anything: a bad address leaves no directory
    try:
        if chunk_size is None:  # a resumed study keeps its chunks; a cluster gets a few per worker
            chunk_size = _chunk_size(len(values), client, Path(output) if output is not None and resume else None)
        spec = StudySpec(
            addresses=addrs,
            free=list(free),
            sets={k: np.atleast_1d(np.asarray(v, dtype=float)).tolist() for k, v in (sets or {}).items()},
            outputs=list(outputs) if outputs is not None else None,
            tol=tol,
            max_iter=max_iter,
            chunk_size=chunk_size,
            method=method,
            samples=samples,
            seed=seed,
            plan_hash=hashlib.sha256(memoryview(np.ascontiguousarray(values))).hexdigest()[:16],  # no copy
            model_hash=_model_hash(model),
            engine=engine,
            scale=dict(scale or {}),
            factors=list(given[0]) if given is not None else None,
            elements=elements,
        )
        n_chunks = -(-len(values) // chunk_size)
        done: set[int] = set()
        directory = Path(output) if output is not None else None
        fresh = directory is not None and not (directory.exists() and any(directory.iterdir()))
        if directory is not None and not fresh:
            manifest = directory / MANIFEST
            if not resume:
                raise AddressError(f"{directory} exists: use --resume to complete it, or remove it")
            if not manifest.exists():
                raise AddressError(f"{directory} is not a study directory (no {MANIFEST})")
            old = json.loads(manifest.read_text())
            if old != asdict(spec):
                diff = sorted(k for k in old if old.get(k) != asdict(spec).get(k))
                raise AddressError(f"cannot resume {directory}: the study differs in {', '.join(diff)}")
            done = _done_chunks(directory) & set(range(n_chunks))
    except BaseException:
        if own_client:
            client.close()
        raise
    if directory is not None and fresh:
        directory.mkdir(parents=True, exist_ok=True)
        tmp = directory / (MANIFEST + ".tmp")
        tmp.write_text(json.dumps(asdict(spec), indent=1))
        os.replace(tmp, directory / MANIFEST)
    payload = _model_payload(base)
    eng = eng0.rebased(_model_from_payload(payload))  # the study's one engine, at its base
    todo = [c for c in range(n_chunks) if c not in done]
    frames: dict[int, pd.DataFrame] = {}
    totals = StudyTotals()
    if not collect:  # the chunks of an earlier run, one at a time
        for c in sorted(done):
            totals.add(_pandas().read_parquet(directory / f"part-{c:06d}.parquet"))

    def store(c: int, frame: pd.DataFrame | StudyTotals) -> None:
        if isinstance(frame, StudyTotals):  # written by a Dask worker that sees the directory
            totals.merge(frame)
            if on_chunk is not None:
                on_chunk(c)
            return
        _with_given(frame, given)
        if directory is not None:
            _write_part(directory, c, frame)
        else:
            frames[c] = frame
        if not collect:
            totals.add(frame)
        if on_chunk is not None:
            on_chunk(c)

    def chunk(c: int) -> Array:
        return values[c * chunk_size : (c + 1) * chunk_size]

    bar = _progress(progress, len(values), sum(len(chunk(c)) for c in done))
    try:
        if client is None:
            _run_local(eng, spec, todo, chunk, chunk_size, store, bar)
        else:
            _run_dask(client, payload, spec, todo, chunk, chunk_size, store, bar, directory, given)
    finally:
        bar.close()
        if own_client:
            client.close()
    if not collect:
        return totals
    if directory is not None:
        return read_study(directory)
    if not frames:
        return _pandas().DataFrame()
    return _pandas().concat([frames[c] for c in sorted(frames)], ignore_index=True)


def _run_local(eng: Engine, spec: StudySpec, todo: list[int], chunk: Callable[[int], Array], chunk_size: int,
               store: Callable[[int, pd.DataFrame], None], bar: Any) -> None:  # fmt: skip
    """The chunks in this process, each stored (written) in a second thread while the next one
    is solved: both release the GIL, so the part's encoding overlaps the next batch's solves. At
    most one chunk waits to be stored; its error (or an interrupt) stops the study."""
    from concurrent.futures import ThreadPoolExecutor

    program = study_program(eng, spec)
    with ThreadPoolExecutor(max_workers=1) as writer:
        pending = None
        try:
            for c in todo:
                frame = evaluate_chunk(eng, spec, chunk(c), c * chunk_size, program)
                if pending is not None:
                    pending.result()
                pending = writer.submit(store, c, frame)
                bar.advance(len(chunk(c)))
        finally:
            if pending is not None:
                pending.result()


def _chunk_size(n: int, client: Any, resumed: Path | None) -> int:
    """The default chunk size: a resumed study's own (its manifest); locally :data:`CHUNK_SIZE`;
    on a cluster about four chunks per worker (so that a slow worker does not hold the study
    up), between 256 and :data:`CHUNK_SIZE` variants."""
    if resumed is not None and (resumed / MANIFEST).exists():
        return int(json.loads((resumed / MANIFEST).read_text())["chunk_size"])
    if client is None:
        return CHUNK_SIZE
    workers = max(1, len(client.scheduler_info().get("workers", {})))
    return int(min(CHUNK_SIZE, max(256, -(-n // (4 * workers)))))


def _connect(scheduler: Any) -> tuple[Any, bool]:
    """``(client, owned)``: a new Client for an address (closed by us), or the given Client."""
    if scheduler is None or not isinstance(scheduler, str):
        return scheduler, False
    from distributed import Client

    try:
        return Client(scheduler, timeout="20s"), True
    except (OSError, TimeoutError) as exc:
        raise AddressError(f"--scheduler {scheduler!r}: cannot connect ({exc})") from None


def _run_dask(client: Any, payload: Any, spec: StudySpec, todo: list[int], chunk: Callable[[int], Array],
              chunk_size: int, store: Callable[[int, Any], None], bar: Any, directory: Path | None = None,
              given: tuple[Sequence[str], Array] | None = None) -> None:  # fmt: skip
    """Submit the chunks to a Dask cluster and store each as it completes (any order); workers
    that see ``directory`` write their parts themselves (:func:`evaluate_payload`)."""
    from distributed import as_completed

    data = client.scatter(payload, broadcast=True)
    futures = {}
    for c in todo:
        start = c * chunk_size
        part = (str(directory.resolve()), c) if directory is not None else None
        mine = (
            None if given is None else (list(given[0]), np.asarray(given[1], dtype=float)[start : start + chunk_size])
        )
        futures[client.submit(evaluate_payload, data, spec, chunk(c), start, part, mine, pure=False)] = c
    for fut in as_completed(futures):
        c = futures[fut]
        store(c, fut.result())
        bar.advance(len(chunk(c)))


class _Bar:
    def __init__(self, enabled: bool, total: int, completed: int) -> None:
        self.p = None
        if enabled:
            from rich.console import Console
            from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

            cols = (TextColumn("study"), BarColumn(), MofNCompleteColumn(), TimeRemainingColumn())
            self.p = Progress(*cols, console=Console(stderr=True))
            self.p.start()
            self.task = self.p.add_task("study", total=total, completed=completed)

    def advance(self, n: int) -> None:
        if self.p is not None:
            self.p.advance(self.task, n)

    def close(self) -> None:
        if self.p is not None:
            self.p.stop()


def _progress(enabled: bool, total: int, completed: int) -> _Bar:
    return _Bar(enabled, total, completed)


__all__ = [
    "Factor",
    "StudySpec",
    "StudyTotals",
    "evaluate_chunk",
    "evaluate_payload",
    "parse_vary",
    "read_study",
    "run_study",
    "sample_plan",
]
