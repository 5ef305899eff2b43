"""One unit convention (issue 11, item 3; docs/units.md): every number a user gives or reads is
in the model's declared units. Each command is checked against the library given the same
numbers (the Python API takes and returns the model's units too) and against the library in
solver units (``units="solver"``, radians) converted by hand."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest
from cli_run import run_kinprop

import kinprop as kp
from kinprop.analysis.sensitivity import design_sensitivity
from kinprop.analysis.tolerance import tolerance_analysis
from kinprop.analysis.units import derivative_scale, unit_of
from kinprop.engine.units import changes_to_internal, from_solver_units, to_solver_units


def _json(*args) -> dict:
    p = run_kinprop(*args)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout)


def test_conversions(examples) -> None:
    m = kp.load_model(examples / "slider_crank.yaml")  # deg; J01 revolute, J03 slide, J32 universal
    assert to_solver_units(m, "J01.q", [45.0]).tolist() == [math.radians(45.0)]
    assert to_solver_units(m, "J03.q", [0.5]).tolist() == [0.5]
    assert to_solver_units(m, "J32.q[1]", 90.0) == pytest.approx(math.pi / 2)
    assert to_solver_units(m, "J12.s_j", [1.0, 2.0, 3.0]).tolist() == [1.0, 2.0, 3.0]
    for addr, v in (("J32.q", [10.0, -20.0]), ("J01.q", [45.0]), ("J12.s_j", [1, 2, 3])):
        np.testing.assert_allclose(from_solver_units(m, addr, to_solver_units(m, addr, v)), v, rtol=1e-15)
    assert [unit_of(m, a) for a in ("J01.q", "J03.q", "J32.q[0]", "J12.s_j[1]", "J01.C_i", "point:rod.x")] == [
        "deg", "m", "deg", "m", "", "m",
    ]  # fmt: skip
    assert derivative_scale(m, "J01.q") == pytest.approx(180 / math.pi) and derivative_scale(m, "J03.q") == 1.0
    rad = kp.load_model(examples / "fourbar.yaml")
    assert unit_of(kp.load_model(examples / "bennett.yaml"), "metric:x.camber") in ("deg", "rad")
    assert changes_to_internal(rad, {"O2.q": [70.0]})["O2.q"].tolist() == [math.radians(70.0)]


def test_tolerance_sigma_in_degrees(examples) -> None:
    """--tolerance LCA.q=1 on a degree model is one degree: camber std 0.21 deg (it read 1 rad,
    11.9 deg, before). Reference: the library with the sigma in radians."""
    path = examples / "double_wishbone.yaml"
    obj = _json("tolerance", path, "--tolerance", "LCA.q=1", "--of", "camber", "--of", "UCA.q", "--json")
    m = kp.load_model(path)
    api = tolerance_analysis(m, {"LCA.q": 1.0}, ["camber", "UCA.q"])  # the same number: one degree
    ref = tolerance_analysis(m, {"LCA.q": math.radians(1.0)}, ["camber", "UCA.q"], units="solver")
    assert obj["units"]["outputs"] == ["deg", "deg"] and obj["units"]["inputs"] == ["deg"]
    assert list(api.output_units) == ["deg", "deg"] and list(api.input_units) == ["deg"]
    assert obj["sigma"] == pytest.approx([1.0]) and api.sigma.tolist() == pytest.approx([1.0])
    assert obj["std"][0] == pytest.approx(ref.std[0], rel=1e-9) and obj["std"][0] == pytest.approx(0.2083, abs=1e-4)
    assert obj["std"][1] == pytest.approx(math.degrees(ref.std[1]), rel=1e-9)  # a coordinate: rad -> deg
    assert obj["nominal"][1] == pytest.approx(math.degrees(ref.nominal[1]), abs=1e-9)
    np.testing.assert_allclose(obj["std"], api.std, rtol=1e-9)
    np.testing.assert_allclose(obj["nominal"], api.nominal, rtol=1e-9, atol=1e-12)


def test_propagate_json_in_model_units(examples) -> None:
    path = examples / "fourbar.yaml"
    obj = _json("propagate", path, "--set", "O2.q=70", "--json")
    api = kp.propagate(kp.load_model(path), {"O2.q": [70.0]})  # the same number: 70 degrees
    ref = kp.propagate(kp.load_model(path), {"O2.q": [math.radians(70.0)]}, units="solver")
    assert obj["coordinates"]["O2"] == [70.0] and obj["changes"] == {"O2.q": [70.0]}
    assert obj["coordinates"]["O4"][0] == pytest.approx(math.degrees(ref.after.coordinates["O4"][0]), abs=1e-9)
    assert obj["coordinates"]["O4"][0] == pytest.approx(api.coordinates["O4"][0], abs=1e-9)
    assert obj["coordinates"]["O4"][0] == pytest.approx(86.4506, abs=1e-4)
    assert api.changes["O2.q"].tolist() == [70.0] and api.solver_changes["O2.q"].tolist() == [math.radians(70.0)]
    assert obj["units"]["coordinates"]["O4"] == ["deg"]


def test_sensitivity_per_model_units(examples) -> None:
    path = examples / "slider_crank.yaml"
    obj = _json("sensitivity", path, "--wrt", "J12.s_j", "--wrt", "J01.C_i", "--json")
    model = kp.assemble(kp.load_model(path)).after
    api = design_sensitivity(model, ["J12.s_j", "J01.C_i"])  # the model's units, like the command
    ref = design_sensitivity(model, ["J12.s_j", "J01.C_i"], units="solver")
    assert obj["of"] == ref.rows and obj["wrt"] == ref.columns
    assert obj["units"]["of"] == ["deg", "m", "deg", "deg"] and obj["units"]["wrt"][:3] == ["m", "m", "m"]
    assert list(api.row_units) == obj["units"]["of"] and list(api.column_units[:3]) == ["m", "m", "m"]
    D = np.array(obj["matrix"])
    np.testing.assert_allclose(D, api.matrix, rtol=1e-9, atol=1e-12)
    deg = 180 / math.pi
    np.testing.assert_allclose(D[0, :3], ref.matrix[0, :3] * deg, rtol=1e-9, atol=1e-12)  # deg per m
    np.testing.assert_allclose(D[1, :3], ref.matrix[1, :3], rtol=1e-9, atol=1e-12)  # m per m
    np.testing.assert_allclose(D[0, 3:], ref.matrix[0, 3:], rtol=1e-9, atol=1e-12)  # deg per deg = rad per rad
    np.testing.assert_allclose(D[1, 3:], ref.matrix[1, 3:] / deg, rtol=1e-9, atol=1e-12)  # m per deg


def test_study_stores_model_units(examples, tmp_path) -> None:
    path, out = examples / "fourbar.yaml", tmp_path / "s"
    p = run_kinprop("study", path, "--vary", "O2.q=60:70", "--free", "A.q", "--free", "O4.q", "--samples", "4",
                    "--engine", "reference", "-o", out)  # fmt: skip
    assert p.returncode == 0, p.stderr
    df = pd.read_parquet(out).sort_values("variant")
    assert df["O2.q"].between(60, 70).all()
    m = kp.load_model(path)
    for _, row in df.iterrows():
        api = kp.propagate(m, {"O2.q": [row["O2.q"]]}, free=["A.q", "O4.q"])  # degrees, as stored
        ref = kp.propagate(m, {"O2.q": [math.radians(row["O2.q"])]}, free=["A.q", "O4.q"], units="solver")
        assert row["O4.q"] == pytest.approx(math.degrees(ref.after.coordinates["O4"][0]), abs=1e-8)
        assert row["O4.q"] == pytest.approx(api.coordinates["O4"][0], abs=1e-8)


def test_sweep_json_states_units(examples) -> None:
    obj = _json("sweep", examples / "fourbar.yaml", "--drive", "O2=0:30:3", "--json")
    assert obj["units"]["O2.q"] == "deg" and obj["units"]["point:coupler.P[x]"] == "m"
    assert [r["O2.q"] for r in obj["rows"]] == [0.0, 10.0, 20.0, 30.0]
