"""Continuation for large design changes: same branch as Freudenstein; infeasible changes diagnosed."""

from __future__ import annotations

import numpy as np
import pytest
from linkages import CRANK_ROCKER, EXAMPLES, freudenstein, load_solved, set_crank, wrap
from typer.testing import CliRunner

from kinprop import ConvergenceError, Status, load_model, propagate
from kinprop.cli import app
from kinprop.propagation.continuation import propagate_continuation
from kinprop.spatial import exp_so3

FREE = ("A.q", "O4.q")  # the crank O2 is the input: it stays where it is


@pytest.fixture(scope="module")
def at150():
    return set_crank(load_solved("fourbar.yaml"), 150.0)


@pytest.fixture(scope="module")
def at60():
    return set_crank(load_solved("fourbar.yaml"), 60.0)


def test_large_change_plain_newton_switches_branch_the_default_does_not(at150):
    a, b, c, d = CRANK_ROCKER
    change = {"B.s_i[0]": 2.0 * b}  # coupler doubled
    t2 = at150.coordinates["O2"][0]
    exact = freudenstein(a, 2.0 * b, c, d, t2)  # the open branch the model is on
    other = freudenstein(a, 2.0 * b, c, d, t2, branch=+1)
    plain = propagate(at150, change, FREE, branch=False)  # the paper's plain Newton
    assert plain.converged  # ... but silently on the crossed branch
    assert abs(wrap(plain.after.coordinates["O4"][0] - other)) < 1e-8
    assert abs(np.degrees(wrap(plain.after.coordinates["O4"][0] - exact))) > 30
    default = propagate(at150, change, FREE, tol=1e-13)  # follows the change on the start's branch
    assert default.converged and abs(np.degrees(wrap(default.after.coordinates["O4"][0] - exact))) < 1e-8
    res = propagate_continuation(at150, change, FREE, tol=1e-13)
    assert res.converged and res.fraction == 1.0, res.message
    assert abs(np.degrees(wrap(res.after.coordinates["O4"][0] - exact))) < 1e-8
    assert res.after.coordinates["O2"][0] == t2
    assert res.propagation.before is at150 and res.propagation.changes["B.s_i"][0] == 2.0 * b
    assert res.substeps >= 2


def test_thirty_percent_changes_of_every_link_stay_on_branch(at60):
    a, b, c, d = CRANK_ROCKER
    t2 = at60.coordinates["O2"][0]
    for key, lengths in (
        ("A.s_i[0]", (1.3 * a, b, c, d)),
        ("B.s_i[0]", (a, 1.3 * b, c, d)),
        ("B.s_j[0]", (a, b, 1.3 * c, d)),
        ("O4.s_i[0]", (a, b, c, 1.3 * d)),
    ):
        res = propagate_continuation(at60, {key: 1.3 * at60.design[key.split("[")[0]][0]}, FREE, tol=1e-13)
        assert res.converged
        assert abs(np.degrees(wrap(res.after.coordinates["O4"][0] - freudenstein(*lengths, t2)))) < 1e-8


def test_impossible_change_is_diagnosed(at60):
    """Coupler shortened to 0.03 m: at theta2 = 60 deg |A O4| = 0.35 m, so the loop closes only
    while b >= |A O4| - c = 0.05 m, i.e. up to (0.40 - 0.05) / (0.40 - 0.03) of the change."""
    a, b, c, d = CRANK_ROCKER
    A = a * np.array([np.cos(np.radians(60)), np.sin(np.radians(60))])
    b_min = np.hypot(*(np.array([d, 0.0]) - A)) - c
    t_exact = (b - b_min) / (b - 0.03)
    res = propagate_continuation(at60, {"B.s_i[0]": 0.03}, FREE)
    assert not res.converged and res.status is Status.INFEASIBLE
    assert abs(res.fraction - t_exact) < 1e-3
    assert res.fraction <= t_exact + 1e-6  # never past the limit
    assert res.conflict_joints == ["B"]
    assert res.conflict and res.conflict[0][0].startswith("B:")
    assert "cannot be assembled beyond" in res.message
    # the last feasible state is a true assembly of the partial change
    assert res.propagation.converged and res.propagation.result.residual_norm < 1e-10
    assert res.propagation.changes["B.s_i"][0] == pytest.approx(b + res.fraction * (0.03 - b))
    assert res.singularity_ratio < 1e-2  # at the fold: coupler and rocker collinear
    with pytest.raises(ConvergenceError):
        res.raise_for_status()


def test_no_change_and_unassembled_start():
    m = load_solved("fourbar.yaml")
    same = propagate_continuation(m, {}, FREE)
    assert same.converged and same.after.coordinates["O4"][0] == m.coordinates["O4"][0]
    stuck = propagate_continuation(load_model(EXAMPLES / "fourbar.yaml"), {"B.s_i[0]": 0.5}, FREE, max_iter=1)
    assert not stuck.converged and stuck.fraction == 0.0 and "does not assemble before the change" in stuck.message


def test_spatial_fourbar_conflict_named_by_cut_joint():
    m = set_crank(load_solved("fourbar_spatial.yaml"), 60.0)
    res = propagate_continuation(m, {"B.s_i[0]": 0.03}, FREE)
    assert not res.converged and res.conflict_joints == ["B"]
    assert abs(res.fraction - 0.35 / 0.37) < 2e-3


def test_orientation_change_matches_plain_newton():
    """A C (orientation) change goes along exp(t log(C1 C0^T)) C0 and ends where Newton does:
    the slider-crank's crank axis tilted by 3 deg."""
    m = load_solved("slider_crank.yaml")
    C0 = m.design["J01.C_i"]
    C1 = exp_so3(np.radians(3.0) * np.array([0.0, 0.6, 0.8])) @ C0
    free = ("J03.q", "J32.q")  # crank angle held: a unique answer (mobility 1)
    plain = propagate(m, {"J01.C_i": C1}, free, tol=1e-12)
    res = propagate_continuation(m, {"J01.C_i": C1}, free, tol=1e-12)
    assert plain.converged and res.converged
    for j, q in plain.after.coordinates.items():
        assert np.allclose(res.after.coordinates[j], q, atol=1e-10)
    assert np.allclose(res.after.design["J01.C_i"], C1, atol=1e-14)


def test_cli_propagate_continuation_and_fallback():
    runner = CliRunner()
    model = str(EXAMPLES / "fourbar.yaml")
    ok = runner.invoke(
        app, ["propagate", model, "--set", "B.s_i[0]=0.52", "--free", "A.q", "--free", "O4.q", "--continuation"]
    )
    assert ok.exit_code == 0, ok.output
    assert "continuation:" in ok.output
    bad = runner.invoke(app, ["propagate", model, "--set", "B.s_i[0]=0.03", "--free", "A.q", "--free", "O4.q"])
    assert bad.exit_code == 1
    assert "cannot be assembled beyond" in bad.output and "B:dot2" in bad.output
    off = runner.invoke(app, ["propagate", model, "--set", "B.s_i[0]=0.03", "--free", "A.q", "--no-continuation"])
    assert off.exit_code == 1 and "continuation" not in off.output
