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
from kinprop.engine.status import Status, message
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


def _statuses(obj: object, key: str = "status") -> list[str]:
    """Every value under ``key`` anywhere in a JSON document (rows of a sweep included)."""
    if isinstance(obj, dict):
        return [v for k, v in obj.items() if k == key] + [s for v in obj.values() for s in _statuses(v, key)]
    if isinstance(obj, list):
        return [s for v in obj for s in _statuses(v, key)]
    return []


def test_every_json_command_says_its_status_in_the_one_vocabulary(examples, tmp_path):
    """Each JSON-producing command (successes and failures) writes only :class:`kinprop.Status`
    words under ``status`` and ``met``/``compromise`` or a status under ``targets_status``."""
    import json
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "cli"))
    from cli_run import invoke_kinprop

    fb, dw, off = examples / "fourbar.yaml", examples / "double_wishbone.yaml", examples / "slider_crank_offset.yaml"
    free = ["--free", "A.q", "--free", "O4.q"]
    runs = {  # name: (arguments before --json, exit code)
        "assemble": (["assemble", fb], 0),
        "propagate": (["propagate", fb, "--set", "O2.q=70"], 0),
        "propagate, stopped short": (["propagate", fb, "--set", "B.s_i[0]=0.03", *free], 1),
        "propagate, iteration cap": (["propagate", fb, "--set", "O2.q=70", "--max-iter", "1", "--no-continuation"], 1),
        "sweep": (["sweep", examples / "fourbar_double_rocker.yaml", "--drive", "O2=0:180:12"], 1),
        "sensitivity": (["sensitivity", fb, "--wrt", "B.s_i[0]"], 0),
        "check": (["check", fb], 0),
        "loads": (["loads", fb, "--force", "coupler.P=30,-45,0"], 0),
        "loads, unbalanced": (["loads", off, "--moment", "crank=0,0,5"], 1),
        "loads, equilibrium": (["loads", dw, "--wheel", "upright=0,0,11000", "--equilibrium"], 0),
        "targets": (["propagate", dw, "--target", "camber@travel=50mm=-1.5deg", "--free", "hardpoint:UBJ"], 0),
        "study": (["study", fb, "--vary", "B.s_i[0]=0.39:0.41", "--samples", "4", "-o", tmp_path / "s"], 0),
    }
    seen = set()
    for name, (argv, code) in runs.items():
        p = invoke_kinprop(*argv, "--json")
        assert p.returncode == code, (name, p.stdout[-1500:], p.stderr[-1500:])
        obj = json.loads(p.stdout)
        words = _statuses(obj)
        assert set(words) <= STATUS_WORDS, (name, set(words) - STATUS_WORDS)
        assert set(_statuses(obj, "targets_status")) <= STATUS_WORDS | {"met", "compromise"}, name
        seen |= set(words)
    # the failures above say their own words, not a generic one
    assert {"converged", "ok", "unbalanced", "infeasible", "not_converged"} <= seen, seen


def test_motion_and_statics_say_ok_singular_unbalanced_from_the_one_table(examples):
    """At an assembled pose: ``ok``, ``singular`` (a dead centre: the slider cannot drive the
    crank) and ``unbalanced`` (a moment on a mechanism with no held input), each a
    :class:`kinprop.Status` with its message from the table, and ``residual`` the pose's
    scaled ``||Phi||`` as a solve reports it."""
    import math

    a, b, c = 0.10, 0.35, 0.05  # examples/slider_crank_offset.yaml
    model = kp.assemble(kp.load_model(examples / "slider_crank_offset.yaml"), tol=1e-13).after
    dead = kp.propagate(model, {"O2.q": math.degrees(math.asin(c / (a + b)))}, tol=1e-13)
    at = dead.after
    records = {
        Status.OK: kp.motion(at, {"O2": 1.0}),
        Status.SINGULAR: kp.motion(at, {"P": 1.0}),
        Status.UNBALANCED: kp.statics(at, PointLoad("crank", (0.0, 0.0, 0.0), moment=(0.0, 0.0, 5.0))),
    }
    held = kp.statics(at, PointLoad("crank", (0.0, 0.0, 0.0), moment=(0.0, 0.0, 5.0)), inputs=["O2"])
    for want, rec in [*records.items(), (Status.OK, held)]:
        assert isinstance(rec.status, kp.Status) and rec.status is want
        assert rec.ok is (want is Status.OK)
        # the pose's ||Phi||, the figure and scaling of Solution.residual (the assembly's own)
        assert rec.residual == pytest.approx(dead.result.residual, abs=1e-15)
    assert records[Status.SINGULAR].message == message(Status.SINGULAR, undetermined=1)
    assert held.message == message(Status.OK) == "ok"
    assert records[Status.UNBALANCED].message.startswith("unbalanced: the constraints and the inputs do not hold")
    assert all(np.isnan(v).all() for v in records[Status.SINGULAR].rates.values())
    assert held.efforts["O2.q"] == pytest.approx(-5.0, rel=1e-9)  # the input holds the couple


def test_a_continuation_result_is_a_view_of_its_solution(examples):
    """``status``, ``fraction`` and ``substeps`` are the engine solution's; the message is the
    table's line with the diagnosis (the coupler shortened beyond the loop's closure:
    docs/analysis/continuation.md)."""
    from kinprop.propagation.continuation import diagnose, propagate_continuation

    m = kp.assemble(kp.load_model(examples / "fourbar.yaml")).after
    bad = propagate_continuation(m, {"B.s_i[0]": 0.03}, free=("A.q", "O4.q"))
    sol = bad.solution
    assert isinstance(sol, kp.Solution) and bad.status is sol.status is Status.INFEASIBLE
    assert (bad.fraction, bad.substeps) == (sol.fraction, sol.substeps)
    assert bad.fraction == pytest.approx(0.945946, abs=1e-3)
    assert bad.diagnosis == diagnose(sol) and bad.conflict_joints == ["B"]
    assert bad.message.startswith(f"the change cannot be assembled beyond {sol.fraction:.6g}")
    good = propagate_continuation(m, {"B.s_i[0]": 0.41}, free=("A.q", "O4.q"))
    assert good.converged and good.fraction == 1.0 and good.message.endswith(good.solution.message)
