"""``Engine.solve_batch``: a leading batch axis through the one loop, serial and threaded.

Truth: the Stewart platform's leg lengths by closed-form inverse kinematics
(``|x + R b_k - a_k|``), and the single-variant ``Engine.solve`` of each variant.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import kinprop as kp
from kinprop.engine import State
from kinprop.solver.newton import FROM_ESTIMATES
from kinprop.spatial import euler_to_matrix

STEWART = Path(__file__).parents[2] / "examples" / "stewart.yaml"
LEGS = [f"L{k}" for k in range(1, 7)]


@pytest.fixture(scope="module")
def stewart():
    model = kp.assemble(kp.load_model(STEWART)).after
    return kp.compile(model)


def leg_lengths(eng, Q):
    """Closed-form inverse kinematics of the platform pose in ``Q`` (batch)."""
    col = eng.target("P.q").start
    x, R = Q[:, col : col + 3], euler_to_matrix(Q[:, col + 3 : col + 7])
    lidx = [eng.joint_index[j] for j in LEGS]
    a, b = eng.reference.S[lidx, 0], eng.reference.S[lidx, 1]
    return np.linalg.norm(x[:, None, :] + np.einsum("nij,kj->nki", R, b) - a, axis=-1)


def variants(eng, n, seed=0, scale=3e-3):
    rng = np.random.default_rng(seed)
    lidx = [eng.joint_index[j] for j in LEGS]
    batch = eng.stack([eng.reference] * n)
    batch.L[:, lidx] += rng.uniform(-scale, scale, (n, 6))
    return batch, batch.L[:, lidx].copy()


@pytest.mark.parametrize("threads", [False, True])
def test_every_variant_reaches_its_own_leg_lengths(stewart, threads):
    batch, lengths = variants(stewart, 300)
    res = stewart.solve_batch(batch, ("q",), exclude=[f"{j}.length" for j in LEGS], threads=threads)
    assert res.converged.all()
    assert np.abs(leg_lengths(stewart, res.state.Q) - lengths).max() < 1e-13
    # the input is not touched: the start of every variant stays the reference
    np.testing.assert_array_equal(batch.Q, np.broadcast_to(stewart.reference.Q, batch.Q.shape))
    # exact derivative of the free joint: quadratic convergence, 2-3 iterations for +-3 mm
    assert res.iterations.max() <= 3


def test_threads_serial_and_single_solves_agree(stewart):
    batch, _ = variants(stewart, 64, seed=1)
    exclude = [f"{j}.length" for j in LEGS]
    serial = stewart.solve_batch(batch, ("q",), exclude=exclude, threads=False)
    threaded = stewart.solve_batch(batch, ("q",), exclude=exclude, threads=True)
    np.testing.assert_array_equal(serial.state.Q, threaded.state.Q)
    np.testing.assert_array_equal(serial.iterations, threaded.iterations)
    for v in (0, 17, 63):
        one = stewart.solve(stewart.reference, ("q",), target=batch[v], exclude=exclude)
        np.testing.assert_allclose(one.state.Q, serial.state.Q[v], atol=1e-15)


def test_a_start_per_variant(stewart):
    """A start with the batch axis: each variant from its own start (assembled or not)."""
    batch, lengths = variants(stewart, 8, seed=2)
    starts = stewart.stack([stewart.reference] * 8)
    starts.Q[4:, 2] += 0.01  # the last four start from estimates (platform 10 mm too high)
    res = stewart.solve_batch(batch, ("q",), start=starts, exclude=[f"{j}.length" for j in LEGS])
    assert res.converged.all()
    assert np.abs(leg_lengths(stewart, res.state.Q) - lengths).max() < 1e-13
    assert [bool(f & FROM_ESTIMATES) for f in res.flags] == [False] * 4 + [True] * 4
    assert isinstance(res.state, State) and res.state.Q.shape == batch.Q.shape
