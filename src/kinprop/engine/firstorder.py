"""Compiled first-order suspension metrics: the velocity solve and the metric formulas of
:mod:`kinprop.analysis.firstorder` (definitions, signs and references in
docs/analysis/suspension.md) over a whole batch of assembled states, with no Python per state.

Tables (one row per item, named columns), beside the point table of
:mod:`kinprop.engine.outputs` (``points`` (np, 3) ``PT_KIND``/``PT_A``/``PT_B`` and ``xyz``,
the same format: a body point, a joint frame's origin, a constant):

* ``wheels`` (nw, 9) int: the wheel body ``FW_BODY``; point slots of the wheel centre
  ``FW_CENTRE``, the spin-axis point ``FW_SPIN``, the steering axis' upper and lower points
  ``FW_UPPER``, ``FW_LOWER`` (-1: none), ``FW_ORDER`` (1: the higher of the two is the upper
  one, at each state), the reference contact point ``FW_REF`` (-1: none); the vehicle's axle
  ``FW_AXLE`` (``AXLE_NONE``, ``AXLE_FRONT``, ``AXLE_REAR``), ``FW_INBOARD`` (bit 0: inboard
  brakes, bit 1: inboard drive);
* ``params`` (nw, 4) float: ``FP_RADIUS`` (the loaded radius; NaN: no contact patch),
  ``FP_LEVER`` (100 wheelbase / cg height), ``FP_BRAKE_FRONT``, ``FP_DRIVE_FRONT``;
* ``elements`` (ne, 2) int: point slots of each element's ends; ``stiffness`` (ne,) float (NaN:
  not a spring).

Each wheel's values are a row of :data:`N_FIRST` metrics in the order of :data:`FIRST_CODES`
followed by one motion ratio per element (NaN where the wheel lacks what a metric needs).

:func:`wheel_first_order` is the formulas, one state, from the points and the bodies' twists;
it calls no other kernel and uses only arithmetic that is analytic in its inputs, so its
Python source (``py_func``) run on complex arrays is the forward-mode derivative by a complex
step (:func:`kinprop.analysis.firstorder.first_order_derivatives`). :func:`batch_first_order`
runs :func:`kinprop.engine.motion.velocity_solve` and the formulas over a batch.
"""

from __future__ import annotations

import math

import numpy as np

from kinprop.engine.motion import SOLVED, velocity_solve
from kinprop.jit import kernel, njit
from kinprop.kinematics.kernels import W_BODY_A, W_BODY_R, W_FRAME_P
from kinprop.kinematics.tables import J_BODY_I, J_BODY_J
from kinprop.solver import newton

FW_BODY, FW_CENTRE, FW_SPIN, FW_UPPER, FW_LOWER, FW_ORDER, FW_REF, FW_AXLE, FW_INBOARD = range(9)
FP_RADIUS, FP_LEVER, FP_BRAKE_FRONT, FP_DRIVE_FRONT = range(4)
AXLE_NONE, AXLE_FRONT, AXLE_REAR = range(3)
#: the metrics of a wheel's row, in order (then one motion ratio per element)
FIRST_CODES = ("camber_gain", "bump_steer", "caster_gain", "half_track_change", "contact_patch_dx",
               "half_track_gain", "contact_patch_dx_gain", "fvic_y", "fvic_z", "fvsa_length", "svic_x",
               "svic_z", "svsa_length", "roll_centre_height", "anti_dive", "anti_lift", "anti_squat",
               "wheel_rate")  # fmt: skip
N_FIRST = len(FIRST_CODES)
(M_CAMBER_GAIN, M_BUMP_STEER, M_CASTER_GAIN, M_HALF_TRACK, M_PATCH_DX, M_HALF_TRACK_GAIN, M_PATCH_DX_GAIN, M_FVIC_Y,
 M_FVIC_Z, M_FVSA, M_SVIC_X, M_SVIC_Z, M_SVSA, M_ROLL_CENTRE, M_ANTI_DIVE, M_ANTI_LIFT, M_ANTI_SQUAT,
 M_WHEEL_RATE) = range(N_FIRST)  # fmt: skip
#: |n.u| below this: the screw axis is parallel to the view plane (the centre at infinity)
PARALLEL_TOL = 1e-12
#: relative |w| below which the wheel's relative motion is a pure translation
TRANSLATION_RTOL = 1e-12
_PT_KIND, _PT_A, _PT_B = range(3)  # kinprop.engine.outputs' point table columns
_PK_BODY, _PK_FRAME = 0, 1


@kernel
def wheel_first_order(wheel, params, pts, body_of, V, elements, stiffness, out) -> None:
    """Every first-order metric of one wheel (row ``wheel`` of the wheels table, ``params``
    its row of parameters) into ``out`` (:data:`N_FIRST` + ne): from the points ``pts`` (np, 3),
    the body each moves with ``body_of`` (np,; -1: fixed), the bodies' twists ``V`` (nb, 6:
    ``[v_O ; omega]``; the travel input at unit rate). Real or complex (module docstring)."""
    deg = 180.0 / math.pi
    nan = math.nan

    def cross(a, b):
        return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])

    def dot(a, b):
        return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]

    def add(a, b, k):  # a + k b
        return (a[0] + k * b[0], a[1] + k * b[1], a[2] + k * b[2])

    def scale(a, k):
        return (a[0] * k, a[1] * k, a[2] * k)

    def at(k):
        return (pts[k, 0], pts[k, 1], pts[k, 2])

    def vel(k):  # velocity of point slot k
        b = body_of[k]
        if b < 0:
            return (0.0 * pts[k, 0], 0.0 * pts[k, 0], 0.0 * pts[k, 0])
        w = (V[b, 3], V[b, 4], V[b, 5])
        return add((V[b, 0], V[b, 1], V[b, 2]), cross(w, at(k)), 1.0)

    def slope(w, forward):  # tan of a side-view line of direction w rising towards forward * x
        if w[0] == 0.0:
            if w[2] == 0.0:
                return nan
            return math.copysign(math.inf, w[2].real * forward)
        return (w[2] / w[0]) * forward

    for m in range(out.shape[0]):
        out[m] = nan
    b = wheel[FW_BODY]
    centre = at(wheel[FW_CENTRE])
    axis = add(at(wheel[FW_SPIN]), centre, -1.0)
    axis = scale(axis, 1.0 / dot(axis, axis) ** 0.5)
    side = 1.0 if axis[1].real >= 0 else -1.0
    vc = vel(wheel[FW_CENTRE])
    w = (V[b, 3], V[b, 4], V[b, 5])
    dz = vc[2]
    per = 1.0 / dz if dz != 0.0 else nan + 0.0 * dz  # a gain is per unit of wheel travel
    da = cross(w, axis)
    out[M_CAMBER_GAIN] = deg * (-da[2] / (1.0 - axis[2] ** 2) ** 0.5) * per
    out[M_BUMP_STEER] = deg * ((axis[1] * side * da[0] - axis[0] * side * da[1]) / (axis[0] ** 2 + axis[1] ** 2)) * per
    if wheel[FW_UPPER] >= 0 and wheel[FW_LOWER] >= 0:
        up, lo = wheel[FW_UPPER], wheel[FW_LOWER]
        if wheel[FW_ORDER] and pts[up, 2].real < pts[lo, 2].real:
            up, lo = lo, up
        k = add(at(up), at(lo), -1.0)
        dk = add(vel(up), vel(lo), -1.0)
        out[M_CASTER_GAIN] = deg * ((-dk[0] * k[2] + k[0] * dk[2]) / (k[0] ** 2 + k[2] ** 2)) * per
    rate = 0.0 * dz
    springs = False
    for e in range(elements.shape[0]):
        pi, pj = elements[e, 0], elements[e, 1]
        d = add(at(pj), at(pi), -1.0)
        dl = dot(d, add(vel(pj), vel(pi), -1.0)) / dot(d, d) ** 0.5 * per
        mr = -dl if dl.real < 0 else dl
        out[N_FIRST + e] = mr
        if not math.isnan(stiffness[e]):
            rate = rate + stiffness[e] * mr * mr
            springs = True
    if springs:
        out[M_WHEEL_RATE] = rate
    radius = params[FP_RADIUS]
    if math.isnan(radius):
        return
    # the contact point: the lowest point of the wheel circle, and its rate
    g = (axis[0] * axis[2], axis[1] * axis[2], axis[2] * axis[2] - 1.0)
    ng = dot(g, g) ** 0.5
    n = scale(g, 1.0 / ng)
    dg = add(scale(axis, da[2]), da, axis[2])
    dn = scale(add(dg, n, -dot(n, dg)), 1.0 / ng)
    E = add(centre, n, radius)
    vE = add(vc, dn, radius)
    if wheel[FW_REF] >= 0:
        ref = at(wheel[FW_REF])
        out[M_HALF_TRACK] = side * (E[1] - ref[1])
        out[M_PATCH_DX] = E[0] - ref[0]
    out[M_HALF_TRACK_GAIN] = side * vE[1] * per
    out[M_PATCH_DX_GAIN] = vE[0] * per
    # each view's instant centre: the pole of the wheel's motion in the view plane through E (the
    # point of the plane whose velocity is normal to it), homogeneous (the module docstring of
    # kinprop.analysis.firstorder); a pure translation puts it at infinity
    v_O = (V[b, 0], V[b, 1], V[b, 2])
    nw, nv = dot(w, w) ** 0.5, dot(vc, vc) ** 0.5
    sc = max(1.0, dot(centre, centre).real ** 0.5)
    translation = nw == 0.0 or abs(nw.real) * sc <= TRANSLATION_RTOL * abs(nv.real)
    for view in range(2):  # front view: the plane x = x_E (normal e_x); side view: y = y_E (e_y)
        if translation:  # the centre at infinity across the contact point's velocity
            H = (0.0 * vE[0], -vE[2], vE[1]) if view == 0 else (vE[2], 0.0 * vE[0], -vE[0])
            s = 0.0 * dz
        elif view == 0:  # v_O + w x X with no y, z part at x = x_E
            s = w[0] / nw
            H = scale((E[0] * w[0], w[1] * E[0] - v_O[2], v_O[1] + w[2] * E[0]), 1.0 / nw)
        else:  # no x, z part at y = y_E
            s = w[1] / nw
            H = scale((v_O[2] + w[0] * E[1], E[1] * w[1], w[2] * E[1] - v_O[0]), 1.0 / nw)
        c0, c1 = (1, 2) if view == 0 else (0, 2)
        first = M_FVIC_Y if view == 0 else M_SVIC_X
        if abs(s.real) >= PARALLEL_TOL:
            X = scale(H, 1.0 / s)
            out[first], out[first + 1] = X[c0], X[c1]
            out[first + 2] = ((X[c0] - E[c0]) ** 2 + (X[c1] - E[c1]) ** 2) ** 0.5
        else:
            out[first + 2] = math.inf
        wE = add(H, E, -s)  # the line from the contact patch towards the centre
        if view == 0:
            if wE[1] != 0.0:
                out[M_ROLL_CENTRE] = -E[1] * wE[2] / wE[1]
        elif wheel[FW_AXLE] != AXLE_NONE:
            wC = add(H, centre, -s)  # from the wheel centre
            brake = wC if wheel[FW_INBOARD] & 1 else wE
            drive = wC if wheel[FW_INBOARD] & 2 else wE
            lever = params[FP_LEVER]
            if wheel[FW_AXLE] == AXLE_FRONT:  # the centre behind a front wheel
                out[M_ANTI_DIVE] = params[FP_BRAKE_FRONT] * slope(brake, -1.0) * lever
                out[M_ANTI_LIFT] = params[FP_DRIVE_FRONT] * slope(drive, -1.0) * lever
            else:  # ahead of a rear wheel
                out[M_ANTI_LIFT] = (1.0 - params[FP_BRAKE_FRONT]) * slope(brake, 1.0) * lever
                out[M_ANTI_SQUAT] = (1.0 - params[FP_DRIVE_FRONT]) * slope(drive, 1.0) * lever


@kernel
def point_positions(tb, ws, points, xyz, pts, body_of) -> None:
    """Global positions ``pts`` (np, 3) of the point table's slots from the poses in the
    workspace ``ws`` after forward kinematics, and the body each moves with ``body_of`` (np,;
    -1 for a constant point)."""
    r, A, P = ws[W_BODY_R], ws[W_BODY_A], ws[W_FRAME_P]
    for k in range(points.shape[0]):
        a, kind = points[k, _PT_A], points[k, _PT_KIND]
        if kind == _PK_BODY:
            body_of[k] = a
        elif kind == _PK_FRAME:
            body_of[k] = tb.joint[a, J_BODY_I] if points[k, _PT_B] == 0 else tb.joint[a, J_BODY_J]
        else:
            body_of[k] = -1
        for x in range(3):
            if kind == _PK_BODY:
                pts[k, x] = r[a, x] + (A[a, x, 0] * xyz[k, 0] + A[a, x, 1] * xyz[k, 1] + A[a, x, 2] * xyz[k, 2])
            elif kind == _PK_FRAME:
                pts[k, x] = P[a, points[k, _PT_B], x]
            else:
                pts[k, x] = xyz[k, x]


@njit
def batch_first_order(tb, plan, Q, S, C, L, ok, rates, need, rows, cols, row_scale, points, xyz, wheels, params,
                      elements, stiffness, out, status) -> None:  # fmt: skip
    """Every wheel's first-order metrics (:func:`wheel_first_order`) at every state of a batch
    (leading axis) where ``ok``, into ``out`` (N, nw, :data:`N_FIRST` + ne): the bump motion's
    velocities by :func:`kinprop.engine.motion.velocity_solve` on ``plan`` (``rates``: the
    driven coordinates' rates, ``need``, ``rows``, ``cols``, ``row_scale`` as there); ``xyz``
    (M, np, 3): the point table's coordinates, one set for every state (M = 1) or one per state
    (M = N: a study's variants with their own element ends). ``status``
    (N,) int: :data:`kinprop.engine.motion.SOLVED` or the solve's code (the caller answers such
    states by the SVD path); -1 where not ``ok``. Rows not solved are NaN."""
    buf = newton.buffers(tb, plan, rows.shape[0])
    nq = rates.shape[0]
    qdot = np.zeros(nq)
    V = np.zeros((tb.fixed.shape[0], 6))
    res = np.zeros(1)
    pts = np.zeros((points.shape[0], 3))
    body_of = np.zeros(points.shape[0], np.int64)
    for n in range(Q.shape[0]):
        for w in range(out.shape[1]):
            for m in range(out.shape[2]):
                out[n, w, m] = np.nan
        if not ok[n]:
            status[n] = -1
            continue
        code = velocity_solve(tb, plan, Q[n], S[n], C[n], L[n], rates, need, rows, cols, row_scale, buf, qdot, V, res)
        status[n] = code
        if code != SOLVED:
            continue
        point_positions(tb, buf[newton.B_WS], points, xyz[n if xyz.shape[0] > 1 else 0], pts, body_of)
        for w in range(wheels.shape[0]):
            wheel_first_order(wheels[w], params[w], pts, body_of, V, elements, stiffness, out[n, w])


__all__ = [
    "FIRST_CODES",
    "N_FIRST",
    "batch_first_order",
    "point_positions",
    "wheel_first_order",
]
