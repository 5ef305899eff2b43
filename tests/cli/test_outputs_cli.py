"""`assemble`/`propagate` outputs people reuse: --csv before/after and the JSON hardpoints.

The hardpoints are checked against the slider-crank worked by hand (PAPER-NOTES): crank pin
``P = s'01 + A1 s'12`` with ``A1 = C01 Rz(q1)``; rod end ``r2 + A2 s'21`` with
``r2 = r3 = s'03 + C03 [0, 0, q4]``, ``A2 = C03 C32 Rz(q2) Ry(q3)``.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from kinprop import load_model, propagate
from kinprop.analysis.points import joint_hardpoints, named_points
from kinprop.cli import app
from kinprop.io.results import comparison_rows

runner = CliRunner()
SET = "J12.s_j=-2.8,0.2,0.1"


def run(*args: object):
    return runner.invoke(app, [str(a) for a in args])


def Rz(t: float) -> np.ndarray:
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def Ry(t: float) -> np.ndarray:
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


C01 = np.array([[0.0, 0, 1], [1, 0, 0], [0, 1, 0]])
C03 = C32 = np.array([[0.0, 1, 0], [0, 0, 1], [1, 0, 0]])
S03 = np.array([0.0, 3.8637, 0.0])


def slider_crank_by_hand(q: dict[str, list[float]], s21: list[float]) -> dict[str, np.ndarray]:
    (q1,), (q4,), (q2, q3) = q["J01"], q["J03"], q["J32"]
    A1 = C01 @ Rz(q1)
    r3 = S03 + C03 @ np.array([0.0, 0.0, q4])
    A2 = C03 @ C32 @ Rz(q2) @ Ry(q3)
    return {
        "J01.i": np.zeros(3),
        "J01.j": np.zeros(3),
        "J03.i": S03,
        "J03.j": r3,
        "J32.i": r3,
        "J32.j": r3,
        "J12.i": A1 @ np.array([2.0, 0.0, 0.0]),
        "J12.j": r3 + A2 @ np.asarray(s21),
    }


def test_json_hardpoints_match_hand_computation(examples) -> None:
    r = run("propagate", examples / "slider_crank.yaml", "--set", SET, "--json")
    assert r.exit_code == 0, r.output
    obj = json.loads(r.stdout)
    hp = obj["hardpoints"]
    assert list(hp) == ["J01.i", "J01.j", "J03.i", "J03.j", "J32.i", "J32.j", "J12.i", "J12.j"]
    # JSON is in the model's units (docs/units.md): the angles in degrees, as obj["units"] says
    units = obj["units"]["coordinates"]
    rad = {
        j: [math.radians(x) if u == "deg" else x for x, u in zip(v, units[j], strict=True)]
        for j, v in obj["coordinates"].items()
    }
    assert units == {"J01": ["deg"], "J03": ["m"], "J32": ["deg", "deg"]}
    want = slider_crank_by_hand(rad, [-2.8, 0.2, 0.1])
    for key, v in want.items():
        assert len(hp[key]) == 3 and all(isinstance(x, float) for x in hp[key])
        np.testing.assert_allclose(hp[key], v, atol=1e-12, err_msg=key)
    # assembled: the cut spherical joint's two points coincide
    np.testing.assert_allclose(hp["J12.i"], hp["J12.j"], atol=1e-9)
    assert obj["points"] == {}


def test_assemble_json_hardpoints_mcpherson(examples) -> None:
    """T-D: the rack origin on the chassis without the q3 slide, r1 + s'12TD (A1 = I)."""
    r = run("assemble", examples / "mcpherson.yaml", "--json")
    assert r.exit_code == 0, r.output
    obj = json.loads(r.stdout)
    hp = obj["hardpoints"]
    r1 = np.array([0.0, 0.0, 0.55])
    np.testing.assert_allclose(hp["TD.i"], r1 + [0, 1.2675, -0.3748], atol=1e-15)
    np.testing.assert_allclose(hp["ST.i"], r1 + [0.5011, 1.1162, 0.1998], atol=1e-15)
    np.testing.assert_allclose(hp["RS.i"], r1 + [0.33, 1.1735, -0.3923], atol=1e-15)
    # the links have their lengths at the assembled state; the tie rod starts at the slid rack end
    assert np.linalg.norm(np.subtract(hp["RS.j"], hp["RS.i"])) == pytest.approx(0.203, abs=1e-9)
    rack_end = np.array(hp["TD.i"]) + np.array([1.0, 0.0, 0.0]) * obj["coordinates"]["TD"][0]  # C12TD e_z = x
    assert np.linalg.norm(np.array(hp["TD.j"]) - rack_end) == pytest.approx(0.3742, abs=1e-9)


def test_named_points_in_json(examples) -> None:
    r = run("assemble", examples / "bennett.yaml", "--json")
    assert r.exit_code == 0, r.output
    obj = json.loads(r.stdout)
    m = load_model(examples / "bennett.yaml")
    after = propagate(m, {}).after
    assert set(obj["points"]) == {"link2.M"}
    np.testing.assert_allclose(obj["points"]["link2.M"], named_points(after)["link2.M"], atol=1e-12)
    want = joint_hardpoints(after)
    assert list(obj["hardpoints"]) == list(want)
    for k, v in want.items():
        np.testing.assert_allclose(obj["hardpoints"][k], v, atol=1e-12, err_msg=k)


def test_csv_before_after(examples, tmp_path) -> None:
    csv = tmp_path / "sc.csv"  # the directory must exist: outputs never create one (issue 11)
    r = run("propagate", examples / "slider_crank.yaml", "--set", SET, "--csv", csv, "--json")
    assert r.exit_code == 0, r.output
    obj = json.loads(r.stdout)  # --csv keeps stdout one JSON object
    df = pd.read_csv(csv, keep_default_na=False)
    assert list(df.columns) == ["variable", "unit", "before", "after", "change", "role"]
    rows = df.set_index("variable")
    # the change that was set, the coordinates the solver moved (angles in degrees)
    assert rows.loc["J12.s_j[0]", "before"] == -2.828 and rows.loc["J12.s_j[0]", "after"] == -2.8
    assert rows.loc["J12.s_j[1]", "role"] == "set"
    assert rows.loc["J01.q", "unit"] == "deg" and rows.loc["J01.q", "before"] == pytest.approx(45.0)
    assert rows.loc["J01.q", "after"] == obj["coordinates"]["J01"][0]  # both in the model's degrees
    assert rows.loc["J01.q", "role"] == "moved"
    np.testing.assert_allclose(df["change"], df["after"] - df["before"], atol=1e-12)
    # the variable rows are exactly comparison_rows, at full precision
    m = load_model(examples / "slider_crank.yaml")
    ref = comparison_rows(propagate(m, {"J12.s_j": [-2.8, 0.2, 0.1]}))
    head = df.iloc[: len(ref)]
    assert list(head["variable"]) == [x["variable"] for x in ref]
    assert list(head["after"]) == [x["after"] for x in ref]
    # then the hardpoints, in the model's length unit
    for axis, k in zip("xyz", range(3), strict=True):
        row = rows.loc[f"hardpoint:J12.i[{axis}]"]
        assert row["unit"] == "m" and row["role"] == "hardpoint"
        assert row["after"] == obj["hardpoints"]["J12.i"][k]
    assert rows.loc["hardpoint:J03.i[y]", "change"] == 0.0


def test_csv_and_human_output(examples, tmp_path) -> None:
    csv = tmp_path / "a.csv"
    r = run("assemble", examples / "mcpherson.yaml", "--csv", csv)
    assert r.exit_code == 0, r.output
    assert "wrote" in r.stdout and csv.name in r.stdout
    df = pd.read_csv(csv, keep_default_na=False)
    assert "ST.q[4]" in set(df["variable"]) and "hardpoint:TD.j[z]" in set(df["variable"])


def test_nothing_written_when_not_converged(examples, tmp_path) -> None:
    csv, png = tmp_path / "x.csv", tmp_path / "x.png"
    r = run("assemble", examples / "mcpherson.yaml", "--max-iter", "1", "--csv", csv, "--plot", png)
    assert r.exit_code == 1
    assert not csv.exists() and not png.exists()
    assert "not writing" in r.output
