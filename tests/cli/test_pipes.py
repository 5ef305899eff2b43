"""Output for people and pipes (issue 11, item 7). The piped table runs in a process of its own
(its stdout a real pipe); the files and the help in the test process."""

from __future__ import annotations

import csv
import re

from cli_run import invoke_kinprop, run_kinprop


def _shortest(field: str) -> bool:
    try:
        x = float(field)
    except ValueError:
        return True  # text
    return field == repr(x) or field == str(int(x))


def test_csv_is_shortest_round_trip_with_lf(examples, tmp_path) -> None:
    out, sw = tmp_path / "p.csv", tmp_path / "s.csv"
    p = invoke_kinprop("propagate", examples / "slider_crank.yaml", "--set", "J12.s_j=-2.8,0.2,0.1", "--csv", out)
    assert p.returncode == 0, p.stderr
    p = invoke_kinprop("sweep", examples / "fourbar.yaml", "--drive", "O2=0:90:9", "-o", sw, "-q")
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
    p = invoke_kinprop("propagate", "--help")
    assert p.returncode == 0
    assert "<bool>" not in p.stdout
    assert "--set ADDRESS=VALUE" in p.stdout and "--continuation / --no-continuation" in p.stdout


def test_large_load_shows_progress_on_a_terminal(tmp_path, monkeypatch, capsys) -> None:
    """A large model file shows a status line while it loads, and what it loaded — on a
    terminal only (a pipe or CI log stays clean)."""
    import importlib
    import io

    cli_app = importlib.import_module("kinprop.cli.app")  # the module (kinprop.cli.app is also the Typer app's name)

    path = tmp_path / "chain.yaml"
    lines = ["kinprop: 1", "name: chain", "units: {length: m, angle: rad}", "bodies:", "  ground: {fixed: true}"]
    lines += [f"  b{k}: {{}}" for k in range(8000)]
    lines.append("joints:")
    lines += [
        f"  R{k}: {{type: revolute, bodies: [{'ground' if k == 0 else f'b{k - 1}'}, b{k}], s_i: [0.001, 0, 0]}}"
        for k in range(8000)
    ]
    path.write_text("\n".join(lines) + "\n")
    assert path.stat().st_size > cli_app.PROGRESS_BYTES
    buf = io.StringIO()
    monkeypatch.setattr(cli_app, "err", cli_app._Console(file=buf, markup=False, emoji=False, highlight=False))
    model = cli_app.load_model_cli(path)  # a pipe: nothing on stderr
    assert len(model.mechanism.bodies) == 8001 and buf.getvalue() == ""
    terminal = cli_app._Console(file=buf, markup=False, emoji=False, highlight=False, force_terminal=True)
    monkeypatch.setattr(cli_app, "err", terminal)
    cli_app.load_model_cli(path)
    shown = " ".join(re.sub(r"\x1b\[[0-9;?]*[a-zA-Z]", "", buf.getvalue()).split())
    assert f"loading {path} (0.7 MB): parsing, validating, building the tree" in shown
    assert f"loaded {path}: 8001 bodies, 8000 joints" in shown
