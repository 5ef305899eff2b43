"""Generalized-inverse Newton-Raphson: convergence, non-convergence as a result, empty free
sets, and the weighted minimum-norm step (PAPER-NOTES 5-6)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from kinprop import ConvergenceError, jit, propagate
from kinprop.engine import Engine as Assembly
from kinprop.jit import kernel
from kinprop.kinematics import kernels
from kinprop.model import Body, Design, Joint, Mechanism, Model, as_coordinates
from kinprop.solver import newton
from kinprop.solver.newton import min_norm_step
from oracle.forward import read
from random_mechanisms import CUT_TYPES, LOOP_KINDS, TREE_TYPES, random_mechanism

pytestmark = pytest.mark.filterwarnings("ignore::kinprop.SingularityWarning")


def assembled(seed: int):
    tree = [TREE_TYPES[(seed + m) % len(TREE_TYPES)] for m in range(5)]
    cuts = [(CUT_TYPES[(3 * seed + m) % len(CUT_TYPES)], LOOP_KINDS[(seed + m) % len(LOOP_KINDS)]) for m in range(2)]
    return random_mechanism(500 + seed, tree, cuts, assembled=True)


def perturbed(model: Model, rng, scale: float = 0.05) -> Model:
    coords = {k: v + rng.normal(scale=scale, size=v.shape) for k, v in model.coordinates.items()}
    return model.with_state(model.design, as_coordinates(coords))


@pytest.mark.parametrize("seed", range(0, 20, 3))
def test_perturbed_random_mechanism_reassembles(seed):
    rm = assembled(seed)
    asm = Assembly(rm.mechanism)
    assert np.linalg.norm(asm.residual(rm.design, rm.coordinates)) < 1e-12
    start = perturbed(rm.model, np.random.default_rng(seed))
    assert np.linalg.norm(asm.residual(start.design, start.coordinates)) > 1e-2
    prop = propagate(start, {}, free=("q",))  # default tolerance
    res = prop.result
    assert res.status == "converged", f"{rm.describe()}: {res.message}"
    assert res.residual <= 1e-10
    assert np.linalg.norm(asm.residual(prop.after.design, prop.after.coordinates)) <= 1e-10
    assert res.residual_history[0] > 1e-2 and len(res.residual_history) == res.iterations + 1
    assert prop.after.design == start.design  # only q was free
    assert "converged" in res.message


@pytest.mark.parametrize("seed", range(3))
def test_perturbed_mechanism_with_couplings_reassembles(seed):
    """A coupling between revolutes and slides (random quartic coefficients) holds after a
    re-assembly from perturbed coordinates; then a coefficient change is followed, and the
    coupling row holds for the new coefficients."""
    tree = ["revolute", "translational", "revolute", "translational", "spherical"]
    rm = random_mechanism(700 + seed, tree, [("distance", "branch")], assembled=True, couplings=1)
    assert len(rm.mechanism.couplings) == 1
    asm = Assembly(rm.mechanism)
    assert np.linalg.norm(asm.residual(rm.design, rm.coordinates)) < 1e-12
    start = perturbed(rm.model, np.random.default_rng(seed), scale=0.02)
    prop = propagate(start, {}, free=("q",))
    assert prop.result.status == "converged", f"{rm.describe()}: {prop.result.message}"
    assert np.linalg.norm(asm.residual(prop.after.design, prop.after.coordinates)) <= 1e-10
    c = rm.mechanism.couplings[0]
    coef = np.array(prop.after.design[f"{c.name}.coef"])
    coef[1] += 0.05
    moved = propagate(prop.after, {f"{c.name}.coef": coef}, free=("q",))
    assert moved.result.status == "converged", moved.result.message
    x = float(moved.after.coordinates[c.joint_b][0]) - c.q_b0
    qa = float(moved.after.coordinates[c.joint_a][0]) - c.q_a0
    assert qa == pytest.approx(sum(coef[k] * x**k for k in range(5)), abs=1e-10)


def test_max_iter_one_is_a_result_not_an_exception():
    rm = assembled(2)
    start = perturbed(rm.model, np.random.default_rng(1), scale=0.2)
    prop = propagate(start, {}, free=("q",), max_iter=1)
    res = prop.result
    assert (res.status, res.converged, res.iterations) == ("not_converged", False, 1)
    assert res.residual > 1e-10 and "not converged" in res.message
    with pytest.raises(ConvergenceError):
        res.raise_for_status()


def unreachable_distance() -> Model:
    """A crank of radius 0.5 that should reach a point 100 away: no assembly exists."""
    bodies = (Body("G0", fixed=True), Body("B1"))
    joints = (
        Joint("T1", "revolute", "G0", "B1", cut=False),
        Joint("K1", "distance", "B1", "G0", frozenset({"s_i", "s_j", "length"})),
    )
    design = Design({"K1.s_i": [0.5, 0.0, 0.0], "K1.s_j": [1.0, 1.0, 0.0], "K1.length": 100.0})
    return Model(Mechanism(bodies, joints), design, as_coordinates({"T1": [0.3]}))


def test_impossible_distance_does_not_converge():
    res = propagate(unreachable_distance(), {}, free=("q",), max_iter=20).result
    assert res.status == "not_converged"
    assert res.message and ("not converged" in res.message or "diverged" in res.message)
    assert res.residual > 1.0 and np.isfinite(res.residual)
    assert res.iterations <= 20


def test_no_free_columns():
    model = unreachable_distance()
    # () frees nothing; a changed variable is never free either
    for free, changes in (((), {}), (("T1.q",), {"T1.q": [0.1]})):
        prop = propagate(model, changes, free=free)
        res = prop.result
        assert (res.status, res.iterations, res.free.size, res.rank) == ("no_free", 0, 0, 0)
        assert not res.converged
        assert "no free variables" in res.message
        assert prop.after.coordinates["T1"][0] == (0.1 if changes else 0.3)
    # already assembled and nothing free: converged without a step
    rm = assembled(4)
    res = propagate(rm.model, {}, free=()).result
    assert (res.status, res.iterations, res.free.size) == ("converged", 0, 0)


# --- weighted minimum norm -----------------------------------------------------------------------
def slider_with_rod() -> Model:
    """A slider on the ground (q along z) tied to a ground point by a rod of length l."""
    bodies = (Body("G0", fixed=True), Body("B1"))
    joints = (
        Joint("T1", "translational", "G0", "B1", frozenset({"s_i"}), cut=False),
        Joint("K1", "distance", "G0", "B1", frozenset({"s_i", "length"})),
    )
    design = Design({"T1.s_i": [1.0, 0.0, 0.0], "K1.s_i": [0.0, 0.0, 0.0], "K1.length": 1.5})
    return Model(Mechanism(bodies, joints), design, as_coordinates({"T1": [0.8]}))


@pytest.mark.parametrize("heavy", ["T1.q", "K1.length"])
def test_heavily_weighted_variable_takes_the_correction(heavy):
    model = slider_with_rod()
    light = "K1.length" if heavy == "T1.q" else "T1.q"
    asm = Assembly(model.mechanism)
    prop = propagate(model, {}, free=("T1.q", "K1.length"), weights={heavy: 1e4})
    assert prop.result.converged
    before = {k: read(asm.layout, model.design, model.coordinates, k)[0] for k in ("T1.q", "K1.length")}
    after = {k: read(asm.layout, prop.after.design, prop.after.coordinates, k)[0] for k in ("T1.q", "K1.length")}
    moved = {k: abs(after[k] - before[k]) for k in before}
    assert moved[heavy] > 0.05
    assert moved[light] < 1e-2 * moved[heavy], moved
    # the first step splits the correction in the ratio w_k J_k^2 of the two columns
    _, J = asm.evaluate(model.design, model.coordinates)
    w = {k: 1e4 if k == heavy else 1.0 for k in ("T1.q", "K1.length")}
    part = {k: w[k] * J[0, asm.layout[k].start] ** 2 for k in w}
    assert part[heavy] / sum(part.values()) > 0.99


def test_weighted_step_matches_hand_computed_solution():
    """One Newton step with weights W is ``dx = -W J^T (J W J^T)^-1 Phi`` (J of full row rank),
    the minimiser of ``sum dx_k^2 / w_k`` subject to ``J dx = -Phi``."""
    rm = assembled(7)
    asm = Assembly(rm.mechanism)
    # overwrite one design number of a cut joint so the loop opens
    key = next(v.key for v in asm.layout.group("s") if v.joint.startswith("K"))
    new_value = np.asarray(rm.design[key]) + np.array([0.05, -0.03, 0.02])
    free = ("q", "s")
    weights = {"s": 0.01, next(v.key for v in asm.layout.group("q")): 50.0}
    prop = propagate(rm.model, {key: new_value}, free=free, weights=weights, max_iter=1, branch=False)
    start = rm.model.with_state(rm.design.replace({key: new_value}), rm.coordinates)

    Phi, J = asm.evaluate(start.design, start.coordinates)
    cols = asm.layout.columns(list(free), exclude={key})
    wfull = np.ones(asm.layout.n)
    for sel, val in weights.items():
        wfull[asm.layout.columns([sel])] = val
    W = np.diag(wfull[cols])
    Jf = J[:, cols]
    assert np.linalg.matrix_rank(Jf) == Jf.shape[0] < Jf.shape[1]
    dx_hand = -W @ Jf.T @ np.linalg.solve(Jf @ W @ Jf.T, Phi)
    np.testing.assert_allclose(Jf @ dx_hand, -Phi, atol=1e-12)
    # the propagated state (one step of the compiled loop) agrees with it
    taken = np.zeros(asm.layout.n)
    for v in asm.layout.variables:
        if v.group in ("q", "s"):
            taken[v.columns] = read(asm.layout, prop.after.design, prop.after.coordinates, v.key) - read(
                asm.layout, start.design, start.coordinates, v.key
            )
    np.testing.assert_allclose(taken[cols], dx_hand, rtol=1e-9, atol=1e-12)
    assert np.all(np.delete(taken, cols) == 0)
    # it is the weighted minimum: any other solution of J dx = -Phi costs more
    N = np.linalg.svd(Jf)[2][Jf.shape[0] :].T  # null space of Jf
    cost = lambda dx: np.sum(dx**2 / np.diag(W))  # noqa: E731
    rng = np.random.default_rng(0)
    for _ in range(5):
        assert cost(dx_hand + N @ rng.normal(size=N.shape[1]) * 1e-3) > cost(dx_hand)
    # and it differs from the unweighted minimum-norm step
    assert not np.allclose(dx_hand, -np.linalg.pinv(Jf) @ Phi, atol=1e-6)


def test_newton_defaults():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = propagate(slider_with_rod(), {}, free=("T1.q",)).result
    assert res.converged and res.residual < 1e-10


@pytest.mark.parametrize("shape", [(3, 5), (5, 3), (4, 4), (6, 6), (1, 7), (7, 1)])
def test_min_norm_step_is_numpy_lstsq_including_rank_deficient(shape):
    """The step is ``-pinv(J) rhs`` as ``numpy.linalg.lstsq`` gives it (LU when square and
    regular, LAPACK dgelsd otherwise), also when rows repeat (rank deficient)."""
    rng = np.random.default_rng(sum(shape))
    for deficient in (False, True):
        J = rng.normal(size=shape)
        if deficient and shape[0] > 1:
            J[-1] = 2.0 * J[0]
        rhs = rng.normal(size=shape[0])
        out = np.zeros(shape[1])
        sign = min_norm_step(J, rhs, out)
        ref = -np.linalg.lstsq(J, rhs, rcond=None)[0]
        np.testing.assert_allclose(out, ref, rtol=1e-10, atol=1e-12)
        if shape[0] == shape[1]:
            assert sign == (0 if deficient else int(np.sign(np.linalg.det(J))))


def test_kernels_compile_without_reference_counting():
    """Allocation-free kernels are compiled without numba's reference counting (kinprop.jit):
    a kernel that allocated would not compile, and the loop's hot functions are kernels."""
    if not jit.JIT:
        pytest.skip("this process runs the kernels uncompiled (KINPROP_JIT)")
    if kernel.keywords.get("_nrt", True):
        pytest.skip("this numba has no _nrt option: kernels are plain njit functions")
    for f in (kernels.evaluate, kernels.forward_kinematics, kernels.retract, newton.newton_step, newton.solve,
              newton.follow, newton.displacement, newton.flipped, newton.rigid_signs, newton.optimality):  # fmt: skip
        assert f.targetoptions.get("_nrt") is False, f.__name__


def test_independent_sub_mechanisms_are_followed_in_one_step_each_judged_on_its_own():
    """K Stewart platforms on the ground (a block-triangular plan): a 2 mm change of every leg
    is small for each platform, but the whole step grows with sqrt(K). The trust radius holds
    per block, so the change is one sub-step (it was subdivided with JUMPED); a change that is
    large for one platform alone is still subdivided."""
    import dataclasses

    from kinprop.builders import stewart_stack
    from kinprop.engine import compile as compile_engine

    K = 128
    rel = stewart_stack(K)
    joints = tuple(dataclasses.replace(j, body_i="base") if j.type == "free" else j for j in rel.mechanism.joints)
    coords = dict(rel.coordinates)
    h = coords["M1_F"][2]
    for k in range(1, K + 1):
        coords[f"M{k}_F"] = np.array([0.0, 0.0, k * h, 1.0, 0.0, 0.0, 0.0])
    eng = compile_engine(Model(Mechanism(rel.mechanism.bodies, joints, name="ground stack"), rel.design, coords))
    legs = [j.name for j in eng.mechanism.joints if j.type == "distance"]
    rng = np.random.default_rng(0)
    rng.choice([-2e-3, 2e-3], size=len(legs))
    delta = rng.choice([-2e-3, 2e-3], size=len(legs))  # with one global trust radius: 3 sub-steps, JUMPED
    lengths = {f"{n}.length": eng.get(eng.reference, f"{n}.length") for n in legs}
    sol = eng.propagate({a: v + d for (a, v), d in zip(lengths.items(), delta, strict=True)})
    assert sol.converged and sol.substeps == 1 and not sol.flags & newton.JUMPED, (sol.substeps, sol.flags)
    assert np.linalg.norm(eng.residual(sol.state) * eng.row_scale) < 1e-10
    # two legs of platform 1 80% longer: a large tilt of that platform alone is still followed
    # in sub-steps (its own block's predictor and corrections fail the tests)
    big = eng.propagate({f"{n}.length": eng.get(eng.reference, f"{n}.length") * 1.8 for n in legs[:2]})
    assert big.substeps > 1 and big.flags & newton.SUBDIVIDED
