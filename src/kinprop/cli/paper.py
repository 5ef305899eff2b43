"""``kinprop paper``: the main job — the paper's Tables 4 and 1 with our values beside them."""

from __future__ import annotations

from typing import Annotated

import typer
from rich.table import Table
from rich.text import Text

from kinprop.cli.app import EXIT_NOT_CONVERGED, app, fail, out, print_json
from kinprop.reference import TABLES
from kinprop.reference.paper import compare_column, reproduce


def _fmt(values: tuple[float, ...]) -> str:
    text = " ".join(f"{v:.9g}" for v in values)
    return text if len(values) == 1 else f"[{text}]"


@app.command()
def paper(
    table: Annotated[
        list[str] | None, typer.Option("--table", metavar="NAME", help="table4 and/or table1 (default both)")
    ] = None,
    tol: Annotated[float, typer.Option("--tol", help="stopping rule ||Phi|| < TOL (the paper's: 1e-3)")] = 1e-3,
    as_json: Annotated[bool, typer.Option("--json", help="print one JSON object")] = False,
) -> None:
    """Reproduce the paper's Table 4 (slider-crank) and Table 1 (McPherson strut)."""
    names = table or ["table4", "table1"]
    unknown = [n for n in names if n not in TABLES]
    if unknown:
        fail(f"--table {unknown[0]!r}: unknown table; choose from {', '.join(TABLES)}")
    report: dict[str, list[dict]] = {}
    total = agree = 0
    for name in names:
        t = TABLES[name]
        report[name] = []
        if not as_json:
            out.print(Text(t.title, style="bold"))
        for col, prop in reproduce(t, tol):
            rows = compare_column(prop, col)
            rt = Table(title=f"column: {col.name}   (free: {' '.join(col.free)})", title_justify="left")
            for h in ("quantity", "paper", "kinprop", "agrees", "note"):
                rt.add_column(h, justify="right" if h in ("paper", "kinprop") else "left")
            for c in rows:
                total += 1
                agree += c.ok
                printed = " ".join(c.printed)
                rt.add_row(
                    c.label,
                    printed if len(c.printed) == 1 else f"[{printed}]",
                    _fmt(c.ours),
                    Text("yes", style="green") if c.ok else Text("NO", style="red"),
                    c.note,
                    style="yellow" if c.note.startswith(("typo", "label typo")) else None,
                )
                report[name].append(
                    {
                        "column": c.column,
                        "quantity": c.label,
                        "paper": list(c.printed),
                        "kinprop": list(c.ours),
                        "agrees": c.ok,
                        "note": c.note,
                    }
                )
            if not as_json:
                out.print(rt)
        if not as_json:
            for n in t.notes:
                out.print(f"  note: {n}")
    if as_json:
        print_json({"agree": agree, "total": total, "tables": report})
    else:
        out.print(
            f"\n{agree} of {total} printed quantities agree (within one unit of the last printed digit, "
            "or to 5e-7 where the note says so — docs/paper.md; typos compared with the corrected value, "
            "marked in yellow; see kinprop.reference.paper)."
        )
    if agree != total:
        raise typer.Exit(EXIT_NOT_CONVERGED)
