"""``kinprop check``: the mechanism report — structure, loops, counts, mobility, redundancy."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer
from rich.table import Table

from kinprop.analysis.mobility import mobility
from kinprop.cli.app import EXIT_NOT_CONVERGED, app, fail, handles_user_errors, load_model_cli, out, print_json
from kinprop.io.commands import ASSEMBLED_TOL, check_json
from kinprop.propagation import assemble

CASES = {
    1: "the cut joint's bodies are also joined by a tree joint",
    2: "the loop closes through the junction body",
}


def _tables(obj: dict[str, Any]) -> list[Table]:
    bodies = Table(title="bodies", title_justify="left")
    for c in ("body", "fixed", "joints", "named points"):
        bodies.add_column(c, overflow="fold")
    for b in obj["bodies"]:
        bodies.add_row(b["name"], "fixed" if b["fixed"] else "", " ".join(b["joints"]), " ".join(b["points"]))
    joints = Table(title="joints", title_justify="left")
    for c in ("joint", "type", "body i", "body j", "role", "coords", "constraint rows"):
        joints.add_column(c, justify="right" if c == "coords" else "left", overflow="fold")
    for j in obj["joints"]:
        joints.add_row(
            j["name"],
            j["type"],
            j["bodies"][0],
            j["bodies"][1],
            j["role"],
            str(j["n_coordinates"]),
            " ".join(r.split(":", 1)[1] for r in j["rows"]),
            style="cyan" if j["role"] == "cut" else None,
        )
    loops = Table(title="loops (one per cut joint)", title_justify="left")
    for c in ("cut joint", "bodies", "junction", "case", "tree path i", "tree path j"):
        loops.add_column(c, overflow="fold")
    for lp in obj["loops"]:
        loops.add_row(
            lp["cut_joint"],
            " - ".join(lp["bodies"]),
            lp["junction"],
            str(lp["case"]),
            " ".join(lp["path_i"]) or "-",
            " ".join(lp["path_j"]) or "-",
        )
    tables = [bodies, joints, loops]
    if not obj.get("couplings"):
        return tables
    couplings = Table(title="couplings (q_a - q_a0 = c0 + c1 (q_b - q_b0) + ... + c4 (q_b - q_b0)^4)",
                      title_justify="left")  # fmt: skip
    for c in ("coupling", "joint a (driven)", "joint b", "constraint rows"):
        couplings.add_column(c, overflow="fold")
    for c in obj["couplings"]:
        couplings.add_row(c["name"], c["joints"][0], c["joints"][1], " ".join(r.split(":", 1)[1] for r in c["rows"]))
    return [*tables, couplings]


def hardpoints_table(obj: dict[str, Any]) -> Table:
    """A suspension's hardpoints in the usual order (chassis pickups, upright points, steering,
    spring/damper, wheel), the group named once."""
    length = obj["units"].get("length", "m")
    hp = Table(title=f"hardpoints (global, {length})", title_justify="left")
    for c in ("group", "point", "x", "y", "z"):
        hp.add_column(c, justify="right" if c in "xyz" else "left")
    group = None
    for r in obj["hardpoints"]:
        hp.add_row("" if r["group"] == group else r["group"], r["point"], *(f"{r[c]:.6g}" for c in "xyz"))
        group = r["group"]
    return hp


def print_report(obj: dict[str, Any], path: Path) -> None:
    """Rich tables and a summary for a human reader."""
    units = obj["units"]
    out.print(f"check {path}: {obj['name']}  (units: {units.get('length')}, {units.get('angle')})")
    for t in _tables(obj):
        out.print(t)
    if obj["loops"]:
        for case in sorted({lp["case"] for lp in obj["loops"]}):
            out.print(f"  case {case}: {CASES[case]}")
    n, m, rank = obj["n_coordinates"], obj["n_constraints"], obj["rank"]
    out.print(f"coordinates n = {n}, constraint rows m = {m}, rank of Phi_q = {rank}")
    out.print(f"Gruebler-Kutzbach count: {obj['gruebler']}")
    out.print(f"mobility (n - rank): {obj['mobility']}", style="bold")
    if obj["redundant"]:
        out.print(
            f"redundant constraint rows ({len(obj['redundant'])}): {' '.join(obj['redundant'])}"
            f"  (joints: {' '.join(obj['redundant_joints'])})",
            style="yellow",
        )
        if obj["mobility"] > obj["gruebler"]:
            out.print(
                f"  the geometry makes {obj['mobility'] - obj['gruebler']} more degree(s) of freedom than the "
                "Gruebler-Kutzbach count (an overconstrained mechanism)"
            )
    else:
        out.print("redundant constraint rows: none")
    res = obj["residual"]
    out.print(f"evaluated at {obj['evaluated_at']}: ||Phi|| = {res:.3g}")
    if not obj["assembled"]:
        out.print(
            f"note: not assembled (||Phi|| >= {ASSEMBLED_TOL:g}); the rank, mobility and redundant rows "
            "hold at this configuration only. Assemble first: "
            f"kinprop assemble {path!s} -o assembled.yaml (or kinprop check --assemble)",
            style="yellow",
            soft_wrap=True,
        )
    if obj.get("hardpoints"):
        out.print(hardpoints_table(obj))


@app.command(name="check")
@handles_user_errors
def check_cmd(
    model: Annotated[Path, typer.Argument(help="model file (YAML or JSON)")],
    as_json: Annotated[bool, typer.Option("--json", help="print one JSON object instead of tables")] = False,
    assemble_first: Annotated[
        bool, typer.Option("--assemble", help="assemble (free: q) before computing the rank")
    ] = False,
) -> None:
    """Mechanism report: structure, loops, counts, mobility and redundant constraints.

    Bodies, joints, tree and cut joints, loops (junction body, case 1 or 2), the numbers of
    coordinates and constraint rows, the Gruebler-Kutzbach count and the true mobility. The
    rank of the Jacobian, the mobility and the redundant rows are computed at the model's
    coordinates as given (or after --assemble); ||Phi|| there is reported. JSON keys: mobility,
    gruebler, n_coordinates, n_constraints, rank, tree_joints, cut_joints, loops, redundant,
    residual, assembled, bodies, joints, couplings (one constraint row each), hardpoints (a
    suspension's, in the usual order: chassis pickups, upright points, steering, spring/damper,
    wheel; group, point, x, y, z).
    """
    m = load_model_cli(model)
    evaluated_at = "the model's coordinates as given"
    if assemble_first:
        prop = assemble(m)
        r = prop.result
        if not r.converged:
            fail(f"{model}: cannot assemble the model: {r.message}", EXIT_NOT_CONVERGED)
        m = prop.after
        evaluated_at = (
            f"the assembled configuration (from ||Phi|| = {r.residual_history[0]:.3g}, {r.iterations} iterations)"
        )
    obj = check_json(m, mobility(m), evaluated_at)
    obj["model"] = str(model)
    if as_json:
        print_json(obj)
    else:
        print_report(obj, model)
