"""``kinprop loads``: the JSON and CSV carry kp.statics' numbers in the model's units; an
unknown load case is invalid input (exit 2, one located line); loads the inputs cannot hold
exit 1."""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

import numpy as np
import pytest

import kinprop as kp

sys.path.insert(0, str(Path(__file__).resolve().parent))
from cli_run import invoke_kinprop, one_error_line

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def test_json_and_csv_match_the_library(tmp_path: Path) -> None:
    out = tmp_path / "loads.csv"
    p = invoke_kinprop("loads", EXAMPLES / "double_wishbone.yaml", "--load-case", "braking_1g", "--json", "--csv", out)
    assert p.returncode == 0, p.stderr
    data = json.loads(p.stdout)
    model = kp.assemble(kp.load_model(EXAMPLES / "double_wishbone.yaml")).after
    s = kp.statics(model, "braking_1g")
    assert data["units"] == {"force": "N", "moment": "N mm", "length": "mm"}
    assert data["efforts"]["LCA.q"] == pytest.approx(s.efforts["LCA.q"], rel=1e-9)
    assert np.allclose(data["reactions"]["UBJ"]["force"][1], s.reactions["UBJ"].force[1], rtol=1e-9)
    assert data["member_forces"]["TR"] == pytest.approx(s.member_forces["TR"], rel=1e-9)
    rows = {r["output"]: r for r in csv.DictReader(out.open())}
    assert float(rows["reaction:UBJ.fz"]["value"]) == pytest.approx(s.value("reaction:UBJ.fz"), rel=1e-9)
    assert rows["reaction:LCA.mx"]["unit"] == "N mm" and rows["force:spring"]["unit"] == "N"
    assert rows["effort:LCA.q"]["unit"] == "N mm"


def test_bad_case_and_unheld_loads() -> None:
    line = one_error_line(invoke_kinprop("loads", EXAMPLES / "double_wishbone.yaml", "--load-case", "nope"))
    assert "'nope'" in line and "bump_3g" in line
    # the offset slider-crank declares no input: a piston force moves it
    p = invoke_kinprop("loads", EXAMPLES / "slider_crank_offset.yaml", "--force", "slider.origin=100,0,0")
    assert p.returncode == 2  # no named point 'origin' on the slider
    p = invoke_kinprop("loads", EXAMPLES / "slider_crank_offset.yaml", "--moment", "crank=0,0,5")
    assert p.returncode == 1, p.stderr
    assert "unbalanced" in p.stderr
    p = invoke_kinprop("loads", EXAMPLES / "slider_crank_offset.yaml", "--moment", "crank=0,0,5", "--input", "O2")
    assert p.returncode == 0, p.stderr
    assert "effort O2.q: -5 force m" in p.stdout


def test_equilibrium_option() -> None:
    dw = EXAMPLES / "double_wishbone.yaml"
    p = invoke_kinprop("loads", dw, "--wheel", "upright=0,0,11000", "--equilibrium", "--json")
    assert p.returncode == 0, p.stderr
    data = json.loads(p.stdout)
    eq = data["equilibrium"]
    assert eq["stable"] and eq["iterations"] >= 1 and eq["status"] == "converged"
    assert abs(data["efforts"]["LCA.q"]) < 1e-9 * 11000 * 1000
    model = kp.assemble(kp.load_model(EXAMPLES / "double_wishbone.yaml")).after
    at = kp.propagate(model, {"LCA.q": eq["coordinates"]["LCA.q"]}, free=["q"], tol=1e-13).after
    s = kp.statics(at, kp.LoadCase("w", wheels={"upright": (0.0, 0.0, 11000.0)}))
    assert abs(s.efforts["LCA.q"]) < 1e-6 * 11000 * 1000  # the printed angle is the balanced pose
    from kinprop.analysis.statics import wheel_rate

    assert eq["wheel_rate"] == pytest.approx(wheel_rate(at), rel=1e-8)


def test_plot_draws_the_reported_forces(tmp_path: Path) -> None:
    """``--plot`` writes a PNG; its arrows are the reported forces: the wheel force at the
    contact point, each joint's force on its body j at its point (the tie rod coloured by the
    sign of its tension), the spring's force on its body-j end along the spring."""
    from kinprop.analysis.metrics import contact_point
    from kinprop.plot.forces import FORCE_STYLE, force_arrows

    out = tmp_path / "loads.png"
    p = invoke_kinprop("loads", EXAMPLES / "double_wishbone.yaml", "--load-case", "braking_1g", "--plot", out)
    assert p.returncode == 0, p.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    model = kp.assemble(kp.load_model(EXAMPLES / "double_wishbone.yaml")).after
    case = model.loads.case("braking_1g")
    s = kp.statics(model, case)
    arrows = {a.label: a for a in force_arrows(s, case)}
    tr = arrows["TR"]
    assert tr.kind == ("tension" if s.member_forces["TR"] > 0 else "compression")
    assert np.allclose(tr.force, s.reactions["TR"].force[1]) and np.allclose(tr.origin, s.reactions["TR"].points[1])
    assert arrows["UBJ"].kind == "reaction"
    spring = arrows["spring"]
    e = model.element("spring")
    kin = kp.compile(model).kinematics(model.design, model.coordinates)
    Pi = kin.r[e.body_i] + kin.A[e.body_i] @ np.array(e.s_i)
    Pj = kin.r[e.body_j] + kin.A[e.body_j] @ np.array(e.s_j)
    assert np.allclose(spring.origin, Pj)
    assert np.allclose(spring.force, s.element_forces["spring"] * (Pj - Pi) / np.linalg.norm(Pj - Pi))
    load = arrows["upright wheel"]
    pts = dict(model.mechanism.body("upright").points)
    centre = kin.r["upright"] + kin.A["upright"] @ np.array(pts["wheel_centre"])
    axis = kin.A["upright"] @ (np.array(pts["spin_axis"]) - np.array(pts["wheel_centre"]))
    radius = np.linalg.norm(np.array(pts["contact_patch"]) - np.array(pts["wheel_centre"]))
    assert np.allclose(load.origin, contact_point(centre, axis, radius))
    assert np.allclose(load.force, case.wheels["upright"])
    html = tmp_path / "plot.html"  # kinprop plot --load-case: the same arrows, in an HTML figure
    from kinprop.io.writer import dump_model_like

    dump_model_like(model, tmp_path / "dw.yaml", EXAMPLES / "double_wishbone.yaml")  # assembled
    p = invoke_kinprop("plot", tmp_path / "dw.yaml", "-o", html, "--load-case", "braking_1g")
    assert p.returncode == 0, p.stderr
    text = html.read_text()
    for kind in {a.kind for a in arrows.values()}:  # one trace per kind, named by its legend text
        assert f'"name":"{FORCE_STYLE[kind][1]}"' in text
    assert '"name":"tension (rod, element)"' not in text  # no member in tension in this case
    assert f"TR: {np.linalg.norm(tr.force):.4g} N" in text and "force arrows: 1 mm per" in text
    bad = invoke_kinprop("loads", EXAMPLES / "double_wishbone.yaml", "--plot", tmp_path / "loads.svg")
    assert bad.returncode == 2 and "--plot" in one_error_line(bad)


def test_sensitivity_of_loads_names_its_method() -> None:
    """``kinprop sensitivity --of force:TR@CASE``: the exact (direct) derivative, the same number
    as ``kp.output_sensitivity``, and each row's method in the JSON."""
    from kinprop.analysis.sensitivity import CENTRAL, DIRECT

    p = invoke_kinprop("sensitivity", EXAMPLES / "double_wishbone.yaml", "--of", "force:TR@braking_1g",
                       "--of", "camber", "--wrt", "TR.length", "--json")  # fmt: skip
    assert p.returncode == 0, p.stderr
    data = json.loads(p.stdout)
    assert data["method"] == {"force:TR@braking_1g": DIRECT, "camber": CENTRAL}
    model = kp.assemble(kp.load_model(EXAMPLES / "double_wishbone.yaml")).after
    D = kp.output_sensitivity(model, ["force:TR@braking_1g"], ["TR.length"])
    assert data["matrix"][0][0] == pytest.approx(D.iloc[0, 0], rel=1e-9)
    assert abs(D.iloc[0, 0]) > 1.0
