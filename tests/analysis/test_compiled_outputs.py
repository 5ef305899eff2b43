"""The compiled outputs (kinprop.engine.outputs, one kernel call for a whole batch) against the
position-level outputs as the library first computed them in numpy, one state at a time
(tests/oracle/outputs.py), on seeded variants of every wheel example and the slider-crank:
every coordinate, design variable, named point, hardpoint, distance and position metric."""

from __future__ import annotations

import numpy as np
import pytest

import kinprop as kp
from kinprop.analysis.context import OutputContext, WheelSpec
from kinprop.analysis.metrics import is_first_order, resolve_metric
from kinprop.analysis.outputs import evaluate_outputs, output_names, output_program
from kinprop.analysis.statics import is_load_output
from kinprop.engine import State
from oracle import outputs as oracle

MODELS = ["double_wishbone.yaml", "mcpherson_axle.yaml", "hmmwv_front_axle.yaml", "multilink_rear_axle.yaml",
          "double_wishbone_hardpoints.yaml", "slider_crank.yaml", "stewart.yaml"]  # fmt: skip


def position_outputs(model, engine) -> list[str]:
    names = []
    for n in output_names(model, engine):
        if is_load_output(n):
            continue
        if (n.startswith("metric:") or "." not in n) and is_first_order(resolve_metric(model, n)[1]):
            continue
        names.append(n)
    return names


def variants(engine, n: int, seed: int) -> State:
    """``n`` seeded states near the reference: coordinates moved by up to 0.05 (rad or the model's
    unit), joint positions s' by up to 2 % of their size (outputs need no assembly)."""
    rng = np.random.default_rng(seed)
    ref = engine.reference.writable()
    st = engine.stack([ref] * n)
    Q = st.Q + rng.uniform(-0.05, 0.05, st.Q.shape)
    S = st.S * (1 + rng.uniform(-0.02, 0.02, st.S.shape))
    return State(Q, S, st.C.copy(), st.L.copy())


def check(model, engine, names, states, reference=None, wheels=None) -> None:
    program = output_program(model, names, reference=reference, wheels=wheels, engine=engine)
    got = program.evaluate(states)
    assert got.shape == (states.Q.shape[0], len(program.names))
    for i in range(states.Q.shape[0]):
        ctx = OutputContext.of(engine.model_of(states[i], model), reference, wheels, engine)
        want = np.array([oracle.scalar(ctx, name) for name in program.names])
        scale = np.maximum(1.0, np.abs(want))
        bad = np.abs(got[i] - want) > 1e-12 * scale
        assert not bad.any(), [(n, got[i][k], want[k]) for k, n in enumerate(program.names) if bad[k]]


@pytest.mark.parametrize("name", MODELS)
def test_every_position_output_matches_the_numpy_oracle(examples, name):
    model = kp.load_model(examples / name)
    engine = kp.compile(model)
    names = position_outputs(model, engine)
    assert names
    check(model, engine, names, variants(engine, 12, seed=len(name)))


def test_distances_steering_axis_spec_and_reference(examples):
    """Distances between points and hardpoints, a steering axis given per call (WheelSpec), a
    reference model for the wheel-centre displacement."""
    model = kp.load_model(examples / "double_wishbone.yaml")
    engine = kp.compile(model)
    states = variants(engine, 8, seed=3)
    reference = engine.model_of(states[7], model)
    names = ["distance:upright.wheel_centre,hardpoint:UCA.front", "distance:hardpoint:TR.i,hardpoint:TR.j",
             "camber", "caster", "kpi", "scrub_radius", "trail", "wheel_centre_dx", "wheel_centre_dz"]  # fmt: skip
    wheels = {"upright": WheelSpec(steering_axis=("hardpoint:TR.j", "hardpoint:LBJ.j"))}
    check(model, engine, names, states, reference=reference, wheels=wheels)


def test_rows_not_ok_are_nan_and_evaluate_outputs_is_the_program(examples):
    model = kp.load_model(examples / "double_wishbone.yaml")
    engine = kp.compile(model)
    names = ["camber", "point:upright.wheel_centre[z]", "LCA.q"]
    program = output_program(model, names, engine=engine)
    states = variants(engine, 4, seed=9)
    got = program.evaluate(states, ok=np.array([True, False, True, False]))
    assert np.isnan(got[[1, 3]]).all() and np.isfinite(got[[0, 2]]).all()
    single = evaluate_outputs(engine.model_of(states[2], model), names, units="solver", engine=engine)
    assert list(single.values()) == got[2].tolist()


def test_study_rows_match_the_oracle_at_their_solved_states(examples):
    """End to end: a study's point and metric columns (one compiled call per chunk) are the
    numpy outputs of the state each row records (its inputs and solved coordinates)."""
    from kinprop.analysis.study import Factor, run_study

    model = kp.load_model(examples / "double_wishbone.yaml")
    engine = kp.compile(model)
    frame = run_study(model, [Factor("UBJ.s_j[2]", 330.0, 340.0), Factor("TR.length", 380.0, 390.0)], samples=6,
                      seed=4, units="solver", compiled=engine, chunk_size=4)  # fmt: skip
    assert frame["converged"].all()
    columns = [c for c in frame.columns if c.startswith(("point:", "metric:"))]
    assert any(c.startswith("metric:") for c in columns)
    qcols = [c for c in frame.columns if ".q" in c]
    for _, row in frame.iterrows():
        st = engine.reference.copy()
        for a in ("UBJ.s_j[2]", "TR.length", *qcols):
            engine.set(st, a, row[a])
        ctx = OutputContext.of(engine.model_of(st, model), engine=engine)
        want = np.array([oracle.scalar(ctx, c) for c in columns])
        np.testing.assert_allclose(row[columns].to_numpy(float), want, rtol=1e-12, atol=1e-12)
