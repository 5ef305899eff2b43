"""``kinprop vehicle FILE [--json]``: the vehicle's parameters and each axle's anti geometry,
roll centre, roll steer and camber and steering ratio, equal to the library's axle metrics
(kinprop.analysis.axle, kinprop.io.vehicle.anti_geometry); invalid files exit 2 naming the
file and the key."""

from __future__ import annotations

import json

import pytest
import yaml
from typer.testing import CliRunner

from kinprop.analysis.axle import roll_centre, roll_gradients, steering_ratio
from kinprop.analysis.drives import travel_input
from kinprop.cli import app
from kinprop.io.vehicle import anti_geometry, load_vehicle
from kinprop.resources import examples_dir

FILE = examples_dir() / "vehicles" / "generic_vehicle.yaml"


def _run(*args):
    return CliRunner().invoke(app, ["vehicle", *map(str, args)])


def test_the_json_report_equals_the_library():
    res = _run(FILE, "--json")
    assert res.exit_code == 0, res.output
    got = json.loads(res.stdout)
    car = load_vehicle(FILE)
    assert (got["wheelbase"], got["cg_height"], got["brake_front"], got["drive_front"]) == (2800, 500, 0.65, 0.0)
    assert got["units"] == {"length": "mm"} and got["rack_travel_per_turn"] == 50
    anti = anti_geometry(car)
    for axle, names in (("front", ("anti_dive", "anti_lift")), ("rear", ("anti_lift", "anti_squat"))):
        model = getattr(car, axle)
        a = got[axle]
        for n in names:
            assert a[n] == pytest.approx(anti[f"{axle}.{n}"], rel=1e-12), (axle, n)
        wheels = ("upright_L", "upright_R")
        assert a["wheels"] == {"left": "upright_L", "right": "upright_R"}
        rc = roll_centre(model, *wheels, {w: travel_input(model, w) for w in wheels})
        assert a["roll_centre_height"] == pytest.approx(rc["height"] * 1e3, rel=1e-9)  # the axles are in metres
        roll = roll_gradients(model, *wheels)
        for w in wheels:
            assert a["roll_steer"][w] == pytest.approx(roll[f"roll_steer:{w}"], rel=1e-9)
            assert a["roll_camber"][w] == pytest.approx(roll[f"roll_camber:{w}"], rel=1e-9)
    assert got["front"]["steering_ratio"] == pytest.approx(steering_ratio(car.front, "upright_L", "upright_R"))
    assert got["rear"]["steering_ratio"] is None  # no rack
    assert got["front"]["track"] == pytest.approx(2199.9993, abs=1e-6) and got["rear"]["track"] == pytest.approx(1900)
    # a production MacPherson's anti-dive and roll centre (docs/analysis/suspension.md)
    assert 0 < got["front"]["anti_dive"] < 30 and 0 < got["front"]["roll_centre_height"] < 200


def test_the_table_prints_the_same_numbers():
    res = _run(FILE)
    assert res.exit_code == 0, res.output
    got = json.loads(_run(FILE, "--json").stdout)
    for text in ("wheelbase [mm]", "2800", "anti-dive", f"{got['front']['anti_dive']:.6g}",
                 f"{got['rear']['anti_squat']:.6g}", f"{got['front']['roll_centre_height']:.6g}",
                 f"{got['front']['steering_ratio']:.4g}"):  # fmt: skip
        assert text in res.stdout, text


def test_invalid_files_exit_2_with_located_messages(tmp_path):
    bad = tmp_path / "car.yaml"
    bad.write_text(yaml.safe_dump({"kinprop": 1, "units": {"length": "mm"}, "front": "none.yaml", "rear": "none.yaml",
                                   "vehicle": {"wheelbase": -1, "cg_height": 500}}))  # fmt: skip
    res = _run(bad)
    assert res.exit_code == 2
    assert f"{bad}: vehicle.wheelbase" in res.output
    missing = tmp_path / "missing.yaml"
    missing.write_text(yaml.safe_dump({"kinprop": 1, "units": {"length": "mm"},
                                       "vehicle": {"wheelbase": 2800, "cg_height": 500},
                                       "front": "a.yaml", "rear": "b.yaml"}))  # fmt: skip
    res = _run(missing)
    assert res.exit_code == 2
    for axle in ("front", "rear"):
        assert f"{missing}: {axle}: no axle model file" in res.output
    res = _run(examples_dir() / "double_wishbone.yaml")  # a model file, not a vehicle
    assert res.exit_code == 2 and "expected a vehicle file" in res.output
    assert _run(tmp_path / "nowhere.yaml").exit_code == 2
