"""`kinprop assemble` / `propagate`: the JSON contract, -o chaining and exit codes."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from kinprop import load_model, propagate
from kinprop.cli import app
from kinprop.propagation import assemble

runner = CliRunner()


def run(*args: str):
    return runner.invoke(app, [str(a) for a in args])


def test_propagate_json_contract(examples) -> None:
    r = run(
        "propagate",
        examples / "slider_crank.yaml",
        "--set",
        "J12.s_j=-2.8,0.2,0.1",
        "--free",
        "q",
        "--tol",
        "1e-3",
        "--json",
    )
    assert r.exit_code == 0, r.output
    obj = json.loads(r.stdout)
    assert obj["status"] == "converged"
    assert obj["iterations"] == 2
    assert isinstance(obj["residual"], float) and obj["residual"] == pytest.approx(1.26576e-05, rel=1e-5)
    assert len(obj["residual_history"]) == 3 and all(isinstance(x, float) for x in obj["residual_history"])
    assert set(obj["coordinates"]) == {"J01", "J03", "J32"}
    assert obj["coordinates"]["J01"][0] == pytest.approx(44.893707, abs=np.degrees(5e-7))  # the model unit: deg
    assert obj["units"]["angle"] == "deg" and obj["units"]["coordinates"]["J01"] == ["deg"]
    m = load_model(examples / "slider_crank.yaml")
    assert set(obj["design"]) == set(m.design)  # every design variable of the model
    for k, v in obj["design"].items():
        assert isinstance(v, float) or all(isinstance(x, float) for x in v), k
    assert obj["design"]["J12.s_j"] == [-2.8, 0.2, 0.1]


def test_json_is_exactly_one_object(examples) -> None:
    r = run("assemble", examples / "mcpherson.yaml", "--tol", "1e-3", "--json")
    assert r.exit_code == 0
    assert len(r.stdout.strip().splitlines()) == 1
    obj = json.loads(r.stdout)
    assert len(obj["coordinates"]["ST"]) == 5 and len(obj["coordinates"]["TD"]) == 1
    assert obj["design"]["RS.length"] == 0.203


def test_output_file_chains_at_full_precision(examples, tmp_path) -> None:
    """assemble -o, then propagate from the file == the in-memory chain, bit for bit."""
    out = tmp_path / "assembled.yaml"
    assert run("assemble", examples / "mcpherson.yaml", "--tol", "1e-3", "--method", "paper", "-o", out).exit_code == 0
    r = run("propagate", out, "--set", "ST.s_i=0.5,1.0,0", "--free", "s", "--free", "q", "--tol", "1e-3", "--json",
            "--method", "paper")  # fmt: skip
    assert r.exit_code == 0
    obj = json.loads(r.stdout)
    base = assemble(load_model(examples / "mcpherson.yaml"), tol=1e-3, method="paper").after
    ref = propagate(base, {"ST.s_i": [0.5, 1.0, 0.0]}, ("s", "q"), tol=1e-3, method="paper")
    assert obj["iterations"] == ref.result.iterations == 3  # the paper's Table 1, column 6
    assert obj["residual"] == ref.result.residual
    np.testing.assert_array_equal(obj["coordinates"]["ST"], ref.after.coordinates["ST"])
    np.testing.assert_array_equal(obj["design"]["RS.s_i"], ref.after.design["RS.s_i"])


def test_human_table_marks_the_change(examples) -> None:
    r = run(
        "propagate", examples / "slider_crank.yaml", "--set", "J12.s_j=-2.8,0.2,0.1", "--free", "s", "--tol", "1e-3"
    )
    assert r.exit_code == 0
    assert "J12.s_j" in r.stdout and "converged in 1 iterations" in r.stdout


def test_not_converged_exit_1(examples, tmp_path) -> None:
    out = tmp_path / "never.yaml"
    r = run(
        "propagate",
        examples / "slider_crank.yaml",
        "--set",
        "J12.s_j=-2.8,0.2,0.1",
        "--max-iter",
        "1",
        "--json",
        "-o",
        out,
    )
    assert r.exit_code == 1
    assert json.loads(r.stdout)["status"] == "not_converged"
    assert not out.exists()  # no half-baked output


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["--set", "J99.s_j=1,2,3"], "J99.s_j"),
        (["--set", "J12.s_j=1,2"], "expected 3 numbers"),
        (["--set", "J12.s_j"], "ADDRESS=VALUE"),
        (["--free", "J01.s_j"], "J01.s_j"),
        (["--free", "x"], "bad address"),
        (["--set", "J12.s_j=a,b,c"], "numbers"),
    ],
)
def test_invalid_input_exit_2(examples, args, needle) -> None:
    r = run("propagate", examples / "slider_crank.yaml", *args)
    assert r.exit_code == 2, r.output
    assert needle in r.output
    assert "Traceback" not in r.output


def test_missing_file_exit_2(tmp_path) -> None:
    r = run("assemble", tmp_path / "nope.yaml")
    assert r.exit_code == 2 and "cannot read" in r.output


def test_changed_variable_never_free(examples) -> None:
    m = load_model(examples / "slider_crank.yaml")
    p = propagate(m, {"J12.s_j": [-2.8, 0.2, 0.1]}, ("s",), tol=1e-12)
    np.testing.assert_array_equal(p.after.design["J12.s_j"], [-2.8, 0.2, 0.1])
    assert "J12.s_j" not in {k for k in p.changed_variables() if k != "J12.s_j"}
