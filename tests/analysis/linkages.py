"""Closed forms of the linkage examples: Freudenstein (four-bar), Bennett, Stewart inverse kinematics."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from kinprop import Model, SingularityWarning, assemble, load_model, propagate
from kinprop.spatial import euler_to_matrix

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

#: link lengths of examples/fourbar.yaml (crank a, coupler b, rocker c, ground d) [m]
CRANK_ROCKER = (0.15, 0.40, 0.30, 0.40)
#: examples/fourbar_double_rocker.yaml
DOUBLE_ROCKER = (0.30, 0.40, 0.35, 0.50)


def load_solved(name: str, tol: float = 1e-12) -> Model:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SingularityWarning)
        prop = assemble(load_model(EXAMPLES / name), tol=tol)
    assert prop.converged, prop.result.message
    return prop.after


def freudenstein(a: float, b: float, c: float, d: float, theta2, branch: int = -1):
    """Output angle theta4 of a four-bar from Freudenstein's equation
    ``K1 cos t4 - K2 cos t2 + K3 = cos(t2 - t4)``, K1 = d/a, K2 = d/c,
    K3 = (a^2 - b^2 + c^2 + d^2) / (2 a c), solved as a quadratic in tan(t4 / 2)
    (Norton, Design of Machinery, eq. 4.10). ``branch`` -1 is the open assembly of the
    examples (B above the ground line). NaN where the loop cannot close."""
    t2 = np.asarray(theta2, dtype=float)
    K1, K2, K3 = d / a, d / c, (a * a - b * b + c * c + d * d) / (2 * a * c)
    A = np.cos(t2) - K1 - K2 * np.cos(t2) + K3
    B = -2.0 * np.sin(t2)
    C = K1 - (K2 + 1.0) * np.cos(t2) + K3
    disc = B * B - 4 * A * C
    with np.errstate(invalid="ignore"):
        return 2.0 * np.arctan2(-B + branch * np.sqrt(disc), 2 * A)


def input_limit(a: float, b: float, c: float, d: float) -> float:
    """Largest input angle of a non-Grashof four-bar: |A O4| = b + c (coupler and output collinear)."""
    return float(np.arccos((a * a + d * d - (b + c) ** 2) / (2 * a * d)))


def wrap(x):
    """Angle difference wrapped to (-pi, pi]."""
    return np.angle(np.exp(1j * np.asarray(x, dtype=float)))


def set_crank(model: Model, degrees: float) -> Model:
    """The four-bar with its crank O2 moved to ``degrees`` (small steps, same branch)."""
    cur = float(np.degrees(model.coordinates["O2"][0]))
    for t in np.linspace(cur, degrees, int(abs(degrees - cur) // 5) + 2)[1:]:
        prop = propagate(model, {"O2.q": [np.radians(t)]}, ("A.q", "O4.q"), tol=1e-12)
        assert prop.converged
        model = prop.after
    return model


# --- Bennett linkage (examples/bennett.yaml) ---------------------------------------------------
BENNETT_ALPHA, BENNETT_BETA = np.radians(30.0), np.radians(70.0)


def bennett_theta2(theta1, alpha: float = BENNETT_ALPHA, beta: float = BENNETT_BETA):
    """``tan(t1 / 2) tan(t2 / 2) = sin((beta + alpha) / 2) / sin((beta - alpha) / 2)`` (Baker 1979)."""
    K = np.sin((beta + alpha) / 2) / np.sin((beta - alpha) / 2)
    return 2.0 * np.arctan2(K, np.tan(np.asarray(theta1, dtype=float) / 2.0))


# --- Stewart platform (examples/stewart.yaml) --------------------------------------------------
def stewart_anchors(model: Model) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Base anchors a_k, platform anchors b_k (platform frame) and the leg joint names."""
    legs = [j.name for j in model.mechanism.joints if j.type == "distance"]
    a = np.array([model.design[f"{n}.s_i"] for n in legs])
    b = np.array([model.design[f"{n}.s_j"] for n in legs])
    return a, b, legs


def stewart_ik(a: np.ndarray, b: np.ndarray, p: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Closed-form inverse kinematics: leg lengths ``|p + R b_k - a_k|``."""
    return np.linalg.norm(p + b @ R.T - a, axis=1)


def platform_pose(model: Model) -> tuple[np.ndarray, np.ndarray]:
    q = np.asarray(model.coordinates["P"], dtype=float)
    return q[:3], euler_to_matrix(q[3:7])
