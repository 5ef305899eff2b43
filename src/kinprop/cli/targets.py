"""``kinprop propagate --target``: propagate to targets (docs/guide/targets.md).

Target specs: :mod:`kinprop.analysis.targets` (``OUTPUT[@COND]=VALUE[UNIT][:WEIGHT]``). The
free set names design variables (``hardpoint:J``, ``hardpoint:J.i``, ``axis:J``, ``J.s_i``,
``J.length``, groups ``s C l``); every configuration's coordinates move as needed. Exit 0 when
the targets are met, 1 when they are not (least-squares compromise or no convergence).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import typer
from rich.markup import escape
from rich.table import Table
from rich.text import Text

from kinprop.analysis.targets import TargetPropagation, propagate_targets
from kinprop.cli.app import EXIT_NOT_CONVERGED, err, out, print_json
from kinprop.io.results import propagation_json
from kinprop.io.writer import dump_model_like
from kinprop.model import Model
from kinprop.propagation import Propagation


def targets_json(tp: TargetPropagation) -> dict[str, Any]:
    """The propagation JSON of the changed design plus the targets: ``targets_status``,
    ``targets`` (wanted, before, achieved, miss; display units), ``conflicts``,
    ``configurations``, ``design_change``, ``hardpoint_moves`` (each changed attachment's ``A ds'``
    with the body's orientation before the change, global) and ``joint_positions`` (per
    configuration, the joint origins that moved: before and after, global)."""
    obj = propagation_json(tp.propagation)
    r = tp.result
    obj.update(
        # the run's status (kinprop.Status): the targets' solve's, not the design-position
        # re-assembly's when that converged; met or compromise in targets_status
        status=obj["status"] if r.converged else r.status,
        targets_status=r.targets_status,
        targets_message=r.message,
        targets=tp.table(),
        conflicts=[[{"target": n, "weight": w} for n, w in g] for g in r.conflicts],
        configurations=list(tp.configuration_names),
        design_change={k: np.asarray(v, float).tolist() for k, v in r.design_change.items()},
        hardpoint_moves={k: np.asarray(v, float).tolist() for k, v in tp.hardpoint_moves().items()},
        design_position_moves={
            k: {"before": a.tolist(), "after": b.tolist()} for k, (a, b) in tp.design_position_moves().items()
        },
        joint_positions={
            name: {j: {"before": a.tolist(), "after": b.tolist()} for j, (a, b) in moved_joints(tp, k).items()}
            for k, name in enumerate(tp.configuration_names)
        },
    )
    return obj


def moved_joints(tp: TargetPropagation, k: int) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Joint origins that moved in configuration ``k`` (before, after), global."""
    tiny = 1e-9 * max(1.0, tp.engine.length_scale or 1.0)
    return {n: (a, b) for n, (a, b) in tp.joint_positions(k).items() if np.linalg.norm(b - a) > tiny}


def targets_table(tp: TargetPropagation, title: str) -> Table:
    t = Table(title=escape(title), title_justify="left")
    for c in ("target", "unit", "wanted", "before", "achieved", "miss"):
        t.add_column(c, justify="left" if c in ("target", "unit") else "right")
    for row in tp.table():
        cells = (f"{row[k]:.6g}" for k in ("value", "before", "achieved", "miss"))
        t.add_row(escape(row["target"]), row["unit"], *cells)
    return t


def run_targets(
    model: Model,
    path: Path,
    targets: Sequence[str],
    free: Sequence[str],
    changes: Mapping[str, Any],
    weights: Mapping[str, float] | None,
    *,
    max_iter: int,
    output: Path | None,
    as_json: bool,
    writers: Sequence[tuple[Path, Callable[[Propagation, Path], None]]] = (),
) -> None:
    """Solve for the targets, print (table or JSON), write the model (and ``writers``: CSV, plot
    of the before/after propagation) when met; exit 1 if not met."""
    if not free or all(f == "q" for f in free):
        raise ValueError("--target needs --free design variables (e.g. --free hardpoint:UBJ --free TR.s_i)")
    tp = propagate_targets(model, targets, [f for f in free if f != "q"], changes=changes, weights=weights,
                           max_iter=max_iter, units="solver")  # fmt: skip
    r = tp.result
    for dest, write in [(output, lambda p, where: dump_model_like(p.after, where, path)), *writers]:
        if dest is None:
            continue
        if r.met:
            write(tp.propagation, dest)
        else:
            err.print(f"not writing {dest}: the targets were not met")
    if as_json:
        print_json(targets_json(tp))
    else:
        out.print(targets_table(tp, f"propagate {path} to targets"))
        unit = model.units.get("length", "")
        moves = tp.design_position_moves() if r.converged else {}
        if moves:
            out.print(f"joints moved at the design position (global, {unit}):")
        for k, (a, b) in moves.items():
            pa, pb = (", ".join(f"{x:.6g}" for x in v) for v in (a, b))
            out.print(escape(f"  {k}: [{pa}] -> [{pb}] (moved {np.linalg.norm(b - a):.6g})"))
        for k, d in r.design_change.items():
            if not k.split(".")[1].startswith("s_"):
                out.print(f"{k} changes by {np.asarray(d).round(9).tolist()}")
        out.print(Text(r.message, style="green" if r.met else "red"))
        if r.met:
            for dest in [output, *(p for p, _ in writers)]:
                if dest is not None:
                    out.print(f"wrote {dest}")
    if not r.met:
        raise typer.Exit(EXIT_NOT_CONVERGED)
