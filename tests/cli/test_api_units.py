"""The Python API in the model's units (issue 11, item 3; docs/units.md): each public function
given the same number as the command's option gives the same assembly, ``units="solver"`` takes
radians, results say their unit, CSV headers carry units, radian models report metric angles in
radians, and results have compact notebook reprs."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from typer.testing import CliRunner

import kinprop as kp
from kinprop.analysis.sensitivity import output_sensitivity
from kinprop.analysis.study import parse_vary, run_study
from kinprop.analysis.tolerance import monte_carlo, tolerance_analysis
from kinprop.cli import app

pytestmark = pytest.mark.filterwarnings("ignore::kinprop.SingularityWarning")
runner = CliRunner()


def cli(*args: object) -> str:
    r = runner.invoke(app, [str(a) for a in args])
    assert r.exit_code == 0, r.output
    return r.stdout


def cli_json(*args: object) -> dict:
    return json.loads(cli(*args, "--json"))


@pytest.fixture(scope="module")
def fourbar(examples) -> Path:
    return examples / "fourbar.yaml"  # units: {length: m, angle: deg}


@pytest.fixture(scope="module")
def dw_rad(examples, tmp_path_factory) -> Path:
    """examples/double_wishbone.yaml declared in radians (its only angles, LCA.q and UCA.q, are 0)."""
    data = yaml.safe_load((examples / "double_wishbone.yaml").read_text())
    assert data["units"]["angle"] == "deg" and data["joints"]["LCA"]["q"] == [0] == data["joints"]["UCA"]["q"]
    data["units"]["angle"] = "rad"
    path = tmp_path_factory.mktemp("rad") / "double_wishbone_rad.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


# --- every API function: the same number as the command ------------------------------------------


def test_propagate_degrees_is_the_cli_set(fourbar, tmp_path) -> None:
    cli("propagate", fourbar, "--set", "O2.q=70", "-o", tmp_path / "out.yaml")
    cli_after = kp.load_model(tmp_path / "out.yaml")
    m = kp.load_model(fourbar)
    prop = kp.propagate(m, {"O2.q": [70.0]})
    solver = kp.propagate(m, {"O2.q": [math.radians(70.0)]}, units="solver")
    for j in ("O2", "A", "O4"):
        np.testing.assert_allclose(prop.after.coordinates[j], cli_after.coordinates[j], atol=1e-12)
        np.testing.assert_allclose(prop.after.coordinates[j], solver.after.coordinates[j], atol=1e-12)
        np.testing.assert_allclose(prop.coordinates[j], np.degrees(prop.after.coordinates[j]), atol=1e-12)
    assert prop.units == {"length": "m", "angle": "deg"}
    assert prop.changes["O2.q"].tolist() == [70.0] and prop.coordinates["O4"][0] == pytest.approx(86.4506, abs=1e-4)
    assert prop.joint_values["O4"]["angle"] == pytest.approx(prop.coordinates["O4"][0], abs=1e-9)
    assert prop.solver_joint_values["O4"]["angle"] == pytest.approx(prop.after.coordinates["O4"][0], abs=1e-12)
    with pytest.raises(ValueError, match="units='radians'"):
        kp.propagate(m, {"O2.q": [70.0]}, units="radians")


def test_assemble_reports_model_units(fourbar) -> None:
    obj = cli_json("assemble", fourbar)
    prop = kp.assemble(kp.load_model(fourbar))
    for j, q in obj["coordinates"].items():
        np.testing.assert_allclose(prop.coordinates[j], q, atol=1e-9)
    assert prop.coordinates["O2"][0] == pytest.approx(60.0)  # the file's crank angle, degrees


def test_continuation_degrees_is_the_cli_set(fourbar) -> None:
    obj = cli_json("propagate", fourbar, "--set", "O2.q=150", "--free", "A.q", "--free", "O4.q", "--continuation")
    res = kp.propagate_continuation(kp.load_model(fourbar), {"O2.q": [150.0]}, ("A.q", "O4.q"))
    assert res.converged and obj["status"] == "converged"
    assert repr(res).startswith("<ContinuationResult converged: fraction 1,") and "set O2.q: 60 -> 150 deg" in repr(res)
    for j in ("A", "O4"):
        assert res.propagation.coordinates[j][0] == pytest.approx(obj["coordinates"][j][0], abs=1e-8)
    assert res.propagation.changes["O2.q"].tolist() == pytest.approx([150.0])


def test_sweep_changes_in_degrees_are_the_cli_set(fourbar) -> None:
    args = ("--drive", "O2=60:70:2", "--set", "O4.q=90", "--free", "A.q", "--free", "B.s_i")
    obj = cli_json("sweep", fourbar, *args)
    m = kp.load_model(fourbar)
    free = ("A.q", "B.s_i")
    res = kp.sweep(m, ["O2=60:70:2"], changes={"O4.q": [90.0]}, free=free, outputs=[])
    solver = kp.sweep(m, ["O2=60:70:2"], changes={"O4.q": [math.radians(90.0)]}, free=free, outputs=[], units="solver")
    assert res.ok and list(res.frame["O4.q"]) == pytest.approx([90.0] * 3)
    assert res.frame.attrs["column_units"] == {"O2.q": "deg", "A.q": "deg", "O4.q": "deg"}
    np.testing.assert_allclose(res.frame["A.q"], [r["A.q"] for r in obj["rows"]], atol=1e-9)
    np.testing.assert_allclose(res.frame["A.q"], solver.frame["A.q"], atol=1e-9)
    assert res.frame["A.q"].iloc[0] == pytest.approx(-34.839, abs=1e-3)


def test_output_sensitivity_is_the_cli_per_model_units(examples) -> None:
    path = examples / "double_wishbone.yaml"
    obj = cli_json("sensitivity", path, "--wrt", "TR.length", "--wrt", "UCA.C_i", "--of", "camber", "--of", "UCA.q")
    model = kp.assemble(kp.load_model(path), tol=1e-9).after
    D = output_sensitivity(model, ["camber", "UCA.q"], ["TR.length", "UCA.C_i"])
    S = output_sensitivity(model, ["camber", "UCA.q"], ["TR.length", "UCA.C_i"], units="solver")
    assert obj["units"]["of"] == ["deg", "deg"] and dict(zip(obj["wrt"], obj["units"]["wrt"], strict=True)) == {
        "UCA.C_i[0]": "deg", "UCA.C_i[1]": "deg", "UCA.C_i[2]": "deg", "TR.length": "mm",
    }  # fmt: skip
    assert obj["wrt"] == list(D.columns)
    np.testing.assert_allclose(obj["matrix"], D.to_numpy(), rtol=1e-6, atol=1e-9)
    # camber: computed in degrees, per mm either way; UCA.q: per radian -> per degree
    tr, c0 = "TR.length", "UCA.C_i[0]"
    assert D.loc["camber", tr] == pytest.approx(S.loc["camber", tr], rel=1e-12)
    assert D.loc["UCA.q", tr] == pytest.approx(math.degrees(S.loc["UCA.q", tr]), rel=1e-12)
    assert D.loc["camber", c0] == pytest.approx(math.radians(S.loc["camber", c0]), rel=1e-12)  # per degree
    assert abs(D.loc["camber", tr]) > 1e-3 and D.attrs["units"] == "model"


def test_design_sensitivity_in_model_units(examples) -> None:
    m = kp.assemble(kp.load_model(examples / "fourbar.yaml")).after
    S = kp.design_sensitivity(m, ["B.s_i"], ["A.q", "O4.q"])
    R = kp.design_sensitivity(m, ["B.s_i"], ["A.q", "O4.q"], units="solver")
    np.testing.assert_allclose(S.matrix, np.degrees(R.matrix), rtol=1e-12)
    assert S.row_units == ("deg", "deg") and S.column_units == ("m", "m", "m") and S.units == "model"
    assert np.abs(S.matrix).max() > 10.0  # degrees of rocker per metre of coupler: real numbers


def test_tolerance_monte_carlo_in_model_units(examples) -> None:
    m = kp.load_model(examples / "fourbar.yaml")  # as the command: at the file's state
    lin = tolerance_analysis(m, {"B.s_i[0]": 5e-4}, ["O4.q"])
    obj = cli_json("tolerance", examples / "fourbar.yaml", "--tolerance", "B.s_i[0]=5e-4", "--of", "O4.q")
    assert lin.output_units == ("deg",) and obj["units"]["outputs"] == ["deg"]
    assert obj["std"][0] == pytest.approx(lin.std[0], rel=1e-9) and 0.01 < lin.std[0] < 1.0
    assert obj["nominal"][0] == pytest.approx(lin.nominal[0], rel=1e-12)
    assert lin.nominal[0] == pytest.approx(82.7, abs=0.5)  # degrees (the file's O4.q), not 1.44 rad
    solver = tolerance_analysis(m, {"B.s_i[0]": 5e-4}, ["O4.q"], units="solver")
    assert lin.std[0] == pytest.approx(math.degrees(solver.std[0]), rel=1e-12)
    mc = monte_carlo(m, {"B.s_i[0]": 5e-4}, ["O4.q"], n=400, seed=1)  # degrees, like the linear std
    assert mc[0] == pytest.approx(lin.std[0], rel=0.15)


def test_targets_changes_in_degrees_are_the_cli_set(examples, tmp_path) -> None:
    path = examples / "double_wishbone.yaml"
    target, free = "metric:camber@travel=50mm=-1.5deg", ["hardpoint:UBJ"]
    cli("propagate", path, "--set", "LCA.q=2", "--target", target, "--free", free[0], "-o", tmp_path / "t.yaml")
    cli_after = kp.load_model(tmp_path / "t.yaml")
    m = kp.load_model(path)
    tp = kp.propagate_targets(m, [target], free, changes={"LCA.q": [2.0]})
    solver = kp.propagate_targets(m, [target], free, changes={"LCA.q": [math.radians(2.0)]}, units="solver")
    assert tp.converged and repr(tp).splitlines()[1] == f"  {target}: wanted -1.5, achieved -1.5 deg"
    assert "<th>achieved</th>" in tp._repr_html_() and len(repr(tp)) < 400
    np.testing.assert_allclose(tp.after.design["UBJ.s_i"], cli_after.design["UBJ.s_i"], atol=1e-6)
    np.testing.assert_allclose(tp.after.design["UBJ.s_i"], solver.after.design["UBJ.s_i"], atol=1e-9)
    assert tp.after.coordinates["LCA"][0] == pytest.approx(0.0)  # the design is reported at the model's own pose


def test_study_degrees_are_the_cli_vary(fourbar, tmp_path) -> None:
    out = tmp_path / "s"
    cli("study", fourbar, "--vary", "O2.q=60:70", "--free", "A.q", "--free", "O4.q", "--samples", "3",
        "--engine", "reference", "-o", out)  # fmt: skip
    stored = pd.read_parquet(out).sort_values("variant")
    m = kp.load_model(fourbar)
    api = run_study(m, [parse_vary("O2.q=60:70")], samples=3, free=("A.q", "O4.q"), engine="reference")
    np.testing.assert_allclose(api["O2.q"], stored["O2.q"], rtol=1e-15)
    np.testing.assert_allclose(api["O4.q"], stored["O4.q"], atol=1e-9)
    assert api["O2.q"].between(60, 70).all() and api["O4.q"].between(80, 95).all()
    free = ("A.q", "B.s_i")
    sets = run_study(m, [parse_vary("O2.q=60:70")], samples=2, free=free, sets={"O4.q": [90.0]}, engine="reference")
    assert sets["converged"].all() and np.allclose(sets["O4.q"], 90.0)  # sets in degrees too


# --- radian models report metric angles in radians (sweep, study) ----------------------------------


def test_radian_model_metrics_in_radians(examples, dw_rad, tmp_path) -> None:
    deg = kp.sweep(
        kp.load_model(examples / "double_wishbone.yaml"), ["LCA=-5:5:2"], outputs=["camber", "toe"], tol=1e-9
    )
    rad = kp.sweep(kp.load_model(dw_rad), [f"LCA={math.radians(-5)!r}:{math.radians(5)!r}:2"],
                   outputs=["camber", "toe"], tol=1e-9)  # fmt: skip
    cols = [c for c in deg.frame.columns if c.endswith(("camber", "toe"))]
    assert cols and deg.ok and rad.ok and rad.frame.attrs["column_units"][cols[0]] == "rad"
    for c in cols:
        np.testing.assert_allclose(rad.frame[c], np.radians(deg.frame[c]), rtol=1e-7, atol=1e-10)
    assert np.abs(deg.frame[cols[0]]).max() > 0.1  # degrees of camber over the travel
    np.testing.assert_allclose(rad.frame["UCA.q"], np.radians(deg.frame["UCA.q"]), atol=1e-10)
    # the command: CSV header and JSON units say rad
    cli("sweep", dw_rad, "--drive", "LCA=-0.05:0.05:2", "--out", "camber", "-o", tmp_path / "r.csv", "--tol", "1e-9")
    header = next(csv.reader((tmp_path / "r.csv").open()))
    assert "camber [rad]" in header and "LCA.q [rad]" in header and "UCA.q [rad]" in header
    # a study of the radian model stores camber in radians
    study_rad = run_study(kp.load_model(dw_rad), [parse_vary("TR.length=386:387")], samples=2, outputs=["camber"],
                          method="grid", tol=1e-9, engine="reference")  # fmt: skip
    study_deg = run_study(kp.load_model(examples / "double_wishbone.yaml"), [parse_vary("TR.length=386:387")],
                          samples=2, outputs=["camber"], method="grid", tol=1e-9, engine="reference")  # fmt: skip
    camber = [c for c in study_deg.columns if c.endswith("camber")]
    assert camber and study_deg["converged"].all()
    np.testing.assert_allclose(study_rad[camber[0]], np.radians(study_deg[camber[0]]), rtol=1e-9)


# --- CSV headers carry units ------------------------------------------------------------------------


def test_every_csv_states_units(fourbar, tmp_path) -> None:
    """Wide CSV (one column per quantity: sweep): ``NAME [unit]`` headers; long CSV (one row per
    quantity: propagate --csv): a ``unit`` column (docs/units.md)."""
    cli("sweep", fourbar, "--drive", "O2=0:10:1", "-o", tmp_path / "s.csv")
    header = next(csv.reader((tmp_path / "s.csv").open()))
    assert header[:3] == ["step", "O2.q [deg]", "status"] and "point:coupler.P[x] [m]" in header
    cli("propagate", fourbar, "--set", "O2.q=70", "--csv", tmp_path / "p.csv")
    rows = list(csv.DictReader((tmp_path / "p.csv").open()))
    assert list(rows[0]) == ["variable", "unit", "before", "after", "change", "role"]
    o2 = next(r for r in rows if r["variable"] == "O2.q")
    assert o2["unit"] == "deg" and float(o2["after"]) == 70.0


# --- notebook reprs ----------------------------------------------------------------------------------


def test_result_reprs_are_compact(fourbar) -> None:
    m = kp.load_model(fourbar)
    prop = kp.propagate(m, {"O2.q": [70.0]})
    text = repr(prop)
    assert len(text) < 600 and len(text.splitlines()) <= 10
    assert "set O2.q: 60 -> 70 deg" in text and "converged" in text
    html = prop._repr_html_()
    assert html.count("<tr>") == 4 and "<th>unit</th>" in html  # header + O2, A, O4
    res = kp.sweep(m, ["O2=0:30:3"], outputs=[])
    assert repr(res) == "<SweepResult: 4 steps (0 failed) driving O2.q 0..30 deg; 10 columns>"
    assert "<table" in res._repr_html_() and res._repr_html_().count("<tr") <= 10
    S = kp.design_sensitivity(kp.assemble(m).after, ["B.s_i"], ["A.q", "O4.q"])
    assert (
        repr(S)
        == "<Sensitivity d(free)/d(design): 2 free x 3 design columns (B.s_i[0], B.s_i[1], B.s_i[2]); model units>"
    )
    assert "<th>A.q [deg]</th>" in S._repr_html_()
    tol = tolerance_analysis(kp.assemble(m).after, {"B.s_i[0]": 5e-4}, ["O4.q"], free=("A.q", "O4.q"))
    assert repr(tol).startswith("<ToleranceResult: 1 outputs from 1 tolerances; model units>\n  O4.q: ")
    assert repr(tol).endswith(" deg") and len(repr(tol)) < 200


def test_evaluate_outputs_in_model_units(examples, dw_rad) -> None:
    """``kp.evaluate_outputs``: joint angles and angle metrics in the model's angle unit (the
    degree model's camber in degrees, the radian copy's in radians, at the same pose)."""
    deg = kp.propagate(kp.load_model(examples / "double_wishbone.yaml"), {"LCA.q": [4.0]}).after
    rad = kp.propagate(kp.load_model(dw_rad), {"LCA.q": [math.radians(4.0)]}).after
    names = ["camber", "toe", "LCA.q", "UCA.q", "scrub_radius"]
    d, r = kp.evaluate_outputs(deg, names), kp.evaluate_outputs(rad, names)
    assert d["LCA.q"] == pytest.approx(4.0, rel=1e-12) and r["LCA.q"] == pytest.approx(math.radians(4.0), rel=1e-12)
    assert abs(d["camber"]) > 0.05  # degrees of camber at 4 degrees of arm rotation
    for name in ("camber", "toe", "UCA.q"):
        assert r[name] == pytest.approx(math.radians(d[name]), rel=1e-7, abs=1e-12), name
    assert r["scrub_radius"] == pytest.approx(d["scrub_radius"], rel=1e-9)
    solver = kp.evaluate_outputs(deg, names, units="solver")
    assert solver["LCA.q"] == pytest.approx(math.radians(4.0)) and solver["camber"] == pytest.approx(d["camber"])


def test_radian_model_targets_without_a_unit_are_radians(examples, dw_rad) -> None:
    """A metric target without a unit is in the model's angle unit: in the radian copy of the
    double wishbone, ``camber@travel=50mm=-0.0261799`` is the degree model's ``-1.5``."""
    target_rad = f"camber@travel=50mm={math.radians(-1.5)!r}"
    rad = kp.propagate_targets(kp.load_model(dw_rad), [target_rad], ["hardpoint:UBJ"])
    deg = kp.propagate_targets(kp.load_model(examples / "double_wishbone.yaml"), ["camber@travel=50mm=-1.5"],
                               ["hardpoint:UBJ"])  # fmt: skip
    explicit = kp.propagate_targets(kp.load_model(dw_rad), ["camber@travel=50mm=-1.5deg"], ["hardpoint:UBJ"])
    assert rad.converged and deg.converged and explicit.converged
    np.testing.assert_allclose(rad.after.design["UBJ.s_i"], deg.after.design["UBJ.s_i"], atol=1e-9)
    np.testing.assert_allclose(explicit.after.design["UBJ.s_i"], deg.after.design["UBJ.s_i"], atol=1e-9)
    row = rad.table()[0]
    assert row["unit"] == "rad" and row["achieved"] == pytest.approx(math.radians(-1.5), abs=1e-9)
    assert deg.table()[0]["unit"] == "deg" and deg.table()[0]["achieved"] == pytest.approx(-1.5, abs=1e-7)
