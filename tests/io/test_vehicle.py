"""A vehicle file (issue 20, item 4): two axle files and the parameters of the anti geometry
and the steering ratio, each axle given them in its own units."""

from __future__ import annotations

import pytest
import yaml

from kinprop.analysis.axle import steering_ratio
from kinprop.errors import ModelError
from kinprop.io.vehicle import anti_geometry, load_vehicle
from kinprop.resources import examples_dir

EXAMPLES = examples_dir()
FILE = EXAMPLES / "vehicles" / "generic_vehicle.yaml"


def _copy(tmp_path, **changes):
    data = yaml.safe_load(FILE.read_text())
    for key, value in changes.items():
        if value is None:
            data.pop(key)
        elif key == "vehicle":
            data["vehicle"] |= value
        else:
            data[key] = value
    for axle in ("front", "rear"):
        if axle in data and (FILE.parent / data[axle]).is_file():
            data[axle] = str((FILE.parent / data[axle]).resolve())
    path = tmp_path / "vehicle.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_each_axle_gets_the_vehicle_in_its_own_unit_and_metres_agree(tmp_path):
    v = load_vehicle(FILE)
    assert v.front.vehicle.axle == "front" and v.rear.vehicle.axle == "rear"
    assert v.front.vehicle.wheelbase == pytest.approx(2.8) and v.rear.vehicle.cg_height == pytest.approx(0.5)
    assert v.front.vehicle.rack_travel_per_turn == pytest.approx(0.05)
    in_m = {"wheelbase": 2.8, "cg_height": 0.5, "rack_travel_per_turn": 0.05}
    metres = load_vehicle(_copy(tmp_path, units={"length": "m"}, vehicle=in_m))
    a, b = anti_geometry(v), anti_geometry(metres)
    assert a.keys() == {"front.anti_dive", "front.anti_lift", "rear.anti_lift", "rear.anti_squat"}
    for k in a:
        assert a[k] == pytest.approx(b[k], abs=1e-9), k
    assert steering_ratio(v.front, "upright_L", "upright_R") == pytest.approx(
        steering_ratio(metres.front, "upright_L", "upright_R"), rel=1e-9
    )


def test_anti_geometry_scales_with_the_vehicles_split_wheelbase_and_cg_height(tmp_path):
    """Milliken's % anti = share x tan(theta) x L / h x 100: theta is the axle's own, so the
    percentages scale with share x L / h (a front brake share of 0.65 -> 0.5, L 2800 -> 3000,
    h 500 -> 600) and anti-squat with the rear drive share."""
    base = anti_geometry(load_vehicle(FILE))
    other = anti_geometry(load_vehicle(_copy(tmp_path, vehicle={"wheelbase": 3000, "cg_height": 600,
                                                                "brake_front": 0.5, "drive_front": 0.25})))  # fmt: skip
    k = (3000 / 600) / (2800 / 500)
    assert other["front.anti_dive"] == pytest.approx(base["front.anti_dive"] * k * 0.5 / 0.65, rel=1e-9)
    assert other["rear.anti_lift"] == pytest.approx(base["rear.anti_lift"] * k * 0.5 / 0.35, rel=1e-9)
    assert other["rear.anti_squat"] == pytest.approx(base["rear.anti_squat"] * k * 0.75, rel=1e-9)
    assert base["front.anti_lift"] == 0.0 and other["front.anti_lift"] != 0.0  # rear-wheel drive: no front anti-lift


def test_bad_vehicle_files_name_the_file_and_the_key(tmp_path):
    with pytest.raises(ModelError, match="rear"):
        load_vehicle(_copy(tmp_path, rear=None))
    with pytest.raises(ModelError, match="no axle model file"):
        load_vehicle(_copy(tmp_path, front="nowhere.yaml"))
    with pytest.raises(ModelError, match="wheelbase"):
        load_vehicle(_copy(tmp_path, vehicle={"wheelbase": -1}))
