"""The least change (issue 24, item 1): with freedom left, a propagation returns the assembly
closest to the changed start, ``argmin sum (si_k dx_k)^2 / w_k`` subject to ``Phi = 0`` with
changes in metres and radians (docs/analysis/weights.md).

Truth: the KKT condition computed here with numpy (the weighted change lies in the row space of
the free Jacobian), an independent constrained minimisation (scipy SLSQP, then the KKT system
by scipy's root finder) written in this file, and the same mechanism written in mm.
"""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
from scipy.optimize import minimize, root
from typer.testing import CliRunner

import kinprop as kp
from kinprop.cli import app
from kinprop.engine import compile
from kinprop.io.writer import dump_model
from kinprop.model import Design, Model, as_coordinates
from random_mechanisms import cycled_set

pytestmark = pytest.mark.filterwarnings("ignore::kinprop.SingularityWarning")

DEG = 1e-7  # degrees: agreement of angles
METRE = 1e-9  # metres: agreement of lengths


@pytest.fixture
def run_cli():
    runner = CliRunner()
    return lambda *args: runner.invoke(app, [str(a) for a in args])


def length_mask(engine, joint: str, size: int) -> np.ndarray:
    """Which coordinates of ``joint`` are lengths (slides): not angles, not Euler parameters;
    a cut joint's own coordinates (T-D) are lengths."""
    jt = engine.mechanism.joint(joint).jtype
    mask = np.ones(size, bool)
    if joint in engine.topology.tree_joints:
        mask[list(jt.angle_indices)] = False
        if jt.euler is not None:
            mask[jt.euler] = False
    return mask


def in_millimetres(model: Model) -> Model:
    """The same mechanism written in mm: every length (fixed bodies' positions, named points,
    s', link lengths, slides) times 1000, ``units.length = mm``."""
    assert not model.mechanism.couplings, "coefficients of couplings are not converted here"
    eng = compile(model)
    mech = model.mechanism
    bodies = tuple(
        replace(b, position=tuple(1000.0 * np.asarray(b.position)), points=tuple((n, tuple(1000.0 * np.asarray(p)))
                                                                                   for n, p in b.points))
        for b in mech.bodies
    )  # fmt: skip
    design = {k: (np.asarray(v) * 1000.0 if k.split(".")[-1] in ("s_i", "s_j", "length") else v)
              for k, v in model.design.items()}  # fmt: skip
    coords = {}
    for j, q in model.coordinates.items():
        q = np.array(q, float)
        q[length_mask(eng, j, q.size)] *= 1000.0
        coords[j] = q
    units = dict(model.units) | {"length": "mm"}
    return Model(replace(mech, bodies=bodies), Design(design), as_coordinates(coords), units=units)


def free_values(engine, state, free: np.ndarray) -> np.ndarray:
    """The values of layout columns ``free`` (q, s', l; no orientations) of a state."""
    x = np.zeros(engine.n_columns)
    for v in engine.layout.variables:
        if v.group in ("q", "s", "l"):
            x[v.columns] = np.ravel(engine.get(state, v.key))
    return x[free]


def kkt_residual(engine, start, state, free: np.ndarray, weights: np.ndarray | None = None) -> float:
    """``|(I - P) W^-1/2 (x - x0)|``: the part of the weighted change outside the row space of
    the free Jacobian (``P`` its projector, numpy's pinv), metres/radians for a metre model."""
    sw = np.ones(free.size) if weights is None else np.sqrt(weights)
    y = (free_values(engine, state, free) - free_values(engine, start, free)) / sw
    _, J = engine.evaluate(state)
    M = J[:, free] * sw
    return float(np.linalg.norm(y - np.linalg.pinv(M, rcond=1e-10) @ (M @ y)))


def closest_assembly(engine, start, free: np.ndarray) -> np.ndarray:
    """The assembly closest to ``start`` (a metre model: the plain Euclidean distance over the
    free columns), written here: scipy's SLSQP on ``min |x - x0|^2 s.t. Phi(x) = 0``, then the
    KKT system ``[x - x0 + J^T lam; Phi] = 0`` by scipy's root finder from its answer."""
    x0 = free_values(engine, start, free)

    def state(x):
        dx = np.zeros(engine.n_columns)
        dx[free] = x - x0
        return engine.retract(start, dx)

    def phi(x):
        return engine.residual(state(x))

    def jac(x):
        return engine.evaluate(state(x))[1][:, free]

    cons = [{"type": "eq", "fun": phi, "jac": jac}]
    res = minimize(lambda x: float((x - x0) @ (x - x0)), x0, jac=lambda x: 2 * (x - x0), method="SLSQP",
                   constraints=cons, options={"ftol": 1e-12, "maxiter": 200})  # fmt: skip
    x = res.x
    lam = np.linalg.lstsq(jac(x).T, -(x - x0), rcond=None)[0]
    n = x.size

    def kkt(z):
        x, lam = z[:n], z[n:]
        return np.concatenate([x - x0 + jac(x).T @ lam, phi(x)])

    def kkt_jac(z):  # [[I + d(J^T lam)/dx, J^T], [J, 0]], the second derivatives by central differences
        x, lam = z[:n], z[n:]
        J = jac(x)
        H = np.zeros((n, n))
        for k in range(n):
            e = np.zeros(n)
            e[k] = 1e-6
            H[:, k] = (jac(x + e).T @ lam - jac(x - e).T @ lam) / 2e-6
        return np.block([[np.eye(n) + H, J.T], [J, np.zeros((J.shape[0], J.shape[0]))]])

    sol = root(kkt, np.concatenate([x, lam]), jac=kkt_jac, method="hybr", options={"xtol": 1e-14})
    assert np.linalg.norm(kkt(sol.x)) < 1e-11, sol.message
    return sol.x[:n]


# --- the paper's slider-crank, in m and in mm ---------------------------------------------------
SC_CHANGE = {"J12.s_j": [-2.8, 0.2, 0.1]}


@pytest.fixture(scope="module")
def slider_crank(examples):
    return kp.load_model(examples / "slider_crank.yaml"), kp.load_model(examples / "slider_crank_mm.yaml")


@pytest.mark.parametrize("free", [("q",), ("q", "s")])
def test_slider_crank_m_and_mm_give_the_closest_assembly(slider_crank, free):
    m, mm = slider_crank
    a = kp.propagate(m, SC_CHANGE, free)
    b = kp.propagate(mm, {"J12.s_j": [-2800.0, 200.0, 100.0]}, free)
    assert a.converged and b.converged, (a.result.message, b.result.message)
    assert a.result.optimality < 1e-10 and b.result.optimality < 1e-10
    np.testing.assert_allclose(b.coordinates["J01"], a.coordinates["J01"], atol=DEG)  # degrees
    np.testing.assert_allclose(np.rad2deg(b.after.coordinates["J32"]), np.rad2deg(a.after.coordinates["J32"]), atol=DEG)
    np.testing.assert_allclose(b.after.coordinates["J03"] / 1000.0, a.after.coordinates["J03"], atol=METRE)
    for key in ("J01.s_i", "J03.s_i", "J32.s_i", "J12.s_i"):
        np.testing.assert_allclose(np.asarray(b.after.design[key]) / 1000.0, a.after.design[key], atol=METRE)
    # the independent closest assembly (metre model: metres and radians as they are)
    eng = compile(m)
    start = eng.apply(eng.reference, SC_CHANGE)[0]
    cols = eng.free_columns(free, SC_CHANGE)
    x = closest_assembly(eng, start, cols)
    ours = free_values(eng, eng.state_of(a.after), cols)
    ang = np.array([eng.column_labels[c].split("[")[0] in ("J01.q", "J32.q") for c in cols])
    np.testing.assert_allclose(np.rad2deg(ours[ang]), np.rad2deg(x[ang]), atol=DEG)
    np.testing.assert_allclose(ours[~ang], x[~ang], atol=METRE)
    assert kkt_residual(eng, start, eng.state_of(a.after), cols) < 1e-10


def test_slider_crank_issue_numbers(slider_crank):
    """The issue's case: the closest assembly is J01 = 44.898928 deg (the paper's iteration
    ends at 44.893814, its Table 4 value with --tol 1e-3 44.893707)."""
    m, mm = slider_crank
    a = kp.propagate(m, SC_CHANGE, ("q",))
    assert a.coordinates["J01"][0] == pytest.approx(44.898928, abs=5e-7)
    paper = kp.propagate(m, SC_CHANGE, ("q",), method="paper")
    assert paper.coordinates["J01"][0] == pytest.approx(44.893814, abs=5e-7)
    assert paper.result.optimality > 1e-4  # the paper's end point is not the least change
    paper_mm = kp.propagate(mm, {"J12.s_j": [-2800.0, 200.0, 100.0]}, ("q",), method="paper")
    assert paper_mm.coordinates["J01"][0] == pytest.approx(paper.coordinates["J01"][0], abs=DEG)


def test_slider_crank_cli_m_and_mm(slider_crank, examples, run_cli):
    out = {}
    for name, change in (("slider_crank", "-2.8,0.2,0.1"), ("slider_crank_mm", "-2800,200,100")):
        r = run_cli("propagate", str(examples / f"{name}.yaml"), "--set", f"J12.s_j={change}", "--free", "q", "--json")
        assert r.exit_code == 0, r.output
        out[name] = json.loads(r.stdout)
    a, b = out["slider_crank"], out["slider_crank_mm"]
    assert a["optimality_residual"] < 1e-10 and b["optimality_residual"] < 1e-10
    assert abs(a["coordinates"]["J01"][0] - b["coordinates"]["J01"][0]) < DEG
    assert abs(a["coordinates"]["J03"][0] - b["coordinates"]["J03"][0] / 1000.0) < METRE
    assert a["coordinates"]["J01"][0] == pytest.approx(44.898928, abs=5e-7)


def test_weights_scale_the_metric(slider_crank):
    """``--weight`` scales the SI metric: the weighted closest assembly satisfies the weighted
    KKT condition, the same in m and in mm."""
    m, mm = slider_crank
    w = {"J03.q": 50.0}
    a = kp.propagate(m, SC_CHANGE, ("q",), weights=w)
    b = kp.propagate(mm, {"J12.s_j": [-2800.0, 200.0, 100.0]}, ("q",), weights=w)
    plain = kp.propagate(m, SC_CHANGE, ("q",))
    assert a.converged and b.converged
    assert abs(a.after.coordinates["J03"][0]) > abs(plain.after.coordinates["J03"][0]) + 1e-4  # the slide moves more
    np.testing.assert_allclose(b.after.coordinates["J03"] / 1000.0, a.after.coordinates["J03"], atol=METRE)
    np.testing.assert_allclose(b.coordinates["J01"], a.coordinates["J01"], atol=DEG)
    eng = compile(m)
    start = eng.apply(eng.reference, SC_CHANGE)[0]
    cols = eng.free_columns(("q",), SC_CHANGE)
    assert kkt_residual(eng, start, eng.state_of(a.after), cols, eng.weights_for(cols, w)) < 1e-10
    assert kkt_residual(eng, start, eng.state_of(a.after), cols) > 1e-4  # not the unweighted one


# --- McPherson (paper, Table 1 setting), in m and in mm --------------------------------------------
@pytest.mark.parametrize("free", [("q",), ("s", "q"), ("s", "q", "l")])
def test_mcpherson_m_and_mm_closest_assembly(examples, free, tmp_path, run_cli):
    base = kp.assemble(kp.load_model(examples / "mcpherson.yaml")).after
    change = {"ST.s_i": [0.5, 1.0, 0.0]}
    a = kp.propagate(base, change, free)
    mm = in_millimetres(base)
    b = kp.propagate(mm, {"ST.s_i": [500.0, 1000.0, 0.0]}, free)
    assert a.converged and b.converged, (a.result.message, b.result.message)
    eng = compile(base)
    start = eng.apply(eng.reference, change)[0]
    cols = eng.free_columns(free, change)
    assert kkt_residual(eng, start, eng.state_of(a.after), cols) < 1e-10
    qa, qb = a.after.coordinates, b.after.coordinates
    np.testing.assert_allclose(qb["ST"][:4], qa["ST"][:4], atol=1e-10)  # Euler parameters as they are
    np.testing.assert_allclose(qb["ST"][4] / 1000.0, qa["ST"][4], atol=METRE)
    np.testing.assert_allclose(qb["TD"] / 1000.0, qa["TD"], atol=METRE)
    for key in ("RS.s_i", "RS.s_j", "TD.s_i", "TD.s_j", "RS.length", "TD.length"):
        np.testing.assert_allclose(np.asarray(b.after.design[key]) / 1000.0, a.after.design[key], atol=METRE)
    x = closest_assembly(eng, start, cols)
    np.testing.assert_allclose(free_values(eng, eng.state_of(a.after), cols), x, atol=METRE)
    # the CLI on the mm file
    path = tmp_path / "mc_mm.yaml"
    dump_model(mm, path)
    args = [a for f in free for a in ("--free", f)]
    r = run_cli("propagate", str(path), "--set", "ST.s_i=500,1000,0", *args, "--json")
    assert r.exit_code == 0, r.output
    got = json.loads(r.stdout)
    assert got["optimality_residual"] < 1e-10
    np.testing.assert_allclose(np.asarray(got["design"]["TD.s_j"]) / 1000.0, a.after.design["TD.s_j"], atol=METRE)


# --- seeded random mechanisms ----------------------------------------------------------------------
def random_cases():
    return cycled_set(12, base=900, cut_stride=5)


@pytest.mark.parametrize("rm", random_cases(), ids=lambda rm: f"seed{rm.seed}")
def test_random_mechanisms_least_change_and_unit_invariance(rm):
    """A change of a cut joint's s' (or a length), free q (and s'): the KKT condition holds,
    and the mm model gives the same physical answer."""
    model = rm.model
    eng = compile(model)
    cut = [j for j in eng.topology.cut_joints if "s_i" in model.mechanism.joint(j).fields]
    if not cut:
        pytest.skip("no cut joint with s_i")
    key = f"{cut[0]}.s_i"
    rng = np.random.default_rng(rm.seed)
    value = np.asarray(model.design[key]) + rng.normal(scale=0.03, size=3)
    solved = 0
    for free in (("q",), ("q", "s")):
        a = kp.propagate(model, {key: value}, free, units="solver")
        if not a.converged:  # a change the mechanism cannot follow: nothing to compare
            continue
        solved += 1
        start = eng.apply(eng.reference, {key: value})[0]
        cols = eng.free_columns(free, {key: value})
        assert a.result.optimality < 1e-10
        assert kkt_residual(eng, start, eng.state_of(a.after), cols) < 1e-8, rm.describe()
        b = kp.propagate(in_millimetres(model), {key: 1000.0 * value}, free, units="solver")
        assert b.converged, b.result.message
        emm = compile(b.before)
        for j, qa in a.after.coordinates.items():
            qb = np.array(b.after.coordinates[j], float)
            lm = length_mask(emm, j, qb.size)
            qb[lm] /= 1000.0
            np.testing.assert_allclose(qb[~lm], qa[~lm], atol=np.deg2rad(DEG), err_msg=f"{rm.describe()} {j}")
            np.testing.assert_allclose(qb[lm], qa[lm], atol=METRE, err_msg=f"{rm.describe()} {j}")
        for k, v in a.after.design.items():
            if k.split(".")[-1] in ("s_i", "s_j", "length"):
                np.testing.assert_allclose(np.asarray(b.after.design[k]) / 1000.0, v, atol=METRE)
    assert solved, f"{rm.describe()}: no free set followed the change"


def test_engine_api_reports_optimality_and_paper_method(examples):
    """``Engine.propagate``: the optimality residual of the closest assembly is at the tolerance,
    the paper's iteration's end point has a larger one; no freedom: 0 for both."""
    eng = compile(kp.load_model(examples / "slider_crank.yaml"))
    sol = eng.propagate(SC_CHANGE, free=["q"])
    paper = eng.propagate(SC_CHANGE, free=["q"], method="paper")
    assert sol.converged and paper.converged
    assert sol.optimality < 1e-10 < paper.optimality
    assert "optimality" in sol.message
    fixed = eng.propagate({"J12.s_j": [-2.8, 0.2, 0.1]}, free=["J01.q", "J32.q"])  # 3 rows, 3 columns
    assert fixed.optimality == 0.0
    with pytest.raises(ValueError, match="method"):
        eng.propagate(SC_CHANGE, free=["q"], method="closest")
