"""`kinprop check`: structure, loops and cases, counts, mobility and redundant rows.

Truth: the slider-crank has mobility 1 and one loop of case 2 closing at the ground (the paper
says case 1; PAPER-NOTES); the McPherson strut has mobility 2 (jounce and steering) and two
case-1 loops at the chassis; the Bennett linkage is overconstrained (Gruebler -2, mobility 1).
"""

from __future__ import annotations

import json

from typer.testing import CliRunner

from kinprop.cli import app

runner = CliRunner()


def check_json(*args: object) -> dict:
    r = runner.invoke(app, ["check", *map(str, args), "--json"])
    assert r.exit_code == 0, r.output
    assert len(r.stdout.strip().splitlines()) == 1
    return json.loads(r.stdout)


def test_slider_crank(examples) -> None:
    obj = check_json(examples / "slider_crank.yaml")
    assert obj["mobility"] == 1 and obj["gruebler"] == 1
    assert (obj["n_coordinates"], obj["n_constraints"], obj["rank"]) == (4, 3, 3)
    assert sorted(obj["tree_joints"]) == ["J01", "J03", "J32"]
    assert obj["cut_joints"] == ["J12"]
    [loop] = obj["loops"]
    assert (loop["cut_joint"], loop["junction"], loop["case"]) == ("J12", "ground", 2)
    assert loop["path_i"] == ["J01"] and loop["path_j"] == ["J03", "J32"]
    assert obj["redundant"] == []
    joints = {j["name"]: j for j in obj["joints"]}
    assert joints["J12"]["role"] == "cut" and joints["J12"]["type"] == "spherical"
    assert joints["J12"]["bodies"] == ["crank", "rod"]
    assert len(joints["J12"]["rows"]) == 3 and joints["J32"]["n_coordinates"] == 2
    assert [b["name"] for b in obj["bodies"] if b["fixed"]] == ["ground"]
    # the file holds the paper's starting estimates: not assembled, and the report says so
    assert obj["evaluated_at"] == "the model's coordinates as given"
    assert obj["assembled"] is False and 1e-5 < obj["residual"] < 1e-3


def test_mcpherson(examples) -> None:
    obj = check_json(examples / "mcpherson.yaml")
    assert obj["mobility"] == 2 and obj["gruebler"] == 2
    # p (4) + strut slide + rack q3; RS dot-2 + distance, TD distance, Euler normalisation
    assert (obj["n_coordinates"], obj["n_constraints"], obj["rank"]) == (6, 4, 4)
    assert obj["tree_joints"] == ["ST"] and obj["cut_joints"] == ["RS", "TD"]
    assert [(lp["cut_joint"], lp["junction"], lp["case"]) for lp in obj["loops"]] == [
        ("RS", "chassis", 1),
        ("TD", "chassis", 1),
    ]
    assert obj["redundant"] == []
    rows = {j["name"]: j["rows"] for j in obj["joints"]}
    assert rows == {"ST": ["ST:normalisation"], "RS": ["RS:dot2", "RS:distance"], "TD": ["TD:distance"]}


def test_bennett_redundant_rows_named_by_joint(examples) -> None:
    obj = check_json(examples / "bennett.yaml", "--assemble")
    assert obj["assembled"] is True and obj["residual"] < 1e-10
    assert obj["evaluated_at"].startswith("the assembled configuration")
    assert obj["gruebler"] == -2 and obj["mobility"] == 1
    assert obj["rank"] == 2 and obj["n_constraints"] == 5
    assert len(obj["redundant"]) == 3 and all(r.startswith("J4:") for r in obj["redundant"])
    assert obj["redundant_joints"] == ["J4"]


def test_human_report(examples) -> None:
    r = runner.invoke(app, ["check", str(examples / "mcpherson.yaml")])
    assert r.exit_code == 0, r.output
    text = " ".join(r.stdout.split())  # undo rich's wrapping
    assert "mobility (n - rank): 2" in text
    assert "Gruebler-Kutzbach count: 2" in text
    assert "coordinates n = 6, constraint rows m = 4" in text
    assert "case 1" in text and "junction" in text
    assert "as given" in text and "||Phi|| = 0.0754" in text
    assert "kinprop assemble" in text  # suggests assembling first


def test_human_report_overconstrained(examples) -> None:
    r = runner.invoke(app, ["check", str(examples / "bennett.yaml"), "--assemble"])
    assert r.exit_code == 0, r.output
    text = " ".join(r.stdout.split())
    assert "redundant constraint rows (3)" in text and "(joints: J4)" in text
    assert "overconstrained" in text and "not assembled" not in text


def test_invalid_model_exit_2(tmp_path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(
        "kinprop: 1\nname: x\nunits: {length: m, angle: rad}\nbodies: {a: {fixed: true}}\n"
        "joints: {J: {type: hinge, bodies: [a, b]}}\n"
    )
    r = runner.invoke(app, ["check", str(bad)])
    assert r.exit_code == 2
    assert "Traceback" not in r.output
