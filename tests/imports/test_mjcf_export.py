"""`kinprop convert --to mjcf`: kinematic MJCF that MuJoCo loads and moves as kinprop does.

Truth: MuJoCo. The round trip MJCF -> kinprop -> MJCF keeps every body pose at the reference
(1e-12); exported joints move bodies as kinprop's joints do (universal joints at non-zero
angles, both tree directions); an exported Chrono suspension, projected onto its constraints
by MuJoCo with the driver hinge set, puts the upright where kinprop's sweep puts it.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from imports_helpers import (
    CHRONO,
    MJCF,
    body_poses,
    equality_rows,
    frame_outputs,
    mujoco_poses,
    mujoco_project,
    pose_from_row,
    with_frame_points,
)
from typer.testing import CliRunner

import kinprop as kp
from kinprop.cli import app
from kinprop.imports.mjcf_export import model_to_mjcf
from kinprop.io.files import model_from_data

mujoco = pytest.importorskip("mujoco")
runner = CliRunner()


def _round_trip(tmp_path, name: str):
    """``kinprop convert FILE --to mjcf``; both files loaded in MuJoCo at their reference:
    ``(a, b, b's data, the worst body-pose difference)``."""
    src, out = MJCF / name, tmp_path / f"out_{name}"
    r = runner.invoke(app, ["convert", str(src), "--to", "mjcf", "-o", str(out)])
    assert r.exit_code == 0, r.output
    a = mujoco.MjModel.from_xml_path(str(src))
    da = mujoco.MjData(a)
    mujoco.mj_kinematics(a, da)
    b = mujoco.MjModel.from_xml_path(str(out))
    db = mujoco.MjData(b)
    mujoco.mj_forward(b, db)
    before, after = mujoco_poses(mujoco, a, da), mujoco_poses(mujoco, b, db)
    assert set(before) <= set(after)
    worst = max(max(np.abs(before[n][0] - after[n][0]).max(), np.abs(before[n][1] - after[n][1]).max()) for n in before)
    return a, b, db, out, worst


def test_cassie_round_trip_keeps_every_body_pose(tmp_path) -> None:
    a, b, db, _, worst = _round_trip(tmp_path, "cassie_left_leg_kinematic.xml")
    assert worst < 1e-12, worst
    r_eq, _ = equality_rows(mujoco, b, db)
    assert b.neq == 2 and np.abs(r_eq).max() < 1e-15
    assert (b.nq, b.nv) == (a.nq, a.nv)


def test_robotiq_round_trip_keeps_the_coupling(tmp_path) -> None:
    _, b, _, out, worst = _round_trip(tmp_path, "robotiq_2f85_kinematic.xml")
    assert worst < 1e-12, worst
    assert b.neq == 3 and list(b.eq_type).count(mujoco.mjtEq.mjEQ_JOINT) == 1
    k = list(b.eq_type).index(mujoco.mjtEq.mjEQ_JOINT)
    np.testing.assert_array_equal(b.eq_data[k][:5], [0, 1, 0, 0, 0])
    assert kp.load_model(out).mechanism.couplings[0].joint_a == "right_driver_joint"


def test_exported_coupling_is_kinprops_row_about_the_current_pose() -> None:
    """A cubic coupling with offsets, exported away from its offsets: MuJoCo's polynomial is
    about qpos0 (the current coordinates), so the exported coefficients are re-expanded there;
    MuJoCo's residual equals kinprop's coupling row at other coordinates too."""
    data = {
        "kinprop": 1,
        "units": {"length": "m", "angle": "deg"},
        "bodies": {"ground": {"fixed": True}, "a": {}, "b": {}},
        "joints": {
            "RA": {"type": "revolute", "bodies": ["ground", "a"], "q": [20]},
            "PB": {"type": "translational", "bodies": ["ground", "b"], "s_i": [1, 0, 0], "q": [0.3]},
        },
        "couplings": {"C": {"joints": ["RA", "PB"], "coef": [5, 40, -10, 7], "q0": [-3, 0.1]}},
    }
    model = kp.assemble(model_from_data(data), free=["RA.q"]).after
    xml, warns = model_to_mjcf(model)
    assert not warns
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    eng = kp.compile(model)
    qa0, qb0 = float(model.coordinates["RA"][0]), float(model.coordinates["PB"][0])
    for dqa, dqb in ((0.0, 0.0), (0.2, -0.4), (-0.5, 0.7)):
        d.qpos[:] = [dqa, dqb]
        mujoco.mj_forward(m, d)
        r, _ = equality_rows(mujoco, m, d)
        ours = eng.residual(model.design, {"RA": [qa0 + dqa], "PB": [qb0 + dqb]})
        assert r[0] == pytest.approx(ours[0], abs=1e-12)


def _universal_model(reversed_: bool) -> kp.Model:
    bodies = ["link", "base"] if reversed_ else ["base", "link"]
    data = {
        "kinprop": 1,
        "name": "u",
        "units": {"length": "m", "angle": "rad"},
        "bodies": {"base": {"fixed": True, "position": [0.1, 0, 0.2]}, "link": {}},
        "joints": {
            "U": {
                "type": "universal",
                "bodies": bodies,
                "s_i": [0.1, 0.2, 0.3],
                "s_j": [-0.2, 0.05, 0.1],
                "C_i": np.eye(3).tolist(),
                "C_j": [[0, 0, 1], [1, 0, 0], [0, 1, 0]],
                "q": [0.3, -0.4],
            }
        },
    }
    return kp.io.model_from_data(data)


@pytest.mark.parametrize("reversed_", [False, True])
def test_universal_joint_moves_as_in_kinprop(reversed_: bool) -> None:
    from kinprop.spatial import exp_so3

    model = _universal_model(reversed_)
    C_i = exp_so3([0.3, -0.2, 0.5])
    model = model.with_state(model.design.replace({"U.C_i": C_i}), model.coordinates)
    xml, warns = model_to_mjcf(model)
    assert not warns
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    for delta in ([0.0, 0.0], [0.2, 0.0], [0.0, -0.3], [0.25, 0.35]):
        d.qpos[m.joint("U__q0").qposadr[0]], d.qpos[m.joint("U__q1").qposadr[0]] = delta
        mujoco.mj_kinematics(m, d)
        p, R = mujoco_poses(mujoco, m, d)["link"]
        moved = model.with_state(model.design, {"U": np.array([0.3, -0.4]) + delta})
        p_k, R_k = body_poses(moved, ["link"])["link"]
        assert np.abs(p - p_k).max() < 1e-12 and np.abs(R - R_k).max() < 1e-12


@pytest.mark.parametrize(
    ("name", "driver"), [("DoubleWishbone", "LCA"), ("MacPhersonStrut", "LCA"), ("MultiLink", "UA")]
)
def test_exported_suspension_moves_as_kinprop_sweeps(name: str, driver: str) -> None:
    model = kp.load_model(CHRONO / f"{name}.json")
    xml, warns = model_to_mjcf(model)
    assert not warns
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    m.opt.jacobian = mujoco.mjtJacobian.mjJAC_DENSE
    mujoco.mj_forward(m, d)
    r, J = equality_rows(mujoco, m, d)
    assert np.abs(r).max() < 1e-15
    rods = [i for i in range(m.njnt) if mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, i).endswith("__rod_ball")]
    idle = len(rods)  # each distance rod spins about itself
    assert m.nv - np.linalg.matrix_rank(J, 1e-9) == 1 + idle  # wheel travel
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", kp.SingularityWarning)
        df = kp.sweep(with_frame_points(model), [f"{driver}=-6:6:4"], outputs=frame_outputs("upright"), tol=1e-12).frame
    assert (df["status"] == "converged").all()
    drv = m.joint(driver)
    dofs = [k for k in range(m.nv) if k != int(drv.dofadr[0])]
    qpos = m.qpos0.copy()
    for _, row in df.iterrows():
        qpos[int(drv.qposadr[0])] = np.radians(row[f"{driver}.q"])
        qpos = mujoco_project(mujoco, m, d, qpos, dofs)
        mujoco.mj_kinematics(m, d)
        p, R = mujoco_poses(mujoco, m, d)["upright"]
        p_k, R_k = pose_from_row(row.to_dict(), "upright")
        assert np.abs(p - p_k).max() < 1e-10 and np.abs(R - R_k).max() < 1e-10


EXAMPLE_DRIVERS = {
    "bennett.yaml": None,
    "double_wishbone.yaml": "LCA",
    "double_wishbone_hardpoints.yaml": "LCA",
    "fourbar.yaml": "O2",
    "fourbar_geared.yaml": "G",
    "fourbar_double_rocker.yaml": None,
    "fourbar_spatial.yaml": None,
    "mcpherson.yaml": None,
    "mcpherson_hardpoints.yaml": None,
    "slider_crank.yaml": "J01",
    "slider_crank_hardpoints.yaml": None,
    "stewart.yaml": None,
}


@pytest.mark.parametrize("name", sorted(EXAMPLE_DRIVERS))
def test_every_example_exports_and_moves_as_in_kinprop(name: str) -> None:
    """Every shipped example: MuJoCo loads it at kinprop's poses with its loops closed; its
    mobility is kinprop's plus one idle spin per ball-jointed rod; driven, it moves as kinprop."""
    from imports_helpers import EXAMPLES

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", kp.SingularityWarning)
        model = kp.assemble(kp.load_model(EXAMPLES / name), tol=1e-12).after
    xml, warns = model_to_mjcf(model)
    assert not warns
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    m.opt.jacobian = mujoco.mjtJacobian.mjJAC_DENSE
    mujoco.mj_forward(m, d)
    r, J = equality_rows(mujoco, m, d)
    scale = max(1.0, float(np.abs(d.xpos).max()))
    assert np.abs(r).max() < 1e-13 * scale
    mj = mujoco_poses(mujoco, m, d)
    names = model.mechanism.body_names
    ours = body_poses(model, names)
    worst = max(max(np.abs(ours[n][0] - mj[n][0]).max() / scale, np.abs(ours[n][1] - mj[n][1]).max()) for n in names)
    # frame-style files print C to ~10 digits, so their A are orthonormal to ~1e-11 only, while
    # MuJoCo's quaternions are exactly orthonormal; hardpoint-style and imported models are exact
    assert worst < (1e-10 if "C_i:" in (EXAMPLES / name).read_text() else 1e-12)
    rods = sum(1 for k in range(m.njnt) if mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, k).endswith("__rod_ball"))
    assert m.nv - np.linalg.matrix_rank(J, 1e-9) == kp.mobility(model).mobility + rods
    driver = EXAMPLE_DRIVERS[name]
    if driver is None:
        return
    q0 = float(np.asarray(model.coordinates[driver])[0])
    deg = model.units.get("angle") == "deg"
    step = 5.0 if deg else 0.08
    q_now = np.degrees(q0) if deg else q0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", kp.SingularityWarning)
        df = kp.sweep(
            with_frame_points(model),
            [f"{driver}={q_now}:{q_now + step}:1"],
            outputs=[o for b in names for o in frame_outputs(b)],
            tol=1e-12,
        ).frame
    assert (df["status"] == "converged").all()
    row = df.iloc[-1].to_dict()
    jd = m.joint(driver)
    qpos = m.qpos0.copy()
    qpos[int(jd.qposadr[0])] = np.radians(step) if deg else step
    mujoco_project(mujoco, m, d, qpos, [k for k in range(m.nv) if k != int(jd.dofadr[0])], tol=1e-12 * scale)
    mujoco.mj_kinematics(m, d)
    mj = mujoco_poses(mujoco, m, d)
    for n in names:
        p_k, R_k = pose_from_row(row, n)
        assert np.abs(p_k - mj[n][0]).max() < 1e-9 * scale and np.abs(R_k - mj[n][1]).max() < 1e-9
