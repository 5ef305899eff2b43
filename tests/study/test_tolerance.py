"""Tolerance analysis: linearised standard deviations against a Monte Carlo study."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from kinprop import propagate
from kinprop.analysis.tolerance import monte_carlo, tolerance_analysis
from kinprop.builders import rssr
from kinprop.cli import app
from kinprop.errors import AddressError

TOLS = {"coupler.length": 5e-4, "rocker.s_i[0]": 5e-4, "coupler.s_i[0]": 3e-4, "rocker.s_i[2]": 2e-4}
OUTS = ["rocker.q", "point:rocker.ball"]
N = 2000


@pytest.mark.parametrize(("free", "fixed"), [(("rocker.q",), ()), (("q",), ("crank.q",))])
def test_linear_std_matches_monte_carlo(free, fixed):
    model = propagate(rssr(), {"crank.q": [1.0]}).after
    lin = tolerance_analysis(model, TOLS, OUTS, free=free, fixed=fixed)
    assert lin.outputs == ["rocker.q", "point:rocker.ball[x]", "point:rocker.ball[y]", "point:rocker.ball[z]"]
    mc = monte_carlo(model, TOLS, OUTS, n=N, seed=11, free=free, fixed=fixed)
    # a sample standard deviation has relative standard error 1/sqrt(2(N-1)) ~ 1.6 %: allow 4 of them
    moving = lin.std > 1e-12
    np.testing.assert_allclose(mc[moving], lin.std[moving], rtol=4 / np.sqrt(2 * (N - 1)))
    assert np.all(mc[~moving] < 1e-12)
    # covariance: symmetric, its diagonal is std^2
    np.testing.assert_allclose(lin.covariance, lin.covariance.T)
    np.testing.assert_allclose(np.diag(lin.covariance), lin.std**2)


def test_gain_of_a_coordinate_is_the_sensitivity():
    from kinprop.analysis.sensitivity import design_sensitivity

    model = propagate(rssr(), {"crank.q": [1.0]}).after
    lin = tolerance_analysis(model, {"coupler.length": 1e-3}, ["rocker.q"], free=("rocker.q",))
    S = design_sensitivity(model, ["coupler.length"], free=["rocker.q"]).matrix
    assert lin.gain[0, 0] == pytest.approx(S[0, 0])
    assert lin.std[0] == pytest.approx(abs(S[0, 0]) * 1e-3)
    with pytest.raises(AddressError):
        tolerance_analysis(model, {"coupler.length": -1.0}, ["rocker.q"])
    with pytest.raises(AddressError):
        tolerance_analysis(model, {"rocker.C_i": 1e-3}, ["rocker.q"])


def test_cli_tolerance(rssr_file):
    runner = CliRunner()
    args = ["tolerance", str(rssr_file), "--tolerance", "coupler.length=5e-4", "--tolerance", "rocker.s_i[0]=5e-4",
            "--of", "rocker.q", "--free", "rocker.q"]  # fmt: skip
    r = runner.invoke(app, [*args, "--json", "--mc", "500"])
    assert r.exit_code == 0, r.output
    obj = json.loads(r.output)
    assert obj["outputs"] == ["rocker.q"] and obj["std"][0] > 0
    assert obj["mc_std"][0] == pytest.approx(obj["std"][0], rel=0.15)
    r = runner.invoke(app, args)
    assert r.exit_code == 0 and "rocker.q" in r.output
    r = runner.invoke(app, ["tolerance", str(rssr_file), "--tolerance", "nope.length=1e-3", "--of", "rocker.q"])
    assert r.exit_code == 2
