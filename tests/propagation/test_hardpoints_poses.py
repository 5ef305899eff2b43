"""Global hardpoint/axis addresses (exact s'/C conversion) and body poses / joint values."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
import yaml

from kinprop import SingularityWarning, assemble, compile, load_model, propagate
from kinprop.analysis.points import joint_hardpoints
from kinprop.errors import AddressError
from kinprop.io import model_from_data
from kinprop.joints import REGISTRY
from kinprop.propagation.hardpoints import global_columns, global_plan, resolve_changes
from kinprop.propagation.poses import joint_value

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
pytestmark = pytest.mark.filterwarnings("ignore::kinprop.SingularityWarning")


def solved(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SingularityWarning)
        prop = assemble(load_model(path), tol=1e-12)
    assert prop.converged
    return prop.after


# --- joint values --------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("jtype", "names"),
    [
        ("revolute", ["angle"]),
        ("translational", ["displacement"]),
        ("cylindrical", ["angle", "displacement"]),
        ("universal", ["angle_1", "angle_2"]),
        ("spherical", ["euler"]),
        ("spherical-translational", ["euler", "displacement"]),
        ("free", ["translation_i", "euler"]),
    ],
)
def test_joint_value_inverts_each_joint_types_own_placement(jtype, names):
    """The value read from (R'', d'') is the coordinate the joint type's placement was built from."""
    rng = np.random.default_rng(7)
    jt = REGISTRY[jtype]
    for _ in range(20):
        q = rng.uniform(-1.2, 1.2, jt.n_coordinates)
        if jt.euler is not None:
            p = q[jt.euler] / np.linalg.norm(q[jt.euler])
            q[jt.euler] = p if p[0] >= 0 else -p
        Rr, d = jt.placement(q)
        got = np.concatenate([np.atleast_1d(joint_value(jtype, Rr, d)[n]) for n in names])
        np.testing.assert_allclose(got, q, atol=1e-12)


def test_cut_joint_value_equals_its_coordinate_when_the_same_joint_is_in_the_tree(tmp_path):
    """Four-bar with B cut (the example) vs the same linkage with A cut and B in the tree."""
    original = solved(EXAMPLES / "fourbar.yaml")
    data = yaml.safe_load((EXAMPLES / "fourbar.yaml").read_text())
    data["joints"]["A"]["cut"] = True
    data["joints"]["B"]["cut"] = False
    del data["joints"]["A"]["q"]
    data["joints"]["O4"]["q"] = [float(np.degrees(original.coordinates["O4"][0]))]
    path = tmp_path / "recut.yaml"
    path.write_text(yaml.safe_dump(data))
    recut = load_model(path)
    prop = propagate(recut, {"O2.q": np.degrees(original.coordinates["O2"])}, ["q"], tol=1e-13)  # degrees
    assert prop.converged
    before = propagate(original, {}, ["q"])
    # A: tree in the original, cut in the re-cut model (joint values in the model's unit: degrees)
    assert prop.joint_values["A"]["angle"] == pytest.approx(np.degrees(original.coordinates["A"][0]), abs=1e-7)
    assert prop.solver_joint_values["A"]["angle"] == pytest.approx(float(original.coordinates["A"][0]), abs=1e-9)
    # B: cut in the original, tree (Euler parameters + slide) in the re-cut model
    qB = np.array(prop.after.coordinates["B"], dtype=float)
    qB[:4] *= np.sign(qB[0])
    np.testing.assert_allclose(before.joint_values["B"]["euler"], qB[:4], atol=1e-9)
    assert before.joint_values["B"]["displacement"] == pytest.approx(qB[4], abs=1e-9)
    # tree joints report their own coordinates; body poses agree between the two models
    assert before.joint_values["O4"]["angle"] == pytest.approx(np.degrees(original.coordinates["O4"][0]), abs=1e-10)
    for body in ("crank", "coupler", "rocker"):
        np.testing.assert_allclose(prop.bodies[body]["t"], before.bodies[body]["t"], atol=1e-9)
        np.testing.assert_allclose(prop.bodies[body]["R"], before.bodies[body]["R"], atol=1e-9)


# --- global hardpoints ---------------------------------------------------------------------------
def test_hardpoint_on_a_fixed_body_lands_exactly():
    m = solved(EXAMPLES / "double_wishbone.yaml")
    p = np.array([-250.0, 450.0, 60.0])
    prop = propagate(m, {"hardpoint:TR.i": p}, ["q"])
    assert prop.converged
    np.testing.assert_allclose(joint_hardpoints(prop.after)["TR.i"], p, atol=1e-9)
    np.testing.assert_allclose(prop.after.design["TR.s_i"], p, atol=1e-12)  # chassis frame = global


@pytest.mark.parametrize(("path", "joint"), [("double_wishbone.yaml", "UBJ"), ("bennett.yaml", "J4")])
def test_moving_a_joint_on_both_sides_keeps_the_assembly_closed(path, joint):
    """Cut joints with s' on both sides: both attachments shift by the same global vector, so
    Phi stays zero and no body moves; the joint sits at the new point."""
    m = solved(EXAMPLES / path)
    eng = compile(m)
    p = np.array(joint_hardpoints(m)[f"{joint}.i"]) + np.array([3.0, -2.0, 5.0]) * eng.length_scale / 1000
    changes = resolve_changes(eng, eng.reference, {f"hardpoint:{joint}": p})
    st, _, _ = eng.apply(eng.reference, changes)
    assert np.linalg.norm(eng.residual(st)) < 1e-9
    r0, A0, _, _ = eng.poses(eng.reference)
    r1, A1, P1, _ = eng.poses(st)
    np.testing.assert_allclose(r1, r0, atol=1e-9)
    np.testing.assert_allclose(A1, A0, atol=1e-12)
    k = eng.joint_index[joint]
    np.testing.assert_allclose(P1[k], [p, p], atol=1e-9)


def test_tree_joint_without_s_j_carries_body_j_along():
    """LBJ (tree, upright frame at the joint): hardpoint:LBJ moves s'_i; the upright follows
    (the joint sits at the new point before re-assembly) and the propagation re-closes."""
    m = solved(EXAMPLES / "double_wishbone.yaml")
    eng = compile(m)
    p = np.array(joint_hardpoints(m)["LBJ.i"]) + [3.0, -2.0, 5.0]
    changes = resolve_changes(eng, eng.reference, {"hardpoint:LBJ": p})
    assert set(changes) == {"LBJ.s_i"}
    st, _, _ = eng.apply(eng.reference, changes)
    _, _, P, _ = eng.poses(st)
    np.testing.assert_allclose(P[eng.joint_index["LBJ"]], [p, p], atol=1e-9)
    assert propagate(m, {"hardpoint:LBJ": p}, ["q"]).converged


def test_frame_style_and_hardpoint_style_models_behave_the_same():
    """Under the same reading of an edit (the paper's, edits: mechanism; the hardpoint file's
    default, edits: design, keeps the design position instead: tests/analysis/test_hardpoint_edits.py)."""
    a = solved(EXAMPLES / "double_wishbone.yaml")
    data = yaml.safe_load((EXAMPLES / "double_wishbone_hardpoints.yaml").read_text()) | {"edits": "mechanism"}
    b = assemble(model_from_data(data), tol=1e-12).after
    ha, hb = joint_hardpoints(a), joint_hardpoints(b)
    for key in ha:
        np.testing.assert_allclose(ha[key], hb[key], atol=1e-6)
    change = {"hardpoint:UBJ.j": np.array(ha["UBJ.i"]) + [0.0, 0.0, 8.0], "hardpoint:TR.i": [-250.0, 450.0, 60.0]}
    pa, pb = propagate(a, change, ["q"]), propagate(b, change, ["q"])
    assert pa.converged and pb.converged
    ha, hb = joint_hardpoints(pa.after), joint_hardpoints(pb.after)
    for key in ha:
        np.testing.assert_allclose(ha[key], hb[key], atol=1e-6)
    # wheel points and joint values agree too (body frames differ between the two styles)
    for key in ("UBJ", "TR"):
        for name, v in pa.joint_values[key].items():
            if name in ("distance", "translation") and key == "TR":
                np.testing.assert_allclose(v, pb.joint_values[key][name], atol=1e-6)


def test_axis_turns_the_joint_axis_and_keeps_the_joint_value():
    m = solved(EXAMPLES / "double_wishbone.yaml")
    u = np.array([0.2, 1.0, 0.1])
    prop = propagate(m, {"axis:UCA": u}, ["q"])
    assert prop.converged
    eng = compile(m)
    _, _, _, R = eng.poses(eng.state_of(prop.after))
    k = eng.joint_index["UCA"]
    for side in (0, 1):
        np.testing.assert_allclose(R[k, side][:, 2], u / np.linalg.norm(u), atol=1e-9)


def test_bad_global_addresses_are_located():
    m = load_model(EXAMPLES / "double_wishbone.yaml")
    eng = compile(m)
    with pytest.raises(AddressError, match="unknown joint 'NOPE'"):
        resolve_changes(eng, eng.reference, {"hardpoint:NOPE": [0, 0, 0]})
    with pytest.raises(AddressError, match="three finite global coordinates"):
        resolve_changes(eng, eng.reference, {"hardpoint:UBJ": [0, 0]})
    with pytest.raises(AddressError, match="has no C_j"):
        resolve_changes(eng, eng.reference, {"axis:TR.j": [0, 0, 1]})
    with pytest.raises(AddressError, match="has no C_i or C_j"):
        resolve_changes(eng, eng.reference, {"axis:UBJ": [0, 0, 1]})


def test_sensitivity_per_global_millimetre_matches_re_solved_differences():
    """d(toe)/d(tie-rod inner point, global) by the implicit-function theorem and the exact
    conversion, against central differences of full propagations of the global hardpoint."""
    import pandas as pd

    from kinprop.io.commands import sensitivities

    m = solved(EXAMPLES / "double_wishbone.yaml")
    sens = sensitivities(
        m, ["hardpoint:TR.i", "hardpoint:UBJ.j[z]", "hardpoint:UBJ[z]"], ["metric:upright.toe"], ("q",), None
    )
    frame = pd.DataFrame(sens.matrix, index=sens.rows, columns=sens.columns)
    assert list(frame.columns) == [f"hardpoint:TR.i[{c}]" for c in "xyz"] + ["hardpoint:UBJ.j[z]", "hardpoint:UBJ[z]"]
    eng = compile(m)
    base = {"TR.i": np.array(joint_hardpoints(m)["TR.i"]), "UBJ.j": np.array(joint_hardpoints(m)["UBJ.j"])}
    base["UBJ"] = base["UBJ.j"]
    from kinprop import evaluate_outputs

    h = 1e-3
    for col in frame.columns:
        name, c = col[len("hardpoint:") :].split("[")
        e = np.zeros(3)
        e["xyz".index(c[0])] = h
        vals = []
        for sgn in (1, -1):
            prop = propagate(m, {f"hardpoint:{name}": base[name] + sgn * e}, ["q"], engine=eng)
            vals.append(evaluate_outputs(prop.after, ["metric:upright.toe"])["metric:upright.toe"])
        fd = (vals[0] - vals[1]) / (2 * h)
        assert frame.loc["metric:upright.toe", col] == pytest.approx(fd, rel=1e-5, abs=1e-7)
    # moving the ball joint on both bodies moves no body: no toe change; on the upright only: toe changes
    assert abs(frame.loc["metric:upright.toe", "hardpoint:UBJ[z]"]) < 1e-7
    assert abs(frame.loc["metric:upright.toe", "hardpoint:UBJ.j[z]"]) > 1e-3


def test_global_plan_equals_the_exact_conversion():
    m = solved(EXAMPLES / "double_wishbone.yaml")
    eng = compile(m)
    P = np.array(joint_hardpoints(m)["UBJ.i"])
    addrs, plan = global_plan(eng, eng.reference, ["hardpoint:UBJ.j[z]", "TR.length"], np.array([[P[2] + 4, 380.0]]))
    assert addrs == ["TR.length", "UBJ.s_j[0]", "UBJ.s_j[1]", "UBJ.s_j[2]"]
    exact = resolve_changes(eng, eng.reference, {"hardpoint:UBJ.j": P + [0, 0, 4]})["UBJ.s_j"]
    np.testing.assert_allclose(plan[0, 1:], exact, atol=1e-12)
    design, combos = global_columns(eng, eng.reference, ["hardpoint:UBJ.j[z]"])
    assert design == ["UBJ.s_j"] and set(combos) == {"hardpoint:UBJ.j[z]"}
