"""Project Chrono suspension templates (examples/chrono/): import, mobility, wheel metrics.

Truth: the HMMWV front double wishbone's camber/toe/wheel-travel curve from an independent
construction on the JSON hardpoints (two 1-D root finds, as tests/analysis/test_double_wishbone.py
does for the inch hardpoints); the metrics' definitions at the reference (toe and camber of
the file's spin axis, caster/KPI of the ball-joint axis); Chrono's file values (a camber or
toe angle in the file tilts the spin axis as Chrono's spindle is tilted).
"""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest
from imports_helpers import CHRONO
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation
from typer.testing import CliRunner

import kinprop as kp
from kinprop.analysis.metrics import camber_toe, steering_angles
from kinprop.cli import app
from kinprop.imports.chrono import chrono_hardpoints
from kinprop.io.hardpoints import model_from_hardpoints

runner = CliRunner()
TEMPLATES = {"DoubleWishbone": "LCA", "MacPhersonStrut": "LCA", "MultiLink": "UA", "HMMWV_DoubleWishboneFront": "LCA"}


def _sweep(model, driver, steps="-6:6:6", outputs=("wheel_centre_dz", "camber", "toe")):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", kp.SingularityWarning)
        return kp.sweep(model, [f"{driver}={steps}"], outputs=list(outputs), tol=1e-12).frame


@pytest.mark.parametrize("name", list(TEMPLATES))
def test_template_imports_with_mobility_one_and_sweeps(name: str) -> None:
    model = kp.load_model(CHRONO / f"{name}.json")
    rep = kp.mobility(model)
    assert (rep.mobility, rep.gruebler, rep.redundant) == (1, 1, [])
    assert kp.assemble(model).result.residual < 1e-14  # the hardpoints are the assembly
    df = _sweep(model, TEMPLATES[name])
    assert (df["status"] == "converged").all()
    dz = df["wheel_centre_dz"].to_numpy()
    assert np.all(np.diff(dz) * np.sign(dz[-1] - dz[0]) > 0) and np.ptp(dz) > 0.05  # > 5 cm of travel
    assert df["camber"].abs().max() > 0.2  # the wheel really cambers through the travel
    # at the reference the file's zero camber/toe come back
    ref = kp.evaluate_outputs(model, ["camber", "toe", "wheel_centre_dz"])
    assert max(abs(v) for v in ref.values()) < 1e-14


def hmmwv_closed(theta: float, hp: dict[str, np.ndarray]) -> tuple[float, float, float]:
    """Lower-arm angle -> (wheel travel, camber, toe), built without kinprop's solver."""

    def rotate(p, origin, axis, angle):
        return origin + Rotation.from_rotvec(angle * axis / np.linalg.norm(axis)).apply(p - origin)

    lbj = rotate(hp["LCA_U"], hp["LCA_B"], hp["LCA_F"] - hp["LCA_B"], theta)
    r_kp = np.linalg.norm(hp["UCA_U"] - hp["LCA_U"])
    uca_axis = hp["UCA_F"] - hp["UCA_B"]
    phi = brentq(lambda a: np.linalg.norm(rotate(hp["UCA_U"], hp["UCA_B"], uca_axis, a) - lbj) - r_kp, -0.6, 0.6)
    ubj = rotate(hp["UCA_U"], hp["UCA_B"], uca_axis, phi)
    k0, k1 = hp["UCA_U"] - hp["LCA_U"], ubj - lbj
    R0 = Rotation.align_vectors([k1], [k0])[0]
    l_tr = np.linalg.norm(hp["TIEROD_U"] - hp["TIEROD_C"])

    def pose(psi):
        return Rotation.from_rotvec(psi * k1 / np.linalg.norm(k1)) * R0

    psi = brentq(
        lambda s: np.linalg.norm(lbj + pose(s).apply(hp["TIEROD_U"] - hp["LCA_U"]) - hp["TIEROD_C"]) - l_tr, -0.5, 0.5
    )
    R = pose(psi)
    centre = lbj + R.apply(hp["SPINDLE"] - hp["LCA_U"])
    camber, toe = camber_toe(R.apply([0.0, 1.0, 0.0]))
    return centre[2] - hp["SPINDLE"][2], camber, toe


def test_hmmwv_curves_match_an_independent_construction() -> None:
    data = json.loads((CHRONO / "HMMWV_DoubleWishboneFront.json").read_text())
    hp = {
        "SPINDLE": data["Spindle"]["COM"],
        "TIEROD_C": data["Tierod"]["Location Chassis"],
        "TIEROD_U": data["Tierod"]["Location Upright"],
    }
    for arm, key in (("Upper Control Arm", "UCA"), ("Lower Control Arm", "LCA")):
        for loc, tag in (("Chassis Front", "F"), ("Chassis Back", "B"), ("Upright", "U")):
            hp[f"{key}_{tag}"] = data[arm][f"Location {loc}"]
    hp = {k: np.array(v, dtype=float) for k, v in hp.items()}
    df = _sweep(kp.load_model(CHRONO / "HMMWV_DoubleWishboneFront.json"), "LCA", "-7:7:7")
    for _, row in df.iterrows():
        dz, camber, toe = hmmwv_closed(math.radians(row["LCA.q"]), hp)
        assert row["wheel_centre_dz"] == pytest.approx(dz, abs=1e-10)
        assert row["camber"] == pytest.approx(camber, abs=1e-8)
        assert row["toe"] == pytest.approx(toe, abs=1e-8)
    assert np.all(np.diff(df["camber"]) < 0)  # camber gain: more negative in bump


def test_steering_metrics_and_scrub_with_a_tyre_radius() -> None:
    data = json.loads((CHRONO / "HMMWV_DoubleWishboneFront.json").read_text())
    hp, notes = chrono_hardpoints(data, "hmmwv.json", tire_radius=0.47)
    model = model_from_hardpoints(hp, "hmmwv.json")
    out = kp.evaluate_outputs(model, ["caster", "kpi", "scrub_radius", "trail"])
    upper = np.array(data["Upper Control Arm"]["Location Upright"])
    lower = np.array(data["Lower Control Arm"]["Location Upright"])
    caster, kpi = steering_angles(upper, lower, 1)
    assert out["caster"] == pytest.approx(caster, abs=1e-12) and out["kpi"] == pytest.approx(kpi, abs=1e-12)
    # ground point of the kingpin axis, 0.47 m below the wheel centre, against the contact point
    centre = np.array(data["Spindle"]["COM"])
    ground_z = centre[2] - 0.47
    k = upper - lower
    g = lower + k * (ground_z - lower[2]) / k[2]
    assert out["scrub_radius"] == pytest.approx(centre[1] - g[1], abs=1e-12)
    assert out["trail"] == pytest.approx(g[0] - centre[0], abs=1e-12)
    assert not any("tire" in n for n in notes)


def test_file_camber_and_toe_tilt_the_spin_axis_as_chrono_does() -> None:
    data = json.loads((CHRONO / "MacPhersonStrut.json").read_text())
    data["Camber Angle (deg)"], data["Toe Angle (deg)"] = -1.5, 0.25
    hp, _ = chrono_hardpoints(data, "mp.json")
    out = kp.evaluate_outputs(model_from_hardpoints(hp, "mp.json"), ["camber", "toe"])
    # Chrono: positive camber tilts the wheel top outboard; positive toe is toe-in (ISO 8855)
    assert out["camber"] == pytest.approx(-1.5, abs=1e-12) and out["toe"] == pytest.approx(0.25, abs=1e-12)


def test_spring_length_is_an_output_not_a_constraint() -> None:
    model = kp.load_model(CHRONO / "DoubleWishbone.json")
    name = "distance:chassis.spring_chassis,lca.spring_lca"
    data = json.loads((CHRONO / "DoubleWishbone.json").read_text())
    free = np.linalg.norm(np.subtract(data["Spring"]["Location Chassis"], data["Spring"]["Location Arm"]))
    df = _sweep(model, "LCA", "-6:6:4", outputs=[name, "wheel_centre_dz"])
    mid = df.iloc[2]
    assert mid[name] == pytest.approx(free, abs=1e-12)
    assert np.all(np.diff(df[name]) < 0)  # bump compresses the spring


def test_two_commands_plot_and_sensitivity_table(tmp_path) -> None:
    model_file = tmp_path / "dw.yaml"
    r = runner.invoke(app, ["import", str(CHRONO / "DoubleWishbone.json"), "-o", str(model_file)])
    assert r.exit_code == 0, r.output
    assert "note:" in r.output and "LCA.q" in r.output
    r = runner.invoke(app, ["check", str(model_file), "--json"])
    assert r.exit_code == 0 and json.loads(r.stdout)["mobility"] == 1
    png = tmp_path / "camber_toe.png"
    r = runner.invoke(
        app,
        [
            "sweep",
            str(CHRONO / "DoubleWishbone.json"),
            "--drive",
            "LCA=-8:8:16",
            "--out",
            "camber",
            "--out",
            "toe",
            "--out",
            "wheel_centre_dz",
            "--x",
            "wheel_centre_dz",
            "--plot",
            str(png),
            "--tol",
            "1e-10",
        ],
    )
    assert r.exit_code == 0, r.output
    assert png.stat().st_size > 10_000
    r = runner.invoke(
        app,
        [
            "sensitivity",
            str(model_file),
            "--wrt",
            "UCA_U.s_j",
            "--wrt",
            "TIEROD.s_j",
            "--of",
            "camber",
            "--of",
            "toe",
            "--free",
            "UCA.q",
            "--free",
            "LCA_U.q",
            "--json",
        ],
    )
    assert r.exit_code == 0, r.output
    obj = json.loads(r.stdout)
    S = np.array(obj["matrix"])
    assert S.shape == (2, 6) and np.abs(S).max() > 1.0
    # each column against central differences of re-assembled models (propagate, same free set)
    model = kp.load_model(model_file)
    h = 1e-6
    for k, col in enumerate(obj["wrt"]):
        joint, field = col.split(".")[0], col.split(".")[1].split("[")[0]
        idx = int(col.split("[")[1].rstrip("]"))
        vals = []
        for sgn in (1, -1):
            v = np.array(model.design[f"{joint}.{field}"], dtype=float)
            v[idx] += sgn * h
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", kp.SingularityWarning)
                p = kp.propagate(model, {f"{joint}.{field}": v}, ["UCA.q", "LCA_U.q"], tol=1e-13)
            assert p.converged
            vals.append(np.array(list(kp.evaluate_outputs(p.after, ["camber", "toe"]).values())))
        fd = (vals[0] - vals[1]) / (2 * h)
        assert np.allclose(S[:, k], fd, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("name", list(TEMPLATES))
def test_cli_import_assemble_and_sweep(tmp_path, name: str) -> None:
    out = tmp_path / "s.yaml"
    r = runner.invoke(app, ["import", str(CHRONO / f"{name}.json"), "-o", str(out)])
    assert r.exit_code == 0, r.output
    r = runner.invoke(app, ["assemble", str(out), "-o", str(tmp_path / "a.yaml")])
    assert r.exit_code == 0, r.output
    r = runner.invoke(
        app, ["sweep", str(out), "--drive", f"{TEMPLATES[name]}=-5:5:4", "--out", "camber", "--out", "toe", "--json"]
    )
    assert r.exit_code == 0, r.output
    obj = json.loads(r.stdout)
    rows = obj["rows"]
    assert len(rows) == 5 and all(row["status"] == "converged" for row in rows)
    assert abs(rows[2]["camber"]) < 1e-9 and abs(rows[0]["camber"] - rows[-1]["camber"]) > 0.1


def test_hmmwv_json_agrees_with_the_hand_written_example() -> None:
    """The same suspension from two sources: examples/double_wishbone.yaml (Chrono's inch
    hardpoints, mm) and Chrono's JSON (metres, rounded to 1 mm). Camber and toe against wheel
    travel agree to what the rounding moves them (measured 0.031 and 0.048 deg over +-50 mm)."""
    from imports_helpers import EXAMPLES

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", kp.SingularityWarning)
        hand = kp.assemble(kp.load_model(EXAMPLES / "double_wishbone.yaml"), tol=1e-9).after
        a = kp.sweep(hand, ["LCA=-6:6:24"], outputs=["wheel_centre_dz", "camber", "toe"], tol=1e-9).frame
    b = _sweep(kp.load_model(CHRONO / "HMMWV_DoubleWishboneFront.json"), "LCA", "-6:6:24")
    x = np.linspace(-50.0, 50.0, 21)  # mm of wheel travel
    for k in ("camber", "toe"):
        ours = np.interp(x, b["wheel_centre_dz"] * 1000.0, b[k])
        theirs = np.interp(x, a["wheel_centre_dz"], a[k])
        assert np.abs(ours - theirs).max() < 0.06
        assert np.ptp(theirs) > 0.5  # the curves are not flat: the agreement means something


def test_distance_output_ends_and_errors() -> None:
    model = kp.load_model(CHRONO / "DoubleWishbone.json")
    data = json.loads((CHRONO / "DoubleWishbone.json").read_text())
    out = kp.evaluate_outputs(model, ["distance:chassis.spring_chassis,hardpoint:TIEROD.j"])
    expected = np.linalg.norm(np.subtract(data["Spring"]["Location Chassis"], data["Tierod"]["Location Upright"]))
    assert out["distance:chassis.spring_chassis,hardpoint:TIEROD.j"] == pytest.approx(expected, abs=1e-15)
    for bad, msg in (
        ("distance:chassis.nope,lca.spring_lca", "has no named point 'nope'"),
        ("distance:chassis.spring_chassis", "expected distance:BODY.NAME,BODY.NAME"),
    ):
        with pytest.raises(kp.AddressError, match=msg):
            kp.evaluate_outputs(model, [bad])
