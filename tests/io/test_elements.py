"""The ``elements:`` and ``vehicle:`` sections: both styles give the same elements (global ends
at the reference), they survive writing, converting and solving, and bad input is located."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
import yaml

import kinprop as kp
from kinprop.errors import ModelError
from kinprop.io import model_from_data
from kinprop.io.hardpoints import model_to_hardpoints
from kinprop.io.writer import dump_model

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
#: the spring's and shock's global ends in both shipped files (Chrono's HMMWV, mm)
SPRING = (np.array([104.0, 510.0, 197.0]), np.array([97.0, 543.0, -47.0]))
SHOCK_I = np.array([104.0, 498.0, 323.0])


def _global_ends(model: kp.Model, name: str) -> tuple[np.ndarray, np.ndarray]:
    e = model.element(name)
    kin = kp.compile(model).kinematics(model.design, model.coordinates)
    return tuple(kin.r[b] + kin.A[b] @ np.array(s) for b, s in ((e.body_i, e.s_i), (e.body_j, e.s_j)))  # type: ignore[return-value]


@pytest.mark.parametrize("file", ["double_wishbone.yaml", "double_wishbone_hardpoints.yaml"])
def test_both_styles_place_the_ends_at_the_published_points(file: str) -> None:
    model = kp.assemble(kp.load_model(EXAMPLES / file)).after
    p_i, p_j = _global_ends(model, "spring")
    assert np.allclose(p_i, SPRING[0], atol=1e-9) and np.allclose(p_j, SPRING[1], atol=1e-9)
    assert np.allclose(_global_ends(model, "shock")[0], SHOCK_I, atol=1e-9)
    spring, shock = model.element("spring"), model.element("shock")
    assert (spring.kind, spring.stiffness, spring.free_length, spring.has_damper) == ("spring", 167.0, 339.0, False)
    assert (shock.kind, shock.damping, shock.has_spring) == ("damper", 19.0155692, False)
    v = model.vehicle
    assert v is not None and (v.wheelbase, v.cg_height, v.brake_front, v.drive_front) == (3300, 700, 0.6, 0.5)
    assert (v.brakes, v.drive, v.axle) == ("outboard", "inboard", "front")


def test_sections_survive_writing_converting_and_propagating(tmp_path: Path) -> None:
    model = kp.load_model(EXAMPLES / "double_wishbone.yaml")
    out = tmp_path / "dw.yaml"
    dump_model(model, out)
    again = kp.load_model(out)
    assert again.elements == model.elements and again.vehicle == model.vehicle
    hp = model_from_data(model_to_hardpoints(kp.assemble(model).after))
    for name in ("spring", "shock"):
        a, b = _global_ends(hp, name), _global_ends(kp.assemble(model).after, name)
        assert np.allclose(a[0], b[0], atol=1e-9) and np.allclose(a[1], b[1], atol=1e-9)
    prop = kp.propagate(kp.assemble(model).after, {"LCA.q": [3.0]}, free=["q"])
    assert prop.after.elements == model.elements and prop.after.vehicle == model.vehicle


def test_bad_sections_are_located() -> None:
    data = yaml.safe_load((EXAMPLES / "double_wishbone.yaml").read_text())
    bad = copy.deepcopy(data)
    bad["elements"]["spring"]["bodies"] = ["chassis", "nope"]
    bad["elements"]["spring"].pop("stiffness")
    bad["elements"]["shock"]["point_i"] = [0, 0, 0]
    bad["vehicle"]["brake_front"] = 1.5
    bad["vehicle"]["axle"] = "middle"
    with pytest.raises(ModelError) as exc:
        model_from_data(bad, "dw.yaml")
    text = str(exc.value)
    for where in ("elements.spring.bodies", "elements.spring.stiffness", "elements.shock.point_i",
                  "vehicle.brake_front", "vehicle.axle"):  # fmt: skip
        assert f"dw.yaml: {where}" in text, text
    assert "unknown body 'nope'" in text
