"""The ``loads:`` section: both styles, written back and converted, bad input located, and
loads that do not depend on the unit the file is written in (the double wishbone in mm and
the same model written in m: forces equal, moments and torques scaled by the length unit)."""

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


def _in_metres(data: dict) -> dict:
    """The double wishbone file with every length in m (mm / 1000; stiffness and damping in N/m)."""
    d = copy.deepcopy(data)
    d["units"]["length"] = "m"

    def v(x):
        return [c / 1000.0 for c in x]

    for b in d["bodies"].values():
        if "position" in b:
            b["position"] = v(b["position"])
        b["points"] = {k: v(p) for k, p in b.get("points", {}).items()}
    for j in d["joints"].values():
        for key in ("s_i", "s_j"):
            if key in j:
                j[key] = v(j[key])
        if "length" in j:
            j["length"] /= 1000.0
    for e in d["elements"].values():
        e["s_i"], e["s_j"] = v(e["s_i"]), v(e["s_j"])
        for key in ("stiffness", "damping"):
            if key in e:
                e[key] *= 1000.0
        if "free_length" in e:
            e["free_length"] /= 1000.0
    d["vehicle"]["wheelbase"] /= 1000.0
    d["vehicle"]["cg_height"] /= 1000.0
    for m in d["loads"]["masses"].values():
        if not isinstance(m["cm"], str):
            m["cm"] = v(m["cm"])
    return d


@pytest.mark.parametrize("case", ["bump_3g", "braking_1g", "cornering_1g"])
def test_loads_do_not_depend_on_the_file_unit(case: str) -> None:
    data = yaml.safe_load((EXAMPLES / "double_wishbone.yaml").read_text())
    mm = kp.assemble(model_from_data(data, "mm.yaml"), tol=1e-13).after
    m = kp.assemble(model_from_data(_in_metres(data), "m.yaml"), tol=1e-13).after
    a, b = kp.statics(mm, case), kp.statics(m, case)
    assert a.units == {"force": "N", "moment": "N mm", "length": "mm"} and b.units["moment"] == "N m"
    for j in a.reactions:
        for side in (0, 1):
            assert np.allclose(a.reactions[j].force[side], b.reactions[j].force[side], rtol=1e-8, atol=1e-6)
            assert np.allclose(a.reactions[j].moment[side] / 1000.0, b.reactions[j].moment[side], rtol=1e-8, atol=1e-6)
    assert a.member_forces["TR"] == pytest.approx(b.member_forces["TR"], rel=1e-8)
    assert a.element_forces["spring"] == pytest.approx(b.element_forces["spring"], rel=1e-8)
    assert a.efforts["LCA.q"] / 1000.0 == pytest.approx(b.efforts["LCA.q"], rel=1e-8)


def test_weights_act_at_their_centres_of_mass() -> None:
    """Gravity: the input effort it adds to the spring's (loads superpose) is minus the
    weights' virtual work, the centres of mass moved by central differences of position solves."""
    model = kp.assemble(kp.load_model(EXAMPLES / "double_wishbone.yaml"), tol=1e-13).after
    case = kp.LoadCase("g", gravity=(0.0, 0.0, -1.0))
    s, springs_only = kp.statics(model, case), kp.statics(model)
    h = 1e-4  # degrees of LCA; central differences of the position solve (Richardson)

    def work(step: float) -> float:
        pos = []
        for t in (-step, step):
            after = kp.propagate(model, {"LCA.q": float(model.coordinates["LCA"][0] + t)}, free=["q"], tol=1e-14).after
            kin = kp.compile(after).kinematics(after.design, after.coordinates)
            pts = {}
            for mass in model.loads.masses:
                cm = dict(model.mechanism.body(mass.body).points)[mass.cm] if isinstance(mass.cm, str) else mass.cm
                pts[mass.body] = kin.r[mass.body] + kin.A[mass.body] @ np.array(cm)
            pos.append(pts)
        return sum(m.weight * (pos[1][m.body][2] - pos[0][m.body][2]) / (2 * step) for m in model.loads.masses)

    dz_per_deg = (4 * work(h / 2) - work(h)) / 3  # sum W_k dz_k/dq per degree
    # effort is per radian: tau = -(-W dz/dq) = W dz/dq (deg -> rad: * 180/pi)
    assert s.efforts["LCA.q"] - springs_only.efforts["LCA.q"] == pytest.approx(dz_per_deg * 180.0 / np.pi, rel=1e-7)


def test_sections_survive_writing_and_converting(tmp_path: Path) -> None:
    model = kp.assemble(kp.load_model(EXAMPLES / "double_wishbone.yaml"), tol=1e-13).after
    out = tmp_path / "dw.yaml"
    dump_model(model, out)
    assert kp.load_model(out).loads == model.loads
    hp = model_from_data(model_to_hardpoints(model))
    for case in model.loads.cases:
        a, b = kp.statics(model, case), kp.statics(kp.assemble(hp, tol=1e-13).after, case)
        assert a.efforts["LCA.q"] == pytest.approx(b.efforts["LCA.q"], rel=1e-8)
        assert np.allclose(a.reactions["UBJ"].force[1], b.reactions["UBJ"].force[1], rtol=1e-8)
    prop = kp.propagate(model, {"LCA.q": [3.0]}, free=["q"])
    assert prop.after.loads == model.loads
    # a distributed study's workers rebuild the model from its payload: the loads come along
    from kinprop.analysis.study import _model_from_payload, _model_payload

    assert _model_from_payload(_model_payload(model)).loads == model.loads


def test_bad_loads_are_located() -> None:
    data = yaml.safe_load((EXAMPLES / "double_wishbone.yaml").read_text())
    bad = copy.deepcopy(data)
    bad["loads"]["masses"]["nope"] = {"weight": 1.0, "cm": [0, 0, 0]}
    bad["loads"]["masses"]["lca"]["cm"] = "no_such_point"
    bad["loads"]["cases"]["bump_3g"]["wheels"]["lca"] = [0, 0, 1]
    bad["loads"]["cases"]["x"] = {"forces": [{"body": "uca", "point": "front_pivot"}], "gravity": [0, 0, -1]}
    with pytest.raises(ModelError) as exc:
        model_from_data(bad, "dw.yaml")
    text = str(exc.value)
    for where in ("loads.masses.nope", "loads.masses.lca.cm", "loads.cases.bump_3g.wheels.lca",
                  "loads.cases.x.forces[0]"):  # fmt: skip
        assert f"dw.yaml: {where}" in text, text
    assert "unknown body 'nope'" in text and "no named point 'no_such_point'" in text
    bad = copy.deepcopy(data)
    bad["loads"]["cases"]["bump_3g"]["wheels"]["upright"] = [0, 0]
    with pytest.raises(ModelError) as exc:
        model_from_data(bad, "dw.yaml")
    assert "loads.cases.bump_3g.wheels.upright" in str(exc.value)
