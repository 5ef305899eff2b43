"""Outputs a model cannot give are refused up front, never written blank (issue 19 item 1).

A wheel without a steering axis has camber and toe but no KPI. Asking a sweep for all three
printed "converged" and left every column blank; now the command exits 2 naming the metric
and the points it needs, and the computable columns are filled (checked against camber and
toe computed here from the wheel's spin axis, ISO 8855 signs).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from kinprop.cli import app

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
runner = CliRunner()


@pytest.fixture(scope="module")
def no_kingpin(tmp_path_factory) -> Path:
    """The imported Chrono MultiLink (no steering axis: no two ball joints on the upright),
    without its reference wheel centre (the issue's reproduction)."""
    path = tmp_path_factory.mktemp("nk") / "no_kingpin.yaml"
    r = CliRunner().invoke(app, ["import", str(EXAMPLES / "chrono" / "MultiLink.json"), "-o", str(path)])
    assert r.exit_code == 0, r.output
    data = yaml.safe_load(path.read_text())
    for body in data["bodies"].values():
        for name in [k for k in body.get("points", {}) if "wheel_centre_ref" in k]:
            del body["points"][name]
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


@pytest.mark.parametrize(
    ("command", "metric", "needs"),
    [
        (["sweep", "--drive", "UA=-4:4:3"], "kpi", "kingpin_upper"),
        (["sweep", "--drive", "UA=-4:4:3"], "wheel_centre_dz", "wheel_centre_ref"),
        (["propagate", "--target", "{m}=1", "--free", "hardpoint:TIEROD.i"], "kpi", "kingpin_upper"),
        (["sensitivity", "--wrt", "TIEROD.s_i", "--of", "{m}"], "kpi", "kingpin_upper"),
    ],
)
def test_missing_metric_is_invalid_input(no_kingpin, command, metric, needs):
    args = [command[0], str(no_kingpin), *(a.format(m=metric) for a in command[1:])]
    if command[0] == "sweep":
        args += ["--out", "camber", "--out", "toe", "--out", metric]
    r = runner.invoke(app, args)
    assert r.exit_code == 2, r.output
    assert metric in r.stderr and needs in r.stderr, r.stderr


def test_computable_columns_are_filled(no_kingpin):
    r = runner.invoke(
        app,
        ["sweep", str(no_kingpin), "--drive", "UA=-4:4:3", "--out", "camber", "--out", "toe",
         "--out", "point:upright.wheel_centre", "--out", "point:upright.spin_axis", "--json"],
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    rows = json.loads(r.stdout)["rows"]
    assert len(rows) == 4
    for row in rows:
        a = np.array([row[f"point:upright.spin_axis[{c}]"] - row[f"point:upright.wheel_centre[{c}]"] for c in "xyz"])
        a /= np.linalg.norm(a)
        assert row["camber"] == pytest.approx(math.degrees(math.asin(-a[2])), abs=1e-9)
        assert row["toe"] == pytest.approx(math.degrees(math.atan2(a[0], abs(a[1]))), abs=1e-9)
    assert rows[0]["camber"] != pytest.approx(rows[3]["camber"], abs=1e-3)  # the wheel moves
