"""Sweeps: rows as computed (CSV / Parquet), failures recorded, interruption, CLI."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from linkages import (
    CRANK_ROCKER,
    EXAMPLES,
    freudenstein,
    load_solved,
    platform_pose,
    stewart_anchors,
    stewart_ik,
    wrap,
)
from typer.testing import CliRunner

from kinprop import AddressError, load_model
from kinprop.analysis.sweep import parse_drive, sweep
from kinprop.cli import app
from kinprop.spatial import euler_to_matrix


@pytest.fixture(scope="module")
def fourbar():
    return load_model(EXAMPLES / "fourbar.yaml")


def test_parse_drive(fourbar):
    d = parse_drive(fourbar, "O2=0:90:3")
    assert (d.joint, d.index, d.label, d.angle) == ("O2", 0, "O2.q", True)
    assert np.allclose(d.values, [0, 30, 60, 90])
    assert parse_drive(fourbar, "O2.q[0]=0:1:1").address == "O2.q[0]"
    for bad in ("O2", "O2=0:90", "O2=a:1:2", "O2=0:1:0", "X=0:1:2", "O2[1]=0:1:2", "B=0:1:2"):
        with pytest.raises(AddressError):
            parse_drive(fourbar, bad)


def test_rows_written_as_computed_csv_and_parquet(fourbar, tmp_path):
    for name in ("r.csv", "r.parquet"):
        res = sweep(fourbar, ["O2=0:120:12"], output=tmp_path / name)
        back = pd.read_csv(tmp_path / name) if name.endswith(".csv") else pd.read_parquet(tmp_path / name)
        if name.endswith(".csv"):  # the CSV header names each column's unit (docs/units.md)
            assert list(back.columns)[:3] == ["step", "O2.q [deg]", "status"]
            assert {"A.q [deg]", "point:coupler.P[x] [m]", "iterations", "message"} <= set(back.columns)
            back.columns = [c.split(" [")[0] for c in back.columns]
        assert list(back.columns) == list(res.frame.columns)
        assert len(back) == 13 and (back["status"] == "converged").all()
        num = [c for c in res.frame.columns if c not in ("status", "message", "near_singular")]
        assert np.allclose(
            back[num].to_numpy(float), res.frame[num].to_numpy(float), rtol=1e-15, atol=0, equal_nan=True
        )
    assert {"point:coupler.P[x]", "point:coupler.P[y]", "A.q", "O4.q", "sv_ratio"} <= set(res.frame.columns)
    assert res.frame["sv_ratio"].between(0.1, 1.0).all() and not res.frame["near_singular"].any()


@pytest.mark.parametrize("name", ["cut.csv", "cut.parquet"])
def test_interrupted_sweep_keeps_finished_rows(fourbar, tmp_path, name):
    def stop(k, n, row):
        if k == 5:
            raise KeyboardInterrupt

    path = tmp_path / name
    with pytest.raises(KeyboardInterrupt):
        sweep(fourbar, ["O2=0:360:360"], output=path, on_step=stop)
    back = pd.read_csv(path) if name.endswith(".csv") else pd.read_parquet(path)
    assert list(back["step"]) == [0, 1, 2, 3, 4, 5]
    assert (back["status"] == "converged").all()


def test_set_changes_apply_from_step_0(fourbar):
    """``changes`` (``--set``) re-dimension the linkage before the sweep: a longer coupler."""
    a, _, c, d = CRANK_ROCKER
    res = sweep(fourbar, ["O2=0:360:24"], changes={"B.s_i[0]": 0.46}, outputs=[], tol=1e-13)
    assert res.ok and res.last.design["B.s_i"][0] == 0.46
    err = wrap(np.radians(res.frame["O4.q"]) - freudenstein(a, 0.46, c, d, np.radians(res.frame["O2.q"])))
    assert np.degrees(np.abs(err).max()) < 1e-8
    with pytest.raises(AddressError, match="driven coordinate"):
        sweep(fourbar, ["O2=0:10:1"], changes={"O2.q": [0.1]})


def test_failed_steps_recorded_and_sweep_continues(tmp_path):
    m = load_model(EXAMPLES / "fourbar_double_rocker.yaml")
    res = sweep(m, ["O2=120:160:4"], output=tmp_path / "dr.csv", max_iter=15)
    assert list(res.frame["status"]) == ["converged", "converged", "infeasible", "infeasible", "infeasible"]
    back = pd.read_csv(tmp_path / "dr.csv")
    assert list(back["status"]) == list(res.frame["status"]) and back.loc[2:, "O4.q [deg]"].isna().all()
    assert res.n_failed == 3 and not res.ok


def test_lockstep_drives_with_free_lengths_is_inverse_kinematics():
    """Stewart platform: drive x and z of the platform together, legs free (``--free l``):
    every step's leg lengths are the closed-form inverse kinematics."""
    m = load_solved("stewart.yaml")
    a, b, legs = stewart_anchors(m)
    res = sweep(m, ["P[0]=0:0.05:5", "P[2]=0.4:0.45:5"], free=("l",), outputs=[f"{n}.length" for n in legs], tol=1e-11)
    assert res.ok
    for _, row in res.frame.iterrows():
        p = np.array([row["P.q[0]"], row["P.q[1]"], row["P.q[2]"]])
        R = euler_to_matrix([row[f"P.q[{k}]"] for k in range(3, 7)])
        assert np.abs(np.array([row[f"{n}.length"] for n in legs]) - stewart_ik(a, b, p, R)).max() < 1e-10
    assert np.allclose(platform_pose(res.last)[0], [0.05, m.coordinates["P"][1], 0.45])
    with pytest.raises(AddressError, match="same number of values"):
        sweep(m, ["P[0]=0:0.05:5", "P[2]=0.4:0.45:4"], free=("l",))


def test_cli_sweep(tmp_path):
    runner = CliRunner()
    csv, png = tmp_path / "fb.csv", tmp_path / "fb.png"
    ok = runner.invoke(
        app, ["sweep", str(EXAMPLES / "fourbar.yaml"), "--drive", "O2=0:360:36", "-o", str(csv), "--plot", str(png)]
    )
    assert ok.exit_code == 0, ok.output
    assert "37 steps: 37 converged, 0 failed" in ok.output
    assert len(pd.read_csv(csv)) == 37 and png.stat().st_size > 10_000
    bad = runner.invoke(
        app, ["sweep", str(EXAMPLES / "fourbar_double_rocker.yaml"), "--drive", "O2=120:160:4", "--max-iter", "15"]
    )
    assert bad.exit_code == 1 and "3 failed" in bad.output and "first failure at step 2" in bad.output
    invalid = runner.invoke(app, ["sweep", str(EXAMPLES / "fourbar.yaml"), "--drive", "O2=0:1"])
    assert invalid.exit_code == 2
    wrong_suffix = runner.invoke(
        app, ["sweep", str(EXAMPLES / "fourbar.yaml"), "--drive", "O2=0:1:1", "-o", str(tmp_path / "x.txt")]
    )
    assert wrong_suffix.exit_code == 2


def test_cli_baseline_plot_and_json(tmp_path) -> None:
    """--baseline sweeps the design without --set too and draws both on one figure; --json."""
    import json as _json

    from typer.testing import CliRunner

    from kinprop.cli import app

    png = tmp_path / "before_after.png"
    r = CliRunner().invoke(
        app,
        [
            "sweep", str(EXAMPLES / "fourbar.yaml"), "--drive", "O2=0:90:6", "--set", "B.s_i[0]=0.42",
            "--baseline", "--plot", str(png), "--json",
        ],
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    obj = _json.loads(r.stdout)
    assert obj["steps"] == 7 and obj["converged"] == 7 and obj["failed"] == []
    assert len(obj["rows"]) == 7 and len(obj["baseline_rows"]) == 7
    # the change moved the rocker: after differs from before at the same crank angle
    col = next(c for c in obj["rows"][0] if c.startswith("O4.q"))
    assert abs(obj["rows"][3][col] - obj["baseline_rows"][3][col]) > 1e-3
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    bad = CliRunner().invoke(app, ["sweep", str(EXAMPLES / "fourbar.yaml"), "--drive", "O2=0:90:6", "--baseline"])
    assert bad.exit_code == 2 and "--set" in bad.output
