"""Spatial algebra: tilde operator (eq. 3), rotations, Euler parameters (eqs. 40-42).

The numpy functions accept an optional leading batch shape (``[..., 3]``, ``[..., 3, 3]``); the
compiled ``*_into`` helpers at the end write one 3-vector / 3x3 result into a given array.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kinprop.jit import kernel

Array = NDArray[np.float64]

EX = np.array([1.0, 0.0, 0.0])
EY = np.array([0.0, 1.0, 0.0])
EZ = np.array([0.0, 0.0, 1.0])


def tilde(a: ArrayLike) -> Array:
    """Skew-symmetric matrix of eq. (3): ``tilde(a) @ b == cross(a, b)``."""
    a = np.asarray(a, dtype=float)
    t = np.zeros(a.shape + (3,))
    t[..., 0, 1], t[..., 0, 2] = -a[..., 2], a[..., 1]
    t[..., 1, 0], t[..., 1, 2] = a[..., 2], -a[..., 0]
    t[..., 2, 0], t[..., 2, 1] = -a[..., 1], a[..., 0]
    return t


def rot_axis(axis: int, angle: ArrayLike) -> Array:
    """Rotation by ``angle`` (radians) about coordinate axis 0, 1 or 2."""
    angle = np.asarray(angle, dtype=float)
    c, s = np.cos(angle), np.sin(angle)
    R = np.zeros(angle.shape + (3, 3))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    R[..., axis, axis] = 1.0
    R[..., i, i], R[..., i, j] = c, -s
    R[..., j, i], R[..., j, j] = s, c
    return R


def rot_x(angle: ArrayLike) -> Array:
    return rot_axis(0, angle)


def rot_y(angle: ArrayLike) -> Array:
    return rot_axis(1, angle)


def rot_z(angle: ArrayLike) -> Array:
    return rot_axis(2, angle)


def exp_so3(w: ArrayLike) -> Array:
    """Rotation matrix ``exp(tilde(w))`` (Rodrigues), stable for small ``|w|``."""
    w = np.asarray(w, dtype=float)
    th = np.linalg.norm(w, axis=-1)[..., None, None]
    W = tilde(w)
    small = th < 1e-8
    ths = np.where(small, 1.0, th)
    a = np.where(small, 1.0 - th**2 / 6.0, np.sin(ths) / ths)
    b = np.where(small, 0.5 - th**2 / 24.0, (1.0 - np.cos(ths)) / ths**2)
    return np.eye(3) + a * W + b * (W @ W)


def log_so3(R: ArrayLike) -> Array:
    """Rotation vector ``w`` with ``exp_so3(w) == R`` (angle in [0, pi])."""
    R = np.asarray(R, dtype=float)
    return matrix_to_rotvec(R)


def matrix_to_rotvec(R: Array) -> Array:
    from scipy.spatial.transform import Rotation

    flat = R.reshape(-1, 3, 3)
    out = Rotation.from_matrix(flat).as_rotvec()
    return out.reshape(R.shape[:-2] + (3,))


def euler_E(p: ArrayLike) -> Array:
    """Semi-rotation matrix E(p) = [-e, tilde(e) + e0 I] of eq. (40)."""
    p = np.asarray(p, dtype=float)
    e0, e = p[..., 0], p[..., 1:]
    E = np.empty(p.shape[:-1] + (3, 4))
    E[..., :, 0] = -e
    E[..., :, 1:] = tilde(e) + e0[..., None, None] * np.eye(3)
    return E


def euler_G(p: ArrayLike) -> Array:
    """Semi-rotation matrix G(p) = [-e, -tilde(e) + e0 I] of eq. (42)."""
    p = np.asarray(p, dtype=float)
    e0, e = p[..., 0], p[..., 1:]
    G = np.empty(p.shape[:-1] + (3, 4))
    G[..., :, 0] = -e
    G[..., :, 1:] = -tilde(e) + e0[..., None, None] * np.eye(3)
    return G


def euler_to_matrix(p: ArrayLike) -> Array:
    """A(p) = E(p) G(p)^T (eq. 42 text); a rotation only when ``p . p = 1``.

    The matrix is evaluated with ``p`` as given, never renormalised (PAPER-NOTES).
    """
    return euler_E(p) @ np.swapaxes(euler_G(p), -1, -2)


def matrix_to_euler(R: ArrayLike) -> Array:
    """Unit Euler parameters [e0, e1, e2, e3] of a rotation matrix, with e0 >= 0."""
    from scipy.spatial.transform import Rotation

    R = np.asarray(R, dtype=float)
    xyzw = Rotation.from_matrix(R.reshape(-1, 3, 3)).as_quat()
    p = np.concatenate([xyzw[:, 3:], xyzw[:, :3]], axis=1)
    p = np.where(p[:, :1] < 0, -p, p)
    return p.reshape(R.shape[:-2] + (4,))


def is_rotation(C: ArrayLike, tol: float = 1e-6) -> bool:
    """True when ``C`` is a proper rotation (orthonormal, det +1) to ``tol``."""
    C = np.asarray(C, dtype=float)
    if C.shape != (3, 3) or not np.all(np.isfinite(C)):
        return False
    return bool(np.allclose(C.T @ C, np.eye(3), atol=tol) and abs(np.linalg.det(C) - 1) < tol)


# --- compiled 3-vector / 3x3 helpers (write into preallocated arrays; used by the kernels) ----


@kernel
def _entries(A: Array) -> tuple:
    """The nine entries of a 3x3, row by row. The helpers below read every input into
    registers before writing: the compiler must assume ``out`` may alias an input, and a
    store between loads would force it to reload them one by one."""
    return (A[0, 0], A[0, 1], A[0, 2], A[1, 0], A[1, 1], A[1, 2], A[2, 0], A[2, 1], A[2, 2])


@kernel
def _entries_T(A: Array) -> tuple:
    """The nine entries of a 3x3's transpose, row by row."""
    return (A[0, 0], A[1, 0], A[2, 0], A[0, 1], A[1, 1], A[2, 1], A[0, 2], A[1, 2], A[2, 2])


@kernel
def _product_into(a: tuple, b: tuple, out: Array) -> None:
    for i in range(3):
        for j in range(3):
            out[i, j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j]


@kernel
def mm_into(A: Array, B: Array, out: Array) -> None:
    """``out = A @ B`` (3 x 3)."""
    _product_into(_entries(A), _entries(B), out)


@kernel
def mmT_into(A: Array, B: Array, out: Array) -> None:
    """``out = A @ B.T`` (3 x 3)."""
    _product_into(_entries(A), _entries_T(B), out)


@kernel
def mTm_into(A: Array, B: Array, out: Array) -> None:
    """``out = A.T @ B`` (3 x 3)."""
    _product_into(_entries_T(A), _entries(B), out)


@kernel
def mv_into(A: Array, v: Array, out: Array) -> None:
    """``out = A @ v``."""
    a, x, y, z = _entries(A), v[0], v[1], v[2]
    out[0] = a[0] * x + a[1] * y + a[2] * z
    out[1] = a[3] * x + a[4] * y + a[5] * z
    out[2] = a[6] * x + a[7] * y + a[8] * z


@kernel
def cross_into(a: Array, b: Array, out: Array) -> None:
    """``out = a x b = tilde(a) b`` (eq. 3)."""
    a0, a1, a2, b0, b1, b2 = a[0], a[1], a[2], b[0], b[1], b[2]
    out[0] = a1 * b2 - a2 * b1
    out[1] = a2 * b0 - a0 * b2
    out[2] = a0 * b1 - a1 * b0


@kernel
def eye_into(out: Array) -> None:
    for a in range(3):
        for b in range(3):
            out[a, b] = 1.0 if a == b else 0.0


@kernel
def rot_z_into(angle: float, out: Array) -> None:
    """``out = Rz(angle)``."""
    c, s = np.cos(angle), np.sin(angle)
    eye_into(out)
    out[0, 0], out[0, 1], out[1, 0], out[1, 1] = c, -s, s, c


@kernel
def euler_A_into(p: Array, out: Array) -> None:
    """``out = E(p) G(p)^T`` (eq. 42 text), with ``p`` as given (never renormalised)."""
    e0, e1, e2, e3 = p[0], p[1], p[2], p[3]
    out[0, 0] = e0 * e0 + e1 * e1 - e2 * e2 - e3 * e3
    out[0, 1] = 2.0 * (e1 * e2 - e0 * e3)
    out[0, 2] = 2.0 * (e1 * e3 + e0 * e2)
    out[1, 0] = 2.0 * (e1 * e2 + e0 * e3)
    out[1, 1] = e0 * e0 - e1 * e1 + e2 * e2 - e3 * e3
    out[1, 2] = 2.0 * (e2 * e3 - e0 * e1)
    out[2, 0] = 2.0 * (e1 * e3 - e0 * e2)
    out[2, 1] = 2.0 * (e2 * e3 + e0 * e1)
    out[2, 2] = e0 * e0 - e1 * e1 - e2 * e2 + e3 * e3


@kernel
def euler_E_into(p: Array, scale: float, out: Array, col0: int) -> None:
    """``out[:, col0:col0+4] = scale * E(p)``, E = [-e, tilde(e) + e0 I] (eq. 40)."""
    e0, e1, e2, e3 = p[0], p[1], p[2], p[3]
    c = col0
    out[0, c], out[0, c + 1], out[0, c + 2], out[0, c + 3] = -e1 * scale, e0 * scale, -e3 * scale, e2 * scale
    out[1, c], out[1, c + 1], out[1, c + 2], out[1, c + 3] = -e2 * scale, e3 * scale, e0 * scale, -e1 * scale
    out[2, c], out[2, c + 1], out[2, c + 2], out[2, c + 3] = -e3 * scale, -e2 * scale, e1 * scale, e0 * scale


@kernel
def exp_so3_into(w: Array, out: Array) -> None:
    """``out = exp(tilde(w))`` (Rodrigues), stable for small ``|w|``."""
    th = np.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    if th < 1e-8:
        a, b = 1.0 - th * th / 6.0, 0.5 - th * th / 24.0
    else:
        a, b = np.sin(th) / th, (1.0 - np.cos(th)) / (th * th)
    x, y, z = w[0], w[1], w[2]
    # I + a W + b W W, with W W = w w^T - th^2 I
    out[0, 0] = 1.0 + b * (x * x - th * th)
    out[1, 1] = 1.0 + b * (y * y - th * th)
    out[2, 2] = 1.0 + b * (z * z - th * th)
    out[0, 1], out[1, 0] = -a * z + b * x * y, a * z + b * x * y
    out[0, 2], out[2, 0] = a * y + b * x * z, -a * y + b * x * z
    out[1, 2], out[2, 1] = -a * x + b * y * z, a * x + b * y * z
