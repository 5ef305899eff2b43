"""Hardpoint-style models: derivation rules, equivalence with the frame-style examples, round trips.

The two styles describe the same mechanism with different body frames and coordinate zeros.
The minimum-norm Newton step is invariant to rotations of body frames (orthogonal changes of
the s' and xi' columns) and to offsets of coordinates, so propagations agree physically:
the joints' global points and axes after the solve, lengths, and the changes of s' expressed
in a common frame (docs/guide/modelling.md, "Frames vs hardpoints").
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
import yaml
from io_helpers import hardpoint_difference

from kinprop import assemble, load_model, propagate
from kinprop.engine import compile as assembly_for
from kinprop.errors import AddressError
from kinprop.io import dump_model, model_from_data
from kinprop.io.hardpoints import (
    axes_frame,
    axis_frame,
    express_in,
    joint_mismatch,
    model_to_hardpoints,
    rotate_into,
    rotation_change,
)
from kinprop.model import Model, as_coordinates
from kinprop.spatial import is_rotation, rot_z

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
TOL = 1e-9

#: the paper's changes (frame-style addresses and values) and free sets
CASES = {
    "slider_crank": ({"J12.s_j": [-2.8, 0.2, 0.1]}, [("q",), ("s",), ("q", "s")]),
    "mcpherson": ({"ST.s_i": [0.5, 1.0, 0.0]}, [("q",), ("s",), ("s", "l"), ("s", "q"), ("s", "q", "l")]),
}
#: s' of joints whose point slides (the hardpoint file puts it at the current slide position)
SLIDING = {"J03.s_i", "TD.s_i"}
PARAMS = [(name, free) for name, (_, frees) in CASES.items() for free in frees]


@pytest.fixture(scope="module")
def pairs() -> dict[str, tuple[Model, Model]]:
    """(assembled frame-style model, shipped hardpoint-style model) per paper example (the
    shipped files hold the paper's iteration's assembly from the estimates: ``method="paper"``)."""
    out = {}
    for name in CASES:
        frames = assemble(load_model(EXAMPLES / f"{name}.yaml"), method="paper").after
        out[name] = (frames, load_model(EXAMPLES / f"{name}_hardpoints.yaml"))
    return out


def _variables(model: Model, group: str) -> list[str]:
    return [v.key for v in assembly_for(model.mechanism).layout.group(group)]


def _body_of(model: Model, key: str) -> str:
    joint, field = key.split(".")
    j = model.mechanism.joint(joint)
    return j.body_i if field.endswith("_i") else j.body_j


# --- the shipped examples -----------------------------------------------------------------------


@pytest.mark.parametrize("name", CASES)
def test_example_is_the_assembled_frame_model(pairs, name):
    frames, hard = pairs[name]
    assert hardpoint_difference(frames, hard) < TOL
    assert max(joint_mismatch(hard).values()) < 1e-12
    assert all(np.all(q == q0) for q, q0 in zip(hard.coordinates.values(), _zero(hard).values(), strict=True))


def _zero(model: Model) -> dict[str, np.ndarray]:
    out = {}
    tree = set(assembly_for(model.mechanism).topology.tree_joints)
    for j in model.mechanism.joints:
        if j.name in model.coordinates:
            jt = j.jtype
            out[j.name] = jt.default_coordinates() if j.name in tree else jt.default_cut_coordinates()
    return out


@pytest.mark.parametrize(("name", "free"), PARAMS)
def test_examples_give_the_same_propagation(pairs, name, free):
    """The paper's change in each style and free set: same points, axes, lengths and s' changes."""
    frames, hard = pairs[name]
    changes, _ = CASES[name]
    hard_changes = {k: express_in(frames, hard, k, v) for k, v in changes.items()}
    pf = propagate(frames, changes, free)
    ph = propagate(hard, hard_changes, free)
    assert pf.converged and ph.converged
    assert pf.result.iterations == ph.result.iterations
    assert hardpoint_difference(pf.after, ph.after) < TOL
    for group in ("s", "l"):
        assert _variables(frames, group) == _variables(hard, group)
    for key in _variables(frames, "s"):
        body = _body_of(frames, key)
        df = pf.after.design[key] - frames.design[key]
        dh = ph.after.design[key] - hard.design[key]
        np.testing.assert_allclose(rotate_into(frames, hard, body, df), dh, atol=TOL)
        # the after-value itself, as a body-fixed point, where the joint point does not slide
        if key not in SLIDING:
            np.testing.assert_allclose(
                express_in(pf.after, ph.after, key, pf.after.design[key]), ph.after.design[key], atol=TOL
            )
    for key in _variables(frames, "l"):
        assert abs(float(pf.after.design[key]) - float(ph.after.design[key])) < TOL


def _zero_slides(model: Model) -> Model:
    """The same physical state with sliding coordinates moved into s_i (prismatic q, T-D q3)."""
    design, coords = {}, dict(model.coordinates)
    for j in model.mechanism.joints:
        if j.jtype.name in ("translational", "translational-distance") and j.name in coords:
            slide = model.design.value(j.name, "C_i") @ np.array([0.0, 0.0, coords[j.name][0]])
            design[f"{j.name}.s_i"] = model.design[f"{j.name}.s_i"] + slide
            coords[j.name] = np.zeros(1)
    return model.with_state(model.design.replace(design), as_coordinates(coords))


@pytest.mark.parametrize("name", CASES)
@pytest.mark.parametrize("free", [("C",), ("s", "C"), ("q", "s", "C", "l")])
def test_joint_body_frames_agree_with_free_orientations(pairs, name, free):
    """``body_frames: joint`` has the paper's design variables, so C-free sets agree too
    (with the sliding coordinates at zero: a C rotates its joint frame about the frame's origin)."""
    frames = _zero_slides(pairs[name][0])
    hard = model_from_data(model_to_hardpoints(frames, "joint"))
    extra = set(_variables(frames, "C")) - set(_variables(hard, "C"))
    assert set(_variables(hard, "C")) <= set(_variables(frames, "C"))
    asm = assembly_for(frames.mechanism)
    jac = asm.evaluate(frames.design, frames.coordinates)[1]
    for key in extra:  # McPherson RS.C_j, TD.C_j: orientations no constraint uses
        assert not np.any(jac[:, asm.layout[key].columns])
    changes, _ = CASES[name]
    # the paper's iteration: the least change with free orientations converges only linearly
    # for large rotations (its step is linear in the rotation vector; docs/analysis/weights.md)
    pf = propagate(frames, changes, free, method="paper")
    ph = propagate(hard, {k: express_in(frames, hard, k, v) for k, v in changes.items()}, free, method="paper")
    assert pf.converged and ph.converged
    assert hardpoint_difference(pf.after, ph.after) < TOL
    for key in _variables(hard, "C"):
        body = _body_of(frames, key)
        xf = rotation_change(frames.design[key], pf.after.design[key])
        xh = rotation_change(hard.design[key], ph.after.design[key])
        np.testing.assert_allclose(rotate_into(frames, hard, body, xf), xh, atol=TOL)


def test_slider_crank_change_in_hardpoint_frames(pairs):
    frames, hard = pairs["slider_crank"]
    s = express_in(frames, hard, "J12.s_j", [-2.828, 0.0, 0.0])
    np.testing.assert_allclose(s, hard.design["J12.s_j"], atol=1e-9)
    assert express_in(frames, hard, "J12.s_i", frames.design["J12.s_i"]) == pytest.approx(hard.design["J12.s_i"])
    with pytest.raises(AddressError):
        express_in(frames, hard, "J01.q", [0.0])


# --- derivation rules ---------------------------------------------------------------------------


def test_axis_frame_rule_matches_the_paper():
    c01 = np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0]], dtype=float)
    c03 = np.array([[0, 1, 0], [0, 0, 1], [1, 0, 0]], dtype=float)
    np.testing.assert_array_equal(axis_frame([2.0, 0, 0]), c01)
    np.testing.assert_array_equal(axis_frame([0, 0.5, 0]), c03)
    np.testing.assert_array_equal(axis_frame([0, 0, 3.0]), np.eye(3))
    rng = np.random.default_rng(1)
    for z in rng.normal(size=(50, 3)):
        r = axis_frame(z)
        assert is_rotation(r, 1e-12)
        np.testing.assert_allclose(r[:, 2], z / np.linalg.norm(z), atol=1e-14)


def test_universal_frame_second_axis_is_y():
    r = axes_frame([1.0, 0, 0], [0, 0.6, 0.8])
    assert is_rotation(r, 1e-12)
    np.testing.assert_allclose(r[:, 1], [0, 0.6, 0.8])
    np.testing.assert_allclose(r[:, 2], [1, 0, 0])
    # slightly off-perpendicular input is made exactly perpendicular
    r = axes_frame([1.0, 0, 0], [1e-4, 0.6, 0.8])
    assert abs(r[:, 1] @ r[:, 2]) < 1e-15


def _all_types_file(rng: np.random.Generator) -> dict:
    """A hardpoint file using every joint type with a hardpoint form, with random hardpoints."""

    def p() -> list[float]:
        return rng.normal(size=3).round(6).tolist()

    z, y = rng.normal(size=3), rng.normal(size=3)
    y -= (y @ z) / (z @ z) * z
    zr, yr = rng.normal(size=3), rng.normal(size=3)
    yr -= (yr @ zr) / (zr @ zr) * zr
    bodies = {"ground": {"fixed": True, "position": p(), "orientation": rot_z(0.3).tolist()}}
    bodies |= {f"b{k}": {} for k in range(1, 9)}
    bodies["b1"] = {"points": {"tip": p(), "centre": p()}}
    bodies["ground"]["points"] = {"mark": p()}
    rs_i, rs_axis, rs_j = np.array(p()), np.array(p()), np.array(p())
    rs_i += ((rs_j - rs_i) @ rs_axis) / (rs_axis @ rs_axis) * rs_axis  # on the foot of the perpendicular
    joints = {
        "R": {"type": "revolute", "bodies": ["ground", "b1"], "point": p(), "axis": p()},
        "P": {"type": "translational", "bodies": ["ground", "b2"], "point": p(), "axis": p()},
        "C": {"type": "cylindrical", "bodies": ["b3", "ground"], "point": p(), "axis": p()},
        "U": {"type": "universal", "bodies": ["b1", "b4"], "point": p(), "axis_i": z.tolist(), "axis_j": y.tolist()},
        "S": {"type": "spherical", "bodies": ["b2", "b5"], "point": p()},
        "F": {"type": "fixed", "bodies": ["b3", "b6"], "point": p()},
        "FR": {"type": "free", "bodies": ["ground", "b7"], "point": p()},
        "ST": {"type": "S-T", "bodies": ["ground", "b8"], "point": p(), "axis": p()},
        "RS": {
            "type": "R-S",
            "bodies": ["ground", "b1"],
            "point_i": rs_i.tolist(),
            "axis": rs_axis.tolist(),
            "point_j": rs_j.tolist(),
        },
        "TD": {"type": "T-D", "bodies": ["ground", "b2"], "point_i": p(), "axis": p(), "point_j": p(), "length": 1.5},
        "D": {"type": "distance", "bodies": ["b4", "b5"], "point_i": p(), "point_j": p()},
        "D1": {"type": "dot-1", "bodies": ["b6", "b7"], "axis_i": p(), "axis_j": p()},
        "D2": {"type": "dot-2", "bodies": ["b7", "b8"], "point_i": p(), "axis": p(), "point_j": p()},
        "SP": {"type": "spherical-point", "bodies": ["b8", "b5"], "point": p()},
        "RC": {"type": "revolute", "bodies": ["b3", "b8"], "cut": True, "point": p(), "axis": p()},
        "UC": {
            "type": "universal",
            "bodies": ["b4", "b6"],
            "cut": True,
            "point": p(),
            "axis_i": zr.tolist(),
            "axis_j": yr.tolist(),
        },
        "STC": {"type": "spherical-translational", "bodies": ["b1", "b6"], "cut": True, "point": p(), "axis": p()},
    }
    return {
        "kinprop": 1,
        "style": "hardpoints",
        "name": "all types",
        "units": {"length": "mm", "angle": "deg", "axes": "ISO8855"},
        "bodies": bodies,
        "joints": joints,
    }


def _normalised(data: dict) -> dict:
    """File data with axes made unit (and universal second axes as given: already perpendicular)."""
    out = yaml.safe_load(yaml.safe_dump(data))
    for j in out["joints"].values():
        for key in ("axis", "axis_i", "axis_j"):
            if key in j:
                v = np.array(j[key])
                j[key] = (v / np.linalg.norm(v)).tolist()
    return out


@pytest.mark.parametrize("body_frames", ["global", "joint"])
def test_every_joint_type_round_trips(body_frames, tmp_path):
    """hardpoints -> frames -> hardpoints reproduces every point, axis and length."""
    data = _all_types_file(np.random.default_rng(7)) | {"body_frames": body_frames}
    model = model_from_data(data)
    back = model_to_hardpoints(model, body_frames)
    assert set(back["joints"]) == set(data["joints"])
    for name, j in back["joints"].items():
        assert set(j) - {"length"} == set(data["joints"][name]) - {"length"}, name
    assert (
        hardpoint_difference(_normalised(data) | {"joints": _with_lengths(_normalised(data)["joints"], back)}, back)
        < 1e-12
    )
    # through a frame-style file as well (the writer's full precision)
    dump_model(model, tmp_path / "frames.yaml")
    again = load_model(tmp_path / "frames.yaml")
    assert again.units == {"length": "mm", "angle": "deg", "axes": "ISO8855"}
    assert hardpoint_difference(back, model_to_hardpoints(again, body_frames)) < 1e-12


def _with_lengths(joints: dict, back: dict) -> dict:
    """Derived lengths are written back explicitly."""
    return {
        k: v | ({"length": back["joints"][k]["length"]} if "length" in back["joints"][k] else {})
        for k, v in joints.items()
    }


def test_body_frame_rules_are_the_same_mechanism():
    """Global and joint body frames differ only in body frames: same joint placement for any q."""
    data = _all_types_file(np.random.default_rng(3))
    a = model_from_data(data | {"body_frames": "global"})
    b = model_from_data(data | {"body_frames": "joint"})
    assert a.coordinates.keys() == b.coordinates.keys()
    rng = np.random.default_rng(5)
    for _ in range(3):
        q = {k: v + 0.3 * rng.normal(size=v.shape) for k, v in a.coordinates.items()}
        qa, qb = a.with_state(a.design, q), b.with_state(b.design, q)
        assert hardpoint_difference(qa, qb) < 1e-12
        phi_a = assembly_for(a.mechanism).residual(a.design, qa.coordinates)
        phi_b = assembly_for(b.mechanism).residual(b.design, qb.coordinates)
        np.testing.assert_allclose(phi_a, phi_b, atol=1e-12)


def test_joint_body_frames_have_no_child_side_vectors():
    """With the paper's reading of edits; edits: design adds them (zero s', the frame's C) so that
    a tree joint can move without moving its child body."""
    data = _all_types_file(np.random.default_rng(3)) | {"body_frames": "joint", "edits": "mechanism"}
    model = model_from_data(data)
    topo = assembly_for(model.mechanism).topology
    for t in topo.tree:
        child = "i" if t.reversed else "j"
        assert f"{t.joint}.s_{child}" not in model.design
        assert f"{t.joint}.C_{child}" not in model.design
    design = model_from_data(data | {"edits": "design"})
    for t in topo.tree:
        child = "i" if t.reversed else "j"
        np.testing.assert_array_equal(design.design[f"{t.joint}.s_{child}"], 0.0)


def test_named_points_live_in_body_frames():
    data = _all_types_file(np.random.default_rng(11))
    model = model_from_data(data)
    b1 = model.mechanism.body("b1")
    r = np.array(data["joints"]["R"]["point"])  # b1's tree joint point = its frame origin
    for name, value in b1.points:
        np.testing.assert_allclose(np.array(value), np.array(data["bodies"]["b1"]["points"][name]) - r, atol=1e-12)
    ground = model.mechanism.body("ground")
    mark = dict(ground.points)["mark"]
    np.testing.assert_allclose(
        ground.r + ground.A @ np.array(mark), data["bodies"]["ground"]["points"]["mark"], atol=1e-12
    )


def test_tree_joint_coordinates_are_zero_at_the_reference():
    model = load_model(EXAMPLES / "mcpherson_hardpoints.yaml")
    np.testing.assert_array_equal(model.coordinates["ST"], [1.0, 0, 0, 0, 0])
    np.testing.assert_array_equal(model.coordinates["TD"], [0.0])
    assert model.units["axes"] == "right-handed"


def test_revolute_spherical_point_moves_to_the_foot_of_the_perpendicular():
    data = yaml.safe_load((EXAMPLES / "mcpherson_hardpoints.yaml").read_text())
    axis = np.array(data["joints"]["RS"]["axis"])
    data["joints"]["RS"]["point_i"] = (np.array(data["joints"]["RS"]["point_i"]) + 0.1 * axis).tolist()
    moved = model_from_data(data)
    assert hardpoint_difference(moved, load_model(EXAMPLES / "mcpherson_hardpoints.yaml")) < 1e-12


def test_lengths_in_millimetres_give_the_same_angles():
    """A model in mm propagates to the same joint angles and 1000 x the lengths, also when the
    free set mixes angles and lengths: the least change is measured in metres and radians
    (docs/analysis/weights.md). A weight changes that metric the same way in every unit."""
    data = yaml.safe_load((EXAMPLES / "slider_crank_hardpoints.yaml").read_text())
    for j in data["joints"].values():
        if "point" in j:
            j["point"] = [1000 * x for x in j["point"]]
    data["units"]["length"] = "mm"
    mm, m = model_from_data(data), load_model(EXAMPLES / "slider_crank_hardpoints.yaml")
    np.testing.assert_allclose(mm.design["J12.s_j"], 1000 * m.design["J12.s_j"])
    change = {"J12.s_j": m.design["J12.s_j"] * 0.99}
    change_mm = {"J12.s_j": mm.design["J12.s_j"] * 0.99}
    for free, weights in ((("J01.q", "J32.q"), None), (("q",), None), (("q",), {"J03.q": 1e6})):
        pm = propagate(m, change, free, weights=weights)
        pmm = propagate(mm, change_mm, free, weights=weights)
        for k in ("J01", "J32"):
            np.testing.assert_allclose(pm.after.coordinates[k], pmm.after.coordinates[k], atol=1e-9)
        np.testing.assert_allclose(1000 * pm.after.coordinates["J03"], pmm.after.coordinates["J03"], atol=1e-6)
    weighted = propagate(mm, change_mm, ("q",), weights={"J03.q": 1e6})
    assert abs(weighted.after.coordinates["J01"][0] - propagate(m, change, ("q",)).after.coordinates["J01"][0]) > 1e-4


def test_axis_conventions_are_recorded_not_converted():
    data = yaml.safe_load((EXAMPLES / "slider_crank_hardpoints.yaml").read_text())
    data["units"]["axes"] = "SAE"
    sae = model_from_data(data)
    assert sae.units["axes"] == "SAE"
    assert model_to_hardpoints(sae)["units"]["axes"] == "SAE"
    assert hardpoint_difference(sae, load_model(EXAMPLES / "slider_crank_hardpoints.yaml")) == 0.0


# --- frames -> hardpoints -> frames -------------------------------------------------------------


@pytest.mark.parametrize("name", CASES)
def test_frames_hardpoints_frames_round_trip(pairs, name, tmp_path):
    """Frame file -> hardpoints -> frame file: the same joints in space, assembled, same propagation."""
    frames, _ = pairs[name]
    hp = model_to_hardpoints(frames)
    (tmp_path / "hp.yaml").write_text(yaml.safe_dump(hp, sort_keys=False))
    dump_model(load_model(tmp_path / "hp.yaml"), tmp_path / "frames.yaml")
    back = load_model(tmp_path / "frames.yaml")
    assert hardpoint_difference(frames, back) < 1e-12
    assert hardpoint_difference(hp, model_to_hardpoints(back)) < 1e-12
    assert np.linalg.norm(assembly_for(back.mechanism).residual(back.design, back.coordinates)) < 1e-12
    assert [b.name for b in back.mechanism.bodies] == [b.name for b in frames.mechanism.bodies]
    assert [(j.name, j.type, j.body_i, j.body_j) for j in back.mechanism.joints] == [
        (j.name, j.type, j.body_i, j.body_j) for j in frames.mechanism.joints
    ]
    changes, frees = CASES[name]
    pf = propagate(frames, changes, frees[-1])
    pb = propagate(back, {k: express_in(frames, back, k, v) for k, v in changes.items()}, frees[-1])
    assert hardpoint_difference(pf.after, pb.after) < TOL


def test_hardpoints_of_an_unassembled_model_report_the_gap():
    raw = load_model(EXAMPLES / "slider_crank.yaml")
    gaps = joint_mismatch(raw)
    assert gaps["J12"] > 1e-4
    assert max(joint_mismatch(assemble(raw).after).values()) < 1e-12


def test_double_wishbone_from_published_hardpoints():
    """The hardpoint file written straight from Chrono's HMMWV hardpoints is the frame-style
    example (whose s' and C were derived by hand, printed to ~10 digits)."""
    frames = load_model(EXAMPLES / "double_wishbone.yaml")
    hard = load_model(EXAMPLES / "double_wishbone_hardpoints.yaml")
    assert hard.units == {"length": "mm", "angle": "deg", "axes": "ISO8855", "force": "N"}
    assert max(joint_mismatch(hard).values()) < 1e-9
    assert hardpoint_difference(frames, hard) < 1e-6
    jounce = {"LCA.q": [np.radians(5.0)]}
    with warnings.catch_warnings():  # a near-singularity warning, if any, is the same for both
        warnings.simplefilter("ignore")
        pf, ph = propagate(frames, jounce, ("q",)), propagate(hard, jounce, ("q",))
    assert pf.converged and ph.converged
    assert hardpoint_difference(pf.after, ph.after) < 1e-6


def test_axes_are_directions_of_any_size():
    data = yaml.safe_load((EXAMPLES / "slider_crank_hardpoints.yaml").read_text())
    data["joints"]["J01"]["axis"] = [1e308, 0.0, 0.0]
    data["joints"]["J03"]["axis"] = [0.0, 1e-9, 0.0]
    data["joints"]["J32"]["axis_j"] = [0.0, 0.49998490280576613e300, 0.8660341199781385e300]
    model = model_from_data(data)
    assert hardpoint_difference(model, load_model(EXAMPLES / "slider_crank_hardpoints.yaml")) < 1e-15
    for key in ("J01.C_i", "J03.C_i", "J32.C_i"):
        assert is_rotation(model.design[key], 1e-14)
