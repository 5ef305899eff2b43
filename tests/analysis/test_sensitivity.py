"""Sensitivities of coordinates, points and metrics against finite differences of full
re-solves (``propagate`` with +-h on one design column, default tight tolerance)."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pandas as pd
import pytest
from analysis_helpers import EXAMPLES, MCPHERSON_STEER, resolve_fd
from typer.testing import CliRunner

from kinprop import SingularityWarning, load_model
from kinprop.analysis.outputs import output_function
from kinprop.analysis.sensitivity import design_sensitivity, output_sensitivity
from kinprop.cli import app

pytestmark = pytest.mark.filterwarnings("ignore::kinprop.SingularityWarning")

#: (fixture, outputs, design variables, wheel specs, re-solve tol, FD step)
CASES = {
    "slider_crank": (
        ["J01.q", "J03.q", "J32.q", "point:rod.mid", "hardpoint:J12.i"],
        ["J12.s_j", "J03.s_i[1]", "J12.s_i[0]"],
        None,
        1e-10,
        1e-6,
    ),
    "mcpherson": (
        ["ST.q", "TD.q", "point:wheel.wheel_centre", "hardpoint:RS.j", "camber", "toe", "caster", "kpi", "trail"],
        ["RS.s_i", "TD.s_j", "RS.length", "TD.length", "ST.s_i[2]"],
        MCPHERSON_STEER,
        1e-10,
        1e-6,
    ),
    # lengths in mm: rows are ~1e5 mm^2, so the re-solves stop at 1e-9 (rounding floor ~5e-11)
    "double_wishbone": (
        [
            "LCA.q",
            "UCA.q",
            "point:upright.wheel_centre",
            "hardpoint:UBJ.j",
            "camber",
            "toe",
            "caster",
            "kpi",
            "scrub_radius",
            "trail",
            "wheel_centre_dz",
        ],
        ["UCA.s_i", "TR.s_i", "TR.length", "LBJ.s_i[1]"],
        None,
        1e-9,
        1e-4,
    ),
}


@pytest.mark.parametrize("case", list(CASES))
def test_output_sensitivity_matches_resolve_fd(case, request):
    model = request.getfixturevalue(case)
    of, wrt, wheels, tol, h = CASES[case]
    # the oracle differences output_function, in solver units (radians, metric angles in degrees)
    D = output_sensitivity(model, of, wrt, wheels=wheels, units="solver")
    f, names = output_function(model, of, wheels=wheels)
    assert list(D.index) == names and D.shape[1] >= len(wrt)
    worst = 0.0
    for col in D.columns:
        fd = resolve_fd(model, f, col, h, tol=tol)
        err = np.abs(fd - D[col].to_numpy()) / np.maximum(1.0, np.abs(fd))
        worst = max(worst, float(err.max()))
    assert worst < 1e-6, f"{case}: max error vs re-solve FD {worst:.3g}"


def test_locked_free_set_matches_resolve_fd(double_wishbone):
    # LCA locked: the jounce is frozen, the upper arm and the upright absorb the change
    free = ("UCA.q", "LBJ.q")
    of = ["UCA.q", "camber", "toe", "point:upright.wheel_centre"]
    D = output_sensitivity(double_wishbone, of, ["UCA.s_i[2]", "TR.length"], free, units="solver")
    f, _ = output_function(double_wishbone, of)
    for col in D.columns:
        fd = resolve_fd(double_wishbone, f, col, 1e-4, free=free, tol=1e-9)
        np.testing.assert_allclose(D[col].to_numpy(), fd, rtol=1e-6, atol=1e-7)
    # the locked lower arm does not move: the wheel centre moves only by the upright's rotation
    assert "LCA.q" not in design_sensitivity(double_wishbone, ["UCA.s_i"], free).rows


def test_design_sensitivity_frame_is_labelled(slider_crank):
    S = design_sensitivity(slider_crank, ["J12.s_j"])
    frame = S.frame()
    assert isinstance(frame, pd.DataFrame)
    assert list(frame.index) == ["J01.q", "J03.q", "J32.q[0]", "J32.q[1]"]
    assert list(frame.columns) == ["J12.s_j[0]", "J12.s_j[1]", "J12.s_j[2]"]
    D = output_sensitivity(slider_crank, ["J01.q", "J03.q", "J32.q"], ["J12.s_j"])
    np.testing.assert_allclose(D.to_numpy(), frame.to_numpy(), atol=1e-9)


def test_unassembled_model_warns():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SingularityWarning)
        raw = load_model(EXAMPLES / "slider_crank.yaml")
    with pytest.warns(RuntimeWarning, match="not assembled"):
        output_sensitivity(raw, ["J01.q"], ["J12.s_j"])


runner = CliRunner()


def run(*args: str):
    return runner.invoke(app, [str(a) for a in args])


def test_cli_json_matches_api(slider_crank):
    r = run(
        "sensitivity",
        EXAMPLES / "slider_crank.yaml",
        "--wrt",
        "J12.s_j",
        "--of",
        "J01.q",
        "--of",
        "hardpoint:J12.i",
        "--json",
    )
    assert r.exit_code == 0, r.output
    obj = json.loads(r.stdout)
    assert obj["of"] == ["J01.q", "hardpoint:J12.i[x]", "hardpoint:J12.i[y]", "hardpoint:J12.i[z]"]
    assert obj["wrt"] == ["J12.s_j[0]", "J12.s_j[1]", "J12.s_j[2]"]
    assert obj["assembly"]["initial_residual"] > 1e-4  # the file is not assembled: it says so
    D = output_sensitivity(slider_crank, ["J01.q", "hardpoint:J12.i"], ["J12.s_j"]).to_numpy()
    # both report the model's units (docs/units.md): the J01.q row in deg per m, not rad per m
    assert obj["units"]["of"] == ["deg", "m", "m", "m"] and obj["units"]["wrt"] == ["m", "m", "m"]
    np.testing.assert_allclose(obj["matrix"], D, atol=1e-8)
    solver = output_sensitivity(slider_crank, ["J01.q"], ["J12.s_j"], units="solver").to_numpy()
    np.testing.assert_allclose(D[0], np.degrees(solver[0]), rtol=1e-12)
    assert abs(D[0, 0]) > 1.0  # a real number: degrees of crank per metre of pin move


def test_cli_table_and_default_outputs():
    r = run(
        "sensitivity",
        EXAMPLES / "double_wishbone.yaml",
        "--wrt",
        "UCA.s_i[2]",
        "--of",
        "camber",
        "--of",
        "metric:upright.toe",
        "--of",
        "point:upright.wheel_centre",
    )
    assert r.exit_code == 0, r.output
    for label in ("camber", "metric:upright.toe", "point:upright.wheel_centre[z]", "UCA.s_i[2]"):
        assert label in r.stdout
    r = run("sensitivity", EXAMPLES / "slider_crank.yaml", "--wrt", "J12.s_j[1]", "--json")
    assert r.exit_code == 0 and json.loads(r.stdout)["of"] == ["J01.q", "J03.q", "J32.q[0]", "J32.q[1]"]


@pytest.mark.parametrize(
    "args",
    [
        ["--wrt", "J12.bogus"],
        ["--wrt", "J99.s_i"],
        ["--wrt", "J12.s_j", "--of", "nothing.q"],
        ["--wrt", "J12.s_j", "--of", "point:rod.nowhere"],
        ["--wrt", "J12.s_j", "--weight", "J12.s_i=-1"],
        ["--wrt", "J12.s_j", "--weight", "J12.s_i"],
    ],
)
def test_cli_bad_input_exits_2(args):
    r = run("sensitivity", EXAMPLES / "slider_crank.yaml", *args)
    assert r.exit_code == 2, r.output
    assert "error" in r.stderr


def test_cli_bad_file_exits_2(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("kinprop: 1\nunits: {length: m, angle: rad}\nbodies: {}\njoints: {}\nextra: 1\n")
    assert run("sensitivity", bad, "--wrt", "s").exit_code == 2
