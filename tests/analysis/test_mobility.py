"""Mobility from the SVD rank versus the Gruebler-Kutzbach count, on every example."""

from __future__ import annotations

import numpy as np
import pytest
from linkages import EXAMPLES, load_solved

from kinprop import load_model
from kinprop.analysis.mobility import RANK_RTOL, gruebler, mobility, row_names
from kinprop.engine import compile as assembly_for

CASES = [
    # file, mobility, Gruebler, joints owning redundant rows
    ("slider_crank.yaml", 1, 1, []),
    ("mcpherson.yaml", 2, 2, []),
    ("fourbar.yaml", 1, 1, []),
    ("fourbar_double_rocker.yaml", 1, 1, []),
    ("fourbar_spatial.yaml", 1, -2, ["B"]),
    ("bennett.yaml", 1, -2, ["J4"]),
    ("stewart.yaml", 0, 0, []),
]


@pytest.mark.parametrize(("name", "dof", "grue", "redundant_joints"), CASES)
def test_mobility_of_examples(name, dof, grue, redundant_joints):
    rep = mobility(load_solved(name))
    assert rep.residual < 1e-10
    assert (rep.mobility, rep.gruebler) == (dof, grue)
    assert rep.redundant_joints == redundant_joints
    assert len(rep.redundant) == rep.n_constraints - rep.rank
    assert rep.overconstrained == (dof > grue)
    sv = np.array(rep.singular_values)
    if rep.rank < sv.size:  # a wide gap around the documented tolerance
        assert sv[rep.rank] < 1e-13 * sv[0] and sv[rep.rank - 1] > 1e-3 * sv[0]


def test_spatial_fourbar_redundant_rows_are_named():
    rep = mobility(load_solved("fourbar_spatial.yaml"))
    assert rep.n_constraints == 5 and rep.rank == 2
    assert len(rep.redundant) == 3 and all(r.startswith("B:") for r in rep.redundant)
    assert len(set(rep.redundant)) == 3  # the two dot-1 rows are told apart
    assert set(rep.dependent) <= set(row_names(assembly_for(load_model(EXAMPLES / "fourbar_spatial.yaml").mechanism)))


def test_bennett_redundancy_needs_the_assembled_configuration():
    """Off assembly a general 4R loop's Jacobian has full rank; the redundancy is Bennett's geometry."""
    rep = mobility(load_model(EXAMPLES / "bennett.yaml"))  # the file's rounded estimates
    assert rep.residual > 1e-6
    assert rep.mobility == 0 and rep.gruebler == -2
    assert mobility(load_solved("bennett.yaml")).mobility == 1


def test_stewart_legs_locked_and_free():
    m = load_solved("stewart.yaml")
    assert mobility(m).mobility == 0  # legs locked: lengths are design values, not free
    free = mobility(m, free=("q", "l"))
    assert free.mobility == 6 and free.n_coordinates == 13 and free.rank == 7
    assert gruebler(m) == 0


def test_tolerance_is_documented_default():
    rep = mobility(load_solved("fourbar.yaml"))
    assert rep.rtol == RANK_RTOL == 1e-9
