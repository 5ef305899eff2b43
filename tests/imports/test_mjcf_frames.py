"""MJCF frames, defaults and joints against MuJoCo's own compiler and forward kinematics.

Truth: ``mujoco`` (MjModel.from_xml_string, mj_kinematics): every body pose at the reference
(qpos0) and at random joint values, mapped to kinprop coordinates by ``q = qpos - ref``, must
agree to rounding; connect residuals must agree; a weld's ``relpose`` must mean what MuJoCo
takes it to mean.
"""

from __future__ import annotations

import numpy as np
import pytest
from imports_helpers import body_poses, equality_rows, mujoco_poses

from kinprop import mobility
from kinprop.imports.mjcf import document_to_model, read_mjcf_text
from kinprop.io.hardpoints import joint_mismatch

mujoco = pytest.importorskip("mujoco")

INERTIAL = '<inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/>'

FRAMES = f"""
<mujoco model="frames">
  <compiler angle="degree" eulerseq="zXy"/>
  <default>
    <joint axis="0 1 0"/>
    <site pos="0 0 0.05"/>
    <default class="a">
      <joint axis="1 0 0" pos="0.1 0 0"/>
      <default class="b"><joint ref="30"/></default>
    </default>
  </default>
  <worldbody>
    <body name="base" pos="0.1 0.2 0.3" euler="10 20 30" childclass="a">
      {INERTIAL}
      <joint name="j1"/>
      <geom type="mesh" mesh="missing_mesh"/>
      <body name="b1" pos="0 0.3 0" axisangle="1 1 0 40">
        {INERTIAL}
        <joint name="j2" class="b"/>
        <joint name="j3" type="slide" axis="0 0.3 1" ref="0.05"/>
        <site name="tip"/>
        <frame pos="0.1 0 0" xyaxes="0 1 0 -1 0.2 0">
          <body name="b2" pos="0.2 0 0" zaxis="0 1 1">
            {INERTIAL}
            <joint name="j4" type="ball" pos="0 0 0.1"/>
            <site name="s2" pos="0.1 0.1 0"/>
            <body name="b3" pos="0 0 0.2" quat="0.5 0.5 -0.5 0.7">
              {INERTIAL}
              <joint name="j5" class="main" ref="-20"/>
            </body>
          </body>
        </frame>
      </body>
    </body>
    <body name="floating" pos="1 0 0" euler="0 90 0">
      {INERTIAL}
      <freejoint name="float"/>
      <site name="fs" pos="0.1 0 0"/>
    </body>
    <body name="anti" zaxis="0 0 -1" pos="0 1 0">
      {INERTIAL}
      <joint name="j6" type="hinge" axis="1 1 1" pos="0 0.1 0"/>
      <body name="welded" pos="0.1 0 0" euler="0 0 45"/>
    </body>
    <body name="fixed_plate" pos="0 0 -1" xyaxes="1 1 0 0 0 1"/>
  </worldbody>
  <asset><mesh name="missing_mesh" file="does/not/exist.stl"/></asset>
  <equality>
    <connect body1="b3" body2="anti" anchor="0.1 0 0"/>
    <weld body1="floating" body2="welded"/>
    <connect site1="tip" site2="fs"/>
  </equality>
  <actuator><motor joint="j1"/></actuator>
  <sensor><jointpos joint="j1"/></sensor>
</mujoco>
"""


#: the same file without the geom whose mesh file does not exist (MuJoCo would open it)
CLEAN = FRAMES.replace('<geom type="mesh" mesh="missing_mesh"/>', "").replace(
    '<asset><mesh name="missing_mesh" file="does/not/exist.stl"/></asset>', ""
)


def _compare(model, mj_model, mj_data, tol: float = 1e-12) -> float:
    mj = mujoco_poses(mujoco, mj_model, mj_data)
    ours = body_poses(model, list(mj))
    worst = 0.0
    for name, (p, R) in mj.items():
        worst = max(worst, float(np.abs(ours[name][0] - p).max()), float(np.abs(ours[name][1] - R).max()))
    assert worst < tol, worst
    return worst


def test_reference_poses_and_notes_match_mujoco() -> None:
    doc = read_mjcf_text(FRAMES, "frames.xml")
    model = document_to_model(doc)
    m = mujoco.MjModel.from_xml_string(CLEAN)
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    _compare(model, m, d)
    assert doc.nq == m.nq == 1 + 1 + 1 + 4 + 1 + 7 + 1
    notes = " ".join(doc.notes)
    for kind in ("<geom>", "<asset>", "<actuator>", "<sensor>", "<inertial>"):
        assert kind in notes
    # the hinge refs in degrees became radians: qpos0 holds them, kinprop starts at q = 0
    assert np.allclose(doc.qpos(model.coordinates), m.qpos0, atol=1e-15)
    # sites are named points of their bodies; body 'fixed_plate' nothing moves: a fixed body
    pts = {b.name: dict(b.points) for b in model.mechanism.bodies}
    assert pts["b1"]["tip"] == pytest.approx((0.0, 0.0, 0.05))
    assert model.mechanism.body("fixed_plate").fixed and not model.mechanism.body("b2").fixed


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_random_configurations_match_mujoco(seed: int) -> None:
    rng = np.random.default_rng(seed)
    xml = CLEAN
    doc = read_mjcf_text(xml, "frames.xml")
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    qpos = m.qpos0 + rng.normal(scale=0.7, size=m.nq)
    d.qpos[:] = qpos
    mujoco.mj_normalizeQuat(m, d.qpos)
    m.opt.jacobian = mujoco.mjtJacobian.mjJAC_DENSE
    mujoco.mj_forward(m, d)
    model = document_to_model(doc)
    model = model.with_state(model.design, doc.coordinates(d.qpos))
    _compare(model, m, d)
    # connect residuals: the distance between the two points, on both sides
    r, _ = equality_rows(mujoco, m, d)
    gaps = joint_mismatch(model)
    mj_connect = [np.linalg.norm(r[0:3]), np.linalg.norm(r[9:12])]  # rows: connect, weld (6), connect
    assert gaps["connect_b3_anti"] == pytest.approx(mj_connect[0], rel=1e-10, abs=1e-13)
    assert gaps["connect_b1_floating"] == pytest.approx(mj_connect[1], rel=1e-10, abs=1e-13)


@pytest.mark.parametrize("order", ["body2 in body1", "body1 in body2"])
def test_weld_relpose_means_what_mujoco_means(order: str) -> None:
    """Write a relpose both ways; kinprop's weld is satisfied exactly when MuJoCo's is."""
    base = CLEAN.replace('<weld body1="floating" body2="welded"/>', "")
    m0 = mujoco.MjModel.from_xml_string(base)
    d0 = mujoco.MjData(m0)
    mujoco.mj_kinematics(m0, d0)
    poses = mujoco_poses(mujoco, m0, d0)
    (p1, R1), (p2, R2) = poses["b2"], poses["b1"]
    if order == "body1 in body2":
        (p1, R1), (p2, R2) = (p2, R2), (p1, R1)
    rel_p, rel_R = R1.T @ (p2 - p1), R1.T @ R2
    q = np.empty(4)
    mujoco.mju_mat2Quat(q, rel_R.ravel())
    rel = " ".join(repr(float(x)) for x in [*rel_p, *q])
    xml = base.replace("<equality>", f'<equality><weld name="w" body1="b2" body2="b1" relpose="{rel}"/>')
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    r, _ = equality_rows(mujoco, m, d)
    mj_ok = np.linalg.norm(r[:6]) < 1e-12
    ours_ok = joint_mismatch(document_to_model(read_mjcf_text(xml, "w.xml")))["w"] < 1e-12
    assert mj_ok == ours_ok
    assert mj_ok == (order == "body2 in body1")  # MuJoCo: relpose is body2's pose in body1's frame


def test_mobility_counts_the_connect_rows() -> None:
    model = document_to_model(read_mjcf_text(FRAMES, "frames.xml"))
    m = mujoco.MjModel.from_xml_string(CLEAN)
    d = mujoco.MjData(m)
    m.opt.jacobian = mujoco.mjtJacobian.mjJAC_DENSE
    mujoco.mj_forward(m, d)
    _, J = equality_rows(mujoco, m, d)
    assert mobility(model).mobility == m.nv - np.linalg.matrix_rank(J, 1e-9)
