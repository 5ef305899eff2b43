"""Bad MJCF and Chrono files: one located line per problem, exit code 2, never a traceback."""

from __future__ import annotations

import json

import pytest
from imports_helpers import CHRONO, MJCF
from typer.testing import CliRunner

from kinprop.cli import app

runner = CliRunner()

BASE = """<mujoco model="m">
  <worldbody>
    <body name="a" pos="0 0 1">
      <joint name="ja" type="hinge" axis="0 1 0"/>
      <body name="b" pos="1 0 0">
        <joint name="jb" type="hinge" axis="0 1 0"/>
      </body>
    </body>
    <body name="c" pos="2 0 0">
      <joint name="jc" type="hinge" axis="0 1 0"/>
    </body>
  </worldbody>
  <equality>
    EQUALITY
  </equality>
</mujoco>
"""


def run_import(tmp_path, text: str, suffix: str = ".xml", name: str = "bad"):
    src = tmp_path / f"{name}{suffix}"
    src.write_text(text)
    r = runner.invoke(app, ["import", str(src), "-o", str(tmp_path / "out.yaml")])
    assert r.exception is None or isinstance(r.exception, SystemExit), r.exception
    assert "Traceback" not in r.output
    return r, src


@pytest.mark.parametrize(
    ("equality", "expected"),
    [
        (
            '<connect body1="b" body2="nope" anchor="0 0 0"/>',
            "line 14 <connect>: body2='nope': no such body; bodies are",
        ),
        ('<connect body1="b" body2="c"/>', "anchor: missing"),
        ('<connect body1="b" body2="c" anchor="0 0"/>', "anchor='0 0': expected 3 numbers, found 2"),
        ('<tendon tendon1="t"/>', "line 14 <tendon>: a tendon equality"),
        ('<distance body1="b" body2="c" distance="1"/>', "a distance equality (removed from MuJoCo"),
        ('<flex flex="f"/>', "a flex equality"),
        ('<joint joint1="ja"/>', "line 14 <joint>: a joint equality without joint2 holds ja at a constant"),
        ('<joint joint1="ja" joint2="nope"/>', "joint2='nope': no such joint"),
        ('<joint joint1="ja" joint2="jc" polycoef="0 2"/>', "polycoef='0 2': expected 5 numbers, found 2"),
        ('<weld body1="b" body2="b"/>', "weld joins body 'b' to itself"),
        ('<connect site1="s1" site2="s2"/>', "site1='s1': no such site"),
        ("<gear/>", "unknown element <gear> in <equality>"),
    ],
)
def test_equality_errors(tmp_path, equality: str, expected: str) -> None:
    r, src = run_import(tmp_path, BASE.replace("EQUALITY", equality))
    assert r.exit_code == 2, r.output
    assert f"error: {src}: " in r.output and expected in r.output
    assert not (tmp_path / "out.yaml").exists()


def test_a_valid_joint_coupling_imports(tmp_path) -> None:
    equality = '<joint name="gear" joint1="ja" joint2="jc" polycoef="0 2 0 0 0"/>'
    r, _ = run_import(tmp_path, BASE.replace("EQUALITY", equality))
    assert r.exit_code == 0, r.output
    r = runner.invoke(app, ["check", str(tmp_path / "out.yaml"), "--json"])
    obj = json.loads(r.stdout)
    assert obj["couplings"] == [{"name": "gear", "joints": ["ja", "jc"], "rows": ["gear:coupling"]}]
    assert obj["mobility"] == obj["gruebler"] == 2  # three hinges, one coupling


def test_a_valid_connect_imports(tmp_path) -> None:
    r, _ = run_import(tmp_path, BASE.replace("EQUALITY", '<connect body1="b" body2="c" anchor="1 0 0"/>'))
    assert r.exit_code == 0, r.output
    r = runner.invoke(app, ["check", str(tmp_path / "out.yaml"), "--json"])
    obj = json.loads(r.stdout)
    assert obj["cut_joints"] == ["connect_b_c"] and obj["mobility"] == 1  # a planar four-bar


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("<mujoco><worldbody><body></worldbody></mujoco>", "malformed XML: mismatched tag"),
        ("", "malformed XML: no element found"),
        ("<robot/>", "line 1 <robot>: expected a <mujoco> root element, found <robot>"),
        ('<!DOCTYPE m [<!ENTITY x "y">]><mujoco/>', "entity declarations are not accepted"),
        ("<mujoco><include file='x.xml'/></mujoco>", "<include> is not resolved"),
        ("<mujoco><worldbody><body><foo/></body></worldbody></mujoco>", "unknown element <foo> in <body>"),
        ("<mujoco><worldbody><body><composite/></body></worldbody></mujoco>", "<composite> bodies are not supported"),
        ('<mujoco><worldbody><body pos="1 2"/></worldbody></mujoco>', "pos='1 2': expected 3 numbers, found 2"),
        ('<mujoco><worldbody><body quat="1 0 0 0" euler="0 0 1"/></worldbody></mujoco>', "more than one orientation"),
        ('<mujoco><worldbody><body><joint class="nope"/></body></worldbody></mujoco>', "class='nope': no such default"),
        ('<mujoco><worldbody><body><joint type="screw"/></body></worldbody></mujoco>', "type='screw': expected one of"),
        ('<mujoco><worldbody><body><joint axis="0 0 0"/></body></worldbody></mujoco>', "axis: expected a non-zero"),
        ('<mujoco><compiler angle="grad"/></mujoco>', "angle='grad': expected 'degree' or 'radian'"),
        (
            "<mujoco><worldbody><body><body><freejoint/></body></body></worldbody></mujoco>",
            "a free joint must be the only joint of a top-level body",
        ),
        (
            '<mujoco><worldbody><body><joint/></body></worldbody><keyframe><key qpos="1 2"/></keyframe></mujoco>',
            "keyframe 'key0': qpos has 2 numbers, the model has nq = 1",
        ),
    ],
)
def test_malformed_or_unsupported_mjcf(tmp_path, text: str, expected: str) -> None:
    r, src = run_import(tmp_path, text)
    assert r.exit_code == 2, r.output
    assert str(src) in r.output and expected in r.output
    assert all(line.startswith(("error:", " ")) for line in r.output.strip().splitlines() if line), r.output


def test_truncated_files_never_crash(tmp_path) -> None:
    text = (MJCF / "cassie_left_leg_kinematic.xml").read_text()
    for cut in range(200, len(text), 397):
        r, _ = run_import(tmp_path, text[:cut], name=f"cut{cut}")
        assert r.exit_code == 2
    chrono = (CHRONO / "MultiLink.json").read_text()
    for cut in range(50, len(chrono), 211):
        r, _ = run_import(tmp_path, chrono[:cut], suffix=".json", name=f"cut{cut}")
        assert r.exit_code == 2


def _chrono(**changes) -> str:
    data = json.loads((CHRONO / "DoubleWishbone.json").read_text())
    for key, value in changes.items():
        section, _, field = key.partition("__")
        if field:
            data[section.replace("_", " ")][field.replace("_", " ")] = value
        else:
            data[section] = value
    return json.dumps(data)


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        (
            _chrono(Template="SolidAxle"),
            "Template: expected one of DoubleWishbone, MacPhersonStrut, MultiLink, found 'SolidAxle'",
        ),
        (
            _chrono(Upper_Control_Arm__Location_Upright=[1, 2]),
            "Upper Control Arm.Location Upright: expected [x, y, z] in metres",
        ),
        (_chrono(Tierod="none"), "Tierod: expected an object with 'Location Chassis', found a str"),
        (_chrono(Type="Tire"), "Type: expected 'Suspension', found 'Tire'"),
        ("[1, 2]", "expected a JSON object, found list"),
        ('{"Template": "DoubleWishbone",}', "syntax"),
    ],
)
def test_bad_chrono_files(tmp_path, text: str, expected: str) -> None:
    r, src = run_import(tmp_path, text, suffix=".json")
    assert r.exit_code == 2, r.output
    assert str(src) in r.output and expected in r.output


def test_other_commands_read_imports_with_the_same_errors(tmp_path) -> None:
    src = tmp_path / "bad.xml"
    src.write_text(BASE.replace("EQUALITY", '<connect body1="b" body2="nope" anchor="0 0 0"/>'))
    r = runner.invoke(app, ["check", str(src)])
    assert r.exit_code == 2 and "body2='nope': no such body" in r.output
    r = runner.invoke(app, ["check", str(CHRONO / "MultiLink.json"), "--json"])
    assert r.exit_code == 0 and json.loads(r.stdout)["mobility"] == 1
    r = runner.invoke(app, ["import", str(CHRONO / "README.md")])
    assert r.exit_code == 2 and "expected an MJCF (.xml) or Project Chrono suspension (.json) file" in r.output


def test_mutated_files_are_models_or_located_errors() -> None:
    """Seeded mutations of the example files: every outcome is a model or a ModelError."""
    import random
    import re
    import warnings

    import kinprop as kp
    from kinprop.errors import ModelError
    from kinprop.imports.chrono import chrono_hardpoints
    from kinprop.imports.mjcf import document_to_model, read_mjcf_text
    from kinprop.io.hardpoints import model_from_hardpoints

    rng = random.Random(7)
    texts = [p.read_text() for p in sorted(MJCF.glob("*.xml"))]
    junk = ["nan", "abc", "1e999", "1e300", "", "0 0 0 0", "1 2", "0 0 0", "-1e308 1e308 1"]
    outcomes = {"model": 0, "error": 0}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for _ in range(150):
            t = rng.choice(texts)
            for _ in range(rng.randint(1, 3)):
                m = rng.choice(list(re.finditer(r'="([^"]*)"', t)))
                t = t[: m.start(1)] + rng.choice([*junk, m.group(1)[::-1]]) + t[m.end(1) :]
            try:
                kp.mobility(document_to_model(read_mjcf_text(t, "f.xml")))
                outcomes["model"] += 1
            except ModelError:
                outcomes["error"] += 1
        datas = [json.loads(p.read_text()) for p in sorted(CHRONO.glob("*.json"))]
        bad = [1e300, 0, None, "x", [1, 2], [0, 0, 0], True, {"a": 1}]
        for _ in range(150):
            d = json.loads(json.dumps(rng.choice(datas)))
            sec = rng.choice(list(d))
            if isinstance(d[sec], dict) and d[sec]:
                d[sec][rng.choice(list(d[sec]))] = rng.choice(bad)
            else:
                d[sec] = rng.choice(bad)
            try:
                model = model_from_hardpoints(chrono_hardpoints(d, "f.json")[0], "f.json")
                kp.mobility(model)
                kp.assemble(model)
                outcomes["model"] += 1
            except ModelError:
                outcomes["error"] += 1
    assert outcomes["model"] > 20 and outcomes["error"] > 20
