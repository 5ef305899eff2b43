"""An independent double wishbone solver from its hardpoints (no kinprop kinematics).

Given the global hardpoints of a left double wishbone at its design position (the arms'
chassis pivots, the ball joints, the tie rod's ends, the wheel centre and a point on the
outboard spin axis), :func:`solve` turns the lower arm by ``theta`` about the line through its
pivots and closes the mechanism by two 1-D roots: the upper arm angle that keeps the upright's
ball-joint distance, then the upright's turn about its new ball-joint line that keeps the tie
rod's length. Metrics by their textbook definitions (ISO 8855 axes, degrees).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation

#: Project Chrono's HMMWV front (inches -> mm), the hardpoints of examples/double_wishbone*.yaml
HMMWV = {
    k: np.array(v) * 25.4
    for k, v in {
        "LCA_F": (8.79, 12.09, 0.0),
        "LCA_B": (-8.79, 12.09, 0.0),
        "LBJ": (-1.40, 30.965, -4.65),
        "UCA_F": (-1.8864, 17.5575, 9.6308),
        "UCA_B": (-10.5596, 18.8085, 7.6992),
        "UBJ": (-2.088, 28.17, 8.484),
        "TR_I": (-9.855, 17.655, 2.135),
        "TR_O": (-6.922, 32.327, -0.643),
        "WC": (-1.59, 35.815, -1.035),
    }.items()
}
HMMWV["SPIN"] = HMMWV["WC"] + np.array([0.0, 1.0, 0.0])
#: loaded radius: the contact patch of examples/double_wishbone_hardpoints.yaml, 470 mm below the wheel centre
RADIUS = 470.0


def rotate(p, origin, axis, angle):
    return origin + Rotation.from_rotvec(angle * axis / np.linalg.norm(axis)).apply(p - origin)


def solve(hp: dict[str, np.ndarray], theta_deg: float, tie_rod: float | None = None) -> dict[str, float]:
    """Metrics of the double wishbone ``hp`` with the lower arm turned by ``theta_deg``; the
    tie rod's length from its two points, or ``tie_rod`` (then ``hp`` need not be assembled:
    the upright first turns about its ball-joint line to meet it)."""
    theta = math.radians(theta_deg)
    lbj = rotate(hp["LBJ"], hp["LCA_B"], hp["LCA_F"] - hp["LCA_B"], theta)
    r_kp = np.linalg.norm(hp["UBJ"] - hp["LBJ"])
    axis = hp["UCA_F"] - hp["UCA_B"]
    phi = brentq(lambda a: np.linalg.norm(rotate(hp["UBJ"], hp["UCA_B"], axis, a) - lbj) - r_kp, -0.8, 0.8)
    ubj = rotate(hp["UBJ"], hp["UCA_B"], axis, phi)
    k0, k1 = hp["UBJ"] - hp["LBJ"], ubj - lbj
    R0 = Rotation.align_vectors([k1], [k0])[0]
    l_tr = np.linalg.norm(hp["TR_O"] - hp["TR_I"]) if tie_rod is None else tie_rod

    def pose(psi):
        return Rotation.from_rotvec(psi * k1 / np.linalg.norm(k1)) * R0

    psi = brentq(lambda s: np.linalg.norm(lbj + pose(s).apply(hp["TR_O"] - hp["LBJ"]) - hp["TR_I"]) - l_tr, -0.5, 0.5)
    R = pose(psi)
    centre = lbj + R.apply(hp["WC"] - hp["LBJ"])
    a = R.apply(hp["SPIN"] - hp["WC"])
    a /= np.linalg.norm(a)
    k = k1 / np.linalg.norm(k1)
    down = np.array([0.0, 0.0, -1.0]) + a[2] * a  # -z in the wheel plane: the contact point 470 mm below
    contact = centre + RADIUS * down / np.linalg.norm(down)
    return {
        "camber": math.degrees(math.asin(-a[2])),
        "toe": math.degrees(math.atan2(a[0], abs(a[1]))),
        "caster": math.degrees(math.atan2(-k[0], k[2])),
        "kpi": math.degrees(math.atan2(-k[1], k[2])),
        "wheel_centre_dz": float(centre[2] - hp["WC"][2]),
        "centre_y": float(centre[1]),
        "centre_z": float(centre[2]),
        "contact_y": float(contact[1]),
    }
