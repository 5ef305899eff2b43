"""Continuation and singularity warnings for ``kinprop propagate`` / ``assemble``.

``--continuation`` runs :func:`kinprop.propagation.continuation.propagate_continuation`;
without the flag a plain Newton propagation runs first and continuation is the fallback when
it fails (``--no-continuation`` turns the fallback off). A change that cannot be assembled
prints the largest feasible fraction and the constraints in conflict and exits 1; no model
is written for it.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator, Mapping, Sequence
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
    """Plain Newton, continuation, or Newton with continuation as the fallback (``None``).

    Returns the propagation to report. When continuation cannot assemble the change either,
    prints the diagnosis (with ``--json``: the failed propagation's JSON, status
    ``not_converged``, plus a ``continuation`` object) and exits 1 itself, writing nothing.
    """
    plain: Propagation | None = None
    with shown_warnings():
        if continuation is not True:
            plain = propagate(model, changes, free, tol=tol, max_iter=max_iter, weights=weights)
            if plain.converged or continuation is False or not changes:
                return plain
            if not as_json:
                err.print(f"plain Newton failed ({plain.result.message}); trying continuation")
        res = propagate_continuation(model, changes, free, tol=tol, max_iter=min(max_iter, 20), weights=weights)
    if res.converged:
        if not as_json:
            print_continuation(res)
        return res.propagation
    if as_json:
        obj = propagation_json(plain if plain is not None else res.propagation)
        obj["status"] = "not_converged"
        if plain is None:
            obj["message"] = res.message
        obj["continuation"] = continuation_json(res)
        print_json(obj)
        raise typer.Exit(EXIT_NOT_CONVERGED)
    print_continuation(res)
    out.print(res.message, style="red")
    if output is not None:
        err.print(f"not writing {output}: the change cannot be assembled")
    raise typer.Exit(EXIT_NOT_CONVERGED)


__all__ = ["continuation_json", "print_continuation", "run_propagation", "shown_warnings"]
