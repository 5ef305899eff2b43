"""Arms by their pivots and hardpoint edits that keep the design position (issue 20, items 1
and 2), against the independent double-wishbone solver of dw_oracle."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import yaml
from analysis_helpers import EXAMPLES
from dw_oracle import HMMWV, solve

from kinprop import SingularityWarning, load_model, propagate
from kinprop.analysis.metrics import suspension_metrics
from kinprop.analysis.outputs import evaluate_outputs
from kinprop.analysis.study import run_study
from kinprop.cli.sensitivity import sensitivities
from kinprop.engine import compile as compile_engine
from kinprop.errors import AddressError, ModelError
from kinprop.imports.chrono import read_chrono
from kinprop.io import model_from_data
from kinprop.io.hardpoints import model_to_hardpoints
from kinprop.propagation.hardpoints import free_addresses, global_plan, resolve_changes

pytestmark = pytest.mark.filterwarnings("ignore::kinprop.SingularityWarning")
FILE = EXAMPLES / "double_wishbone_hardpoints.yaml"
METRICS = ("camber", "toe", "kpi", "caster", "wheel_centre_dz")


def _data() -> dict:
    return yaml.safe_load(FILE.read_text())


def _run(model, changes, theta=None, tol=1e-9):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SingularityWarning)
        prop = propagate(model, changes, ("q",), tol=tol)
        assert prop.converged, prop.result.message
        if theta is not None:
            prop = propagate(prop.after, {"LCA.q": theta}, ("q",), tol=tol)
            assert prop.converged, prop.result.message
    return prop.after


def _check(after, truth, atol=1e-7):
    m = suspension_metrics(after, "upright")
    for name in METRICS:
        assert m[name] == pytest.approx(truth[name], abs=atol), name


def test_pivots_in_the_file_are_the_arm_axis():
    model = load_model(FILE)
    pts = evaluate_outputs(model, ["point:chassis.UCA.front", "point:chassis.UCA.rear"])
    np.testing.assert_allclose([pts[f"point:chassis.UCA.front[{c}]"] for c in "xyz"], HMMWV["UCA_F"], atol=1e-12)
    np.testing.assert_allclose([pts[f"point:chassis.UCA.rear[{c}]"] for c in "xyz"], HMMWV["UCA_B"], atol=1e-12)
    _check(_run(model, {}, theta=4.0), solve(HMMWV, 4.0))


@pytest.mark.parametrize("theta", [-5.0, 4.0])
def test_moving_pivots_against_the_independent_solver(theta):
    """UCA front pivot 10 mm up, LCA rear pivot 6 mm inboard and 4 mm down: nothing moves at
    the design position; over travel the arms turn about the new axes."""
    model = load_model(FILE)
    uca_f = HMMWV["UCA_F"] + [0.0, 0.0, 10.0]
    lca_b = HMMWV["LCA_B"] + [0.0, -6.0, -4.0]
    edits = {"hardpoint:UCA.front": uca_f, "hardpoint:LCA.rear": lca_b}
    static = _run(model, edits)
    _check(static, solve(HMMWV, 0.0), atol=1e-9)  # the design position is kept
    chassis = dict(static.mechanism.body("chassis").points)
    np.testing.assert_allclose(chassis["UCA.front"], uca_f, atol=1e-12)
    np.testing.assert_allclose(chassis["LCA.rear"], lca_b, atol=1e-12)
    _check(_run(static, {"LCA.q": theta}), solve({**HMMWV, "UCA_F": uca_f, "LCA_B": lca_b}, theta))


@pytest.mark.parametrize("theta", [-5.0, 4.0])
def test_moving_ball_joints_and_tie_rod_keeps_the_design_position(theta):
    """LBJ (the upright's tree joint) 8 mm down, UBJ 5 mm outboard, tie-rod inner end 5 mm
    outboard: the other hardpoints stay, lengths are re-derived, static alignment unchanged."""
    model = load_model(FILE)
    hp = {
        **HMMWV,
        "LBJ": HMMWV["LBJ"] + [0.0, 0.0, -8.0],
        "UBJ": HMMWV["UBJ"] + [0.0, 5.0, 0.0],
        "TR_I": HMMWV["TR_I"] + [0.0, 5.0, 0.0],
    }
    edits = {"hardpoint:LBJ": hp["LBJ"], "hardpoint:UBJ": hp["UBJ"], "hardpoint:TR.i": hp["TR_I"]}
    static = _run(model, edits)
    m = suspension_metrics(static, "upright")
    assert m["toe"] == pytest.approx(0.0, abs=1e-12) and m["camber"] == pytest.approx(0.0, abs=1e-12)
    assert m["wheel_centre_dz"] == pytest.approx(0.0, abs=1e-12)
    _check(_run(static, {"LCA.q": theta}), solve(hp, theta))


def test_the_papers_reading_keeps_the_tie_rod_length():
    """edits: mechanism (the paper's): moving the tie rod's inner end 5 mm outboard keeps its
    length, so the wheel steers (+2.049 deg of toe-in here), as the oracle turns it."""
    data = _data()
    data["edits"] = "mechanism"
    model = model_from_data(data, "dw.yaml")
    tr_i = HMMWV["TR_I"] + [0.0, 5.0, 0.0]
    after = _run(model, {"hardpoint:TR.i": tr_i})
    truth = solve({**HMMWV, "TR_I": tr_i}, 0.0, tie_rod=float(np.linalg.norm(HMMWV["TR_O"] - HMMWV["TR_I"])))
    toe = suspension_metrics(after, "upright")["toe"]
    assert toe == pytest.approx(truth["toe"], abs=1e-8)
    assert toe == pytest.approx(2.048867, abs=1e-6)
    design = _run(load_model(FILE), {"hardpoint:TR.i": tr_i})
    assert suspension_metrics(design, "upright")["toe"] == pytest.approx(0.0, abs=1e-12)


def test_pivot_sensitivity_equals_central_differences():
    """d(camber, toe, kpi)/d(UCA front pivot) at 4 deg of lower arm, per mm, with the paper's
    reading (the arm turns with its axis, the loop re-closes): the chain rule through the pivot
    -> design map (rotations) against re-propagated models. With edits: design the design
    position is kept, so the same derivatives are zero."""
    data = _data()
    data["edits"] = "mechanism"
    design = _run(load_model(FILE), {}, theta=4.0, tol=1e-11)
    s = sensitivities(design, ["hardpoint:UCA.front"], ["camber", "toe", "kpi"], ("UCA.q", "LBJ.q"), None)
    assert np.max(np.abs(s.matrix)) < 1e-6  # zero to the differences of the map
    model = _run(model_from_data(data, "dw.yaml"), {}, theta=4.0, tol=1e-11)
    s = sensitivities(model, ["hardpoint:UCA.front"], ["camber", "toe", "kpi"], ("UCA.q", "LBJ.q"), None)
    table = {r: dict(zip(s.columns, row, strict=True)) for r, row in zip(s.rows, s.matrix, strict=True)}
    p0 = HMMWV["UCA_F"]
    h = 1e-3
    for c, axis in enumerate("xyz"):
        e = np.zeros(3)
        e[c] = h
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", SingularityWarning)
            plus = propagate(model, {"hardpoint:UCA.front": p0 + e}, ("UCA.q", "LBJ.q"), tol=1e-11).after
            minus = propagate(model, {"hardpoint:UCA.front": p0 - e}, ("UCA.q", "LBJ.q"), tol=1e-11).after
        mp, mm = suspension_metrics(plus, "upright"), suspension_metrics(minus, "upright")
        for out in ("camber", "toe", "kpi"):
            fd = (mp[out] - mm[out]) / (2 * h)
            assert table[out][f"hardpoint:UCA.front[{axis}]"] == pytest.approx(fd, abs=2e-6), (out, axis)
    assert abs(table["camber"]["hardpoint:UCA.front[z]"]) > 1e-3


def test_pivot_addresses_in_free_sets_plans_and_errors():
    model = load_model(FILE)
    eng = compile_engine(model)
    assert set(free_addresses(eng, ["hardpoint:UCA.front"])) == {"UCA.s_i", "UCA.C_i", "UCA.s_j", "UCA.C_j"}
    assert set(free_addresses(eng, ["hardpoint:TR.i"])) == {"TR.s_i", "TR.length"}
    # a study plan varying one component: each sample as the --set of the whole point
    z = HMMWV["UCA_F"][2] + np.array([-5.0, 7.0])
    addrs, plan = global_plan(eng, eng.reference, ["hardpoint:UCA.front[z]"], z[:, None])
    for n, zn in enumerate(z):
        p = HMMWV["UCA_F"].copy()
        p[2] = zn
        ref = resolve_changes(eng, eng.reference, {"hardpoint:UCA.front": p})
        for k, a in enumerate(addrs):
            key, _, idx = a.partition("[")
            want = np.ravel(ref[key])[int(idx[:-1])] if idx else ref[key]
            assert plan[n, k] == pytest.approx(float(want), abs=1e-12)
    with pytest.raises(AddressError, match=r"a pivot \(UCA.front, UCA.rear\)"):
        resolve_changes(eng, eng.reference, {"hardpoint:UCA.middle": [0, 0, 0]})
    with pytest.raises(AddressError, match="not given by pivots"):
        resolve_changes(eng, eng.reference, {"hardpoint:UBJ.top": [0, 0, 0]})


def test_pivots_are_written_back_and_bad_pivots_reported():
    model = _run(load_model(FILE), {"hardpoint:UCA.front": HMMWV["UCA_F"] + [0.0, 0.0, 10.0]})
    hp = model_to_hardpoints(model)
    assert "point" not in hp["joints"]["UCA"] and "axis" not in hp["joints"]["UCA"]
    np.testing.assert_allclose(hp["joints"]["UCA"]["pivots"]["front"], HMMWV["UCA_F"] + [0.0, 0.0, 10.0])
    assert "points" not in hp["bodies"]["uca"] and "UCA.front" not in hp["bodies"]["chassis"]["points"]
    again = model_from_data(hp, "again.yaml")
    assert dict(again.mechanism.body("chassis").points)["UCA.front"] == pytest.approx(HMMWV["UCA_F"] + [0, 0, 10])
    bad = _data()
    bad["joints"]["UBJ"]["pivots"] = {"a": [0, 0, 0], "b": [1, 0, 0]}
    bad["joints"]["UCA"]["point"] = [0, 0, 0]
    bad["joints"]["LCA"]["pivots"]["rear"] = bad["joints"]["LCA"]["pivots"]["front"]
    with pytest.raises(ModelError) as exc:
        model_from_data(bad, "dw.yaml")
    text = str(exc.value)
    assert "joints.UBJ.pivots: only revolute and cylindrical joints take pivots, found type 'spherical'" in text
    assert "joints.UCA.pivots: give either pivots or point and axis, not both" in text
    assert "joints.LCA.pivots: the two pivots coincide: they define no axis" in text


def test_pivots_are_outputs_and_the_chrono_importer_writes_them():
    model = _run(load_model(FILE), {"hardpoint:UCA.front": HMMWV["UCA_F"] + [0.0, 0.0, 10.0]})
    v = evaluate_outputs(model, ["hardpoint:UCA.front", "hardpoint:LCA.rear[y]"])
    np.testing.assert_allclose([v[f"hardpoint:UCA.front[{c}]"] for c in "xyz"], HMMWV["UCA_F"] + [0, 0, 10])
    assert v["hardpoint:LCA.rear[y]"] == pytest.approx(HMMWV["LCA_B"][1])
    with pytest.raises(AddressError, match=r"bad output.*none is named .middle."):
        evaluate_outputs(model, ["hardpoint:UCA.middle"])
    chrono, _ = read_chrono(EXAMPLES / "chrono" / "HMMWV_DoubleWishboneFront.json")
    hp = model_to_hardpoints(chrono)
    assert set(hp["joints"]["UCA"]["pivots"]) == {"front", "rear"} and "axis" not in hp["joints"]["UCA"]
    eng = compile_engine(chrono)
    raised = resolve_changes(
        eng, eng.reference, {"hardpoint:LCA.front": np.add(hp["joints"]["LCA"]["pivots"]["front"], [0, 0, 0.01])}
    )
    assert set(raised) == {"LCA.s_i", "LCA.C_i", "LCA.s_j", "LCA.C_j"}


def test_a_study_varying_a_pivot_against_the_independent_solver():
    """study --vary hardpoint:UCA.front[z] with the lower arm held at 5 deg: each variant's
    camber, toe and caster are the oracle's for that pivot height."""
    pytest.importorskip("pyarrow")
    model = load_model(FILE)
    eng = compile_engine(model)
    z = HMMWV["UCA_F"][2] + np.array([-10.0, 0.0, 12.0])
    addrs, plan = global_plan(eng, eng.reference, ["hardpoint:UCA.front[z]"], z[:, None])
    frame = run_study(
        model, plan=plan, addresses=addrs, sets={"LCA.q": np.radians(5.0)}, outputs=["camber", "toe", "caster"],
        tol=1e-9, units="solver", engine="reference",
    )  # fmt: skip
    assert frame["converged"].all()
    for n, zn in enumerate(z):
        truth = solve({**HMMWV, "UCA_F": np.array([*HMMWV["UCA_F"][:2], zn])}, 5.0)
        for name in ("camber", "toe", "caster"):
            assert frame[name].iloc[n] == pytest.approx(truth[name], abs=1e-7), (name, zn)
