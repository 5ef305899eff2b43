"""``kinprop report`` and the workbench's report download: one self-contained HTML file whose
hardpoint table is the model's global hardpoints and whose curve numbers are ``kinprop sweep``'s."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from workbench import cli, cli_json

pytest.importorskip("plotly")


def table(text: str, table_id: str) -> list[list[str]]:
    """The cells of the HTML table ``table_id`` (rows of <td>, headers left out)."""
    body = re.search(rf'<table id="{table_id}">(.*?)</table>', text, re.S)
    assert body, f"no table {table_id}"
    rows = [re.findall(r"<td>(.*?)</td>", r) for r in re.findall(r"<tr>(.*?)</tr>", body.group(1), re.S)]
    return [r for r in rows if r]


def test_report_has_the_hardpoints_and_the_sweeps_numbers(examples: Path, tmp_path: Path) -> None:
    model = examples / "double_wishbone_hardpoints.yaml"
    report = tmp_path / "report.html"
    code, _, err = cli("report", model, "-o", report)
    assert code == 0, err
    text = report.read_text(encoding="utf-8")
    assert "<script src=" not in text  # self-contained: plotly.js inline, nothing fetched
    rows = {r[1]: [float(x) for x in r[3:]] for r in table(text, "hardpoints") if r[1]}
    # the file's global hardpoints (mm), as written there
    assert rows["hardpoint:TR.i"] == [-250.317, 448.437, 54.229]
    assert rows["hardpoint:LCA.front"] == [223.266, 307.086, 0.0]
    assert rows["hardpoint:UBJ"] == pytest.approx([-53.0352, 715.518, 215.4936], abs=1e-9)
    spec = re.search(r"kinprop sweep --drive (\S+):", text).group(1)
    assembled = tmp_path / "assembled.yaml"
    assert cli("assemble", model, "-o", assembled)[0] == 0
    outs = ["--out", "metric:upright.camber", "--out", "metric:upright.toe"]
    want = cli_json("sweep", assembled, "--drive", spec, *outs, "--json")
    drive = want["drives"][0]
    got = [[float(x) for x in r] for r in table(text, "curve-rows")]
    assert len(got) == 50
    for g, w in zip(got, want["rows"], strict=True):
        assert g == pytest.approx([w[drive], w["metric:upright.camber"], w["metric:upright.toe"]], rel=1e-9, abs=1e-12)


def test_report_refuses_a_wrong_suffix(examples: Path, tmp_path: Path) -> None:
    code, _, err = cli("report", examples / "fourbar.yaml", "-o", tmp_path / "r.png")
    assert code == 2 and "expected a name ending in .html" in err
    assert not (tmp_path / "r.png").exists()


def test_report_download_is_the_current_design(make_client) -> None:
    c = make_client("double_wishbone_hardpoints.yaml")
    r = c.post("/api/propagate", json={"set": {"hardpoint:TR.i": [-250.317, 448.437, 60.0]}})
    assert r.json()["status"] == "converged"
    page = c.get("/api/report.html")
    assert page.status_code == 200 and "attachment" in page.headers["content-disposition"]
    rows = {r[1]: [float(x) for x in r[3:]] for r in table(page.text, "hardpoints") if r[1]}
    assert rows["hardpoint:TR.i"] == pytest.approx([-250.317, 448.437, 60.0], abs=1e-9)
