"""Presentation a new user met (issue 19 item 11): what is printed, listed and drawn reads
right. Each check compares with the data behind it: the CSV's full-precision values, the
model's own counts and units, the example files' own comments, the plotted data's range."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import kinprop as kp
from kinprop.cli import app

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
runner = CliRunner()


def run(*args: object):
    return runner.invoke(app, [str(a) for a in args])


def _cells(table: str) -> list[list[str]]:
    """The body rows of a rich table as printed (``│ a │ b │``)."""
    return [[c.strip() for c in line.split("│")[1:-1]] for line in table.splitlines() if line.startswith("│")]


def test_round_off_is_shown_as_zero_never_minus_zero(tmp_path) -> None:
    """At the design position toe and camber are round-off (|x| < 1e-12 in the CSV); the table
    shows 0, not -0 or 2.55e-14, and every other cell is the CSV value to 6 digits."""
    path = tmp_path / "dw.csv"
    r = run("sweep", EXAMPLES / "double_wishbone_hardpoints.yaml", "--drive", "LCA=-2:2:2", "--out", "toe",
            "--out", "camber", "-o", path)  # fmt: skip
    assert r.exit_code == 0, r.output
    header = [c.split(" [")[0] for c in next(csv.reader(path.open()))]
    df = pd.read_csv(path, header=0, names=header)
    assert max(abs(df.loc[1, "toe"]), abs(df.loc[1, "camber"])) < 1e-12  # the design position
    head = next(line for line in r.stdout.splitlines() if line.startswith("┃"))
    names = [c.strip().split(" [")[0] for c in head.split("┃")[1:-1]]
    rows = _cells(r.stdout)
    assert len(rows) == 3
    for k, row in enumerate(rows):
        for name, cell in zip(names, row, strict=True):
            assert cell != "-0" and "e-1" not in cell, (name, cell)
            if df[name].dtype.kind == "f":
                scale = float(df[name].abs().max())
                v = float(df.loc[k, name])
                want = 0.0 if abs(v) <= max(1e-12, 1e-10 * scale) else v
                assert float(cell) == pytest.approx(want, rel=5e-6, abs=0), (name, cell, v)
    assert rows[1][names.index("toe")] == "0" and rows[1][names.index("camber")] == "0"


def test_a_vector_with_mixed_units_shows_each_components_unit() -> None:
    """The Stewart platform's free joint: position (m) then Euler parameters (no unit)."""
    m = kp.load_model(EXAMPLES / "stewart.yaml")
    prop = kp.propagate(m, {"P.q[0]": [0.01]}, free=("l",))
    text = repr(prop)
    assert ",," not in text and "m,m" not in text
    assert "set P.q: [0 m, 0 m, 0.4 m, 1, 0, 0, 0] -> [0.01 m, 0 m, 0.4 m, 1, 0, 0, 0]" in text
    r = run("propagate", EXAMPLES / "stewart.yaml", "--set", "P.q[0]=0.01", "--free", "l")
    assert r.exit_code == 0, r.output
    assert "[m, m, m, -, -, -, -]" in r.stdout and "m,m,m" not in r.stdout


def test_repr_of_a_model_is_one_line_with_its_counts() -> None:
    m = kp.load_model(EXAMPLES / "hmmwv_front_axle.yaml")
    text = repr(m)
    assert "\n" not in text and len(text) < 300
    mech = m.mechanism
    assert f"{len(mech.bodies)} bodies, {len(mech.joints)} joints" in text
    assert "length: mm" in text and "inputs: LCA_L, LCA_R, RACK" in text


def _comment(path: Path) -> str:
    lines = []
    for line in path.read_text().splitlines():
        if not line.startswith("#"):
            break
        lines.append(line.lstrip("#").strip())
    return " ".join(" ".join(lines).split())


def test_examples_table_gives_whole_sentences() -> None:
    r = runner.invoke(app, ["examples"], env={"COLUMNS": "400"})
    assert r.exit_code == 0, r.output
    what = {row[0]: row[1] for row in _cells(r.stdout) if row and row[0]}
    assert len(what) >= 25 and all(what.values()), what
    for name, text in what.items():
        if not name.endswith(".yaml"):
            continue
        comment = _comment(EXAMPLES / name)
        assert comment.startswith(text), (name, text)
        rest = comment[len(text) :]
        # a whole sentence (ends with a full stop) or a whole clause (the comment goes on with ": ")
        assert (text.endswith(".") and (rest == "" or rest.startswith(" "))) or rest.startswith(": "), (name, text)
    assert what["bennett.yaml"] == "Bennett linkage (Bennett 1903): the only movable spatial 4R loop."
    assert what["chrono/MultiLink.json"] == "Project Chrono MultiLink suspension 'Generic Multi-Link' (kinprop import)"


def test_help_lists_the_commands_in_a_sessions_order() -> None:
    r = runner.invoke(app, ["--help"])
    assert r.exit_code == 0
    listed = [line.split()[0] for line in r.stdout.split("Commands:")[1].splitlines() if line.strip()]
    assert listed == ["examples", "check", "plot", "assemble", "propagate", "sweep", "sensitivity", "tolerance",
                      "study", "loads", "vehicle", "report", "serve", "import", "convert", "paper"]  # fmt: skip


def test_curves_fill_a_grid_and_fit_their_data() -> None:
    """Six outputs: two rows of three panels (not one 3024 px strip); all-positive data is not
    stretched down to 0."""
    from kinprop.plot.curves import plot_curves

    x = np.linspace(-50.0, 50.0, 11)
    frame = pd.DataFrame({"travel": x, **{f"y{k}": 5.0 + k + 0.01 * x for k in range(6)}})
    fig = plot_curves({"design": frame}, "travel", [f"y{k}" for k in range(6)])
    shown = [ax for ax in fig.axes if ax.get_visible()]
    assert len(shown) == 6
    rows = {round(ax.get_position().y0, 3) for ax in shown}
    cols = {round(ax.get_position().x0, 3) for ax in shown}
    assert len(rows) == 2 and len(cols) == 3
    w, h = fig.get_size_inches() * 120
    assert w <= 1600 and w / h < 2.0
    for k, ax in enumerate(shown):
        lo, hi = ax.get_ylim()
        assert lo > 0.0 and lo <= 4.5 + k and hi >= 5.5 + k  # the data's range, not forced through 0


def test_plot_sweep_returns_a_figure(tmp_path) -> None:
    from matplotlib.figure import Figure

    from kinprop.analysis.sweep import plot_sweep, sweep

    res = sweep(kp.load_model(EXAMPLES / "fourbar.yaml"), ["O2=0:90:3"], outputs=[])
    fig = plot_sweep(res)
    assert isinstance(fig, Figure) and fig.axes
    lines = [ln for ax in fig.axes for ln in ax.get_lines() if ln.get_label() == "O4.q"]
    np.testing.assert_allclose(lines[0].get_ydata(), res.frame["O4.q"])  # the rows, as plotted
    out = tmp_path / "sweep.png"
    assert isinstance(plot_sweep(res, out), Figure) and out.stat().st_size > 5_000


def test_the_fixed_body_is_not_drawn_from_a_phantom_centre() -> None:
    """No segment belongs to the chassis: the chassis has no body at the centroid of its
    points; its joints are markers where they are."""
    from kinprop.plot.scene import build_scene

    m = kp.load_model(EXAMPLES / "double_wishbone_hardpoints.yaml")
    scene = build_scene(m)
    fixed = [b.name for b in m.mechanism.bodies if b.fixed]
    assert fixed and not [s for s in scene.segments if s.owner in fixed]
    chassis_joints = {j.name for j in m.mechanism.joints if fixed[0] in (j.body_i, j.body_j)}
    assert chassis_joints <= {mk.joint for mk in scene.markers}
    assert {s.kind for s in scene.segments} <= {"body", "link", "slide", "gap"}


def test_output_sensitivity_columns_come_in_the_order_asked() -> None:
    m = kp.propagate(kp.load_model(EXAMPLES / "slider_crank.yaml")).after
    wrt = ["J12.s_j[1]", "hardpoint:J12.i[z]", "J12.s_i[0]"]
    frame = kp.output_sensitivity(m, ["J03.q", "J01.q"], wrt)
    assert list(frame.columns) == wrt
    for w in wrt:  # each column is the one asked for alone
        alone = kp.output_sensitivity(m, ["J03.q", "J01.q"], [w])
        np.testing.assert_allclose(frame[w], alone[w], rtol=1e-12, atol=0)
    assert math.isfinite(float(frame.to_numpy().sum()))
