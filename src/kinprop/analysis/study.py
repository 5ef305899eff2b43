"""Design studies: a design of experiments of propagations, local or on a Dask cluster.

A study varies scalar design variables (``RS.s_i[2]``, ``coupler.length``, ``crank.q``) over
ranges — a full grid, a Latin hypercube (``scipy.stats.qmc``) or plain Monte Carlo — or over
a given plan, and re-assembles every variant from the model's state with the varied
variables (and ``sets``) overwritten and never free, like :func:`kinprop.propagate`.

Per variant it records the inputs, ``converged``, ``status``, ``iterations``, ``residual``,
every coordinate (layout labels ``J01.q``, ``J32.q[1]``), every named point
(``point:BODY.NAME[x]``) and the outputs of :func:`kinprop.analysis.outputs.evaluate_outputs`
(by default the suspension metrics of wheel bodies, if any).

Variants run in chunks. Locally the compiled engine (:meth:`kinprop.Engine.solve_batch`) solves a
chunk in one call (the numpy reference when the mechanism cannot be compiled); with a
``scheduler`` address the chunks go to a Dask distributed cluster. Finished chunks are
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
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from kinprop.analysis.drives import DrivenOutputs, expand_driven, is_driven
from kinprop.analysis.metrics import metric_names
from kinprop.analysis.outputs import evaluate_outputs
from kinprop.analysis.units import derivative_scale
from kinprop.engine import Engine, Status
from kinprop.engine import compile as compile_engine
from kinprop.engine.units import changes_to_internal, check_units
from kinprop.errors import AddressError
from kinprop.kinematics.layout import column_labels
from kinprop.model import Design, Model
from kinprop.model.design import as_coordinates, parse_address
from kinprop.propagation.propagate import apply_changes
from kinprop.spatial import Array

if TYPE_CHECKING:  # pandas (the data extra) is imported where a frame is built
    import pandas as pd

METHODS = ("grid", "lhs", "mc")
MANIFEST = "_study.json"
#: the most variants one study may plan (a grid grows as samples**factors): 10^7 rows of results
#: are already gigabytes; a larger plan is refused up front with its count
MAX_VARIANTS = 10_000_000


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
    chunk_size: int = 256
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


# --- model transport (Design holds read-only mapping proxies, which do not pickle) ---------------


def _model_payload(model: Model) -> dict[str, Any]:
    return {
        "mechanism": model.mechanism,
        "design": {k: np.array(v) for k, v in model.design.items()},
        "coordinates": {k: np.array(v) for k, v in model.coordinates.items()},
        "units": dict(model.units),
        "elements": model.elements,
        "vehicle": model.vehicle,
    }


def _model_from_payload(p: Mapping[str, Any]) -> Model:
    return Model(p["mechanism"], Design(p["design"]), as_coordinates(p["coordinates"]), p["units"],
                 elements=p.get("elements", ()), vehicle=p.get("vehicle"))  # fmt: skip


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


def _point_specs(model: Model) -> list[tuple[int, Array, str]]:
    idx = {b.name: k for k, b in enumerate(model.mechanism.bodies)}
    return [
        (idx[b.name], np.array(p, dtype=float), f"point:{b.name}.{name}")
        for b in model.mechanism.bodies
        for name, p in b.points
    ]


def _default_outputs(model: Model) -> list[str]:
    try:
        return list(metric_names(model))
    except Exception:  # a model without wheel bodies
        return []


def _outputs_for(engine: Engine, model: Model, names: list[str]) -> dict[str, float]:
    if not names:
        return {}
    return evaluate_outputs(model, names, units="solver", engine=engine)


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


def evaluate_payload(payload: Mapping[str, Any], spec: StudySpec, values: Array, start: int) -> pd.DataFrame:
    """:func:`evaluate_chunk` on a Dask worker: the model travels as a payload and is compiled
    there (once per chunk: a worker holds no engine of ours)."""
    return evaluate_chunk(compile_engine(_model_from_payload(payload)), spec, values, start)


def evaluate_chunk(eng: Engine, spec: StudySpec, values: Array, start: int) -> pd.DataFrame:
    """Rows of variants ``start .. start + len(values) - 1`` with the study's engine (compiled
    once from the base model: ``eng.model``)."""
    model = eng.model
    labels = column_labels(eng.layout)
    qcols = [v for v in eng.layout.variables if v.group == "q"]
    nq = sum(v.size for v in qcols)
    n = values.shape[0]
    points = _point_specs(model)
    point_cols = {f"{name}[{ax}]" for _, _, name in points for ax in "xyz"}
    out_names = spec.outputs if spec.outputs is not None else _default_outputs(model)
    if out_names:
        out_names = [x for x in expand_driven(model, out_names, eng) if x not in point_cols]
    driven = [x for x in out_names if is_driven(x)]  # outputs at a drive position: solved below
    out_names = [x for x in out_names if not is_driven(x)]
    rows: dict[str, Any] = {"variant": np.arange(start, start + n, dtype=np.int64)}
    for k, a in enumerate(spec.addresses):
        rows[a] = values[:, k]
    # the plan is in the stored units (e.g. degrees); the solver takes solver units (radians)
    solver_values = values / np.array([spec.scale.get(a, 1.0) for a in spec.addresses])[None, :]
    base = eng.reference
    if spec.sets:
        base, _, _ = eng.apply(base, spec.sets)
    st = eng.stack([base] * n) if n else base
    ok = np.ones(n, dtype=bool)
    # an orientation varied as all nine components (a pivot's joint frame) is set as one matrix
    whole_c = _whole_rotations(eng, spec.addresses)
    in_c = {k for cols in whole_c.values() for k in cols}
    for i in range(n):
        try:
            for k, a in enumerate(spec.addresses):
                if k not in in_c:
                    eng.set(st[i], a, solver_values[i, k])
            for key, cols in whole_c.items():
                eng.set(st[i], key, solver_values[i, cols].reshape(3, 3))
        except AddressError:
            ok[i] = False
    changed = {parse_address(a).key for a in spec.addresses} | {parse_address(a).key for a in spec.sets}
    res = eng.solve_batch(st, tuple(spec.free), exclude=changed, tol=spec.tol, max_iter=spec.max_iter)
    conv = res.converged & ok
    iters, resid = res.iterations.copy(), res.residual.copy()
    status = np.array([res.status(i).value if o else Status.INVALID.value for i, o in enumerate(ok)], dtype=object)
    Q = res.state.Q.copy()
    P = np.full((n, len(points), 3), np.nan)
    states: list[tuple[Design, Mapping[str, Array]] | None] = [None] * n
    outs: dict[str, Array] = {}
    for i in np.flatnonzero(conv):
        r, A, _, _ = eng.poses(res.state[i])
        for k, (b, p, _) in enumerate(points):
            P[i, k] = r[b] + A[b] @ p
        if out_names:
            states[i] = eng.unpack(res.state[i])
    Q[~conv] = np.nan
    P[~conv] = np.nan
    for i in range(n):
        if out_names and states[i] is not None and conv[i]:
            vals = _outputs_for(eng, model.with_state(*states[i]), out_names)
            for key, v in vals.items():
                outs.setdefault(key, np.full(n, np.nan))[i] = v
    if driven:  # every converged variant at each drive position: one batched engine solve each
        done = np.flatnonzero(conv)
        at = DrivenOutputs(model, driven, free=spec.free, tol=spec.tol, max_iter=spec.max_iter, engine=eng)
        vals = at.values([model.with_state(*eng.unpack(res.state[i])) for i in done]) if done.size else {}
        for key in driven:
            outs[key] = np.full(n, np.nan)
            if done.size:
                outs[key][done] = vals[key]
    rows["converged"] = conv
    rows["status"] = status.astype(str)
    rows["iterations"] = iters
    rows["residual"] = resid
    for c in range(nq):
        if labels[c] not in rows:
            rows[labels[c]] = Q[:, c] * spec.scale.get(labels[c], 1.0)
    for k, (_, _, name) in enumerate(points):
        for x, ax in enumerate("xyz"):
            rows[f"{name}[{ax}]"] = P[:, k, x]
    for key in outs:
        rows[key] = outs[key] * spec.scale.get(key, 1.0)
    import pandas as pd

    return pd.DataFrame(rows)


# --- the study ----------------------------------------------------------------------------------


def _write_part(directory: Path, index: int, frame: pd.DataFrame) -> None:
    final = directory / f"part-{index:06d}.parquet"
    tmp = directory / f".part-{index:06d}.parquet.tmp"
    frame.to_parquet(tmp, index=False)
    os.replace(tmp, final)


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
    chunk_size: int = 256,
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
) -> pd.DataFrame:
    """Run a design study and return one row per variant (see the module docstring).

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
    if chunk_size < 1:
        raise AddressError("--chunk-size must be >= 1")
    if engine not in ("auto", "fast", "reference"):
        raise AddressError(f"engine {engine!r}: expected auto, fast or reference")
    # validate every address once (component, group, existence) with the reference code path
    lay = eng0.layout
    for a in addrs:
        addr = parse_address(a)
        if addr.key in lay and lay[addr.key].group == "C" and addr.key not in _whole_rotations(eng0, addrs):
            raise AddressError(f"--vary {a!r}: orientations cannot be varied component by component")
        if addr.key in lay and lay[addr.key].size > 1 and addr.index is None:
            raise AddressError(f"--vary {a!r}: give a component, e.g. {a}[0]")
    base, _, _ = apply_changes(model, dict(sets or {}), eng0)
    if len(values):
        whole = _whole_rotations(eng0, addrs)
        first = {a: values[0, k] for k, a in enumerate(addrs) if parse_address(a).key not in whole}
        first.update({key: values[0, cols].reshape(3, 3) for key, cols in whole.items()})
        apply_changes(base, first, eng0)
    if outputs:  # unknown output names fail here, before any directory is created
        expand_driven(base, list(outputs), eng0)
    if scale is None and model_units:
        scale = model_unit_scale(model, addrs, outputs, eng0)
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
        plan_hash=hashlib.sha256(np.ascontiguousarray(values).tobytes()).hexdigest()[:16],
        model_hash=_model_hash(model),
        engine=engine,
        scale=dict(scale or {}),
        factors=list(given[0]) if given is not None else None,
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
    client, own_client = _connect(scheduler)  # before creating anything: a bad address leaves no directory
    if directory is not None and fresh:
        directory.mkdir(parents=True, exist_ok=True)
        tmp = directory / (MANIFEST + ".tmp")
        tmp.write_text(json.dumps(asdict(spec), indent=1))
        os.replace(tmp, directory / MANIFEST)
    payload = _model_payload(base)
    eng = eng0.rebased(_model_from_payload(payload))  # the study's one engine, at its base
    todo = [c for c in range(n_chunks) if c not in done]
    frames: dict[int, pd.DataFrame] = {}

    def store(c: int, frame: pd.DataFrame) -> None:
        if given is not None:  # the factors as given, beside the variant
            rows = frame["variant"].to_numpy()
            for k, name in enumerate(given[0]):
                frame.insert(1 + k, name, np.asarray(given[1], dtype=float)[rows, k])
        if directory is not None:
            _write_part(directory, c, frame)
        else:
            frames[c] = frame
        if on_chunk is not None:
            on_chunk(c)

    def chunk(c: int) -> Array:
        return values[c * chunk_size : (c + 1) * chunk_size]

    bar = _progress(progress, len(values), sum(len(chunk(c)) for c in done))
    try:
        if client is None:
            for c in todo:
                store(c, evaluate_chunk(eng, spec, chunk(c), c * chunk_size))
                bar.advance(len(chunk(c)))
        else:
            _run_dask(client, payload, spec, todo, chunk, chunk_size, store, bar)
    finally:
        bar.close()
        if own_client:
            client.close()
    if directory is not None:
        return read_study(directory)
    if not frames:
        return _pandas().DataFrame()
    return _pandas().concat([frames[c] for c in sorted(frames)], ignore_index=True)


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
              chunk_size: int, store: Callable[[int, pd.DataFrame], None], bar: Any) -> None:  # fmt: skip
    """Submit the chunks to a Dask cluster and store each as it completes (any order)."""
    from distributed import as_completed

    data = client.scatter(payload, broadcast=True)
    futures = {client.submit(evaluate_payload, data, spec, chunk(c), c * chunk_size, pure=False): c for c in todo}
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
    "evaluate_chunk",
    "evaluate_payload",
    "parse_vary",
    "read_study",
    "run_study",
    "sample_plan",
]
