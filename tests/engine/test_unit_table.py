"""Units in one place (issue 24, item 4): one module owns the factors and the conversions
(:mod:`kinprop.engine.units`), and which coordinate components are angles is resolved once per
compiled engine, not per conversion."""

from __future__ import annotations

import math

import numpy as np
import pytest

import kinprop as kp
import kinprop.engine.units as units
from kinprop.analysis.targets import parse_target
from kinprop.engine.units import METRES_PER, RADIANS_PER, UnitTable, address_unit, from_solver_units, to_solver_units


def test_factors_are_the_definitions():
    # SI definitions: 1 in = 25.4 mm exactly (1959 international yard and pound), 1 deg = pi/180 rad
    assert METRES_PER["mm"] * 1000 == METRES_PER["m"] == 1.0
    assert METRES_PER["in"] == pytest.approx(25.4e-3, rel=1e-15)
    assert RADIANS_PER["deg"] * 180 == pytest.approx(math.pi, rel=1e-15)


def test_target_values_use_the_same_factors(examples):
    mm = kp.load_model(examples / "double_wishbone.yaml")  # mm, deg
    assert parse_target(mm, "hardpoint:UBJ.j[x]=2in").value == pytest.approx(50.8, rel=1e-12)
    assert parse_target(mm, "hardpoint:UBJ.j[x]=5cm").value == pytest.approx(50.0, rel=1e-12)
    assert parse_target(mm, "LCA.q=0.1rad").value == pytest.approx(0.1, rel=1e-12)  # coordinates: radians inside
    assert parse_target(mm, "camber=0.01rad").value == pytest.approx(math.degrees(0.01), rel=1e-12)  # degrees inside


def test_the_angle_table_is_resolved_once_per_engine(examples, monkeypatch):
    model = kp.load_model(examples / "fourbar.yaml")  # deg; B is the cut joint
    eng = kp.compile(model)
    table = eng.unit_table
    assert table == UnitTable.of(model.mechanism)
    assert table.angles["O2"] == (0,) and table.angles["B"] == ()  # a cut joint's coordinates are not angles
    calls = []
    monkeypatch.setattr(units, "build_topology", lambda m: calls.append(m))  # would fail if called
    for _ in range(3):
        q = to_solver_units(model, "O2.q", [70.0], eng)
        assert float(q[0]) == pytest.approx(math.radians(70.0), rel=1e-15)
        assert float(from_solver_units(model, "O2.q", q, eng)[0]) == pytest.approx(70.0, rel=1e-15)
        assert address_unit(model, "O2.q", eng) == "deg" and address_unit(model, "B.s_i[0]", eng) == "m"
    assert calls == []
    np.testing.assert_array_equal(to_solver_units(model, "B.s_i", [0.4, 0, 0], eng), [0.4, 0, 0])


def test_without_an_engine_the_table_is_resolved_once_per_mechanism(examples, monkeypatch):
    model = kp.load_model(examples / "fourbar.yaml")
    calls = []
    real = units.build_topology
    monkeypatch.setattr(units, "build_topology", lambda m: calls.append(m) or real(m))
    units._TABLES.clear()
    for _ in range(3):
        assert float(from_solver_units(model, "O2.q", [math.pi / 2])[0]) == pytest.approx(90.0, rel=1e-15)
    assert len(calls) == 1
