"""Named outputs: coordinates, design variables, named points, hardpoints, metrics."""

from __future__ import annotations

import numpy as np
import pytest

from kinprop import AddressError
from kinprop.analysis.outputs import evaluate_outputs, expand_outputs, output_names


def test_coordinates_and_design_variables(slider_crank):
    m = slider_crank
    out = evaluate_outputs(m, ["J01.q", "J32.q", "J32.q[1]", "J12.s_j", "J12.s_j[0]"])
    assert m.units["angle"] == "deg"  # outputs in the model's units; coordinates are stored in radians
    assert out["J01.q"] == pytest.approx(np.degrees(m.coordinates["J01"][0]), rel=1e-15)
    np.testing.assert_allclose([out["J32.q[0]"], out["J32.q[1]"]], np.degrees(m.coordinates["J32"]), rtol=1e-15)
    assert out["J12.s_j[0]"] == m.design["J12.s_j"][0] == -2.828
    solver = evaluate_outputs(m, ["J01.q", "J12.s_j[0]"], units="solver")
    assert solver["J01.q"] == m.coordinates["J01"][0] and solver["J12.s_j[0]"] == -2.828
    # vector names expand into components; a repeated name is one key
    assert set(out) == {"J01.q", "J32.q[0]", "J32.q[1]", "J12.s_j[0]", "J12.s_j[1]", "J12.s_j[2]"}


def test_hardpoints_closed_form(slider_crank):
    m = slider_crank
    out = evaluate_outputs(m, ["hardpoint:J12.i", "hardpoint:J12.j", "hardpoint:J01.j", "hardpoint:J03.i"])
    tip = np.array([out[f"hardpoint:J12.i[{c}]"] for c in "xyz"])
    # the crank turns about global x: its tip is 2 * (0, cos q1, sin q1)
    q1 = m.coordinates["J01"][0]
    np.testing.assert_allclose(tip, 2.0 * np.array([0.0, np.cos(q1), np.sin(q1)]), atol=1e-12)
    # the cut spherical joint is closed: both frame origins coincide
    np.testing.assert_allclose(tip, [out[f"hardpoint:J12.j[{c}]"] for c in "xyz"], atol=1e-10)
    assert [out[f"hardpoint:J01.j[{c}]"] for c in "xyz"] == pytest.approx([0.0, 0.0, 0.0], abs=1e-15)
    assert [out[f"hardpoint:J03.i[{c}]"] for c in "xyz"] == pytest.approx([0.0, 3.8637, 0.0])


def test_named_point_is_body_frame(slider_crank):
    from kinprop.engine import compile as assembly_for

    m = slider_crank
    kin = assembly_for(m.mechanism).kinematics(m.design, m.coordinates)
    expect = kin.r["rod"] + kin.A["rod"] @ np.array([-1.414, 0.1, 0.05])
    out = evaluate_outputs(m, ["point:rod.mid", "point:rod.mid[z]"])
    np.testing.assert_allclose([out[f"point:rod.mid[{c}]"] for c in "xyz"], expect, atol=1e-14)
    assert out["point:rod.mid[z]"] == out["point:rod.mid[z]"]


def test_double_wishbone_points_and_hardpoints(double_wishbone):
    m = double_wishbone
    names = ["point:upright.kingpin_upper", "hardpoint:UBJ.i", "hardpoint:UBJ.j", "point:upright.wheel_centre"]
    out = evaluate_outputs(m, names)
    ubj = [out[f"hardpoint:UBJ.j[{c}]"] for c in "xyz"]
    np.testing.assert_allclose(ubj, [out[f"hardpoint:UBJ.i[{c}]"] for c in "xyz"], atol=1e-8)
    np.testing.assert_allclose(ubj, [out[f"point:upright.kingpin_upper[{c}]"] for c in "xyz"], atol=1e-12)
    # the file is the published hardpoints: assembled, the wheel centre is where Chrono puts it
    wc = [out[f"point:upright.wheel_centre[{c}]"] for c in "xyz"]
    np.testing.assert_allclose(wc, [-40.386, 909.701, -26.289], atol=1e-3)


def test_output_names_lists_every_kind_and_all_evaluate(double_wishbone):
    names = output_names(double_wishbone)
    for expected in (
        "LCA.q",
        "LBJ.q[3]",
        "TR.length",
        "UCA.s_i[2]",
        "point:upright.wheel_centre[y]",
        "hardpoint:TR.i[x]",
        "metric:upright.camber",
        "metric:upright.wheel_centre_dz",
    ):
        assert expected in names
    assert not any(".C_i" in n for n in names)
    values = evaluate_outputs(double_wishbone, names)
    assert list(values) == names and all(np.isfinite(list(values.values())))


def test_expand(mcpherson):
    assert expand_outputs(mcpherson, ["ST.q"]) == [f"ST.q[{k}]" for k in range(5)]
    assert expand_outputs(mcpherson, ["TD.q", "RS.length", "camber"]) == ["TD.q", "RS.length", "camber"]


@pytest.mark.parametrize(
    "name, fragment",
    [
        ("J99.q", "not a variable"),
        ("J01.C_i", "orientations"),
        ("J32.q[5]", "out of range"),
        ("point:rod.nowhere", "no named point"),
        ("point:nobody.mid[x]", "unknown body"),
        ("hardpoint:J99.i[x]", "unknown joint"),
        ("hardpoint:J12.k", "bad output"),
        ("camber", "exactly one wheel"),
        ("metric:rod.camber", "not a wheel body"),
        ("bogus name", "not a variable"),
        ("J01.bogus", "bad output"),
    ],
)
def test_bad_names_raise_address_error(slider_crank, name, fragment):
    with pytest.raises(AddressError, match=fragment):
        evaluate_outputs(slider_crank, [name])
    with pytest.raises(KeyError):  # AddressError is a KeyError too
        evaluate_outputs(slider_crank, [name])
