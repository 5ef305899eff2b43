"""Continuation and singularity warnings for ``kinprop propagate`` / ``assemble``.

Every propagation is one engine solve that follows the change on the start's branch
(:meth:`kinprop.Engine.propagate`). When it fails, the solution is diagnosed
(:func:`kinprop.propagation.continuation.diagnose`: fraction reached, constraints in
conflict; ``--no-continuation`` turns the diagnosis off); ``--continuation`` reports the
sub-steps of a successful one too. A change that cannot be assembled
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
from kinprop.engine import compile as compile_engine
from kinprop.errors import SingularityWarning
from kinprop.io.results import coordinates_json, design_json, propagation_json
from kinprop.model import Model
from kinprop.propagation import Propagation
from kinprop.propagation.continuation import ContinuationResult, continuation_of
from kinprop.propagation.propagate import propagation_of, solve_changes


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
        "status": res.status.value,
        "fraction": res.fraction,
        "message": res.message,
        "conflict": [{"row": r, "weight": w} for r, w in res.conflict],
        "residual_rows": [{"row": r, "value": v} for r, v in res.residual_rows],
        "singularity_ratio": res.singularity_ratio,
        "sub_steps": res.substeps,
        "last_feasible": {"coordinates": coordinates_json(res.after), "design": design_json(res.after)},
    }


def print_continuation(res: ContinuationResult) -> None:
    """One summary line, and on failure the diagnosis: fraction and conflicting rows."""
    if res.converged:
        out.print(f"continuation: {res.substeps} sub-steps")
        return
    out.print(f"continuation: the change cannot be assembled beyond {res.fraction:.6g} of its size", style="red")
    for r, w in res.conflict:
        out.print(f"  in conflict: {r}  (weight {w:+.3f} in the left singular vector of the smallest singular value)")
    for r, v in res.residual_rows:
        out.print(f"  residual of the full change at the last feasible state: {r} = {v:.3g}")
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
) -> tuple[Propagation, ContinuationResult | None, bool]:
    """One engine solve of the change, on the start's branch; its diagnosis when it failed
    (``continuation`` None or True) or always (True). No second solve: the diagnosis is a
    function of the solution (:func:`kinprop.propagation.continuation.diagnose`).

    Returns ``(prop, res, newton_ran)``: the propagation to report (a failed one is the
    solver's record), the continuation view when asked for (else None) and True.
    ``on_fallback(prop)`` is called when the solve failed and the diagnosis follows.
    """
    engine = compile_engine(model)
    sol = solve_changes(engine, model, changes, free, tol=tol, max_iter=max_iter, weights=weights, units="solver")
    prop = propagation_of(engine, model, sol, free)
    if continuation is False or (continuation is None and (sol.converged or not changes)):
        return prop, None, True
    if not sol.converged and on_fallback is not None:
        on_fallback(prop)
    res = continuation_of(model, sol, free)
    return (res.propagation if res.converged else prop), res, True


def propagate_json(prop: Propagation, res: ContinuationResult | None = None, newton_ran: bool = True) -> dict[str, Any]:
    """What ``kinprop propagate --json`` prints for :func:`solve_propagation`'s result: the
    propagation's JSON (its ``status`` the solution's, :class:`kinprop.Status`), and when the
    change failed, a ``continuation`` object with the diagnosis."""
    obj = propagation_json(prop)
    if res is None or res.converged:
        return obj
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
) -> Propagation:
    """:func:`solve_propagation` for the CLI: returns the propagation to report. When
    continuation cannot assemble the change either, prints the diagnosis (with ``--json``:
    :func:`propagate_json`) and exits 1 itself, writing nothing.
    """

    def say_fallback(plain: Propagation) -> None:
        if not as_json:
            err.print(f"{plain.result.message}; diagnosing")

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
