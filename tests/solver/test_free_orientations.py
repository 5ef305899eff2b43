"""The least change with free orientations (``--free C``): the closest assembly in the metric
``sum |u_k|^2`` over the free orientations' rotation vectors ``u = log(C C_start^T)`` (plus the
other free variables' squared changes), reached by Newton on the KKT system
(``kinprop.solver.newton.kkt_step``) within the default iteration cap.

Truth: an independent constrained minimisation written here (scipy's SLSQP, then the KKT system
by scipy's Levenberg-Marquardt), parameterised by scipy's rotation vectors, with every derivative by
finite differences of the residual, so neither the engine's Jacobian nor its SO(3) Jacobian
enters it.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import qr
from scipy.optimize import least_squares, minimize
from scipy.spatial.transform import Rotation

import kinprop as kp
from kinprop.engine import compile
from random_mechanisms import cycled_set

pytestmark = pytest.mark.filterwarnings("ignore::kinprop.SingularityWarning")

DEG = 1e-7  # degrees
METRE = 1e-9


def columns_of(engine, v) -> list[int]:
    return list(range(engine.n_columns))[v.columns]


def rotation_columns(engine, cols: np.ndarray) -> dict[int, tuple[str, int]]:
    """Free column -> (orientation address, component) for the free orientation columns."""
    out = {}
    for v in engine.layout.group("C"):
        for k, c in enumerate(columns_of(engine, v)):
            if c in cols:
                out[int(c)] = (v.key, k)
    return out


def metric_coordinates(engine, start, state, cols: np.ndarray) -> np.ndarray:
    """A state's coordinates in the metric: changes of q, s', l from ``start``; rotation vectors
    ``log(C C_start^T)`` (scipy) of the orientations."""
    rot = rotation_columns(engine, cols)
    out = np.zeros(cols.size)
    for i, c in enumerate(cols):
        if int(c) in rot:
            key, k = rot[int(c)]
            R = np.asarray(engine.get(state, key)).reshape(3, 3) @ np.asarray(engine.get(start, key)).reshape(3, 3).T
            out[i] = Rotation.from_matrix(R).as_rotvec()[k]
        else:
            for v in engine.layout.variables:
                if c in columns_of(engine, v):
                    d = np.ravel(engine.get(state, v.key)) - np.ravel(engine.get(start, v.key))
                    out[i] = d[columns_of(engine, v).index(c)]
    return out


def closest_assembly(engine, start, cols: np.ndarray) -> np.ndarray:
    """``argmin |x|^2 s.t. Phi(x) = 0`` in the metric coordinates ``x`` (a metre model): the
    state at ``x`` has ``C = Rotation.from_rotvec(u) C_start`` (checked against the engine's
    retraction) and ``q, s', l`` moved by ``x``; Jacobians by 5-point differences of Phi."""
    rot = rotation_columns(engine, cols)

    def state(x):
        dx = np.zeros(engine.n_columns)
        dx[cols] = x
        return engine.retract(start, dx)

    x_test = np.linspace(0.1, 0.4, cols.size)
    s = state(x_test)
    for key in {k for k, _ in rot.values()}:
        u = np.array([x_test[list(cols).index(c)] for c in columns_of(engine, engine.layout[key])])
        C0 = np.asarray(engine.get(start, key)).reshape(3, 3)
        np.testing.assert_allclose(np.asarray(engine.get(s, key)).reshape(3, 3),
                                   Rotation.from_rotvec(u).as_matrix() @ C0, atol=1e-14)  # fmt: skip

    def phi(x):
        return engine.residual(state(x))

    def jac(x, h=1e-3):
        J = np.zeros((phi(x).size, x.size))
        for k in range(x.size):
            e = np.zeros(x.size)
            e[k] = h
            J[:, k] = (8 * (phi(x + e) - phi(x - e)) - (phi(x + 2 * e) - phi(x - 2 * e))) / (12 * h)
        return J

    # independent rows (column-pivoted QR of J^T at the start): SLSQP fails on redundant ones
    _, R, piv = qr(jac(np.zeros(cols.size)).T, pivoting=True)
    d = np.abs(np.diag(R))
    rows = np.sort(piv[: int(np.sum(d > 1e-9 * d.max()))]) if d.size and d.max() > 0 else piv[:0]

    def phi_r(x):
        return phi(x)[rows]

    cons = [{"type": "eq", "fun": phi_r, "jac": lambda x: jac(x)[rows]}]
    res = minimize(lambda x: float(x @ x), np.zeros(cols.size), jac=lambda x: 2 * x, method="SLSQP",
                   constraints=cons, options={"ftol": 1e-14, "maxiter": 500})  # fmt: skip
    x = res.x
    lam = np.linalg.lstsq(jac(x)[rows].T, -x, rcond=None)[0]
    n = x.size

    def kkt(z):
        return np.concatenate([z[:n] + jac(z[:n])[rows].T @ z[n:], phi_r(z[:n])])

    sol = least_squares(kkt, np.concatenate([x, lam]), method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15)
    assert np.linalg.norm(kkt(sol.x)) < 1e-10, sol.message
    assert np.linalg.norm(phi(sol.x[:n])) < 1e-10  # the redundant rows too
    return sol.x[:n]


def check_against_independent(engine, start, cols, after) -> None:
    ours = metric_coordinates(engine, start, engine.state_of(after), cols)
    x = closest_assembly(engine, start, cols)
    rot = np.array([int(c) in rotation_columns(engine, cols) for c in cols])
    labels = [engine.column_labels[c].split("[")[0] for c in cols]
    ang = rot | np.array([lab.endswith(".q") and not engine.mechanism.joint(lab[:-2]).jtype.name.startswith("trans")
                          for lab in labels])  # fmt: skip
    np.testing.assert_allclose(np.rad2deg(ours[ang]), np.rad2deg(x[ang]), atol=DEG)
    np.testing.assert_allclose(ours[~ang], x[~ang], atol=METRE)


def orthonormal(model):
    """``model`` with every orientation the nearest rotation (SVD): the paper's ``RS.C_i`` is
    printed to 4 digits (|C C^T - I| = 1e-4), where ``log(C C_start^T)`` (the metric) and the
    rotation ``C C_start^-1`` differ by that much."""
    design = {}
    for k, v in model.design.items():
        if k.split(".")[-1] in ("C_i", "C_j"):
            U, _, Vt = np.linalg.svd(np.asarray(v, float).reshape(3, 3))
            design[k] = U @ Vt
    return model.with_state(model.design.replace(design), model.coordinates)


@pytest.mark.parametrize("free", [("C",), ("C", "q")])
def test_mcpherson_free_orientations_closest_assembly(examples, free):
    """The McPherson strut, the top mount moved 23 cm, only orientations (and the coordinates)
    free: converged within the default 50 iterations (Gauss-Newton needed 115 for ``C``), at
    the closest assembly."""
    base = kp.assemble(orthonormal(kp.load_model(examples / "mcpherson.yaml"))).after
    change = {"ST.s_i": [0.5, 1.0, 0.0]}
    p = kp.propagate(base, change, free)
    assert p.converged, p.result.message
    assert p.result.optimality < 1e-10
    eng = compile(base)
    start = eng.apply(eng.reference, change)[0]
    cols = eng.free_columns(free, change)
    turn = max(np.linalg.norm(Rotation.from_matrix(np.asarray(p.after.design[k]) @ np.asarray(base.design[k]).T)
                              .as_rotvec()) for k in ("ST.C_i", "TD.C_i"))  # fmt: skip
    assert turn > np.deg2rad(15 if free == ("C",) else 2)  # C alone: large turns, where the linear rate was slow
    check_against_independent(eng, start, cols, p.after)


def random_cases():
    return cycled_set(8, base=700, tree_joints=4)


@pytest.mark.parametrize("rm", random_cases(), ids=lambda rm: f"seed{rm.seed}")
def test_random_mechanisms_free_orientations(rm):
    """A cut joint's s' moved by a few cm, orientations free (with the coordinates, and alone):
    each solve that follows the change ends at the independently computed closest assembly."""
    model = rm.model
    eng = compile(model)
    cut = [j for j in eng.topology.cut_joints if "s_i" in model.mechanism.joint(j).fields]
    if not cut:
        pytest.skip("no cut joint with s_i")
    key = f"{cut[0]}.s_i"
    rng = np.random.default_rng(rm.seed)
    value = np.asarray(model.design[key]) + rng.normal(scale=0.05, size=3)
    solved = 0
    for free in (("C", "q"), ("C",)):
        p = kp.propagate(model, {key: value}, free, units="solver")
        if not p.converged:  # orientations alone may not reach the moved point
            continue
        solved += 1
        assert p.result.optimality < 1e-10
        start = eng.apply(eng.reference, {key: value})[0]
        check_against_independent(eng, start, eng.free_columns(free, {key: value}), p.after)
    assert solved, f"{rm.describe()}: no free set followed the change"
