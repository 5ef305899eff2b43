"""The Cassie leg and the Robotiq 2F-85 gripper from MuJoCo Menagerie (examples/mjcf/).

Truth: MuJoCo itself. Cassie: its mobility is nv - rank of MuJoCo's equality Jacobian at the
reference; a sweep of the knee with the loop joints free reproduces MuJoCo's constrained
kinematics (Newton on MuJoCo's own constraint residual ``efc_pos`` and Jacobian ``efc_J``,
moving the same joints). Robotiq: the two drivers' ``<equality><joint>`` is a coupling row, so
the gripper's mobility is MuJoCo's 3 (4 without the coupling), and a sweep of the right driver
with the left driver, spring links and followers free (couplers held) reproduces MuJoCo's
constrained kinematics (the same Newton on MuJoCo's ``efc_pos``, coupling row included).
"""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from imports_helpers import MJCF, frame_outputs, mujoco_poses, mujoco_project, pose_from_row, with_frame_points
from typer.testing import CliRunner

import kinprop as kp
from kinprop.cli import app
from kinprop.imports.mjcf import document_to_model, read_mjcf, read_mjcf_text

CASSIE = MJCF / "cassie_left_leg_kinematic.xml"
ROBOTIQ = MJCF / "robotiq_2f85_kinematic.xml"
LOOP_JOINTS = ["left-achilles-rod", "left-tarsus", "left-plantar-rod", "left-foot"]
runner = CliRunner()


def test_cassie_assembles_from_its_keyframe_and_reports_mobility() -> None:
    model = kp.load_model(CASSIE)
    assert kp.mobility(model).mobility == 8
    start = document_to_model(read_mjcf(CASSIE), keyframe="home_left")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", kp.SingularityWarning)
        prop = kp.assemble(start, tol=1e-13)
    assert prop.result.residual_history[0] > 1e-3  # the keyframe leaves the loops ~1.5 mm open
    assert prop.converged and prop.result.residual < 1e-12


def _mujoco_equalities(path):
    """MuJoCo's equality-constraint rows and their dense Jacobian at the file's reference."""
    mujoco = pytest.importorskip("mujoco")
    from imports_helpers import equality_rows

    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    m.opt.jacobian = mujoco.mjtJacobian.mjJAC_DENSE
    mujoco.mj_forward(m, d)
    return m, *equality_rows(mujoco, m, d)


def test_cassie_mobility_is_mujocos() -> None:
    m, _, J = _mujoco_equalities(CASSIE)
    r = runner.invoke(app, ["check", str(CASSIE), "--assemble", "--json"])
    assert r.exit_code == 0, r.output
    obj = json.loads(r.stdout)
    assert obj["mobility"] == m.nv - np.linalg.matrix_rank(J, 1e-9) == 8
    assert obj["gruebler"] == 7 and len(obj["redundant"]) == 1  # the plantar four-bar is planar


def test_cassie_knee_sweep_reproduces_mujoco() -> None:
    mujoco = pytest.importorskip("mujoco")
    doc = read_mjcf(CASSIE)
    model = with_frame_points(document_to_model(doc))
    bodies = [b.name for b in model.mechanism.bodies if not b.fixed]
    res = kp.sweep(
        model,
        ["left-knee=-0.6:0.1:7"],
        free=[f"{j}.q" for j in LOOP_JOINTS],
        outputs=[o for b in bodies for o in frame_outputs(b)],
        tol=1e-12,
    )
    df = res.frame
    assert (df["status"] == "converged").all()
    m = mujoco.MjModel.from_xml_path(str(CASSIE))
    d = mujoco.MjData(m)
    dofs = [
        int(m.jnt_dofadr[m.joint(j).id]) + k for j in LOOP_JOINTS for k in range(3 if j == "left-achilles-rod" else 1)
    ]
    knee = int(m.jnt_qposadr[m.joint("left-knee").id])
    qpos = m.qpos0.copy()
    worst = 0.0
    tarsus = []
    for _, row in df.iterrows():
        qpos[knee] = row["left-knee.q"] + m.qpos0[knee]  # q = qpos - ref
        qpos = mujoco_project(mujoco, m, d, qpos, dofs)
        mujoco.mj_kinematics(m, d)
        for name, (p, R) in mujoco_poses(mujoco, m, d).items():
            if name == "cassie-pelvis":
                continue
            p_k, R_k = pose_from_row(row.to_dict(), name)
            cols = [0] if name == "left-achilles-rod" else [0, 1, 2]  # the rod's spin is idle
            worst = max(worst, float(np.abs(p_k - p).max()), float(np.abs(R_k[:, cols] - R[:, cols]).max()))
        tarsus.append(qpos[int(m.jnt_qposadr[m.joint("left-tarsus").id])])
    assert worst < 1e-9, worst
    assert np.ptp(tarsus) > 0.3  # the tarsus really followed the knee through the achilles loop


ROBOTIQ_FREE = ["left_driver_joint", "right_spring_link_joint", "right_follower_joint", "left_spring_link_joint",
                "left_follower_joint"]  # fmt: skip


def test_robotiq_imports_with_its_coupling(tmp_path) -> None:
    model = kp.load_model(ROBOTIQ)
    [c] = model.mechanism.couplings
    assert (c.joint_a, c.joint_b, c.q_a0, c.q_b0) == ("right_driver_joint", "left_driver_joint", 0.0, 0.0)
    np.testing.assert_array_equal(model.design[f"{c.name}.coef"], [0, 1, 0, 0, 0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", kp.SingularityWarning)
        prop = kp.assemble(model)
    assert prop.converged and prop.result.residual < 1e-14  # connects and coupling hold at the reference
    r = runner.invoke(app, ["check", str(ROBOTIQ), "--assemble", "--json"])
    assert r.exit_code == 0, r.output
    obj = json.loads(r.stdout)
    assert obj["mobility"] == 3 and obj["n_constraints"] == 7 and obj["rank"] == 5
    assert obj["couplings"] == [
        {"name": c.name, "joints": ["right_driver_joint", "left_driver_joint"], "rows": [f"{c.name}:coupling"]}
    ]
    out = tmp_path / "robotiq.yaml"
    r = runner.invoke(app, ["import", str(ROBOTIQ), "-o", str(out)])
    assert r.exit_code == 0, r.output
    assert f"(2 cut: connect_right_follower_right_coupler, connect_left_follower_left_coupler), 1 coupling: {c.name}" \
        in " ".join(r.output.split())  # fmt: skip
    back = kp.load_model(out)  # the written file keeps the coupling
    assert back.mechanism.couplings == model.mechanism.couplings
    np.testing.assert_array_equal(back.design[f"{c.name}.coef"], [0, 1, 0, 0, 0])


def test_robotiq_mobility_is_mujocos() -> None:
    m, r, J = _mujoco_equalities(ROBOTIQ)
    assert len(r) == 7  # two connects (3 rows each) and the joint coupling
    assert kp.mobility(kp.load_model(ROBOTIQ)).mobility == m.nv - np.linalg.matrix_rank(J, 1e-9) == 3


def test_robotiq_driver_sweep_reproduces_mujoco() -> None:
    mujoco = pytest.importorskip("mujoco")
    doc = read_mjcf(ROBOTIQ)
    model = with_frame_points(document_to_model(doc))
    bodies = [b.name for b in model.mechanism.bodies if not b.fixed]
    res = kp.sweep(
        model,
        ["right_driver_joint=0:0.8:8"],
        free=[f"{j}.q" for j in ROBOTIQ_FREE],
        outputs=[o for b in bodies for o in frame_outputs(b)] + ["left_driver_joint.q"],
        tol=1e-12,
    )
    df = res.frame
    assert (df["status"] == "converged").all()
    np.testing.assert_allclose(df["left_driver_joint.q"], df["right_driver_joint.q"], rtol=0, atol=1e-12)
    m = mujoco.MjModel.from_xml_path(str(ROBOTIQ))
    d = mujoco.MjData(m)
    dofs = [int(m.jnt_dofadr[m.joint(j).id]) for j in ROBOTIQ_FREE]
    driver = int(m.jnt_qposadr[m.joint("right_driver_joint").id])
    qpos = m.qpos0.copy()
    worst = 0.0
    follower = []
    for _, row in df.iterrows():
        qpos[driver] = row["right_driver_joint.q"] + m.qpos0[driver]
        qpos = mujoco_project(mujoco, m, d, qpos, dofs)
        mujoco.mj_kinematics(m, d)
        for name, (p, R) in mujoco_poses(mujoco, m, d).items():
            if name in ("base_mount", "base"):
                continue
            p_k, R_k = pose_from_row(row.to_dict(), name)
            worst = max(worst, float(np.abs(p_k - p).max()), float(np.abs(R_k - R).max()))
        follower.append(qpos[int(m.jnt_qposadr[m.joint("left_follower_joint").id])])
    assert worst < 1e-9, worst
    assert np.ptp(follower) > 0.3  # the left finger really followed the right driver through the coupling


def test_robotiq_without_the_coupling_has_mujocos_mobility() -> None:
    mujoco = pytest.importorskip("mujoco")
    from imports_helpers import equality_rows

    text = ROBOTIQ.read_text()
    start = text.index('    <joint joint1="right_driver_joint"')
    text = text[:start] + text[text.index("\n", start) + 1 :]
    model = document_to_model(read_mjcf_text(text, "robotiq_uncoupled.xml"))
    m = mujoco.MjModel.from_xml_string(text)
    d = mujoco.MjData(m)
    m.opt.jacobian = mujoco.mjtJacobian.mjJAC_DENSE
    mujoco.mj_forward(m, d)
    _, J = equality_rows(mujoco, m, d)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", kp.SingularityWarning)
        prop = kp.assemble(model)
    assert prop.converged and prop.result.residual < 1e-14  # connects hold at the reference
    assert kp.mobility(prop.after).mobility == m.nv - np.linalg.matrix_rank(J, 1e-9) == 4
    # the class defaults (axis, follower pivot pos) and quats place every body as MuJoCo does
    from imports_helpers import body_poses

    doc = read_mjcf_text(text, "robotiq_uncoupled.xml")
    rng = np.random.default_rng(3)
    for _ in range(3):
        d.qpos[:] = rng.uniform(-0.5, 0.5, m.nq)
        mujoco.mj_kinematics(m, d)
        mj = mujoco_poses(mujoco, m, d)
        ours = body_poses(model.with_state(model.design, doc.coordinates(d.qpos)), list(mj))
        worst = max(max(np.abs(ours[n][0] - mj[n][0]).max(), np.abs(ours[n][1] - mj[n][1]).max()) for n in mj)
        assert worst < 1e-14


def test_imported_yaml_loads_back_with_the_same_poses(tmp_path) -> None:
    from imports_helpers import body_poses

    out = tmp_path / "cassie.yaml"
    r = runner.invoke(app, ["import", str(CASSIE), "-o", str(out)])
    assert r.exit_code == 0, r.output
    assert "note:" in r.output and "<inertial>" in r.output and "2 cut" in r.output
    r = runner.invoke(app, ["check", str(out), "--assemble", "--json"])
    assert r.exit_code == 0 and json.loads(r.stdout)["mobility"] == 8
    direct, back = kp.load_model(CASSIE), kp.load_model(out)
    names = direct.mechanism.body_names
    a, b = body_poses(direct, names), body_poses(back, names)
    # the written numbers are rounded to 15 digits of their vector (no last-digit noise, issue 19)
    assert max(np.abs(a[n][0] - b[n][0]).max() + np.abs(a[n][1] - b[n][1]).max() for n in names) < 1e-14


def test_coupling_record_matches_mujocos_residual() -> None:
    """The recorded coupling, in kinprop coordinates (q = qpos - ref), is MuJoCo's residual
    q[joint1] - poly(q[joint2]), and so is the imported model's coupling row."""
    mujoco = pytest.importorskip("mujoco")
    xml = """<mujoco><compiler angle="radian"/><worldbody>
      <body><inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/><joint name="a" axis="0 1 0" ref="0.3"/></body>
      <body><inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/><joint name="b" axis="0 1 0" ref="-0.2"/></body>
      </worldbody><equality><joint joint1="b" joint2="a" polycoef="0.1 2 0.5 -0.3 0.2"/></equality></mujoco>"""
    doc = read_mjcf_text(xml, "c.xml")
    [c] = doc.couplings
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    for qpos in ([0.3, -0.2], [0.5, 0.1], [1.0, -1.0]):
        d.qpos[:] = qpos
        mujoco.mj_forward(m, d)
        q = doc.coordinates(np.array(qpos))
        x = float(q[c.joint2][0])
        ours = float(q[c.joint1][0]) - sum(a * x**k for k, a in enumerate(c.polycoef))
        assert ours == pytest.approx(float(d.efc_pos[0]), abs=1e-14)
        model = document_to_model(doc)
        row = kp.compile(model).residual(model.design, q)
        assert row[0] == pytest.approx(float(d.efc_pos[0]), abs=1e-14)
