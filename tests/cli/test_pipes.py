"""Output for people and pipes (issue 11, item 7)."""

from __future__ import annotations

import csv

from cli_run import run_kinprop


def _shortest(field: str) -> bool:
    try:
        x = float(field)
    except ValueError:
        return True  # text
    return field == repr(x) or field == str(int(x))


def test_csv_is_shortest_round_trip_with_lf(examples, tmp_path) -> None:
    out, sw = tmp_path / "p.csv", tmp_path / "s.csv"
    p = run_kinprop("propagate", examples / "slider_crank.yaml", "--set", "J12.s_j=-2.8,0.2,0.1", "--csv", out)
    assert p.returncode == 0, p.stderr
    p = run_kinprop("sweep", examples / "fourbar.yaml", "--drive", "O2=0:90:9", "-o", sw, "-q")
    assert p.returncode == 0, p.stderr
    for path in (out, sw):
        raw = path.read_bytes()
        assert b"\r" not in raw and raw.endswith(b"\n")
        rows = list(csv.reader(raw.decode().splitlines()))
        assert all(_shortest(f) for row in rows[1:] for f in row), path
    rows = {r["variable"]: r for r in csv.DictReader(out.read_text().splitlines())}
    assert rows["J12.s_j[1]"]["after"] == "0.2" and rows["J12.s_j[0]"]["before"] == "-2.828"


def test_piped_sweep_table_is_whole_and_requested_first(examples) -> None:
    p = run_kinprop("sweep", examples / "fourbar.yaml", "--drive", "O2=0:120:40", "--out", "point:coupler.P[y]")
    assert p.returncode == 0, p.stderr
    lines = p.stdout.splitlines()
    header = next(x for x in lines if "step" in x)
    cols = [c.strip() for c in header.strip("┃│ ").replace("┃", "│").split("│")]
    assert cols[:4] == ["step", "O2.q [deg]", "point:coupler.P[y] [m]", "status"]
    body = [x for x in lines if x.startswith("│")]
    assert len(body) == 41 and not any("..." in x for x in body)


def test_flags_show_as_flags_in_help() -> None:
    p = run_kinprop("propagate", "--help")
    assert p.returncode == 0
    assert "<bool>" not in p.stdout
    assert "--set ADDRESS=VALUE" in p.stdout and "--continuation / --no-continuation" in p.stdout
