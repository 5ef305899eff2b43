"""Bennett linkage: mobility 1 (Gruebler -2) and its closed-form input-output relation."""

from __future__ import annotations

import numpy as np
from linkages import BENNETT_ALPHA, BENNETT_BETA, bennett_theta2, load_solved, wrap

from kinprop.analysis.sweep import sweep
from kinprop.engine import compile as assembly_for


def test_bennett_condition_holds_in_the_file():
    m = load_solved("bennett.yaml")
    a, b = m.design["J2.s_i"][0], m.design["J3.s_i"][0]
    assert abs(a / np.sin(BENNETT_ALPHA) - b / np.sin(BENNETT_BETA)) < 1e-12


def test_bennett_sweep_matches_closed_form():
    m = load_solved("bennett.yaml")
    res = sweep(m, ["J1=-170:170:68"], outputs=["point:link2.M"], tol=1e-13)
    assert res.ok
    df = res.frame
    t1, t2, t3 = (np.radians(df[c]) for c in ("J1.q", "J2.q", "J3.q"))
    err = np.abs(wrap(t2 - bennett_theta2(t1)))
    assert np.degrees(err.max()) < 1e-8
    assert np.degrees(np.abs(wrap(t3 + t1)).max()) < 1e-8  # theta3 = -theta1
    # theta4 = -theta2: the cut revolute's angle from the two joint frames
    asm = assembly_for(m.mechanism)
    last = res.last
    kin = asm.kinematics(last.design, last.coordinates)
    R_i = kin.A["link3"] @ last.design["J4.C_i"]
    R_j = kin.A["ground"] @ last.design["J4.C_j"]
    rel = R_i.T @ R_j  # Rz(theta4) up to the sign convention of frame i -> j
    t4 = np.arctan2(rel[1, 0], rel[0, 0])
    assert abs(wrap(t4 + t2.iloc[-1])) < 1e-8
