"""The sweep's drive forms are documented where a user looks (issue 19 item 10), and each
form gives the values it says (a list and a CSV column against the same START:STOP:STEPS)."""

from __future__ import annotations

import json
from pathlib import Path

from typer.testing import CliRunner

from kinprop.cli import app

ROOT = Path(__file__).resolve().parents[2]
runner = CliRunner()


def test_drive_forms_in_help_and_docs():
    r = runner.invoke(app, ["sweep", "--help"], env={"COLUMNS": "200"})
    text = " ".join(r.stdout.split())
    assert "JOINT=v1,v2,..." in text and "JOINT=@FILE.csv[:COL]" in text
    doc = (ROOT / "docs/analysis/sweeps.md").read_text()
    assert "`--drive JOINT=v1,v2,...`" in doc and "`--drive JOINT=@FILE.csv[:COL]`" in doc
    assert "plain Newton" not in doc


def test_the_three_drive_forms_agree(tmp_path):
    (tmp_path / "d.csv").write_text("angle\n0\n30\n60\n90\n")
    rows = {}
    for spec in ("O2=0:90:3", "O2=0,30,60,90", f"O2=@{tmp_path / 'd.csv'}:angle"):
        r = runner.invoke(app, ["sweep", str(ROOT / "examples/fourbar.yaml"), "--drive", spec, "--json"])
        assert r.exit_code == 0, r.output
        rows[spec] = [(row["O2.q"], row["O4.q"]) for row in json.loads(r.stdout)["rows"]]
    first, *rest = rows.values()
    assert [a for a, _ in first] == [0, 30, 60, 90]
    assert all(r == first for r in rest)
