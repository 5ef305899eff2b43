"""Sweeps a person can drive and read (issue 19 item 10): ``--out body:NAME`` gives a body's
pose in every row, ``--hold J`` holds a joint as a declared input is held.

Truth: the slider-crank's rod pose worked by hand (``A2 = C03 C32 Rz(q2) Ry(q3)``,
``r2 = s'03 + C03 [0, 0, q4]``, as tests/cli/test_outputs_cli.py), rebuilt here from the
printed yaw, pitch and roll with ``Rz Ry Rx`` written in the test; the four-bar's rocker angle
from Freudenstein's equation.
"""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pandas as pd
import pytest
from linkages import CRANK_ROCKER, freudenstein
from typer.testing import CliRunner

from kinprop import load_model
from kinprop.analysis.outputs import evaluate_outputs
from kinprop.cli import app

runner = CliRunner()

C01 = np.array([[0.0, 0, 1], [1, 0, 0], [0, 1, 0]])
C03 = C32 = np.array([[0.0, 1, 0], [0, 0, 1], [1, 0, 0]])
S03 = np.array([0.0, 3.8637, 0.0])


def run(*args: object):
    return runner.invoke(app, [str(a) for a in args])


def Rx(t: float) -> np.ndarray:
    c, s = math.cos(t), math.sin(t)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def Ry(t: float) -> np.ndarray:
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def Rz(t: float) -> np.ndarray:
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def test_body_pose_in_sweep_rows_matches_the_hand_computation(examples, tmp_path) -> None:
    path = tmp_path / "rod.csv"
    rod_ends = "distance:hardpoint:J12.j,hardpoint:J32.j"
    r = run("sweep", examples / "slider_crank.yaml", "--drive", "J01=30:60:3", "--out", "body:rod",
            "--out", rod_ends, "-o", path, "-q")  # fmt: skip
    assert r.exit_code == 0, r.output
    header = next(csv.reader(path.open()))
    pose = [f"body:rod[{c}]" for c in ("x", "y", "z", "roll", "pitch", "yaw")]
    units = ["m", "m", "m", "deg", "deg", "deg"]
    assert [f"{c} [{u}]" for c, u in zip(pose, units, strict=True)] == [h for h in header if h.startswith("body:")]
    assert f"{rod_ends} [m]" in header  # a distance has its length unit in the header (item 11)
    df = pd.read_csv(path)
    df.columns = [c.split(" [")[0] for c in df.columns]
    assert (df["status"] == "converged").all() and len(df) == 4
    for _, row in df.iterrows():
        q2, q3, q4 = math.radians(row["J32.q[0]"]), math.radians(row["J32.q[1]"]), row["J03.q"]
        A2 = C03 @ C32 @ Rz(q2) @ Ry(q3)
        r2 = S03 + C03 @ np.array([0.0, 0.0, q4])
        roll, pitch, yaw = (math.radians(row[f"body:rod[{c}]"]) for c in ("roll", "pitch", "yaw"))
        np.testing.assert_allclose(Rz(yaw) @ Ry(pitch) @ Rx(roll), A2, atol=1e-12)
        np.testing.assert_allclose([row[f"body:rod[{c}]"] for c in "xyz"], r2, atol=1e-12)
        assert -90.0 <= row["body:rod[pitch]"] <= 90.0
        assert row[rod_ends] == pytest.approx(2.828, abs=1e-9)  # |s'21|: the rod's length


def test_body_pose_angles_follow_the_model_angle_unit(examples) -> None:
    m = load_model(examples / "fourbar.yaml")  # degrees; the crank turns about the global z axis
    deg = evaluate_outputs(m, ["body:crank", "body:coupler[yaw]"])
    rad = evaluate_outputs(m, ["body:crank", "body:coupler[yaw]"], units="solver")
    theta2 = float(m.coordinates["O2"][0])
    assert rad["body:crank[yaw]"] == pytest.approx(theta2, abs=1e-14)
    assert deg["body:crank[yaw]"] == pytest.approx(math.degrees(theta2), abs=1e-12)
    assert deg["body:crank[roll]"] == pytest.approx(0.0, abs=1e-12) == deg["body:crank[pitch]"]
    assert [deg[f"body:crank[{c}]"] for c in "xyz"] == pytest.approx([0.0, 0.0, 0.0], abs=1e-15)
    theta3 = theta2 + float(m.coordinates["A"][0])
    assert rad["body:coupler[yaw]"] == pytest.approx(math.remainder(theta3, 2 * math.pi), abs=1e-14)


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (("--out", "body:nobody"), "unknown body 'nobody'"),
        (("--out", "body:crank[spin]"), "body:BODY[x|y|z|roll|pitch|yaw]"),
        (("--hold", "NOPE"), "--hold 'NOPE': unknown joint"),
        (("--hold", "B"), "--hold 'B': B has no coordinates of its own"),
    ],
)
def test_bad_body_and_hold_are_invalid_input(examples, args, says) -> None:
    r = run("sweep", examples / "fourbar.yaml", "--drive", "O2=0:10:1", *args)
    assert r.exit_code == 2, r.output
    assert says in r.output


def _without_inputs(examples, tmp_path, name: str) -> object:
    text = (examples / name).read_text()
    line = next(x for x in text.splitlines() if x.startswith("inputs:"))
    path = tmp_path / name
    path.write_text(text.replace(line, ""))
    assert load_model(path).mechanism.inputs == ()
    return path


def test_hold_keeps_the_crank_where_a_declared_input_would(examples, tmp_path) -> None:
    """Moving the rocker pivot with the crank held at 60 deg: Freudenstein's rocker angle for
    the new ground length; without --hold the least change moves the crank too."""
    path = _without_inputs(examples, tmp_path, "fourbar.yaml")
    out = tmp_path / "moved.yaml"
    change = ("--set", "O4.s_i=0.42,0,0")
    held = run("propagate", path, *change, "--hold", "O2", "--json", "-o", out)
    loose = run("propagate", path, *change, "--json")
    assert held.exit_code == 0 and loose.exit_code == 0, (held.output, loose.output)
    q = json.loads(held.stdout)["coordinates"]
    assert q["O2"][0] == pytest.approx(60.0, abs=1e-12)
    a, b, c, _ = CRANK_ROCKER
    want = math.degrees(float(freudenstein(a, b, c, 0.42, math.radians(60.0))))
    assert math.remainder(q["O4"][0] - want, 360.0) == pytest.approx(0.0, abs=1e-9)
    assert abs(json.loads(loose.stdout)["coordinates"]["O2"][0] - 60.0) > 0.1  # --hold made the difference
    assert load_model(out).mechanism.inputs == ()  # the run's hold is not written into the model


def test_hold_two_joints_in_a_sweep_as_declared_inputs(examples, tmp_path) -> None:
    """The HMMWV axle without ``inputs:``: holding the right arm and the rack while the left
    arm is driven gives the rows the file with its declared inputs gives."""
    path = _without_inputs(examples, tmp_path, "hmmwv_front_axle.yaml")
    drive, outs = ("--drive", "LCA_L=-4:4:2"), ("--out", "point:upright_L.wheel_centre", "--out", "RACK.q")
    held, declared = tmp_path / "held.csv", tmp_path / "declared.csv"
    r = run("sweep", path, *drive, *outs, "--hold", "LCA_R", "--hold", "RACK", "-o", held, "-q")
    assert r.exit_code == 0, r.output
    r = run("sweep", examples / "hmmwv_front_axle.yaml", *drive, *outs, "-o", declared, "-q")
    assert r.exit_code == 0, r.output
    a, b = pd.read_csv(held), pd.read_csv(declared)
    numbers = [c for c in a.columns if c not in ("status", "message")]
    np.testing.assert_allclose(a[numbers].to_numpy(float), b[numbers].to_numpy(float), atol=1e-9)
    start = load_model(path)
    assert a["LCA_R.q [deg]"].to_numpy() == pytest.approx(math.degrees(start.coordinates["LCA_R"][0]), abs=1e-9)
    assert a["RACK.q [mm]"].to_numpy() == pytest.approx(start.coordinates["RACK"][0], abs=1e-9)
