"""Four-bar examples against Freudenstein's equation; the double rocker's input limit; toggle warning."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from linkages import CRANK_ROCKER, DOUBLE_ROCKER, freudenstein, input_limit, load_solved, wrap

from kinprop import SingularityWarning, load_model, propagate
from kinprop.analysis.sweep import sweep


def test_crank_rocker_full_crank_sweep_matches_freudenstein(examples):
    res = sweep(load_model(examples / "fourbar.yaml"), ["O2=0:360:360"], outputs=[], tol=1e-13)
    df = res.frame
    assert res.ok and len(df) == 361
    t2, t4 = np.radians(df["O2.q"]), np.radians(df["O4.q"])
    err4 = np.abs(wrap(t4 - freudenstein(*CRANK_ROCKER, t2)))
    assert np.degrees(err4.max()) < 1e-8  # measured ~1e-12 deg
    # coupler angle theta3 = theta2 + A.q closes the loop: B from the crank side = B from the rocker side
    a, b, c, d = CRANK_ROCKER
    t3 = t2 + np.radians(df["A.q"])
    gap = np.hypot(
        a * np.cos(t2) + b * np.cos(t3) - d - c * np.cos(t4), a * np.sin(t2) + b * np.sin(t3) - c * np.sin(t4)
    )
    assert gap.max() < 1e-10
    # the crank turns fully and comes back to the same pose (same branch all the way)
    assert abs(wrap(t4.iloc[-1] - t4.iloc[0])) < 1e-10


def test_double_rocker_fails_past_its_input_limit(examples):
    limit = np.degrees(input_limit(*DOUBLE_ROCKER))  # 137.87 deg
    res = sweep(
        load_model(examples / "fourbar_double_rocker.yaml"), ["O2=100:170:70"], outputs=[], max_iter=15, tol=1e-13
    )
    df = res.frame
    ok = df["status"] == "converged"
    assert ok[df["O2.q"] < limit].all()
    assert not ok[df["O2.q"] > limit].any()  # recorded failures, the sweep went on to the end
    assert len(df) == 71 and res.n_failed == int((df["O2.q"] > limit).sum())
    last = df.loc[ok, "O2.q"].max()
    assert limit - 1.0 < last < limit
    t2 = np.radians(df.loc[ok, "O2.q"])
    err = np.abs(wrap(np.radians(df.loc[ok, "O4.q"]) - freudenstein(*DOUBLE_ROCKER, t2)))
    assert np.degrees(err.max()) < 1e-8
    # each failure says how far the step could be followed on the branch (the toggle), never a pose
    assert df.loc[~ok, "message"].str.contains("followed on the start's branch only to|not converged").all()
    assert df.loc[~ok, "O4.q"].isna().all()


def test_singularity_warning_near_toggle(examples):
    """Rocker driven to within 0.01 deg of its extreme (crank and coupler collinear): the
    crank's free-variable Jacobian is near singular; 10 deg away it is not."""
    m = load_solved("fourbar.yaml")
    a, b, c, d = CRANK_ROCKER
    t4min = np.arccos(((a + b) ** 2 - d * d - c * c) / (2 * d * c))  # 77.36 deg
    with pytest.warns(SingularityWarning, match="near-singular"):
        near = propagate(m, {"O4.q": [np.degrees(t4min) + 0.01]}, ("O2.q", "A.q"))  # degrees: the model's unit
    assert near.converged and near.singularity_ratio < 1e-2
    with warnings.catch_warnings():
        warnings.simplefilter("error", SingularityWarning)
        far = propagate(m, {"O4.q": [np.degrees(t4min) + 10.0]}, ("O2.q", "A.q"))
    assert far.converged


def test_spatial_fourbar_follows_the_planar_one(examples):
    """The tilted spatial-revolute model has the same input-output relation."""
    res = sweep(load_model(examples / "fourbar_spatial.yaml"), ["O2=0:360:36"], outputs=[], tol=1e-13)
    assert res.ok
    df = res.frame
    err = wrap(np.radians(df["O4.q"]) - freudenstein(*CRANK_ROCKER, np.radians(df["O2.q"])))
    assert np.degrees(np.abs(err).max()) < 1e-8


def test_singularity_measure_is_unit_independent():
    """The same four-bar in millimetres (every length x 1000) has the same measure; unscaled
    singular values would differ (distance-like rows grow, angle columns do not)."""
    m = load_solved("fourbar.yaml")
    mm = m.with_state(m.design.replace({k: 1000.0 * v for k, v in m.design.items()}), m.coordinates)
    a = propagate(m, {"O2.q": [1.0]}, ("A.q", "O4.q"), tol=1e-12, units="solver")  # 1 rad
    b = propagate(mm, {"O2.q": [1.0]}, ("A.q", "O4.q"), tol=1e-9, units="solver")
    assert a.converged and b.converged
    assert b.singularity_ratio == pytest.approx(a.singularity_ratio, rel=1e-6)
    assert 0.1 < a.singularity_ratio < 1.0
