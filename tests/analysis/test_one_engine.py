"""Compile once at the boundary, and one address grammar on every surface (issue 24 items 3-4).

Compilations are counted by wrapping ``Engine.__init__``: a public call compiles its model
once, whatever the number of variants, steps or outputs. Global hardpoint addresses are
checked against re-solved models: the derivative of ``toe`` with respect to the tie-rod's
global z position is the central difference of two propagations that move that hardpoint.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from analysis_helpers import EXAMPLES
from typer.testing import CliRunner

import kinprop as kp
import kinprop.engine.engine as engine_module
from kinprop.analysis.study import run_study
from kinprop.analysis.tolerance import monte_carlo, tolerance_analysis
from kinprop.cli import app


@pytest.fixture
def compiles(monkeypatch):
    """The number of engines built (``kp.compile``) since the fixture was taken."""
    count = [0]
    init = engine_module.Engine.__init__

    def counted(self, *args, **kwargs):
        count[0] += 1
        init(self, *args, **kwargs)

    monkeypatch.setattr(engine_module.Engine, "__init__", counted)
    return count


@pytest.mark.parametrize("n", [4, 24])
def test_a_study_compiles_once_whatever_its_size(double_wishbone, compiles, n):
    plan = 0.05 * np.arange(n)[:, None] + double_wishbone.design["TR.s_i"][2]
    df = run_study(double_wishbone, plan=plan, addresses=["TR.s_i[2]"], outputs=["toe"], units="solver")
    assert len(df) == n and df["converged"].all()
    assert compiles[0] == 1


@pytest.mark.parametrize("steps", [3, 18])
def test_a_sweep_compiles_once_whatever_its_length(compiles, steps):
    res = kp.sweep(kp.load_model(EXAMPLES / "fourbar.yaml"), [f"O2=60:90:{steps}"])
    assert res.ok and res.n_steps == steps + 1
    assert compiles[0] == 1


def test_a_travel_sweep_compiles_once(compiles):
    """``kinprop sweep FILE --drive travel=-50:50:5`` (five engines before: the model three times
    more for its wheel points, and the model with the travel joint): one engine, the model with
    its travel joint, whose drive joint follows the wheel when the outputs' motions and statics
    are evaluated, so the rows equal those of the model's own engine."""
    path = EXAMPLES / "double_wishbone_hardpoints.yaml"
    outs = ["camber", "toe", "camber_gain", "anti_dive", "motion_ratio:spring", "force:spring"]
    res = kp.sweep(kp.load_model(path), ["travel=-50:50:5"], outputs=outs)
    assert res.ok and compiles[0] == 1
    compiles[0] = 0
    args = ["sweep", str(path), "--drive", "travel=-50:50:5", "--json"] + [a for o in outs for a in ("--out", o)]
    cli = CliRunner().invoke(app, args)
    assert cli.exit_code == 0, cli.output
    assert compiles[0] == 1
    # each row against the model's own engine at that step's pose (outputs of the base mechanism)
    for k, row in res.frame.iterrows():
        at = kp.propagate(kp.load_model(path), {"LCA.q": row["LCA.q"]}, tol=1e-12).after
        got = kp.evaluate_outputs(at, outs)
        for o in outs:
            assert row[o] == pytest.approx(got[o], rel=1e-8, abs=1e-9), (k, o)


def test_sensitivity_tolerance_monte_carlo_targets_compile_once(double_wishbone, compiles):
    m = double_wishbone
    for run in (
        lambda: kp.output_sensitivity(m, ["toe", "camber"], ["TR.s_i", "hardpoint:UBJ.i"]),
        lambda: kp.design_sensitivity(m, ["TR.s_i"]),
        lambda: tolerance_analysis(m, {"TR.s_i[2]": 0.5, "hardpoint:UBJ.i[z]": 0.2}, ["toe", "camber"]),
        lambda: monte_carlo(m, {"TR.s_i[2]": 0.5}, ["toe"], n=40),
        lambda: kp.propagate_continuation(m, {"TR.s_i[2]": m.design["TR.s_i"][2] + 5.0}),
    ):
        compiles[0] = 0
        run()
        assert compiles[0] == 1
    compiles[0] = 0
    kp.propagate_targets(m, ["toe=0.1"], ["TR.s_i"])
    assert compiles[0] == 2  # the model, and the point-Jacobian probe (another mechanism: a joint more)


def _toe_after_moving(m, dz: float) -> float:
    p = kp.propagate(m, {"hardpoint:TR.i": m_hardpoint(m) + [0.0, 0.0, dz]}, tol=1e-12)
    assert p.converged
    return kp.evaluate_outputs(p.after, ["toe"])["toe"]


def m_hardpoint(m) -> np.ndarray:
    from kinprop.analysis.points import joint_hardpoints

    return np.array(joint_hardpoints(m)["TR.i"])


def test_output_sensitivity_takes_global_hardpoints(double_wishbone):
    """``kp.output_sensitivity(m, ["toe"], ["hardpoint:TR.i"])`` (refused before): per global mm,
    equal to a central difference of re-solved models."""
    m = double_wishbone
    d = kp.output_sensitivity(m, ["toe"], ["hardpoint:TR.i"])
    assert list(d.columns) == ["hardpoint:TR.i[x]", "hardpoint:TR.i[y]", "hardpoint:TR.i[z]"]
    h = 1e-3  # mm
    fd = (_toe_after_moving(m, h) - _toe_after_moving(m, -h)) / (2 * h)
    assert d.loc["toe", "hardpoint:TR.i[z]"] == pytest.approx(fd, rel=1e-6)
    cli = CliRunner().invoke(
        app, ["sensitivity", str(EXAMPLES / "double_wishbone.yaml"), "--of", "toe", "--wrt", "hardpoint:TR.i", "--json"]
    )
    assert cli.exit_code == 0, cli.output
    obj = json.loads(cli.stdout)
    assert obj["wrt"] == list(d.columns)
    np.testing.assert_allclose(obj["matrix"][0], d.loc["toe"].to_numpy(), rtol=1e-6, atol=1e-12)


def test_tolerance_takes_a_global_hardpoint_component(double_wishbone):
    """``kinprop tolerance --tolerance hardpoint:TR.i[z]=0.5`` (refused before): the linearised
    std of toe is |d toe / d z| 0.5, the derivative from re-solved models."""
    m = double_wishbone
    res = tolerance_analysis(m, {"hardpoint:TR.i[z]": 0.5}, ["toe"])
    h = 1e-3
    fd = (_toe_after_moving(m, h) - _toe_after_moving(m, -h)) / (2 * h)
    assert res.inputs == ["hardpoint:TR.i[z]"] and res.input_units == ("mm",)
    assert res.std[0] == pytest.approx(abs(fd) * 0.5, rel=1e-6)
    path = EXAMPLES / "double_wishbone.yaml"
    cli = CliRunner().invoke(
        app, ["tolerance", str(path), "--of", "toe", "--tolerance", "hardpoint:TR.i[z]=0.5", "--json"]
    )
    assert cli.exit_code == 0, cli.output
    assert json.loads(cli.stdout)["inputs"] == ["hardpoint:TR.i[z]"]


def test_continuation_takes_a_global_hardpoint(double_wishbone):
    """``kp.propagate_continuation(m, {"hardpoint:TR.i": p})`` (refused before) moves the joint
    to ``p`` and lands where the propagation does."""
    m = double_wishbone
    target = m_hardpoint(m) + [2.0, -1.0, 4.0]
    res = kp.propagate_continuation(m, {"hardpoint:TR.i": target}, tol=1e-12)
    plain = kp.propagate(m, {"hardpoint:TR.i": target}, tol=1e-12)
    assert res.converged and res.fraction == 1.0 and res.status is kp.Status.CONVERGED
    np.testing.assert_allclose(m_hardpoint(res.after), target, atol=1e-9)
    for j, q in plain.after.coordinates.items():
        np.testing.assert_allclose(res.after.coordinates[j], q, atol=1e-10)
