"""A hand example with a closed form: the four-bar of examples/fourbar.yaml driven through a
2:1 gear pair (examples/fourbar_geared.yaml), ``theta2 = 60 deg - 0.5 qG``; the rocker angle
follows from Freudenstein's equation (tests/analysis/linkages.py)."""

from __future__ import annotations

import csv
import io
import json
import math

import numpy as np
import pytest
from linkages import CRANK_ROCKER, EXAMPLES, freudenstein, wrap
from typer.testing import CliRunner

import kinprop as kp
from kinprop.cli import app

GEARED = EXAMPLES / "fourbar_geared.yaml"
runner = CliRunner()
D = math.pi / 180.0


@pytest.fixture(scope="module")
def engine() -> kp.Engine:
    return kp.compile(kp.assemble(kp.load_model(GEARED), tol=1e-13).after)


def test_mobility_is_one(engine) -> None:
    rep = kp.mobility(engine.model)
    assert (rep.n_coordinates, rep.n_constraints, rep.rank, rep.mobility, rep.gruebler) == (4, 3, 3, 1, 1)


def test_propagating_the_pinion_turns_the_crank_at_half_speed(engine) -> None:
    for g in (-40.0, 15.0, 70.0):
        sol = engine.propagate({"G.q": g * D}, free=["q"], tol=1e-13)
        assert sol.converged
        t2 = (60.0 - 0.5 * g) * D
        assert float(sol.value("O2.q")[0]) == pytest.approx(t2, abs=1e-13)
        assert float(wrap(sol.value("O4.q")[0] - freudenstein(*CRANK_ROCKER, t2))) == pytest.approx(0.0, abs=1e-12)


def test_changing_the_ratio_and_a_quadratic_term(engine) -> None:
    """At G = 20 deg: c1 = -1 gives theta2 = 40 deg; c2 (rad/rad^2 inside) bends it further."""
    at20 = engine.propagate({"G.q": 20 * D}, free=["q"], tol=1e-13)
    sol = engine.propagate({"DRIVE.coef[1]": -1.0}, free=["q"], start=at20, tol=1e-13)
    assert sol.converged and float(sol.value("O2.q")[0]) == pytest.approx(40 * D, abs=1e-13)
    c2 = 0.01 / D  # 0.01 deg/deg^2 in solver units
    sol = engine.propagate({"DRIVE.coef[2]": c2}, free=["q"], start=at20, tol=1e-13)
    assert sol.converged and float(sol.value("O2.q")[0]) == pytest.approx((60 - 10 + 0.01 * 400) * D, abs=1e-13)
    # a coefficient can be free: hold the crank at 45 deg, the ratio follows (c1 = (45 - 60) / 20)
    sol = engine.propagate({"O2.q": 45 * D}, free=["q", "DRIVE.coef[1]"], start=at20, tol=1e-13)
    assert sol.converged and float(sol.value("DRIVE.coef[1]")) == pytest.approx(-0.75, abs=1e-13)


def test_cli_sweep_and_degree_units(tmp_path) -> None:
    out = tmp_path / "g.csv"
    r = runner.invoke(app, ["sweep", str(GEARED), "--drive", "G=-60:120:9", "-o", str(out), "--tol", "1e-12"])
    assert r.exit_code == 0, r.output
    rows = list(csv.DictReader(io.StringIO(out.read_text())))  # headers carry units (docs/units.md)
    g = np.array([float(x["G.q [deg]"]) for x in rows])
    assert all(x["status"] == "converged" for x in rows)
    np.testing.assert_allclose([float(x["O2.q [deg]"]) for x in rows], 60 - 0.5 * g, atol=1e-9)
    t4 = np.degrees(freudenstein(*CRANK_ROCKER, np.radians(60 - 0.5 * g)))
    np.testing.assert_allclose(np.degrees(wrap(np.radians([float(x["O4.q [deg]"]) for x in rows] - t4))), 0, atol=1e-9)
    # --set in the model's units: c2 in deg/deg^2
    r = runner.invoke(app, ["propagate", str(GEARED), "--set", "G.q=20", "--set", "DRIVE.coef[2]=0.01", "--json"])
    assert r.exit_code == 0, r.output
    obj = json.loads(r.stdout)
    assert obj["status"] == "converged"
    assert obj["coordinates"]["O2"][0] == pytest.approx(54.0, abs=1e-12)
    assert obj["design"]["DRIVE.coef"] == pytest.approx([0, -0.5, 0.01, 0, 0], abs=1e-15)
