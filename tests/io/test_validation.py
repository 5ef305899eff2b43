"""Validation at load time: every problem at once, naming file, location and expected vs found.

Each problem class is checked through the API (``load_model`` raises one ``ModelError``
carrying every problem) and through the CLI (exit code 2, one ``error:`` line per problem on
stderr, no traceback).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
import yaml
from typer.testing import CliRunner

from kinprop import load_model
from kinprop.cli import app
from kinprop.errors import ModelError
from kinprop.io import model_from_data, parse_text
from kinprop.joints import REGISTRY

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
runner = CliRunner()


def example(name: str) -> dict[str, Any]:
    return yaml.safe_load((EXAMPLES / name).read_text())


def write(tmp_path: Path, data: dict[str, Any] | str, name: str = "model.yaml") -> Path:
    path = tmp_path / name
    if isinstance(data, str):
        path.write_text(data)
    elif name.endswith(".json"):
        path.write_text(json.dumps(data))
    else:
        path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def problems_of(path: Path) -> list[tuple[str, str]]:
    """(location, message) of every problem the loader reports; checks the file is named."""
    with pytest.raises(ModelError) as info:
        load_model(path)
    for p in info.value.problems:
        assert p.file == str(path)
    return [(p.location, p.message) for p in info.value.problems]


def cli_lines(*args: Any) -> list[str]:
    """stderr lines of a CLI run that must fail with exit code 2 and no traceback."""
    r = runner.invoke(app, [str(a) for a in args])
    assert r.exit_code == 2, (r.exit_code, r.output)
    assert "Traceback" not in r.output
    assert r.exception is None or isinstance(r.exception, SystemExit), repr(r.exception)
    lines = [line for line in r.stderr.splitlines() if line.strip()]
    assert lines and all(line.startswith("error: ") for line in lines), r.stderr
    return lines


def assert_reported(tmp_path: Path, data: dict[str, Any] | str, expected: list[tuple[str, str]], name: str = "m.yaml"):
    """Both surfaces report each (location, fragment); the CLI prints one line per problem."""
    path = write(tmp_path, data, name)
    found = problems_of(path)
    for loc, fragment in expected:
        assert any(p_loc == loc and fragment in msg for p_loc, msg in found), (loc, fragment, found)
    lines = cli_lines("convert", path, "--to", "hardpoints")
    assert len(lines) == len(found)
    for (loc, msg), line in zip(found, lines, strict=True):
        assert line == f"error: {path}: {loc}: {msg}"
    return found


# --- one test per problem class -----------------------------------------------------------------


def test_unknown_joint_type_lists_the_known_ones(tmp_path):
    data = example("slider_crank.yaml")
    data["joints"]["J01"]["type"] = "revolut"
    found = assert_reported(tmp_path, data, [("joints.J01.type", "unknown joint type 'revolut'")])
    assert all(name in found[0][1] for name in REGISTRY)


def test_unknown_joint_type_in_hardpoints(tmp_path):
    data = example("mcpherson_hardpoints.yaml")
    data["joints"]["ST"]["type"] = "strut"
    assert_reported(tmp_path, data, [("joints.ST.type", "known: cylindrical, distance")])


def test_unknown_body(tmp_path):
    data = example("slider_crank.yaml")
    data["joints"]["J03"]["bodies"] = ["ground", "slidr"]
    assert_reported(tmp_path, data, [("joints.J03.body_j", "unknown body 'slidr'; bodies are")])
    hp = example("slider_crank_hardpoints.yaml")
    hp["joints"]["J12"]["bodies"] = ["crank", "rood"]
    assert_reported(tmp_path, hp, [("joints.J12.body_j", "unknown body 'rood'")])


def test_duplicate_names_yaml(tmp_path):
    text = (EXAMPLES / "slider_crank.yaml").read_text()
    text = text.replace("  crank: {}\n", "  crank: {}\n  crank: {}\n")
    text += "  J01:\n    type: revolute\n    bodies: [ground, crank]\n"
    assert_reported(
        tmp_path,
        text,
        [("bodies.crank", "duplicate name 'crank' (lines"), ("joints.J01", "duplicate name 'J01' (lines")],
    )


def test_duplicate_names_json(tmp_path):
    text = json.dumps(example("slider_crank.yaml"))
    text = text.replace('"crank": {}', '"crank": {}, "crank": {"fixed": true}')
    assert_reported(tmp_path, text, [("bodies.crank", "duplicate name 'crank'")], name="m.json")


def test_duplicate_names_are_reported_with_the_other_problems(tmp_path):
    text = (EXAMPLES / "slider_crank.yaml").read_text().replace("units: {length: m, angle: deg}\n", "")
    text = text.replace("  rod: {}\n", "  rod: {}\n  rod: {}\n")
    assert_reported(tmp_path, text, [("bodies.rod", "duplicate name"), ("units", "missing: declare the units")])


def test_missing_units(tmp_path):
    data = example("slider_crank.yaml")
    del data["units"]
    assert_reported(tmp_path, data, [("units", "missing: declare the units, e.g. units: {length: mm, angle: deg}")])
    hp = example("mcpherson_hardpoints.yaml")
    del hp["units"]["length"]
    del hp["units"]["axes"]
    assert_reported(
        tmp_path, hp, [("units.length", "missing: one of m, mm"), ("units.axes", "missing: one of ISO8855")]
    )


def test_unknown_unit_and_axis_convention(tmp_path):
    hp = example("mcpherson_hardpoints.yaml")
    hp["units"] = {"length": "inch", "angle": "grad", "axes": "NED"}
    assert_reported(
        tmp_path,
        hp,
        [
            ("units.length", "'m' or 'mm' (found 'inch')"),
            ("units.angle", "'deg' or 'rad' (found 'grad')"),
            ("units.axes", "'ISO8855', 'SAE' or 'right-handed' (found 'NED')"),
        ],
    )


def test_rotation_that_is_not_proper(tmp_path):
    data = example("slider_crank.yaml")
    data["joints"]["J01"]["C_i"] = [[0, 0, 1], [1, 0, 0], [0, -1, 0]]  # det -1
    data["joints"]["J03"]["C_i"] = [[1, 0, 0], [0, 1, 0], [0, 0, 2]]  # not orthonormal
    assert_reported(
        tmp_path,
        data,
        [("joints.J01.C_i", "expected a proper rotation matrix"), ("joints.J03.C_i", "found [[1.0, 0.0, 0.0]")],
    )
    hp = example("mcpherson_hardpoints.yaml")
    hp["bodies"]["chassis"]["orientation"] = [[1, 0, 0], [0, 1, 0], [0, 0, -1]]
    assert_reported(tmp_path, hp, [("bodies.chassis.orientation", "expected a proper rotation matrix")])


def test_zero_or_nan_axis(tmp_path):
    hp = example("mcpherson_hardpoints.yaml")
    hp["joints"]["ST"]["axis"] = [0, 0, 0]
    hp["joints"]["TD"]["axis"] = [1, float("nan"), 0]
    assert_reported(
        tmp_path,
        hp,
        [("joints.ST.axis", "expected a non-zero direction, found [0.0, 0.0, 0.0]"), ("joints.TD.axis[1]", "finite")],
    )
    data = example("slider_crank.yaml")
    data["joints"]["J12"]["s_j"] = [float("inf"), 0, 0]
    assert_reported(tmp_path, data, [("joints.J12.s_j[0]", "finite number (found inf)")])


def test_wrong_vector_length(tmp_path):
    data = example("slider_crank.yaml")
    data["joints"]["J12"]["s_i"] = [2, 0]
    data["joints"]["J01"]["C_i"] = [[0, 0, 1], [1, 0, 0]]
    data["joints"]["J32"]["q"] = [-30, 0, 0]
    assert_reported(
        tmp_path,
        data,
        [
            ("joints.J12.s_i", "expected at least 3 items, found 2"),
            ("joints.J01.C_i", "expected at least 3 items, found 2"),
            ("joints.J32.q", "expected 2 coordinates for a tree universal joint, found 3"),
        ],
    )
    hp = example("slider_crank_hardpoints.yaml")
    hp["joints"]["J12"]["point"] = [0, 1.4, 1.4, 0]
    assert_reported(tmp_path, hp, [("joints.J12.point", "expected at most 3 items, found 4")])


def test_no_fixed_body(tmp_path):
    data = example("slider_crank.yaml")
    data["bodies"]["ground"] = {}
    assert_reported(tmp_path, data, [("bodies", "no fixed body")])
    hp = example("mcpherson_hardpoints.yaml")
    hp["bodies"] = {}
    hp["joints"] = {}
    assert_reported(tmp_path, hp, [("bodies", "no bodies")])


def test_body_not_connected_to_a_fixed_body(tmp_path):
    data = example("slider_crank.yaml")
    data["bodies"]["spare"] = {}
    data["bodies"]["wheel"] = {}
    data["joints"]["JW"] = {"type": "revolute", "bodies": ["spare", "wheel"]}
    assert_reported(
        tmp_path,
        data,
        [("bodies.spare", "not connected to a fixed body"), ("bodies.wheel", "not connected to a fixed body")],
    )
    hp = example("mcpherson_hardpoints.yaml")
    hp["joints"]["ST"]["cut"] = True  # the wheel then hangs on cut-only joints
    assert_reported(tmp_path, hp, [("bodies.wheel", "reachable from a fixed body only through cut-only joints")])


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["--set", "J99.s_j=1,2,3"], "'J99.s_j' is not a design variable or coordinate of this model; known: J01.q"),
        (["--set", "J12.s_j=1,2"], "'J12.s_j': expected 3 numbers, found 2"),
        (["--set", "J12.s_j=a,b,c"], "values must be comma-separated numbers"),
        (["--set", "J12.length=1"], "'J12.length' is not a design variable"),
        (["--free", "J77.s_i"], "'J77.s_i' is not a variable of this model"),
        (["--free", "J12.s_x"], "bad address 'J12.s_x'"),
        (["--weight", "J01.q=-1"], "must be positive"),
    ],
)
def test_design_address_that_does_not_exist(args, fragment):
    lines = cli_lines("propagate", EXAMPLES / "slider_crank.yaml", *args)
    assert len(lines) == 1 and fragment in lines[0], lines


def test_design_address_through_the_api():
    from kinprop import propagate
    from kinprop.errors import AddressError

    model = load_model(EXAMPLES / "slider_crank_hardpoints.yaml")
    with pytest.raises(AddressError, match="not a design variable"):
        propagate(model, {"J12.length": 1.0})
    with pytest.raises(AddressError, match="not a variable of this model"):
        propagate(model, {}, ("J12.C_i",))


# --- hardpoint-specific and general problems ----------------------------------------------------


def test_hardpoint_keys_per_joint_type(tmp_path):
    hp = example("slider_crank_hardpoints.yaml")
    del hp["joints"]["J01"]["axis"]
    hp["joints"]["J12"]["axis"] = [1, 0, 0]
    hp["joints"]["J32"]["axis_j"] = [1, 0.2, 0]
    hp["bodies"]["crank"] = {"position": [0, 0, 0]}
    assert_reported(
        tmp_path,
        hp,
        [
            ("joints.J01.axis", "missing: a revolute joint takes point, axis"),
            ("joints.J12.axis", "a spherical joint does not take 'axis'; it takes point"),
            ("joints.J32.axis_j", "expected perpendicular to axis_i, found 11.3099 deg"),
            ("bodies.crank", "only fixed bodies take a pose"),
        ],
    )


def test_frame_keys_in_a_hardpoint_file_and_back(tmp_path):
    hp = example("mcpherson_hardpoints.yaml")
    hp["joints"]["ST"]["s_i"] = [0, 0, 0]
    assert_reported(tmp_path, hp, [("joints.ST.s_i", "unknown key (s_i, s_j, C_i and C_j belong in a frame-style")])
    data = example("mcpherson.yaml")
    data["joints"]["ST"]["point"] = [0, 0, 0]
    assert_reported(tmp_path, data, [("joints.ST.point", "unknown key (hardpoint keys need 'style: hardpoints'")])


def test_unknown_style(tmp_path):
    data = example("mcpherson.yaml") | {"style": "hardpoint"}
    assert_reported(tmp_path, data, [("style", "expected one of frames, hardpoints, found 'hardpoint'")])


def test_every_problem_at_once(tmp_path):
    """Schema and semantic problems in different places come in one report."""
    hp = example("slider_crank_hardpoints.yaml")
    hp["units"]["length"] = "cm"
    hp["joints"]["J01"]["type"] = "hinge"
    hp["joints"]["J03"]["axis"] = [0, 0, 0]
    hp["joints"]["J12"]["point"] = [0, "x", 1]
    hp["joints"]["J32"]["bodies"] = ["slider", "rodd"]
    found = assert_reported(
        tmp_path,
        hp,
        [
            ("units.length", "found 'cm'"),
            ("joints.J01.type", "unknown joint type 'hinge'"),
            ("joints.J03.axis", "non-zero direction"),
            ("joints.J12.point[1]", "valid number"),
            ("joints.J32.body_j", "unknown body 'rodd'"),
        ],
    )
    assert len(found) == 5


def test_syntax_and_file_problems(tmp_path):
    assert_reported(tmp_path, "kinprop: 1\nbodies: {a\n", [("line 3, column 1", "YAML syntax: while parsing")])
    assert_reported(tmp_path, "- 1\n- 2\n", [("model", "expected a mapping at the top level, found list")])
    assert_reported(tmp_path, "", [("model", "found NoneType")])
    path = tmp_path / "latin1.yaml"
    path.write_bytes("name: caf\xe9\n".encode("latin-1"))
    assert problems_of(path) == [("file", "not UTF-8 text (byte 9)")]
    assert len(cli_lines("convert", path, "--to", "frames")) == 1
    assert problems_of(tmp_path / "missing.yaml")[0][1].startswith("cannot read")
    with pytest.raises(ModelError, match="nested too deeply"):
        parse_text("[" * 100000, "deep.json")


def test_free_joint_that_closes_a_loop(tmp_path):
    data = example("slider_crank.yaml")
    data["joints"]["F2"] = {"type": "free", "bodies": ["ground", "rod"]}
    data["joints"]["F1"] = {"type": "free", "bodies": ["ground", "rod"]}
    assert_reported(tmp_path, data, [("joints.F1", "a free joint cannot be cut, but it closes a loop")])


def test_bad_euler_parameters(tmp_path):
    data = example("mcpherson.yaml")
    data["joints"]["ST"]["q"] = [0, 0, 0, 0, -0.4]
    assert_reported(tmp_path, data, [("joints.ST.q", "expected Euler parameters with p.p = 1, found p.p = 0")])


def test_reserved_body_name(tmp_path):
    data = example("mcpherson.yaml")
    data["bodies"]["__world__"] = {}
    data["joints"]["X"] = {"type": "revolute", "bodies": ["chassis", "__world__"]}
    assert_reported(tmp_path, data, [("bodies.__world__", "reserved")])
    hp = example("mcpherson_hardpoints.yaml")
    hp["bodies"]["__world__"] = {"fixed": True}
    assert_reported(tmp_path, hp, [("bodies.__world__", "reserved")])


def test_names_must_be_text(tmp_path):
    assert_reported(
        tmp_path,
        "kinprop: 1\nunits: {length: m, angle: rad}\nbodies: {1: {fixed: true}}\njoints: {}\n",
        [("bodies.1", "expected a name (text), found 1")],
    )


def test_valid_files_still_load():
    for path in sorted(EXAMPLES.glob("*.yaml")):
        model = load_model(path)
        assert model.source == str(path)
    assert model_from_data(example("mcpherson_hardpoints.yaml")).units["axes"] == "right-handed"


def test_error_lines_keep_square_brackets(tmp_path):
    path = write(tmp_path, "kinprop: 1\nbodies: [a\n")
    (problem,) = problems_of(path)
    assert cli_lines("convert", path, "--to", "frames") == [f"error: {path}: {problem[0]}: {problem[1]}"]
