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
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path

import typer
from rich.text import Text

from kinprop.cli.app import EXIT_NOT_CONVERGED, err, out, print_json
from kinprop.errors import SingularityWarning
from kinprop.io.commands import propagate_json, solve_propagation
from kinprop.model import Model
from kinprop.propagation import Propagation
from kinprop.propagation.continuation import ContinuationResult


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
    "print_continuation",
    "run_propagation",
    "shown_warnings",
]
