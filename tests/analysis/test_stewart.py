"""Stewart platform: forward kinematics after leg-length changes against closed-form inverse kinematics."""

from __future__ import annotations

import numpy as np
from linkages import load_solved, platform_pose, stewart_anchors, stewart_ik

from kinprop import propagate
from kinprop.spatial import exp_so3, log_so3, matrix_to_euler


def _target():
    return np.array([0.02, -0.015, 0.43]), exp_so3(np.array([0.05, -0.03, 0.1]))


def test_forward_kinematics_after_leg_length_changes():
    m = load_solved("stewart.yaml")
    a, b, legs = stewart_anchors(m)
    p1, R1 = _target()
    lengths = stewart_ik(a, b, p1, R1)
    prop = propagate(m, {f"{n}.length": float(l) for n, l in zip(legs, lengths, strict=True)}, ("q",), tol=1e-13)
    assert prop.converged, prop.result.message
    p, R = platform_pose(prop.after)
    # the solved pose reproduces the set leg lengths by closed-form inverse kinematics
    assert np.abs(stewart_ik(a, b, p, R) - lengths).max() < 1e-12
    # and it is the pose the lengths were made from (same assembly branch)
    assert np.abs(p - p1).max() < 1e-10
    assert np.linalg.norm(log_so3(R @ R1.T)) < 1e-10
    assert abs(np.linalg.norm(prop.after.coordinates["P"][3:]) - 1.0) < 1e-12


def test_inverse_kinematics_by_propagation():
    """Set the platform pose, free the leg lengths: the lengths are the closed form."""
    m = load_solved("stewart.yaml")
    a, b, legs = stewart_anchors(m)
    p1, R1 = _target()
    pose = np.concatenate([p1, matrix_to_euler(R1)])
    prop = propagate(m, {"P.q": pose}, ("l",), tol=1e-13)
    assert prop.converged
    got = np.array([prop.after.design[f"{n}.length"] for n in legs])
    assert np.abs(got - stewart_ik(a, b, p1, R1)).max() < 1e-12
