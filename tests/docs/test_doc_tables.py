"""Numbers the docs print in Markdown tables and prose agree with the commands (issue 19 item 3).

The doc test compares console blocks; the import guide's sensitivity table is a Markdown
table, and it had the tie rod's sign wrong (toe-in for what is toe-out). Checked here: every
cell of that table against the command it documents (4 significant digits, sign included),
the prose's "0.35 deg of toe-out", and that the docs cite no file outside the repository.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

from typer.testing import CliRunner

from kinprop.cli import app

ROOT = Path(__file__).resolve().parents[2]


def _table(text: str, header: str) -> dict[str, list[float]]:
    lines = text[text.index(header) :].splitlines()
    cols = [c.strip() for c in lines[0].strip("|").split("|")][1:]
    rows = {}
    for line in lines[2:]:
        if not line.startswith("|"):
            break
        cells = [c.strip() for c in line.strip("|").split("|")]
        rows[cells[0]] = [float(c) for c in cells[1:]]
    return {"columns": cols, **rows}


def _same(doc: float, got: float) -> bool:
    digits = 4 if doc else 0
    return abs(doc - got) <= 0.5 * 10 ** (math.floor(math.log10(abs(got))) - digits + 1) if doc else abs(got) < 1e-9


def test_import_guide_sensitivity_table_matches_the_command():
    text = (ROOT / "docs/guide/importing.md").read_text()
    table = _table(text, "| d(output)/d(design) |")
    r = CliRunner().invoke(app, ["sensitivity", str(ROOT / "examples/chrono/DoubleWishbone.json"), "--wrt", "UCA_U.s_j",
                                 "--wrt", "TIEROD.s_j", "--of", "camber", "--of", "toe", "--free", "UCA.q", "--free",
                                 "LCA_U.q", "--json"])  # fmt: skip
    assert r.exit_code == 0, r.output
    got = json.loads(r.stdout)
    assert got["wrt"] == table["columns"]
    for k, out in enumerate(got["of"]):
        for doc, value in zip(table[out], got["matrix"][k], strict=True):
            assert _same(doc, value), (out, doc, value)
    toe_per_mm = got["matrix"][1][got["wrt"].index("TIEROD.s_j[1]")] / 1000  # toe-in positive
    assert f"{abs(toe_per_mm):.2f} deg of toe-{'in' if toe_per_mm > 0 else 'out'}" in text


def test_docs_cite_no_file_outside_the_repository():
    for md in [ROOT / "README.md", *(ROOT / "docs").rglob("*.md")]:
        text = md.read_text()
        assert "../shared/" not in text, md
        for target in re.findall(r"\]\(([^)#:]+\.md)(?:#[^)]*)?\)", text):
            assert (md.parent / target).resolve().is_file(), (md, target)
