"""One result record and one status vocabulary (issue 24, item 3).

Every surface reports its outcome with :class:`kinprop.Status` and the one message table
(:mod:`kinprop.engine.status`): a propagation's ``result`` is the engine's own
:class:`kinprop.Solution`, a batch row says what a single solve of the same variant says, a
study variant whose values cannot be applied is ``invalid``, an analysis at a pose that is not
an assembly is ``not_assembled``, and targets say ``converged`` with ``met``/``compromise`` beside.
"""

from __future__ import annotations

import numpy as np
import pytest

import kinprop as kp
from kinprop.analysis.study import run_study
from kinprop.builders import rssr
from kinprop.engine.status import message
from kinprop.model.loads import PointLoad

STATUS_WORDS = {s.value for s in kp.Status}


def test_a_propagation_carries_the_engine_solution_and_a_batch_row_says_the_same():
    model = rssr(theta=1.0)
    prop = kp.propagate(model, {"coupler.length": 0.31}, ("rocker.q",))
    sol = prop.result
    assert isinstance(sol, kp.Solution) and sol.status is kp.Status.CONVERGED
    # the singular values are those of the free Jacobian at the returned state (numpy's SVD)
    _, J = sol.engine.evaluate(sol.state)
    np.testing.assert_allclose(sol.singular_values, np.linalg.svd(J[:, sol.free], compute_uv=False), rtol=1e-12)
    assert sol.rank == np.linalg.matrix_rank(J[:, sol.free]) == sol.free.size
    assert sol.residual_history[-1] == sol.residual
    # the batch form: same field names, same numbers for the same variant
    eng = sol.engine
    goal = eng.apply(eng.reference, {"coupler.length": 0.31})[0]
    batch = eng.solve_batch(eng.stack([goal, goal]), ("rocker.q",), exclude={"coupler.length"})
    for name in ("iterations", "residual", "optimality", "fraction"):
        assert getattr(batch, name)[1] == pytest.approx(getattr(sol, name), rel=1e-12, abs=1e-300), name
    assert batch.status(1) is sol.status and batch.message(1) == sol.message
    np.testing.assert_allclose(batch.state.Q[1], sol.state.Q, atol=1e-12)


def test_a_study_variant_that_cannot_be_applied_is_invalid_and_the_others_match_propagate():
    model = rssr(theta=1.0)
    plan = np.array([[0.31], [-0.2], [0.305]])  # a negative length is outside its domain
    df = run_study(model, plan=plan, addresses=["coupler.length"], free=("rocker.q",), units="solver")
    assert list(df["status"]) == ["converged", "invalid", "converged"]
    assert set(df["status"]) <= STATUS_WORDS and kp.Status(df["status"][1]) is kp.Status.INVALID
    assert not df["converged"][1] and np.isnan(df["rocker.q"][1])
    for k in (0, 2):
        ref = kp.propagate(model, {"coupler.length": plan[k, 0]}, ("rocker.q",), units="solver")
        assert df["rocker.q"][k] == pytest.approx(ref.after.coordinates["rocker"][0], abs=1e-10)
    assert message(kp.Status.INVALID).startswith("the values could not be applied")


def test_motion_and_statics_at_a_pose_that_is_not_an_assembly_say_not_assembled(examples):
    raw = kp.load_model(examples / "slider_crank.yaml")  # the file's estimates: J12 open
    eng = kp.compile(raw)
    residual = float(np.linalg.norm(eng.residual(eng.reference) * eng.row_scale))
    assert residual > 1e-4
    mo = kp.motion(raw, {"J01": 1.0})
    st = kp.statics(raw, PointLoad("slider", (0.0, 0.0, 0.0), force=(100.0, 0.0, 0.0)))
    for record in (mo, st):
        assert record.status is kp.Status.NOT_ASSEMBLED
        assert record.message == message(kp.Status.NOT_ASSEMBLED, residual=residual)
    assert all(np.isnan(v).all() for v in mo.rates.values())


@pytest.mark.filterwarnings("ignore::kinprop.SingularityWarning")
def test_targets_say_converged_and_met_or_compromise_beside(examples):
    model = kp.assemble(kp.load_model(examples / "double_wishbone.yaml"), tol=1e-12).after
    met = kp.propagate_targets(model, ["camber@travel=50=-1.5"], ["hardpoint:UBJ"])
    both = kp.propagate_targets(model, ["camber@travel=50=-1.5", "camber@travel=50=-1.0"], ["hardpoint:UBJ"])
    assert met.status is both.status is kp.Status.CONVERGED
    assert (met.targets_status, both.targets_status) == ("met", "compromise")
    assert met.met and not both.met
    # every configuration at the end is an engine solution, assembled
    assert all(isinstance(s, kp.Solution) and s.converged for s in met.result.solutions)
