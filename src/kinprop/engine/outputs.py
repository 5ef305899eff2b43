"""Compiled outputs: points, distances and position-level suspension metrics of a whole batch of
solved states, evaluated from one forward-kinematics pass per state (eq. 28) with no Python per
variant. The one implementation of these outputs: ``kinprop.evaluate_outputs``, sweeps, studies,
targets and sensitivities evaluate them here (:mod:`kinprop.analysis.program` translates output
names into the tables below).

An output **program** is four flat tables (one row per item, named columns):

* ``points`` (np, 3) int: ``PT_KIND`` (``PK_BODY``: ``r_b + A_b p'`` of body ``PT_A`` with
  ``p'`` = ``xyz[k]``, body frame; ``PK_FRAME``: the global origin ``P`` of joint ``PT_A``'s frame
  on side ``PT_B`` (0: i, 1: j); ``PK_CONST``: ``xyz[k]``, global), ``PT_A``, ``PT_B``;
  ``xyz`` (np, 3) float;
* ``wheels`` (nw, 7) int: point slots of the wheel centre ``WH_CENTRE``, the spin-axis point
  ``WH_SPIN``, the steering axis' upper and lower points ``WH_UPPER``, ``WH_LOWER`` (-1: none),
  ``WH_ORDER`` (1: the higher of the two is the upper one, at each state), the contact patch
  ``WH_CONTACT`` and the reference wheel centre ``WH_REF`` (-1: none);
* ``outputs`` (no, 4) int: ``OT_KIND`` and its arguments ``OT_A``, ``OT_B``, ``OT_C``:
  ``OK_Q`` (coordinate column ``A``), ``OK_S`` (``S[A, B, C]``), ``OK_L`` (``L[A]``),
  ``OK_POINT`` (component ``B`` of point ``A``), ``OK_DISTANCE`` (between points ``A`` and
  ``B``), ``OK_METRIC`` (metric ``B`` of wheel ``A``: ``M_CAMBER`` .. ``M_DZ``), ``OK_NONE``
  (evaluated elsewhere: NaN here).

Metric definitions, signs and units (degrees, the model's length unit) are those of
:mod:`kinprop.analysis.metrics` (ISO 8855 axes; SAE J670): camber ``asin(-a_z)``, toe
``atan2(a_x, |a_y|)`` (``a`` the unit outboard spin axis), caster ``atan2(-k_x, k_z)``, KPI
``atan2(-side k_y, k_z)`` (``k`` the steering axis, upper minus lower), scrub radius and trail
in the ground plane through the contact point, the wheel-centre displacement from the reference.
"""

from __future__ import annotations

import math

import numpy as np

from kinprop.jit import kernel, njit
from kinprop.kinematics.kernels import W_BODY_A, W_BODY_R, W_FRAME_P, forward_kinematics, workspace

PT_KIND, PT_A, PT_B = range(3)
PK_BODY, PK_FRAME, PK_CONST = range(3)
WH_CENTRE, WH_SPIN, WH_UPPER, WH_LOWER, WH_ORDER, WH_CONTACT, WH_REF = range(7)
OT_KIND, OT_A, OT_B, OT_C = range(4)
OK_NONE, OK_Q, OK_S, OK_L, OK_POINT, OK_DISTANCE, OK_METRIC = range(7)
#: metric codes (``OT_B`` of an ``OK_METRIC`` row), in the order of :data:`METRIC_CODES`
M_CAMBER, M_TOE, M_CASTER, M_KPI, M_SCRUB, M_TRAIL, M_DX, M_DY, M_DZ = range(9)
METRIC_CODES = ("camber", "toe", "caster", "kpi", "scrub_radius", "trail",
                "wheel_centre_dx", "wheel_centre_dy", "wheel_centre_dz")  # fmt: skip
#: rows of the per-state scratch ``wv`` (:func:`wheel_values`): the nine metrics
N_METRICS = len(METRIC_CODES)


@kernel
def _norm3(x: float, y: float, z: float) -> float:
    return math.sqrt(x * x + y * y + z * z)


@kernel
def camber_toe(a0: float, a1: float, a2: float) -> tuple[float, float]:
    """``(camber, toe)`` in degrees of the outboard spin axis ``a`` (any length)."""
    n = _norm3(a0, a1, a2)
    c = -a2 / n
    c = min(1.0, max(-1.0, c))
    return math.degrees(math.asin(c)), math.degrees(math.atan2(a0 / n, abs(a1 / n)))


@kernel
def steering_angles(k0: float, k1: float, k2: float, side: float) -> tuple[float, float]:
    """``(caster, kpi)`` in degrees of the steering axis ``k`` (upper minus lower)."""
    return math.degrees(math.atan2(-k0, k2)), math.degrees(math.atan2(-side * k1, k2))


@kernel
def contact_point(centre: np.ndarray, axis: np.ndarray, radius: float, out: np.ndarray) -> None:
    """Lowest point of the wheel circle (centre, outboard axis of any length, radius), into ``out``."""
    n = _norm3(axis[0], axis[1], axis[2])
    a0, a1, a2 = axis[0] / n, axis[1] / n, axis[2] / n
    d0, d1, d2 = a2 * a0, a2 * a1, -1.0 + a2 * a2  # -z projected onto the wheel plane
    nd = _norm3(d0, d1, d2)
    out[0] = centre[0] + radius * d0 / nd
    out[1] = centre[1] + radius * d1 / nd
    out[2] = centre[2] + radius * d2 / nd


@kernel
def ground_offsets(upper: np.ndarray, lower: np.ndarray, contact: np.ndarray, axis: np.ndarray) -> tuple[float, float]:
    """``(scrub_radius, trail)``: the steering axis' ground point G relative to the contact
    point, in the horizontal plane through the contact point (``axis``: unit outboard)."""
    k0, k1, k2 = upper[0] - lower[0], upper[1] - lower[1], upper[2] - lower[2]
    dz = contact[2] - lower[2]
    g0, g1 = lower[0] + k0 * dz / k2, lower[1] + k1 * dz / k2
    side = 1.0 if axis[1] >= 0 else -1.0
    n = math.sqrt(axis[0] * axis[0] + axis[1] * axis[1])
    l0, l1 = axis[0] / n, axis[1] / n  # the horizontal outboard direction; heading = side (lateral x z)
    scrub = (contact[0] - g0) * l0 + (contact[1] - g1) * l1
    trail = (g0 - contact[0]) * (side * l1) + (g1 - contact[1]) * (side * -l0)
    return scrub, trail


@kernel
def wheel_values(wheel: np.ndarray, pts: np.ndarray, v: np.ndarray, out: np.ndarray) -> None:
    """Every metric of one wheel (row ``wheel`` of the wheels table) from the points ``pts``
    (np, 3) of one state, into ``out`` (:data:`N_METRICS`; NaN where the wheel lacks a point);
    ``v`` (4, 3) scratch."""
    for m in range(N_METRICS):
        out[m] = np.nan
    c = pts[wheel[WH_CENTRE]]
    axis, contact = v[0], v[1]
    n = _norm3(pts[wheel[WH_SPIN], 0] - c[0], pts[wheel[WH_SPIN], 1] - c[1], pts[wheel[WH_SPIN], 2] - c[2])
    for x in range(3):
        axis[x] = (pts[wheel[WH_SPIN], x] - c[x]) / n
    side = 1.0 if axis[1] >= 0 else -1.0
    out[M_CAMBER], out[M_TOE] = camber_toe(axis[0], axis[1], axis[2])
    if wheel[WH_UPPER] >= 0 and wheel[WH_LOWER] >= 0:
        up, lo = pts[wheel[WH_UPPER]], pts[wheel[WH_LOWER]]
        if wheel[WH_ORDER] and up[2] < lo[2]:
            up, lo = lo, up
        out[M_CASTER], out[M_KPI] = steering_angles(up[0] - lo[0], up[1] - lo[1], up[2] - lo[2], side)
        if wheel[WH_CONTACT] >= 0:
            p = pts[wheel[WH_CONTACT]]
            d = (p[0] - c[0]) * axis[0] + (p[1] - c[1]) * axis[1] + (p[2] - c[2]) * axis[2]
            radius = _norm3(p[0] - c[0] - d * axis[0], p[1] - c[1] - d * axis[1], p[2] - c[2] - d * axis[2])
            contact_point(c, axis, radius, contact)
            out[M_SCRUB], out[M_TRAIL] = ground_offsets(up, lo, contact, axis)
    if wheel[WH_REF] >= 0:
        ref = pts[wheel[WH_REF]]
        out[M_DX], out[M_DY], out[M_DZ] = c[0] - ref[0], c[1] - ref[1], c[2] - ref[2]


@kernel
def state_outputs(tb, Q, S, C, L, points, xyz, wheels, outputs, ws, pts, wv, v, out) -> None:
    """Every output of one state into ``out`` (no): forward kinematics into ``ws``, the points
    into ``pts`` (np, 3), each wheel's metrics into ``wv`` (nw, :data:`N_METRICS`)."""
    forward_kinematics(tb, Q, S, C, ws)
    r, A, P = ws[W_BODY_R], ws[W_BODY_A], ws[W_FRAME_P]
    for k in range(points.shape[0]):
        a, kind = points[k, PT_A], points[k, PT_KIND]
        for x in range(3):
            if kind == PK_BODY:
                pts[k, x] = r[a, x] + (A[a, x, 0] * xyz[k, 0] + A[a, x, 1] * xyz[k, 1] + A[a, x, 2] * xyz[k, 2])
            elif kind == PK_FRAME:
                pts[k, x] = P[a, points[k, PT_B], x]
            else:
                pts[k, x] = xyz[k, x]
    for w in range(wheels.shape[0]):
        wheel_values(wheels[w], pts, v, wv[w])
    for k in range(outputs.shape[0]):
        kind, a, b = outputs[k, OT_KIND], outputs[k, OT_A], outputs[k, OT_B]
        if kind == OK_Q:
            out[k] = Q[a]
        elif kind == OK_S:
            out[k] = S[a, b, outputs[k, OT_C]]
        elif kind == OK_L:
            out[k] = L[a]
        elif kind == OK_POINT:
            out[k] = pts[a, b]
        elif kind == OK_DISTANCE:
            out[k] = _norm3(pts[a, 0] - pts[b, 0], pts[a, 1] - pts[b, 1], pts[a, 2] - pts[b, 2])
        elif kind == OK_METRIC:
            out[k] = wv[a, b]
        else:
            out[k] = np.nan


@njit
def batch_outputs(tb, Q, S, C, L, ok, points, xyz, wheels, outputs, out) -> None:
    """:func:`state_outputs` of every state of a batch (leading axis) where ``ok``, into
    ``out`` (N, no); rows where not ``ok`` are NaN."""
    ws = workspace(tb)
    pts = np.zeros((points.shape[0], 3))
    wv = np.zeros((max(wheels.shape[0], 1), N_METRICS))
    v = np.zeros((4, 3))
    for n in range(Q.shape[0]):
        if ok[n]:
            state_outputs(tb, Q[n], S[n], C[n], L[n], points, xyz, wheels, outputs, ws, pts, wv, v, out[n])
        else:
            for k in range(out.shape[1]):
                out[n, k] = np.nan


__all__ = [
    "METRIC_CODES",
    "batch_outputs",
    "camber_toe",
    "contact_point",
    "ground_offsets",
    "state_outputs",
    "steering_angles",
    "wheel_values",
]
