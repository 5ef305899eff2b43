"""P3: spatial RSSR four-bar driven through 360 degrees in 1-degree steps, each solved from the previous.

Methods: ``engine.solve_sequence`` (one compiled call for the whole sweep: the issue's number),
``engine.propagate`` by address one call per step (Python loop, each step from the previous
Solution), the model-level ``kp.propagate`` per step (with the engine passed; timed on the first
steps only), a hand-written numpy scalar Newton on the input-output equation, and
``least_squares`` (finite differences) per step.
Check: the input-output equation ``|P(theta) - Q(phi)| - l`` over the whole sweep.
"""

from __future__ import annotations

import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from common import Row, compare

import kinprop as kp
from kinprop.builders import RSSR, rssr, rssr_crank_point, rssr_rocker_point

THETA = np.radians(np.arange(1.0, 361.0, 1.0))


def run(trials: int = 20, reference_steps: int = 36) -> list[Row]:
    model = rssr()
    eng = kp.compile(model)
    st0 = eng.reference
    rc = eng.target("rocker.q").start
    pivot, a, r = np.asarray(RSSR["pivot"], float), float(RSSR["crank"]), float(RSSR["rocker"])
    length = float(model.design["coupler.length"])
    phi0 = float(model.coordinates["rocker"][0])

    def io_error(theta, phi):
        gap = np.linalg.norm(rssr_crank_point(theta, a) - rssr_rocker_point(phi, pivot, r), axis=-1)
        return np.abs(gap - length).max()

    values = THETA[:, None]

    def sequence(_):
        Q, res = eng.solve_sequence(st0, ["crank.q"], values, free=("q",))
        assert res.converged.all()
        return THETA, Q[:, rc]

    def per_step(_):
        sol = eng.reference
        out = np.empty(THETA.size)
        for k, th in enumerate(THETA):
            sol = eng.propagate({"crank.q": th}, start=sol)
            out[k] = sol.state.Q[rc]
        return THETA, out

    def reference(_):
        m, out = model, []
        for th in THETA[:reference_steps]:
            m = kp.propagate(m, {"crank.q": [th]}, engine=eng).after
            out.append(m.coordinates["rocker"][0])
        return THETA[:reference_steps], np.array(out)

    def hand(_):
        out = np.empty(THETA.size)
        phi = phi0
        for k, th in enumerate(THETA):
            P = np.array([a * np.cos(th), a * np.sin(th), 0.0])
            for _it in range(50):
                Qp = pivot + r * np.array([np.sin(phi), 0.0, np.cos(phi)])
                d = P - Qp
                f = d @ d - length * length
                if abs(f) < 1e-10:
                    break
                dQ = r * np.array([np.cos(phi), 0.0, -np.sin(phi)])
                phi -= f / (-2.0 * d @ dQ)
            out[k] = phi
        return THETA, out

    def lsq(_):
        from scipy.optimize import least_squares

        out = np.empty(THETA.size)
        phi = phi0
        for k, th in enumerate(THETA):
            P = np.array([a * np.cos(th), a * np.sin(th), 0.0])

            def f(z, P=P):
                d = P - pivot - r * np.array([np.sin(z[0]), 0.0, np.cos(z[0])])
                return [d @ d - length * length]

            phi = least_squares(f, [phi], method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15).x[0]
            out[k] = phi
        return THETA, out

    def check(_, res):
        return io_error(*res)

    methods = {"engine.solve_sequence": sequence, "engine.propagate per step": per_step,
               "kp.propagate per step (engine=)": reference, "hand numpy Newton": hand,
               "scipy least_squares (FD)": lsq}  # fmt: skip
    rows = compare(
        "P3 RSSR 360 x 1 deg",
        list(range(trials)),
        methods,
        check,
        unit="ms/step",
        per=THETA.size,
        notes={"engine.solve_sequence": "one call, 360 steps"},
    )
    for row in rows:
        if row.method == "kp.propagate per step (engine=)":  # timed on fewer steps: scale to per step
            row.times = [t * THETA.size / reference_steps for t in row.times]
            row.ratios = [x * THETA.size / reference_steps for x in row.ratios]
            row.note = f"first {reference_steps} steps only"
    return rows


if __name__ == "__main__":
    from common import print_table

    print_table(run(int(sys.argv[1]) if len(sys.argv) > 1 else 20))
