"""Couplings in model files: validation with located errors, degree units, writing back.

The geared four-bar (examples/fourbar_geared.yaml) couples the crank O2 to a pinion G:
``q_O2 - 60 deg = -0.5 (q_G - 0)``, in a degree model.
"""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

import kinprop as kp
from kinprop.analysis.units import derivative_scale, unit_of
from kinprop.cli import app
from kinprop.engine.units import from_solver_units, to_solver_units
from kinprop.io import model_from_data
from kinprop.io.writer import dump_model

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
GEARED = EXAMPLES / "fourbar_geared.yaml"
runner = CliRunner()
D = math.pi / 180.0


def geared() -> dict[str, Any]:
    return yaml.safe_load(GEARED.read_text())


def problems(data: dict[str, Any]) -> list[tuple[str, str]]:
    with pytest.raises(kp.ModelError) as info:
        model_from_data(data)
    return [(p.location, p.message) for p in info.value.problems]


def test_coupling_is_read_in_solver_units() -> None:
    model = kp.load_model(GEARED)
    [c] = model.mechanism.couplings
    assert (c.name, c.joint_a, c.joint_b) == ("DRIVE", "O2", "G")
    assert c.q_a0 == pytest.approx(60 * D, abs=1e-15) and c.q_b0 == 0.0
    np.testing.assert_array_equal(model.design["DRIVE.coef"], [0, -0.5, 0, 0, 0])
    eng = kp.compile(model)
    assert eng.row_labels[-1] == "DRIVE:coupling" and "DRIVE.coef" in eng.layout
    assert eng.columns(["coef"]).tolist() == list(range(eng.layout["DRIVE.coef"].start, eng.n_columns))


def test_coefficients_convert_with_the_joints_units() -> None:
    """c_k is in [q_a] / [q_b]^k: a degree model stores c_k (pi/180)^(1-k) times the file's."""
    data = geared()
    data["couplings"]["DRIVE"] = {"joints": ["O2", "G"], "coef": [2, -0.5, 0.01, 1e-4, 1e-6], "q0": [60, 5]}
    model = model_from_data(data)
    expected = [2 * D, -0.5, 0.01 / D, 1e-4 / D**2, 1e-6 / D**3]
    np.testing.assert_allclose(model.design["DRIVE.coef"], expected, rtol=1e-15)
    assert model.mechanism.couplings[0].q_b0 == pytest.approx(5 * D, rel=1e-15)
    assert [unit_of(model, f"DRIVE.coef[{k}]") for k in range(5)] == ["deg", "", "deg/deg^2", "deg/deg^3",
                                                                       "deg/deg^4"]  # fmt: skip
    assert unit_of(model, "DRIVE.coef") == "deg/deg^k"
    for k in range(5):
        address = f"DRIVE.coef[{k}]"
        assert to_solver_units(model, address, 3.0) == pytest.approx(3.0 * D ** (1 - k), rel=1e-15)
        assert from_solver_units(model, address, to_solver_units(model, address, 3.0)) == pytest.approx(3.0)
        assert derivative_scale(model, address) == pytest.approx(D ** (k - 1), rel=1e-15)
    np.testing.assert_allclose(to_solver_units(model, "DRIVE.coef", [1, 1, 1, 1, 1]), [D, 1, 1 / D, D**-2, D**-3])
    # a slide driven by a revolute: c_k in m / deg^k
    data = geared()
    data["joints"]["P"] = {"type": "translational", "bodies": ["ground", "slider"], "q": [0]}
    data["bodies"]["slider"] = {}
    data["couplings"]["RACK"] = {"joints": ["P", "G"], "coef": [0, 0.01]}
    model = model_from_data(data)
    assert unit_of(model, "RACK.coef[1]") == "m/deg" and unit_of(model, "RACK.coef[0]") == "m"
    np.testing.assert_allclose(model.design["RACK.coef"], [0, 0.01 / D, 0, 0, 0], rtol=1e-15)


def test_written_back_in_the_files_units(tmp_path) -> None:
    data = geared()
    data["couplings"]["DRIVE"]["coef"] = [1, -0.5, 0.01]
    src = tmp_path / "g.yaml"
    src.write_text(yaml.safe_dump(data))
    model = kp.load_model(src)
    out = tmp_path / "out.yaml"
    dump_model(model, out)
    written = yaml.safe_load(out.read_text())["couplings"]["DRIVE"]
    assert written["joints"] == ["O2", "G"]
    np.testing.assert_allclose(written["coef"], [1, -0.5, 0.01, 0, 0], rtol=1e-14)
    np.testing.assert_allclose(written["q0"], [60, 0], rtol=1e-14)
    back = kp.load_model(out)
    np.testing.assert_allclose(back.design["DRIVE.coef"], model.design["DRIVE.coef"], rtol=1e-15)
    assert back.mechanism.couplings == model.mechanism.couplings or np.allclose(
        [back.mechanism.couplings[0].q_a0], [model.mechanism.couplings[0].q_a0], rtol=1e-15
    )


def test_hardpoint_style_keeps_the_coordinates_or_shifts_the_offsets(tmp_path) -> None:
    """Converting at G = 20 deg (O2 = 50 deg): both joints sit on the fixed body, so the file
    keeps their coordinates (``q``) and the offsets q0 = [60, 0]; the model moves as before.
    Written re-zeroed (``keep_coordinates=False``) the offsets shift to [60 - 50, 0 - 20]."""
    eng = kp.compile(kp.load_model(GEARED))
    at20 = eng.propagate({"G.q": 20 * D}, free=["q"])
    assert at20.converged
    assembled = tmp_path / "g20.yaml"
    dump_model(eng.model_of(at20.state, eng.model), assembled)
    hp = tmp_path / "g_hp.yaml"
    r = runner.invoke(app, ["convert", str(assembled), "--to", "hardpoints", "-o", str(hp)])
    assert r.exit_code == 0, r.output
    data = yaml.safe_load(hp.read_text())
    np.testing.assert_allclose(data["couplings"]["DRIVE"].get("q0", [0, 0]), [60, 0], atol=1e-9)
    np.testing.assert_allclose(data["joints"]["G"]["q"], [20], atol=1e-9)
    h = kp.compile(kp.load_model(hp))
    sol = h.propagate({"G.q": 30 * D}, free=["q"])
    ref = eng.propagate({"G.q": 30 * D}, free=["q"])
    assert sol.converged and ref.converged
    assert float(sol.value("O2.q")[0]) == pytest.approx(float(ref.value("O2.q")[0]), abs=1e-12)
    assert float(sol.value("O4.q")[0]) == pytest.approx(float(ref.value("O4.q")[0]), abs=1e-12)

    from kinprop.io.hardpoints import model_from_hardpoints, model_to_hardpoints

    rezeroed = model_to_hardpoints(kp.load_model(assembled), keep_coordinates=False)
    np.testing.assert_allclose(rezeroed["couplings"]["DRIVE"]["q0"], [10, -20], atol=1e-9)
    h = kp.compile(model_from_hardpoints(rezeroed))
    sol = h.propagate({"G.q": 10 * D}, free=["q"])  # G at 30 deg overall
    assert sol.converged
    assert float(sol.value("O2.q")[0]) == pytest.approx(float(ref.value("O2.q")[0]) - 50 * D, abs=1e-12)
    assert float(sol.value("O4.q")[0]) == pytest.approx(float(ref.value("O4.q")[0]) - float(at20.value("O4.q")[0]),
                                                        abs=1e-12)  # fmt: skip


@pytest.mark.parametrize(
    ("change", "location", "fragment"),
    [
        ({"joints": ["O2", "nope"]}, "couplings.DRIVE.joints[1]", "unknown joint 'nope'"),
        ({"joints": ["O2", "B"]}, "couplings.DRIVE.joints[1]", "a spherical-translational joint has 5 coordinates"),
        ({"coef": []}, "couplings.DRIVE.coef", "expected 1 to 5 coefficients c0..c4, found 0"),
        ({"coef": [0, 1, 2, 3, 4, 5]}, "couplings.DRIVE.coef", "expected 1 to 5 coefficients c0..c4, found 6"),
        ({"joints": ["O2", "O2"]}, "couplings.DRIVE.joints", "couples joint 'O2' to itself"),
        ({"joints": ["O2"]}, "couplings.DRIVE.joints", "expected at least 2 items, found 1"),
        ({"q0": [1]}, "couplings.DRIVE.q0", "expected at least 2 items, found 1"),
        ({"gear": 2}, "couplings.DRIVE.gear", "unknown key"),
    ],
)
def test_bad_couplings_are_located(change: dict[str, Any], location: str, fragment: str) -> None:
    data = geared()
    data["couplings"]["DRIVE"].update(change)
    found = problems(data)
    assert any(loc == location and fragment in msg for loc, msg in found), found


def test_a_coupled_joint_must_be_able_to_be_a_tree_joint() -> None:
    data = geared()
    data["joints"]["U"] = {"type": "universal", "bodies": ["ground", "spare"]}
    data["bodies"]["spare"] = {}
    data["joints"]["O4"]["cut"] = True
    data["joints"]["D"] = {"type": "distance", "bodies": ["ground", "spare"], "length": 1.0}
    data["couplings"] = {
        "X": {"joints": ["U", "G"], "coef": [0, 1]},
        "Y": {"joints": ["O4", "G"], "coef": [0, 1]},
        "A": {"joints": ["G", "O2"], "coef": [0, 1]},  # a joint's name
        "Z": {"joints": ["G", "D"], "coef": [0, 1]},
    }
    found = problems(data)
    assert (
        "couplings.Z.joints[1]",
        "a distance joint cannot be a tree joint, so it has no coordinate to couple",
    ) in found
    assert ("couplings.X.joints[0]", "a universal joint has 2 coordinates; a coupling takes single-coordinate "
            "joints (revolute, translational)") in found  # fmt: skip
    assert ("couplings.Y.joints[0]", "joint 'O4' is marked 'cut: true'; a coupled joint must be a tree joint") in found
    assert any(loc == "couplings.A" and "duplicate name 'A'" in msg for loc, msg in found), found


def test_coupled_joints_closing_a_loop_are_a_located_error() -> None:
    """All four revolutes of a four-bar coupled: one of them must be cut, so it cannot be coupled."""
    data = copy.deepcopy(geared())
    data["joints"]["B"] = {"type": "revolute", "bodies": ["coupler", "rocker"], "s_i": [0.4, 0, 0],
                           "s_j": [0.3, 0, 0]}  # fmt: skip
    data["couplings"]["OTHER"] = {"joints": ["A", "B"], "coef": [0, 1]}
    data["couplings"]["THIRD"] = {"joints": ["O4", "G"], "coef": [0, 1]}
    found = problems(data)
    assert [loc for loc, _ in found] == ["couplings.OTHER.joints[1]"], found
    assert "joint 'B' must be a tree joint to be coupled, but it closes a loop" in found[0][1]


def test_check_counts_a_coupling_as_one_row_and_names_a_redundant_one(tmp_path) -> None:
    data = geared()
    data["couplings"]["AGAIN"] = {"joints": ["O2", "G"], "coef": [0, -0.5], "q0": [60, 0]}
    src = tmp_path / "twice.yaml"
    src.write_text(yaml.safe_dump(data))
    r = runner.invoke(app, ["check", str(src), "--assemble", "--json"])
    assert r.exit_code == 0, r.output
    obj = json.loads(r.stdout)
    counts = (obj["n_coordinates"], obj["n_constraints"], obj["rank"], obj["mobility"], obj["gruebler"])
    assert counts == (4, 4, 3, 1, 0)
    assert obj["redundant"] in (["DRIVE:coupling"], ["AGAIN:coupling"])
    assert set(obj["dependent"]) == {"DRIVE:coupling", "AGAIN:coupling"}
