"""One style in, the same style out, nothing lost (issue 19 item 8).

``propagate --target -o`` on a hardpoint-style model writes hardpoint style; ``import``
writes no YAML anchors nor last-digit float noise; ``sweep --baseline -o`` writes both
designs, each to its own labelled file, the baseline equal to a plain sweep of the input.
"""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd
import pytest
import yaml
from typer.testing import CliRunner

from kinprop.cli import app

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
runner = CliRunner()


def run(*args: object):
    r = runner.invoke(app, [str(a) for a in args])
    assert r.exit_code == 0, r.output
    return r


def test_targets_output_keeps_the_hardpoint_style(tmp_path):
    out = tmp_path / "t.yaml"
    run("propagate", EXAMPLES / "double_wishbone_hardpoints.yaml", "--target", "camber@travel=0mm=-0.5deg",
        "--free", "hardpoint:UBJ", "-o", out)  # fmt: skip
    data = yaml.safe_load(out.read_text())
    assert data["style"] == "hardpoints" and "point" in data["joints"]["UBJ"]


@pytest.mark.parametrize("source", ["chrono/MultiLink.json", "chrono/DoubleWishbone.json",
                                    "mjcf/cassie_left_leg_kinematic.xml"])  # fmt: skip
def test_import_writes_no_anchors_nor_float_noise(source):
    text = run("import", EXAMPLES / source).stdout
    assert "&id" not in text and "*id" not in text
    assert not re.search(r"\d(0{9,}|9{9,})\d", text), re.search(r".*\d(0{9,}|9{9,})\d.*", text).group(0)


def test_sweep_baseline_writes_both(tmp_path):
    out = tmp_path / "s.csv"
    r = run("sweep", EXAMPLES / "fourbar.yaml", "--drive", "O2=0:90:3", "--set", "A.s_i=0.16,0,0", "--baseline",
            "-o", out)  # fmt: skip
    base = tmp_path / "s.baseline.csv"
    assert str(base) in r.stdout
    plain = tmp_path / "plain.csv"
    run("sweep", EXAMPLES / "fourbar.yaml", "--drive", "O2=0:90:3", "-o", plain)
    pd.testing.assert_frame_equal(pd.read_csv(base), pd.read_csv(plain))
    assert not pd.read_csv(out)["O4.q [deg]"].equals(pd.read_csv(plain)["O4.q [deg]"])
