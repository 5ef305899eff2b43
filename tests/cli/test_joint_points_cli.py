"""A declared steering-axis point off its joint is one ``warning:`` line when a command loads
the model (issue 20, item 3); the model loads and runs."""

from __future__ import annotations

from pathlib import Path

import yaml
from cli_run import run_kinprop

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def test_check_warns_about_a_kingpin_point_off_its_joint(tmp_path):
    data = yaml.safe_load((EXAMPLES / "double_wishbone_hardpoints.yaml").read_text())
    del data["bodies"]["upright"]["kingpin"]
    data["bodies"]["upright"]["points"]["kingpin_upper"] = [-53.0352, 705.518, 215.4936]  # UBJ 10 mm inboard
    data["bodies"]["upright"]["points"]["kingpin_lower"] = [-35.56, 786.511, -118.11]
    path = tmp_path / "edited.yaml"
    path.write_text(yaml.safe_dump(data))
    r = run_kinprop("check", path, env={"KINPROP_JIT": "off"})
    assert r.returncode == 0, r.stderr
    lines = [x for x in r.stderr.splitlines() if x.startswith("warning:")]
    assert len(lines) == 1 and "kingpin_upper is 10 from joint UBJ" in lines[0], r.stderr
    assert "Traceback" not in r.stderr and "JointPointWarning:" not in r.stderr
