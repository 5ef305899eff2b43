"""Design changes by address: components, units at the CLI boundary."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from kinprop import load_model
from kinprop.cli import app
from kinprop.propagation import apply_changes


def test_several_components_of_one_variable(examples) -> None:
    m = load_model(examples / "fourbar.yaml")
    before = np.array(m.design["B.s_i"])
    changed, _, keys = apply_changes(m, {"B.s_i[0]": 0.41, "B.s_i[1]": 0.01})
    np.testing.assert_array_equal(changed.design["B.s_i"], [0.41, 0.01, before[2]])
    assert keys == {"B.s_i"}


def test_cli_set_coordinates_in_model_angle_unit(examples) -> None:
    """The four-bar file uses degrees: --set O2.q=30 means 30 degrees, and the JSON is in the
    model's units too (docs/units.md): 30 again, to the last bit of the deg -> rad -> deg trip."""
    r = CliRunner().invoke(app, ["propagate", str(examples / "fourbar.yaml"), "--set", "O2.q=30", "--json"])
    assert r.exit_code == 0, r.output
    obj = json.loads(r.stdout)
    assert obj["coordinates"]["O2"][0] == pytest.approx(30.0, rel=1e-15) and obj["units"]["coordinates"]["O2"] == [
        "deg"
    ]
    assert obj["coordinates"]["O2"][0] == np.degrees(np.radians(30))


def test_models_pickle_for_distributed_studies(examples) -> None:
    import pickle

    from kinprop import assemble, propagate

    m = assemble(load_model(examples / "mcpherson.yaml")).after
    m2 = pickle.loads(pickle.dumps(m))
    assert m2.mechanism == m.mechanism
    np.testing.assert_array_equal(m2.coordinates["ST"], m.coordinates["ST"])
    a = propagate(m, {"ST.s_i": [0.5, 1.0, 0.0]}, ("q",))
    b = propagate(m2, {"ST.s_i": [0.5, 1.0, 0.0]}, ("q",))
    np.testing.assert_array_equal(a.after.coordinates["ST"], b.after.coordinates["ST"])
