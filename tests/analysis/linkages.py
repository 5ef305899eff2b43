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
        prop = propagate(model, {"O2.q": [t]}, ("A.q", "O4.q"), tol=1e-12)  # degrees: the model's unit
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


# --- angle-sum equations A cos(phi) + B sin(phi) = C ---------------------------------------------
def solve_cos_sin(A, B, C, branch: int):
    """Roots ``phi = atan2(B, A) + branch * acos(C / hypot(A, B))`` of ``A cos phi + B sin phi = C``
    (``branch`` +1 or -1); NaN where ``|C| > hypot(A, B)`` (the loop cannot close)."""
    with np.errstate(invalid="ignore"):
        return np.arctan2(B, A) + branch * np.arccos(C / np.hypot(A, B))


# --- spherical four-bar (examples/spherical_fourbar.yaml) ----------------------------------------
#: axis angles [rad]: ground alpha1, input alpha2, coupler alpha3, output alpha4
SPHERICAL = tuple(np.radians((55.0, 20.0, 50.0, 45.0)))


def spherical_phi(theta, alphas=SPHERICAL, branch: int = -1):
    """Output angle of the spherical four-bar from the spherical Freudenstein equation
    ``u2(theta) . u3(phi) = cos alpha3`` (Chiang, Kinematics of spherical mechanisms),
    written as ``A cos phi + B sin phi = C`` (coefficients in the example's header)."""
    a1, a2, a3, a4 = alphas
    t = np.asarray(theta, dtype=float)
    A = np.sin(a2) * np.sin(a4) * np.cos(a1) * np.cos(t) - np.cos(a2) * np.sin(a1) * np.sin(a4)
    B = np.sin(a2) * np.sin(a4) * np.sin(t)
    C = np.cos(a3) - np.sin(a2) * np.cos(a4) * np.sin(a1) * np.cos(t) - np.cos(a2) * np.cos(a1) * np.cos(a4)
    return solve_cos_sin(A, B, C, branch)


def spherical_axes(theta, phi, alphas=SPHERICAL) -> tuple[np.ndarray, np.ndarray]:
    """Axes u2(theta) (input-coupler) and u3(phi) (coupler-output) built with scipy rotations
    (independent of kinprop's kinematics): their angle must be alpha3 on every assembly."""
    from scipy.spatial.transform import Rotation

    a1, a2, _, a4 = alphas
    z = np.array([0.0, 0.0, 1.0])
    t, p = np.atleast_1d(theta), np.atleast_1d(phi)
    u2 = Rotation.from_euler("ZY", np.c_[t, np.full_like(t, a2)]).apply(z)
    u3 = Rotation.from_euler("YZY", np.c_[np.full_like(p, a1), p, np.full_like(p, a4)]).apply(z)
    return u2, u3


# --- spatial RSSR (kinprop.builders.rssr) ---------------------------------------------------------
def rssr_phi(theta, crank: float, pivot, rocker: float, length: float, branch: int):
    """Rocker angle of the RSSR from ``|P(theta) - Q(phi)| = length`` with P = crank (cos, sin, 0),
    Q = pivot + rocker (sin phi, 0, cos phi): with D = P - pivot,
    ``D_z cos phi + D_x sin phi = (|D|^2 + rocker^2 - length^2) / (2 rocker)``."""
    t = np.asarray(theta, dtype=float)
    px, py, pz = (float(v) for v in pivot)
    Dx, Dy, Dz = crank * np.cos(t) - px, crank * np.sin(t) - py, -pz + 0.0 * t
    C = (Dx * Dx + Dy * Dy + Dz * Dz + rocker * rocker - length * length) / (2.0 * rocker)
    return solve_cos_sin(Dz, Dx, C, branch)


# --- offset slider-crank (examples/slider_crank_offset.yaml) --------------------------------------
#: crank r, rod l, offset e [m]
OFFSET_SLIDER = (0.10, 0.35, 0.05)


def slider_x(theta, r: float = 0.10, l: float = 0.35, e: float = 0.05, branch: int = +1):
    """Slider position ``x = r cos theta + branch * sqrt(l^2 - (e - r sin theta)^2)``."""
    t = np.asarray(theta, dtype=float)
    with np.errstate(invalid="ignore"):
        return r * np.cos(t) + branch * np.sqrt(l * l - (e - r * np.sin(t)) ** 2)


def set_input(model: Model, joint: str, degrees: float, free: tuple[str, ...]) -> Model:
    """``model`` with the input ``joint`` moved to ``degrees`` in 5 deg steps (same branch)."""
    cur = float(np.degrees(model.coordinates[joint][0]))
    for t in np.linspace(cur, degrees, int(abs(degrees - cur) // 5) + 2)[1:]:
        prop = propagate(model, {f"{joint}.q": [np.radians(t)]}, free, tol=1e-12, units="solver")  # any model
        assert prop.converged
        model = prop.after
    return model
