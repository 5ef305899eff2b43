"""Helpers of the importer tests: body poses through the public output API, MuJoCo's reference."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from kinprop import Model, evaluate_outputs

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
MJCF = EXAMPLES / "mjcf"
CHRONO = EXAMPLES / "chrono"
#: frame points: origin and the three unit axes, in every body's frame
FRAME = {"o": (0.0, 0.0, 0.0), "ex": (1.0, 0.0, 0.0), "ey": (0.0, 1.0, 0.0), "ez": (0.0, 0.0, 1.0)}


def with_frame_points(model: Model) -> Model:
    """The model with points o, ex, ey, ez on every body (its frame, seen through outputs)."""
    mech = model.mechanism
    bodies = tuple(dataclasses.replace(b, points=b.points + tuple(FRAME.items())) for b in mech.bodies)
    return dataclasses.replace(model, mechanism=dataclasses.replace(mech, bodies=bodies))


def frame_outputs(body: str) -> list[str]:
    return [f"point:{body}.{p}" for p in FRAME]


def pose_from_row(row: dict, body: str) -> tuple[np.ndarray, np.ndarray]:
    """(position, rotation matrix) of ``body`` from a row of frame-point outputs."""

    def p(name: str) -> np.ndarray:
        return np.array([row[f"point:{body}.{name}[{c}]"] for c in "xyz"])

    o = p("o")
    return o, np.column_stack([p("ex") - o, p("ey") - o, p("ez") - o])


def body_poses(model: Model, bodies: list[str]) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Global poses of ``bodies`` at the model's coordinates (public output API)."""
    m = with_frame_points(model)
    row = evaluate_outputs(m, [o for b in bodies for o in frame_outputs(b)])
    return {b: pose_from_row(row, b) for b in bodies}


def mujoco_poses(mj, m, d) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Body poses of MuJoCo data (after mj_kinematics / mj_forward), by body name."""
    out = {}
    for i in range(1, m.nbody):
        name = mj.mj_id2name(m, mj.mjtObj.mjOBJ_BODY, i)
        out[name] = (d.xpos[i].copy(), d.xmat[i].reshape(3, 3).copy())
    return out


def equality_rows(mj, m, d) -> tuple[np.ndarray, np.ndarray]:
    """(residual, dense Jacobian) of the equality constraint rows after mj_forward."""
    n = d.nefc
    eq = d.efc_type[:n] == mj.mjtConstraint.mjCNSTR_EQUALITY
    J = np.asarray(d.efc_J[: n * m.nv]).reshape(n, m.nv)[eq] if n else np.zeros((0, m.nv))
    return np.asarray(d.efc_pos[:n])[eq], J


def mujoco_project(mj, m, d, qpos: np.ndarray, dofs: list[int], tol: float = 1e-13) -> np.ndarray:
    """Newton on MuJoCo's own equality residual and Jacobian, moving only ``dofs`` (min-norm)."""
    m.opt.jacobian = mj.mjtJacobian.mjJAC_DENSE
    d.qpos[:] = qpos
    for _ in range(50):
        mj.mj_forward(m, d)
        r, J = equality_rows(mj, m, d)
        if np.linalg.norm(r) < tol:
            return d.qpos.copy()
        dv = np.zeros(m.nv)
        dv[dofs] = -np.linalg.lstsq(J[:, dofs], r, rcond=None)[0]
        q = d.qpos.copy()
        mj.mj_integratePos(m, q, dv, 1.0)
        d.qpos[:] = q
    raise AssertionError(f"MuJoCo projection did not converge: {np.linalg.norm(r)}")
