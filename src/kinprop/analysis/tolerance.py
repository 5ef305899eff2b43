"""Tolerance analysis: linearised output covariance from design-variable standard deviations.

With independent tolerances ``sigma_p`` on scalar design variables ``p`` (components such as
``RS.s_i[2]``, or a whole vector, each component with the same sigma), the first-order
output change is ``do = G dp`` with ``G = do/dx_free S + do/dp``, where
``S = dx_free/dp`` is the min-norm sensitivity matrix of
:func:`kinprop.analysis.sensitivity.design_sensitivity` (the step a propagation takes). Then
``cov(o) = G diag(sigma^2) G^T``.

Outputs are coordinates (``J32.q[1]``, ``rocker.q``: rows of ``S`` directly) or any name of
:func:`kinprop.analysis.outputs.evaluate_outputs` (named points, hardpoints, metrics): those
are differentiated along the linearised solution ``x(p + h e_k) = x + h S e_k`` by central
differences (O(h^2), h = 1e-4 sigma), which keeps them on the same first-order model.
:func:`monte_carlo` samples the same tolerances (normal) through a design study.

Units (docs/units.md): with ``units="model"`` (the default) sigmas are given and every result
(nominal, std, covariance, gain, sigma) is returned in the model's declared units (a sigma of
``LCA.q`` in degrees in a degree model; camber in the model's angle unit); ``units="solver"``:
sigmas and coordinates in radians, metric angles in degrees, as computed.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from kinprop.analysis.outputs import evaluate_outputs, expand_outputs
from kinprop.analysis.sensitivity import design_sensitivity
from kinprop.analysis.study import run_study
from kinprop.analysis.units import derivative_scale, unit_of
from kinprop.engine import Engine
from kinprop.engine import compile as compile_engine
from kinprop.engine.units import check_units, to_solver_units
from kinprop.errors import AddressError
from kinprop.kinematics.layout import column_labels
from kinprop.model import Model
from kinprop.model.design import parse_address
from kinprop.propagation.hardpoints import global_columns, is_global
from kinprop.spatial import Array


@dataclass(frozen=True)
class ToleranceResult:
    """Linearised output statistics; values in ``units`` ("model" or "solver", module docstring),
    ``output_units``/``input_units`` name each one's unit in the model's units."""

    outputs: list[str]
    nominal: Array  # (n_out,)
    std: Array  # (n_out,)
    covariance: Array  # (n_out, n_out)
    gain: Array  # (n_out, n_in): d output / d input
    inputs: list[str]  # scalar input labels (layout column labels)
    sigma: Array  # (n_in,)
    units: str = "solver"
    output_units: tuple[str, ...] = ()
    input_units: tuple[str, ...] = ()

    def __repr__(self) -> str:
        rows = [
            f"  {o}: {n + 0.0:.6g} +- {s:.4g} {u}".rstrip()
            for o, n, s, u in zip(self.outputs, self.nominal, self.std, self.output_units or [""] * len(self.outputs),
                                  strict=True)
        ][:8]  # fmt: skip
        more = [f"  ... and {len(self.outputs) - 8} more outputs"] if len(self.outputs) > 8 else []
        head = f"<ToleranceResult: {len(self.outputs)} outputs from {len(self.inputs)} tolerances; {self.units} units>"
        return "\n".join([head, *rows, *more])


def _in_model_units(eng: Engine, model: Model, res: ToleranceResult) -> ToleranceResult:
    so = np.array([derivative_scale(model, n, eng) for n in res.outputs])
    si = np.array([derivative_scale(model, n, eng) for n in res.inputs])
    return replace(
        res,
        nominal=res.nominal * so,
        std=res.std * so,
        covariance=res.covariance * np.outer(so, so),
        gain=res.gain * so[:, None] / si[None, :] if res.gain.size else res.gain,
        sigma=res.sigma * si,
        units="model",
    )


def _sigmas_to_solver(eng: Engine, model: Model, tolerances: Mapping[str, float]) -> dict[str, float]:
    """Sigmas in solver units; a global ``hardpoint:`` sigma is a length in the model's unit
    (the solver's too)."""
    return {
        a: float(s) if is_global(a.split("[")[0]) else float(np.asarray(to_solver_units(model, a, s, eng)).ravel()[0])
        for a, s in tolerances.items()
    }


def _inputs(eng: Engine, tolerances: Mapping[str, float]) -> tuple[list[int], Array]:
    layout = eng.layout
    cols: dict[int, float] = {}
    for text, sigma in tolerances.items():
        if not sigma > 0:
            raise AddressError(f"tolerance {text!r}: the standard deviation must be positive, found {sigma}")
        addr = parse_address(text)
        if addr.key in layout and layout[addr.key].group == "C":
            raise AddressError(
                f"tolerance {text!r}: orientation tolerances are not supported; give positions or lengths"
            )
        for c in layout.columns([text]):
            cols[int(c)] = float(sigma)
    order = sorted(cols)
    return order, np.array([cols[c] for c in order])


def _output_value(eng: Engine, model: Model, name: str, labels: list[str]) -> float:
    if name in labels:
        col = labels.index(name)
        for v in eng.layout.variables:
            if v.start <= col < v.start + v.size:
                return float(eng.get(eng.state_of(model), v.key)[col - v.start])
    return float(evaluate_outputs(model, [name], units="solver", engine=eng)[name])


def expand_names(model: Model, names: Sequence[str], engine: Engine | None = None) -> list[str]:
    """Scalar output names: ``J.q`` of a multi-coordinate joint becomes ``J.q[0]``, ...; others via outputs."""
    eng = engine if engine is not None else compile_engine(model.mechanism)
    labels = column_labels(eng.layout)
    out: list[str] = []
    for n in names:
        if n in labels:
            out.append(n)
        elif any(lab.startswith(n + "[") for lab in labels):
            out += [lab for lab in labels if lab.startswith(n + "[")]
        else:
            out += expand_outputs(model, [n], eng)
    return out


def _global_inputs(
    eng: Engine, model: Model, tolerances: Mapping[str, float]
) -> tuple[dict[str, float], dict[str, tuple[float, dict[str, float]]]]:
    """Split tolerances into design addresses and global hardpoint components
    (``hardpoint:J.i[z]``: label -> (sigma, coefficients over the ``s'`` column labels), exact
    at the model's assembly, :func:`kinprop.propagation.hardpoints.global_columns`). A whole
    ``hardpoint:J.i`` is its three components."""
    plain: dict[str, float] = {}
    glob: dict[str, tuple[float, dict[str, float]]] = {}
    state = eng.state_of(model)
    for a, sigma in tolerances.items():
        if not is_global(a.split("[")[0]):
            plain[a] = sigma
            continue
        if not sigma > 0:
            raise AddressError(f"tolerance {a!r}: the standard deviation must be positive, found {sigma}")
        _, combos = global_columns(eng, state, [a])
        if not combos:
            raise AddressError(f"tolerance {a!r}: only hardpoint:JOINT[.i|.j][x|y|z] global tolerances are supported")
        for label, coef in combos.items():
            glob[label] = (float(sigma), coef)
    return plain, glob


def tolerance_analysis(
    model: Model,
    tolerances: Mapping[str, float],
    outputs: Sequence[str],
    free: Sequence[str] = ("q",),
    fixed: Sequence[str] = (),
    *,
    units: str = "model",
    engine: Engine | None = None,
) -> ToleranceResult:
    """Linearised standard deviations and covariance of ``outputs`` at the model's (assembled) state.

    ``tolerances``: address -> standard deviation (design addresses, or global hardpoints
    ``hardpoint:J.i[z]``: a sigma of the joint's global position, in the length unit);
    ``free``: what absorbs the variations (as in a propagation); ``fixed``: addresses that are
    never free (e.g. set drives); ``units``: the units of sigmas and results (module docstring).
    """
    model_units = check_units(units)
    asm = engine if engine is not None else compile_engine(model)
    if model_units:
        tolerances = _sigmas_to_solver(asm, model, tolerances)
    plain, glob = _global_inputs(asm, model, tolerances)
    layout = asm.layout
    labels = column_labels(layout)
    pcols, sigma = _inputs(asm, plain)
    # the s' columns a global tolerance moves are inputs too (their gains combine into its own)
    extra = sorted({labels.index(c) for _, coef in glob.values() for c in coef} - set(pcols))
    allcols = pcols + extra
    step_sigma = np.concatenate([sigma, np.full(len(extra), max([g[0] for g in glob.values()], default=1.0))])
    wrt = [labels[c] for c in allcols]
    sens = design_sensitivity(model, wrt, free=[*free], engine=asm, units="solver")
    # design_sensitivity frees everything in `free` except the wrt keys; drop `fixed` addresses too
    fixed_cols = set(layout.columns(list(fixed)).tolist()) if fixed else set()
    if fixed_cols & set(sens.free_columns.tolist()):
        keep = [f for f in free if f not in fixed]
        excl = {parse_address(a).key for a in fixed}
        fc = layout.columns(keep, exclude=excl | {parse_address(w).key for w in wrt})
        _, J = asm.evaluate(model.design, model.coordinates)
        S = -np.linalg.pinv(J[:, fc]) @ J[:, allcols]
        free_cols = fc
    else:
        S = sens.matrix[:, [list(sens.wrt_columns).index(c) for c in allcols]]
        free_cols = sens.free_columns
    names = expand_names(model, outputs, asm)
    G = np.zeros((len(names), len(allcols)))
    nominal = np.array([_output_value(asm, model, n, labels) for n in names])
    frow = {int(c): k for k, c in enumerate(free_cols)}
    pidx = {c: k for k, c in enumerate(allcols)}
    state = asm.state_of(model)
    for i, name in enumerate(names):
        if name in labels:
            c = labels.index(name)
            if c in frow:
                G[i] = S[frow[c]]
            elif c in pidx:
                G[i, pidx[c]] = 1.0
            continue
        for k, c in enumerate(allcols):
            h = 1e-4 * step_sigma[k]
            vals = []
            for sgn in (1.0, -1.0):
                dx = np.zeros(layout.n)
                dx[free_cols] = sgn * h * S[:, k]
                dx[c] += sgn * h
                moved = asm.model_of(asm.retract(state, dx), model)
                vals.append(_output_value(asm, moved, name, labels))
            G[i, k] = (vals[0] - vals[1]) / (2 * h)
    # inputs: the plain design columns, then each global component (its gain: sum coef * gain of s')
    inputs = [labels[c] for c in pcols] + list(glob)
    gains = [G[:, : len(pcols)]] + [
        sum(coef * G[:, [pidx[labels.index(c)]]] for c, coef in g[1].items()) for g in glob.values()
    ]
    G = np.hstack(gains) if gains else G[:, :0]
    sig = np.concatenate([sigma, [g[0] for g in glob.values()]])
    cov = G @ np.diag(sig**2) @ G.T
    out_units = tuple(unit_of(model, n, asm) for n in names)
    in_units = tuple(unit_of(model, n, asm) for n in inputs)
    res = ToleranceResult(names, nominal, np.sqrt(np.diag(cov)), cov, G, inputs, sig, "solver", out_units, in_units)
    return _in_model_units(asm, model, res) if model_units else res


def monte_carlo(
    model: Model,
    tolerances: Mapping[str, float],
    outputs: Sequence[str],
    n: int = 2000,
    seed: int = 0,
    free: Sequence[str] = ("q",),
    fixed: Sequence[str] = (),
    *,
    units: str = "model",
) -> Array:
    """Sample standard deviations of ``outputs`` over ``n`` normal draws of the tolerances
    (a design study with an explicit plan; failed variants are dropped); sigmas and results in
    ``units`` as in :func:`tolerance_analysis`."""
    model_units = check_units(units)
    layout_engine = compile_engine(model)
    if model_units:
        tolerances = _sigmas_to_solver(layout_engine, model, tolerances)
    layout = layout_engine.layout
    labels = column_labels(layout)
    pcols, sigma = _inputs(layout_engine, tolerances)
    addrs = [labels[c] for c in pcols]
    nominal = [_output_value(layout_engine, model, a, labels) for a in addrs]
    rng = np.random.default_rng(seed)
    plan = np.array(nominal) + rng.normal(size=(n, len(addrs))) * sigma
    names = expand_names(model, outputs, layout_engine)
    extra = [x for x in names if x not in labels and not x.startswith("point:")]  # the study records points itself
    sets: dict[str, object] = {}
    for a in fixed:
        addr = parse_address(a)
        if addr.field == "q":
            q = np.asarray(model.coordinates[addr.joint], dtype=float)
            sets[a] = q if addr.index is None else q[addr.index]
    df = run_study(model, plan=plan, addresses=addrs, free=free, outputs=extra or [], sets=sets or None, units="solver",
                   compiled=layout_engine)  # fmt: skip
    ok = df[df["converged"]]
    std = np.array([ok[x].std(ddof=1) for x in names])
    return std * np.array([derivative_scale(model, x, layout_engine) for x in names]) if model_units else std


__all__ = ["ToleranceResult", "expand_names", "monte_carlo", "tolerance_analysis"]
