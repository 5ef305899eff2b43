"""MJCF orientation specifiers to rotation matrices, as MuJoCo's compiler reads them.

``quat`` (w, x, y, z; normalised), ``axisangle``, ``euler`` (with the compiler's
``eulerseq``: lower-case letters rotate with the frame, upper-case stay fixed), ``xyaxes``
(y made orthogonal to x) and ``zaxis`` (the smallest rotation taking z onto it). Angles are in
the compiler's unit (degrees unless ``angle="radian"``).
"""

from __future__ import annotations

import math

import numpy as np

from kinprop.spatial import Array

#: a vector shorter than this is zero
TINY = 1e-14


def quat_to_matrix(q: Array) -> Array:
    """Rotation matrix of the quaternion ``(w, x, y, z)`` (normalised first)."""
    w, x, y, z = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def matrix_to_quat(R: Array) -> Array:
    """Unit quaternion ``(w, x, y, z)`` of a rotation matrix, ``w >= 0``."""
    from scipy.spatial.transform import Rotation

    x, y, z, w = Rotation.from_matrix(np.asarray(R, dtype=float)).as_quat()
    q = np.array([w, x, y, z])
    return -q if w < 0 else q


def axis_angle_matrix(axis: Array, angle: float) -> Array:
    """Rotation by ``angle`` (radians) about ``axis`` (normalised first)."""
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    s, c = math.sin(angle / 2), math.cos(angle / 2)
    return quat_to_matrix(np.array([c, *(s * a)]))


def euler_matrix(angles: Array, seq: str) -> Array:
    """Rotation of three Euler angles (radians) in MuJoCo's ``eulerseq`` convention."""
    R = np.eye(3)
    for angle, letter in zip(angles, seq, strict=True):
        step = axis_angle_matrix(np.eye(3)["xyz".index(letter.lower())], float(angle))
        R = R @ step if letter.islower() else step @ R
    return R


def xyaxes_matrix(x: Array, y: Array) -> Array:
    """Columns x, y (made orthogonal to x), z = x cross y."""
    x = np.asarray(x, dtype=float) / np.linalg.norm(x)
    y = np.asarray(y, dtype=float)
    y = y - (x @ y) * x
    y = y / np.linalg.norm(y)
    return np.column_stack([x, y, np.cross(x, y)])


def zaxis_matrix(z: Array) -> Array:
    """The smallest rotation taking (0, 0, 1) onto ``z``."""
    z = np.asarray(z, dtype=float) / np.linalg.norm(z)
    axis = np.cross([0.0, 0.0, 1.0], z)
    s = float(np.linalg.norm(axis))
    if s < TINY:
        return np.eye(3) if z[2] > 0 else np.diag([1.0, -1.0, -1.0])
    return axis_angle_matrix(axis / s, math.atan2(s, float(z[2])))


__all__ = ["axis_angle_matrix", "euler_matrix", "matrix_to_quat", "quat_to_matrix", "xyaxes_matrix", "zaxis_matrix"]
