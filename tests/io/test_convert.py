"""`kinprop convert`: both directions through the CLI, files readable back, exit codes."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from io_helpers import hardpoint_difference
from typer.testing import CliRunner

from kinprop import assemble, load_model, propagate
from kinprop.cli import app
from kinprop.io.hardpoints import express_in

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
runner = CliRunner()


def run(*args):
    return runner.invoke(app, [str(a) for a in args])


def test_frames_to_hardpoints_to_frames(tmp_path):
    asm = tmp_path / "assembled.yaml"
    assert run("assemble", EXAMPLES / "slider_crank.yaml", "-o", asm, "--json", "--method", "paper").exit_code == 0
    r = run("convert", asm, "--to", "hardpoints", "-o", tmp_path / "hp.yaml")
    assert r.exit_code == 0, r.output
    assert r.stderr == ""  # assembled: no warning
    hp = yaml.safe_load((tmp_path / "hp.yaml").read_text())
    assert hp["style"] == "hardpoints" and hp["body_frames"] == "global"
    assert hp["joints"]["J32"]["type"] == "universal" and set(hp["joints"]["J32"]) >= {"axis_i", "axis_j", "point"}
    example = load_model(EXAMPLES / "slider_crank_hardpoints.yaml")
    assert hardpoint_difference(load_model(tmp_path / "hp.yaml"), example) < 1e-12
    r = run("convert", tmp_path / "hp.yaml", "--to", "frames", "-o", tmp_path / "frames.json")
    assert r.exit_code == 0, r.output
    data = json.loads((tmp_path / "frames.json").read_text())
    original = load_model(asm)
    # the input's zero is kept through both conversions (issue 19 item 0)
    assert "style" not in data and data["joints"]["J01"]["q"] == pytest.approx(np.degrees(original.coordinates["J01"]))
    back = load_model(tmp_path / "frames.json")
    assert hardpoint_difference(original, back) < 1e-12
    change = {"J12.s_j": [-2.8, 0.2, 0.1]}
    pf = propagate(original, change, ("q", "s"))
    pb = propagate(back, {k: express_in(original, back, k, v) for k, v in change.items()}, ("q", "s"))
    assert hardpoint_difference(pf.after, pb.after) < 1e-9


def test_joint_body_frames_option(tmp_path):
    r = run("convert", EXAMPLES / "mcpherson_hardpoints.yaml", "--to", "hardpoints", "--body-frames", "joint")
    assert r.exit_code == 0, r.output
    data = yaml.safe_load(r.stdout)
    assert data["body_frames"] == "joint"
    (tmp_path / "j.yaml").write_text(r.stdout)
    model = load_model(tmp_path / "j.yaml")
    assert "ST.C_j" not in model.design and "ST.C_i" in model.design
    assert hardpoint_difference(model, load_model(EXAMPLES / "mcpherson_hardpoints.yaml")) < 1e-12


def test_unassembled_model_warns_and_still_converts(tmp_path):
    r = run("convert", EXAMPLES / "slider_crank.yaml", "--to", "hardpoints", "-o", tmp_path / "hp.yaml")
    assert r.exit_code == 0
    assert "joints.J12: not assembled" in r.stderr
    model = load_model(tmp_path / "hp.yaml")
    assert np.isfinite(model.design["J12.s_i"]).all()
    assert assemble(model).converged


def test_bad_target_and_bad_model(tmp_path):
    assert run("convert", EXAMPLES / "slider_crank.yaml", "--to", "pdf").exit_code == 2
    bad = tmp_path / "bad.yaml"
    bad.write_text("kinprop: 1\nstyle: hardpoints\nbodies: {}\njoints: {}\n")
    r = run("convert", bad, "--to", "frames", "-o", tmp_path / "out.yaml")
    assert r.exit_code == 2
    assert not (tmp_path / "out.yaml").exists()
    assert r.stderr.splitlines()[0].startswith(f"error: {bad}: units: missing")
