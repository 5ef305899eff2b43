"""A suspension's hardpoints in the usual order (issue 20, item 7): `kinprop check` lists the
file's own points, grouped as a designer reads them (chassis pickups, upright points,
steering, spring/damper, wheel)."""

from __future__ import annotations

import json

import numpy as np
import pytest
import yaml
from analysis_helpers import EXAMPLES
from typer.testing import CliRunner

from kinprop import load_model
from kinprop.analysis.points import HARDPOINT_GROUPS, hardpoint_table
from kinprop.cli import app
from kinprop.engine import compile as compile_engine
from kinprop.propagation.hardpoints import current_point


def test_the_corner_lists_its_file_points_in_the_usual_order():
    data = yaml.safe_load((EXAMPLES / "double_wishbone_hardpoints.yaml").read_text())
    j, e, up = data["joints"], data["elements"], data["bodies"]["upright"]["points"]
    expected = [
        ("chassis pickups", "LCA front", j["LCA"]["pivots"]["front"]),
        ("chassis pickups", "LCA rear", j["LCA"]["pivots"]["rear"]),
        ("chassis pickups", "UCA front", j["UCA"]["pivots"]["front"]),
        ("chassis pickups", "UCA rear", j["UCA"]["pivots"]["rear"]),
        ("upright points", "LBJ", j["LBJ"]["point"]),
        ("upright points", "UBJ", j["UBJ"]["point"]),
        ("steering", "TR inner", j["TR"]["point_i"]),
        ("steering", "TR outer", j["TR"]["point_j"]),
        ("spring/damper", "spring i", e["spring"]["point_i"]),
        ("spring/damper", "spring j", e["spring"]["point_j"]),
        ("spring/damper", "shock i", e["shock"]["point_i"]),
        ("spring/damper", "shock j", e["shock"]["point_j"]),
        ("wheel", "wheel_centre", up["wheel_centre"]),
        ("wheel", "spin_axis", up["spin_axis"]),
        ("wheel", "contact_patch", up["contact_patch"]),
    ]
    rows = hardpoint_table(load_model(EXAMPLES / "double_wishbone_hardpoints.yaml"))
    assert [(r["group"], r["point"]) for r in rows] == [(g, n) for g, n, _ in expected]
    for r, (_, _, p) in zip(rows, expected, strict=True):
        assert [r["x"], r["y"], r["z"]] == pytest.approx(p, abs=1e-9), r["point"]


def test_an_axle_lists_the_rack_and_both_sides_mirrored_and_check_prints_the_table():
    rows = hardpoint_table(load_model(EXAMPLES / "hmmwv_front_axle.yaml"))
    groups = [r["group"] for r in rows]
    assert groups == sorted(groups, key=HARDPOINT_GROUPS.index)
    by = {r["point"]: r for r in rows}
    assert by["RACK"]["group"] == "steering"
    for left, right in (("LCA_L front", "LCA_R front"), ("TR_L inner", "TR_R inner"), ("UBJ_L", "UBJ_R")):
        assert by[right]["y"] == pytest.approx(-by[left]["y"]) and by[right]["z"] == pytest.approx(by[left]["z"])
    r = CliRunner().invoke(app, ["check", str(EXAMPLES / "double_wishbone_hardpoints.yaml"), "--json"])
    assert r.exit_code == 0
    assert json.loads(r.stdout)["hardpoints"][0] == {"group": "chassis pickups", "point": "LCA front",
                                                     "x": 223.266, "y": 307.086, "z": 0.0,
                                                     "address": "hardpoint:LCA.front", "body": "chassis"}  # fmt: skip
    r = CliRunner().invoke(app, ["check", str(EXAMPLES / "double_wishbone_hardpoints.yaml")])
    assert "hardpoints (global, mm)" in r.stdout and "TR inner" in r.stdout
    r = CliRunner().invoke(app, ["check", str(EXAMPLES / "fourbar.yaml"), "--json"])
    assert json.loads(r.stdout)["hardpoints"] == []  # no wheel: check lists no suspension table


def test_every_editable_row_is_the_address_that_moves_it():
    """The table is the report's and the workbench's too: each row with an address is where
    that address puts the point (``--set ADDRESS=x,y,z`` with the row's own numbers changes
    nothing), and the rows of a wheel-less mechanism are its joints."""
    for name in ("double_wishbone_hardpoints.yaml", "hmmwv_front_axle.yaml", "fourbar.yaml", "stewart.yaml"):
        model = load_model(EXAMPLES / name)
        eng = compile_engine(model)
        rows = hardpoint_table(model, eng)
        assert rows and all(r["group"] in HARDPOINT_GROUPS for r in rows)
        for r in rows:
            if r["address"] is not None:
                p = current_point(eng, eng.reference, r["address"])
                np.testing.assert_allclose(p, [r["x"], r["y"], r["z"]], atol=1e-9, err_msg=f"{name}: {r['point']}")
    rows = hardpoint_table(load_model(EXAMPLES / "fourbar.yaml"))
    assert [r["address"] for r in rows if r["address"]] == [f"hardpoint:{j}" for j in ("O2", "O4", "A", "B")]
