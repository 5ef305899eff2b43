"""Continuation and singularity warnings for ``kinprop propagate`` / ``assemble``.

``--continuation`` runs :func:`kinprop.propagation.continuation.propagate_continuation`;
without the flag a plain Newton propagation runs first and continuation is the fallback when
it fails (``--no-continuation`` turns the fallback off). A change that cannot be assembled
prints the largest feasible fraction and the constraints in conflict and exits 1; no model
is written for it.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import typer
from rich.text import Text

from kinprop.cli.app import EXIT_NOT_CONVERGED, err, out, print_json
from kinprop.errors import SingularityWarning
from kinprop.io.results import coordinates_json, design_json, propagation_json
from kinprop.model import Model
from kinprop.propagation import Propagation, propagate
from kinprop.propagation.continuation import ContinuationResult, propagate_continuation


@contextmanager
def shown_warnings() -> Iterator[None]:
    """Print each distinct warning raised inside once, as a ``warning:`` line on stderr.

    The records are printed after the recording context has closed: re-emitting a warning
    while still recording appends it to the list being read (an endless loop on the first
    numpy overflow warning, issue 11 item 2)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            yield
        finally:
            records = list(caught)
    seen: set[tuple[type, str]] = set()
    for w in records:
        key = (w.category, " ".join(str(w.message).split()))
        if key in seen:
            continue
        seen.add(key)
        kind = "" if issubclass(w.category, SingularityWarning) else f"{w.category.__name__}: "
        err.print(Text.assemble(("warning:", "yellow"), f" {kind}{key[1]}"), soft_wrap=True)


def continuation_json(res: ContinuationResult) -> dict[str, Any]:
    return {
        "status": res.status,
        "fraction": res.fraction,
        "message": res.message,
        "conflict": [{"row": r, "weight": w} for r, w in res.conflict],
        "residual_rows": [{"row": r, "value": v} for r, v in res.residual_rows],
        "singularity_ratio": res.singularity_ratio,
        "sub_steps": [s.__dict__ for s in res.steps],
        "last_feasible": {"coordinates": coordinates_json(res.after), "design": design_json(res.after)},
    }


def print_continuation(res: ContinuationResult) -> None:
    """One summary line, and on failure the diagnosis: fraction and conflicting rows."""
    n_ok = sum(s.accepted for s in res.steps)
    if res.converged:
        out.print(f"continuation: {n_ok} sub-steps ({len(res.steps)} attempts)")
        return
    out.print(f"continuation: the change cannot be assembled beyond {res.fraction:.6g} of its size", style="red")
    for r, w in res.conflict:
        out.print(f"  in conflict: {r}  (weight {w:+.3f} in the left singular vector of the smallest singular value)")
    for r, v in res.residual_rows:
        out.print(f"  residual at the failed attempt: {r} = {v:.3g}")
    out.print(f"  smallest/largest singular value at the last feasible state: {res.singularity_ratio:.3g}")


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
    """Plain Newton, continuation, or Newton with continuation as the fallback (``None``).

    Returns ``(prop, res, newton_ran)``: the propagation to report, the continuation result
    when continuation ran (else None) and whether plain Newton ran first. When ``res`` did
    not converge, ``prop`` is the failed plain Newton propagation (or continuation's own).
    ``on_fallback(plain)`` is called when plain Newton failed and continuation starts.
    """
    plain: Propagation | None = None
    if continuation is not True:
        plain = propagate(model, changes, free, tol=tol, max_iter=max_iter, weights=weights, units="solver",
                          method=method)  # fmt: skip
        if plain.converged or continuation is False or not changes:
            return plain, None, True
        if on_fallback is not None:
            on_fallback(plain)
    res = propagate_continuation(
        model, changes, free, tol=tol, max_iter=min(max_iter, 20), weights=weights, units="solver"
    )
    if res.converged:
        return res.propagation, res, plain is not None
    return (plain if plain is not None else res.propagation), res, plain is not None


def propagate_json(prop: Propagation, res: ContinuationResult | None = None, newton_ran: bool = True) -> dict[str, Any]:
    """What ``kinprop propagate --json`` prints for :func:`solve_propagation`'s result: the
    propagation's JSON, and when continuation failed too, status ``not_converged`` and a
    ``continuation`` object."""
    obj = propagation_json(prop)
    if res is None or res.converged:
        return obj
    obj["status"] = "not_converged"
    if not newton_ran:
        obj["message"] = res.message
    obj["continuation"] = continuation_json(res)
    return obj


def run_propagation(
    model: Model,
    changes: Mapping[str, object],
    free: Sequence[str],
    *,
    tol: float,
    max_iter: int,
    weights: Mapping[str, float] | None,
    continuation: bool | None,
    output: Path | None,
    as_json: bool,
    method: str = "least-change",
) -> Propagation:
    """:func:`solve_propagation` for the CLI: returns the propagation to report. When
    continuation cannot assemble the change either, prints the diagnosis (with ``--json``:
    :func:`propagate_json`) and exits 1 itself, writing nothing.
    """

    def say_fallback(plain: Propagation) -> None:
        if not as_json:
            err.print(f"{plain.result.message}; diagnosing by continuation")

    with shown_warnings():
        prop, res, newton_ran = solve_propagation(
            model,
            changes,
            free,
            tol=tol,
            max_iter=max_iter,
            weights=weights,
            continuation=continuation,
            on_fallback=say_fallback,
            method=method,
        )
    if res is None:
        return prop
    if res.converged:
        if not as_json:
            print_continuation(res)
        return prop
    if as_json:
        print_json(propagate_json(prop, res, newton_ran))
        raise typer.Exit(EXIT_NOT_CONVERGED)
    print_continuation(res)
    out.print(res.message, style="red")
    if output is not None:
        err.print(f"not writing {output}: the change cannot be assembled")
    raise typer.Exit(EXIT_NOT_CONVERGED)


__all__ = [
    "continuation_json",
    "print_continuation",
    "propagate_json",
    "run_propagation",
    "shown_warnings",
    "solve_propagation",
]
