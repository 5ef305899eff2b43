"""``Engine.apply``: changes by address, one-number changes checked and written together.

Truth: the same changes written one by one with ``Engine.set`` (the rules: finite, within the
length bound, lengths positive, rotations proper), and the order of the changes.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import kinprop as kp
from kinprop import AddressError

EXAMPLES = Path(__file__).parents[2] / "examples"


@pytest.fixture(scope="module")
def stewart():
    return kp.compile(kp.load_model(EXAMPLES / "stewart.yaml"))


def one_by_one(eng, changes):
    st = eng.reference.copy()
    for address, value in changes.items():
        eng.set(st, address, value)
    return st


def test_many_numbers_equal_set_one_by_one(stewart):
    changes = {"L1.length": 0.52, "L2.s_i[1]": 0.09, "P.q[2]": 0.41, "L3.s_j": [0.1, 0.28, 0.0],
               "L4.length": np.float64(0.51), "L5.s_j[0]": -0.3}  # fmt: skip
    st, done, keys = stewart.apply(stewart.reference, changes)
    ref = one_by_one(stewart, changes)
    for a in "QSCL":
        np.testing.assert_array_equal(getattr(st, a), getattr(ref, a))
    assert list(done) == list(changes)  # in the order given
    assert keys == {"L1.length", "L2.s_i", "P.q", "L3.s_j", "L4.length", "L5.s_j"}
    assert done["L1.length"].shape == () and float(done["L1.length"]) == 0.52
    # the start is not touched
    assert stewart.reference.L[stewart.joint_index["L1"]] != 0.52


def test_changes_apply_in_their_order(stewart):
    """A component then the whole vector (and the other way round): the last one wins."""
    st, _, _ = stewart.apply(stewart.reference, {"L2.s_i[1]": 0.5, "L2.s_i": [1.0, 2.0, 3.0]})
    np.testing.assert_array_equal(st.S[stewart.joint_index["L2"], 0], [1.0, 2.0, 3.0])
    st, _, _ = stewart.apply(stewart.reference, {"L2.s_i": [1.0, 2.0, 3.0], "L2.s_i[1]": 0.5})
    np.testing.assert_array_equal(st.S[stewart.joint_index["L2"], 0], [1.0, 0.5, 3.0])


@pytest.mark.parametrize(
    ("bad", "message"),
    [
        ({"L2.length": float("nan")}, "'L2.length': value must be finite"),
        ({"L2.length": -0.1}, "'L2.length': a length must be positive"),
        ({"L2.s_i[0]": 1e9}, "'L2.s_i[0]': 1e+09 is beyond"),
        ({"P.q[0]": float("inf")}, "'P.q[0]': value must be finite"),
    ],
)
def test_a_bad_number_among_many_is_named(stewart, bad, message):
    changes = {f"L{k}.length": 0.52 for k in (1, 3, 4, 5, 6)} | bad
    with pytest.raises(AddressError, match=re.escape(message)):
        stewart.apply(stewart.reference, changes)
