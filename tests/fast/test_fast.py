"""Fast paths (numba kernels, batched and sparse Newton) against the numpy reference."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("numba")

from kinprop import Assembly, propagate
from kinprop.builders import leg_addresses, rssr, rssr_crank_point, rssr_rocker_point, stewart, stewart_stack
from kinprop.fast import Solver, compile_model, evaluate, pack, propagate_fast, solve_batch, unpack
from kinprop.fast.sparse import SparseSolver
from kinprop.io import load_model
from kinprop.propagation import apply_changes
from kinprop.spatial import exp_so3

TOL = 1e-10


def _models(examples):
    return {
        "slider_crank": load_model(examples / "slider_crank.yaml"),
        "mcpherson": load_model(examples / "mcpherson.yaml"),
        "stewart": stewart(),
        "stewart_ups": stewart("ups"),
        "stack3": stewart_stack(3),
        "rssr": rssr(),
    }


def _perturb(comp, state, rng, scale=0.05):
    """Random change of every layout variable (C through the exponential map)."""
    st = state.copy()
    st.Q += rng.normal(scale=scale, size=st.Q.shape)
    c = 0
    info = comp.colinfo
    while c < comp.n:
        kind, j, side, _ = info[c]
        if kind == 1:
            st.S[0, j, side, info[c, 3]] += rng.normal(scale=scale)
        elif kind == 3:
            st.L[0, j] += rng.normal(scale=scale)
        elif kind == 2:
            st.C[0, j, side] = exp_so3(rng.normal(scale=scale, size=3)) @ st.C[0, j, side]
            c += 2
        c += 1
    return st


@pytest.mark.parametrize("name", ["slider_crank", "mcpherson", "stewart", "stewart_ups", "stack3", "rssr"])
def test_evaluate_matches_reference(examples, name):
    model = _models(examples)[name]
    comp = compile_model(model.mechanism)
    asm = Assembly(model.mechanism)
    rng = np.random.default_rng(7)
    for _ in range(5):
        st = _perturb(comp, pack(comp, model.design, model.coordinates), rng)
        design, coords = unpack(comp, st)
        Phi, J = asm.evaluate(design, coords)
        Phi_f, J_f = evaluate(comp, st)
        np.testing.assert_allclose(Phi_f[0], Phi, atol=1e-12)
        np.testing.assert_allclose(J_f[0], J, atol=1e-12)


def _check_same(comp, state, prop, k=0):
    design, coords = unpack(comp, state, k)
    for j, q in prop.after.coordinates.items():
        np.testing.assert_allclose(coords[j], q, atol=TOL, err_msg=j)
    for key, v in prop.after.design.items():
        np.testing.assert_allclose(design[key], v, atol=TOL, err_msg=key)


PAPER_CASES = [
    ("slider_crank", {"J12.s_j": [-2.8, 0.2, 0.1]}, ("q",)),
    ("slider_crank", {"J12.s_j": [-2.8, 0.2, 0.1]}, ("s",)),
    ("slider_crank", {"J12.s_j": [-2.8, 0.2, 0.1]}, ("q", "s")),
    ("slider_crank", {"J12.s_j": [-2.8, 0.2, 0.1]}, ("q", "C")),
    ("slider_crank", {"J12.s_j": [-2.8, 0.2, 0.1]}, ("J01.q", "J32.q", "J03.s_i[2]", "J32.C_i[1]", "J12.s_i[0]")),
    ("mcpherson", {}, ("q",)),
    ("mcpherson", {"ST.s_i": [0.5, 1.0, 0.0]}, ("q",)),
    ("mcpherson", {"ST.s_i": [0.5, 1.0, 0.0]}, ("q", "RS.s_i", "RS.s_j", "TD.s_i", "TD.s_j", "l")),
]


@pytest.mark.parametrize(("name", "changes", "free"), PAPER_CASES)
def test_solver_matches_propagate_on_paper_examples(examples, name, changes, free):
    model = _models(examples)[name]
    ref = propagate(model, changes, free)
    start, _, changed = apply_changes(model, changes)
    comp = compile_model(model.mechanism)
    res = Solver(comp, free, exclude=changed).solve(pack(comp, start.design, start.coordinates))
    assert bool(res.converged[0]) == ref.converged
    assert int(res.iterations[0]) == ref.result.iterations
    assert res.residual[0] == pytest.approx(ref.result.residual_norm, rel=1e-3, abs=1e-14)
    _check_same(comp, res.state, ref)


def test_batch_matches_propagate_with_per_variant_convergence():
    model = stewart()
    comp = compile_model(model.mechanism)
    legs = leg_addresses(model)
    rng = np.random.default_rng(3)
    changes = [{a: float(model.design[a]) + rng.uniform(-4e-3, 4e-3) for a in legs} for _ in range(6)]
    changes[2] = {a: 5.0 for a in legs}  # unreachable: every leg 5 m (cannot converge to this pose)
    starts = [apply_changes(model, ch) for ch in changes]
    excl = starts[0][2]
    res = solve_batch(comp, [s[0].design for s in starts], [s[0].coordinates for s in starts], ("q",), exclude=excl)
    for k, ch in enumerate(changes):
        ref = propagate(model, ch)
        assert bool(res.converged[k]) == ref.converged
        assert int(res.iterations[k]) == ref.result.iterations
        if ref.converged:
            _check_same(comp, res.state, ref, k)
    assert res.converged.sum() >= 5
    par = Solver(comp, ("q",), exclude=excl).solve(
        pack(comp, [s[0].design for s in starts], [s[0].coordinates for s in starts]), parallel=True
    )
    np.testing.assert_array_equal(par.status, res.status)
    np.testing.assert_allclose(par.x, res.x, atol=1e-14)


def test_hardpoint_change_batch():
    model = stewart()
    comp = compile_model(model.mechanism)
    change = {"M1_L1.s_i": np.asarray(model.design["M1_L1.s_i"]) + [0.005, 0.0, 0.0]}
    ref = propagate(model, change)
    start, _, excl = apply_changes(model, change)
    res = solve_batch(comp, start.design, start.coordinates, exclude=excl)
    _check_same(comp, res.state, ref)


def test_sequence_rssr_matches_propagate_and_io_equation():
    model = rssr()
    comp = compile_model(model.mechanism)
    thetas = np.radians(np.arange(1.0, 361.0, 1.0))
    solver = Solver(comp, ("q",), exclude={"crank.q"})
    Q, res = solver.sequence(pack(comp, model.design, model.coordinates), comp.column("crank.q[0]"), thetas)
    assert res.converged.all()
    m = model
    for k in range(10):  # reference: the same continuation, step by step
        m = propagate(m, {"crank.q": [thetas[k]]}).after
        np.testing.assert_allclose(Q[k, comp.column("rocker.q[0]")], m.coordinates["rocker"][0], atol=TOL)
    phi = Q[:, comp.column("rocker.q[0]")]
    g = {"crank": 0.1, "pivot": (0.35, 0.05, 0.15), "rocker": 0.3}
    gap = np.linalg.norm(
        rssr_crank_point(thetas, g["crank"]) - rssr_rocker_point(phi, np.array(g["pivot"]), g["rocker"]), axis=1
    )
    np.testing.assert_allclose(gap, float(model.design["coupler.length"]), atol=1e-10)


@pytest.mark.parametrize("method", ["blocks", "splu"])
def test_sparse_matches_propagate(method):
    model = stewart_stack(3)
    comp = compile_model(model.mechanism)
    rng = np.random.default_rng(5)
    change = {a: float(model.design[a]) + rng.choice([-2e-3, 2e-3]) for a in leg_addresses(model)}
    ref = propagate(model, change)
    start, _, excl = apply_changes(model, change)
    ss = SparseSolver(comp, ("q",), exclude=excl, method=method)
    st, (status, it, _) = ss.solve(pack(comp, start.design, start.coordinates))
    assert status == 0 and it == ref.result.iterations
    _check_same(comp, st, ref)
    J = ss.jacobian(pack(comp, start.design, start.coordinates)).toarray()
    _, Jd = Assembly(model.mechanism).evaluate(start.design, start.coordinates)
    np.testing.assert_allclose(J, Jd[:, ss.free], atol=1e-12)


def test_sparse_min_norm_underdetermined():
    model = stewart_stack(2)
    comp = compile_model(model.mechanism)
    change = {"M1_L1.length": float(model.design["M1_L1.length"]) + 3e-3}
    free = ("q", "M1_L2.s_i", "M2_L4.s_j")
    ref = propagate(model, change, free)
    start, _, excl = apply_changes(model, change)
    ss = SparseSolver(comp, free, exclude=excl, method="splu")
    assert comp.m < ss.free.size
    st, (status, it, _) = ss.solve(pack(comp, start.design, start.coordinates))
    assert status == 0 and it == ref.result.iterations
    _check_same(comp, st, ref)


@pytest.mark.parametrize(("name", "changes", "free"), PAPER_CASES[:3] + PAPER_CASES[5:])
def test_propagate_fast_returns_the_same_propagation(examples, name, changes, free):
    model = _models(examples)[name]
    ref = propagate(model, changes, free)
    fast = propagate_fast(model, changes, free)
    assert fast.converged == ref.converged and fast.result.iterations == ref.result.iterations
    assert fast.result.rank == ref.result.rank
    np.testing.assert_allclose(fast.result.singular_values, ref.result.singular_values, rtol=1e-8, atol=1e-12)
    assert fast.result.residual_history[0] == pytest.approx(ref.result.residual_history[0], rel=1e-12)
    for j, q in ref.after.coordinates.items():
        np.testing.assert_allclose(fast.after.coordinates[j], q, atol=TOL)
    for key, v in ref.after.design.items():
        np.testing.assert_allclose(fast.after.design[key], v, atol=TOL)
