"""The steering axis from its joints (issue 20, item 3): KPI and caster follow every edit of the
ball joints, references to joints in files, the default axes, and the mismatch report."""

from __future__ import annotations

import copy
import math
import warnings

import numpy as np
import pytest
import yaml
from analysis_helpers import EXAMPLES
from dw_oracle import HMMWV, solve

from kinprop import SingularityWarning, load_model, propagate
from kinprop.analysis.metrics import suspension_metrics
from kinprop.analysis.outputs import evaluate_outputs
from kinprop.cli.sensitivity import sensitivities
from kinprop.errors import ModelError
from kinprop.imports.chrono import read_chrono
from kinprop.io import model_from_data
from kinprop.io.hardpoints import model_to_hardpoints
from kinprop.io.points import JointPointWarning

pytestmark = pytest.mark.filterwarnings("ignore::kinprop.SingularityWarning")

FILES = ["double_wishbone.yaml", "double_wishbone_hardpoints.yaml"]
UBJ_OUT = HMMWV["UBJ"] + np.array([0.0, 10.0, 0.0])  # 10 mm outboard (left wheel: +y)


def _hp_data() -> dict:
    return yaml.safe_load((EXAMPLES / "double_wishbone_hardpoints.yaml").read_text())


def _moved(model, changes, *, theta: float | None = None):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SingularityWarning)
        prop = propagate(model, changes, ("q",), tol=1e-9)
        assert prop.converged, prop.result.message
        if theta is not None:
            prop = propagate(prop.after, {"LCA.q": theta}, ("q",), tol=1e-9)
            assert prop.converged, prop.result.message
    return prop.after


@pytest.mark.parametrize("file", FILES)
def test_kpi_follows_the_upper_ball_joint(file):
    """Moving UBJ 10 mm outboard: KPI from the edited joints (it stayed 12.01 deg before)."""
    model = load_model(EXAMPLES / file)
    after = _moved(model, {"hardpoint:UBJ": UBJ_OUT})
    k = UBJ_OUT - HMMWV["LBJ"]
    expected = math.degrees(math.atan2(-k[1], k[2]))  # 10.361 deg, from 12.014
    m = suspension_metrics(after, "upright")
    assert expected == pytest.approx(10.360996, abs=1e-5)
    assert m["kpi"] == pytest.approx(expected, abs=1e-9)
    assert m["caster"] == pytest.approx(math.degrees(math.atan2(-k[0], k[2])), abs=1e-9)


@pytest.mark.parametrize("theta", [-5.0, 4.0])
def test_ball_joint_edit_against_an_independent_solver(theta):
    """After moving UBJ 10 mm outboard and 6 mm up, camber, toe, KPI and caster with the lower
    arm turned: kinprop against the independent closed construction of dw_oracle."""
    model = load_model(EXAMPLES / "double_wishbone_hardpoints.yaml")
    ubj = UBJ_OUT + np.array([0.0, 0.0, 6.0])
    after = _moved(model, {"hardpoint:UBJ": ubj}, theta=theta)
    truth = solve({**HMMWV, "UBJ": ubj}, theta)
    m = suspension_metrics(after, "upright")
    for name in ("camber", "toe", "kpi", "caster", "wheel_centre_dz"):
        assert m[name] == pytest.approx(truth[name], abs=1e-7), name


def test_kpi_sensitivity_to_the_ball_joint_equals_central_differences():
    """sensitivity --wrt hardpoint:UBJ --of kpi: non-zero, equal to re-propagated differences."""
    model = load_model(EXAMPLES / "double_wishbone_hardpoints.yaml")
    s = sensitivities(model, ["hardpoint:UBJ"], ["kpi", "caster"], ("q",), None)
    table = {r: dict(zip(s.columns, row, strict=True)) for r, row in zip(s.rows, s.matrix, strict=True)}
    h = 1e-3
    for c, axis in enumerate("xyz"):
        e = np.zeros(3)
        e[c] = h
        plus = suspension_metrics(_moved(model, {"hardpoint:UBJ": HMMWV["UBJ"] + e}), "upright")
        minus = suspension_metrics(_moved(model, {"hardpoint:UBJ": HMMWV["UBJ"] - e}), "upright")
        for out in ("kpi", "caster"):
            fd = (plus[out] - minus[out]) / (2 * h)
            assert table[out][f"hardpoint:UBJ[{axis}]"] == pytest.approx(fd, abs=1e-7), (out, axis)
    assert table["kpi"]["hardpoint:UBJ[y]"] == pytest.approx(-0.164307, abs=1e-6)


def test_default_axis_is_the_ball_joints():
    """Without kingpin points the steering axis runs through the two ball joints."""
    data = _hp_data()
    del data["bodies"]["upright"]["kingpin"]
    plain = model_from_data(data, "dw.yaml")
    assert plain.mechanism.body("upright").joint_points == ()
    after = _moved(plain, {"hardpoint:UBJ": UBJ_OUT})
    k = UBJ_OUT - HMMWV["LBJ"]
    assert suspension_metrics(after, "upright")["kpi"] == pytest.approx(math.degrees(math.atan2(-k[1], k[2])))


def test_coincident_points_are_bound_to_their_joint():
    """Points declared by coordinates where a joint is become that joint's point."""
    data = _hp_data()
    del data["bodies"]["upright"]["kingpin"]
    data["bodies"]["upright"]["points"]["kingpin_upper"] = HMMWV["UBJ"].tolist()
    data["bodies"]["upright"]["points"]["kingpin_lower"] = HMMWV["LBJ"].tolist()
    data["bodies"]["upright"]["points"]["tie_rod_outer"] = HMMWV["TR_O"].tolist()
    model = model_from_data(data, "dw.yaml")
    links = {n: (j, s) for n, j, s, _ in model.mechanism.body("upright").joint_points}
    assert links == {"kingpin_upper": ("UBJ", "j"), "kingpin_lower": ("LBJ", "j"), "tie_rod_outer": ("TR", "j")}
    after = _moved(model, {"hardpoint:TR.j": HMMWV["TR_O"] + np.array([0.0, 0.0, 5.0])})
    v = evaluate_outputs(after, ["point:upright.tie_rod_outer", "hardpoint:TR.j"])
    for c in "xyz":
        assert v[f"point:upright.tie_rod_outer[{c}]"] == pytest.approx(v[f"hardpoint:TR.j[{c}]"], abs=1e-12)


def test_a_declared_point_off_its_joint_is_reported():
    data = _hp_data()
    del data["bodies"]["upright"]["kingpin"]
    data["bodies"]["upright"]["points"]["kingpin_upper"] = (HMMWV["UBJ"] - np.array([0.0, 10.0, 0.0])).tolist()
    data["bodies"]["upright"]["points"]["kingpin_lower"] = HMMWV["LBJ"].tolist()
    with pytest.warns(JointPointWarning, match=r"kingpin_upper is 10 from joint UBJ") as rec:
        model = model_from_data(data, "dw.yaml")
    assert "dw.yaml: bodies.upright.points.kingpin_upper" in str(rec[0].message)
    # used as declared: KPI of the declared axis
    k = HMMWV["UBJ"] - np.array([0.0, 10.0, 0.0]) - HMMWV["LBJ"]
    assert suspension_metrics(model, "upright")["kpi"] == pytest.approx(math.degrees(math.atan2(-k[1], k[2])))


def test_references_in_files_and_their_errors():
    data = _hp_data()
    del data["bodies"]["upright"]["kingpin"]
    data["bodies"]["upright"]["points"].update(kingpin_upper="UBJ", kingpin_lower="LBJ.j", rod="TR.j")
    model = model_from_data(data, "dw.yaml")
    links = {n: (j, s, d) for n, j, s, d in model.mechanism.body("upright").joint_points}
    assert links == {"kingpin_upper": ("UBJ", "j", True), "kingpin_lower": ("LBJ", "j", True), "rod": ("TR", "j", True)}
    bad = copy.deepcopy(data)
    bad["bodies"]["upright"]["points"].update(kingpin_upper="UBX", rod="TR")
    with pytest.raises(ModelError) as exc:
        model_from_data(bad, "dw.yaml")
    text = str(exc.value)
    assert "bodies.upright.points.kingpin_upper: unknown joint 'UBX'" in text
    assert "bodies.upright.points.rod: a distance joint has two points: write TR.i or TR.j" in text
    twice = _hp_data()
    twice["bodies"]["upright"]["points"]["kingpin_upper"] = "UBJ"
    with pytest.raises(ModelError, match="given twice"):
        model_from_data(twice, "dw.yaml")


def test_references_survive_conversion():
    model = load_model(EXAMPLES / "double_wishbone_hardpoints.yaml")
    hp = model_to_hardpoints(model)
    assert hp["bodies"]["upright"]["points"]["kingpin_upper"] == "UBJ.j"
    again = model_from_data(hp, "again.yaml")
    assert again.mechanism.body("upright").joint_points == model.mechanism.body("upright").joint_points


def test_mcpherson_default_axis_is_top_mount_to_lower_ball_joint():
    """Chrono's MacPherson: kingpin [STRUT_TOP, LCA_U] by reference; the paper's strut: S-T
    top mount and the R-S ball by default."""
    model, _ = read_chrono(EXAMPLES / "chrono" / "MacPhersonStrut.json")
    links = {n: (j, s) for n, j, s, _ in model.mechanism.body("upright").joint_points}
    assert links["kingpin_upper"] == ("STRUT_TOP", "i") and links["kingpin_lower"] == ("LCA_U", "j")
    data = yaml.safe_load((EXAMPLES / "mcpherson_hardpoints.yaml").read_text())
    data["bodies"]["wheel"]["points"] = {
        "wheel_centre": [0.6, 1.2, 0.2],
        "spin_axis": [1.6, 1.2, 0.2],
    }
    data["units"]["axes"] = "right-handed"
    strut = model_from_data(data, "mcp.yaml")
    # the axis from the top mount (upper) to the ball joint: caster and KPI of exactly that line
    k = np.array(data["joints"]["ST"]["point"], dtype=float) - np.array(data["joints"]["RS"]["point_j"], dtype=float)
    m = suspension_metrics(strut, "wheel")  # a left wheel: its spin axis has y >= 0
    assert m["caster"] == pytest.approx(math.degrees(math.atan2(-k[0], k[2])))
    assert m["kpi"] == pytest.approx(math.degrees(math.atan2(-k[1], k[2])))
