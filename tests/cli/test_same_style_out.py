"""One style in, the same style out, nothing lost (issue 19 item 8).

``propagate --target -o`` on a hardpoint-style model writes hardpoint style; ``import``
writes no YAML anchors nor last-digit float noise; ``sweep --baseline -o`` writes both
designs, each to its own labelled file, the baseline equal to a plain sweep of the input.
"""

from __future__ import annotations

import json
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


def _comments(text: str) -> list[str]:
    """Every comment of a YAML text: whole comment lines and the ``# ...`` ends of value lines."""
    out = []
    for line in text.splitlines():
        k = line.find("#")
        if k >= 0:
            out.append(line[k:].strip())
    return out


@pytest.mark.parametrize(
    ("source", "change", "gone"),
    [
        # the hardpoint writer states the steering axis as two named points, so the kingpin line goes
        ("double_wishbone_hardpoints.yaml", "LCA.q=5", {"kingpin"}),
        ("fourbar.yaml", "O2.q=75", set()),
    ],
)
def test_written_model_keeps_the_input_comments(tmp_path, source, change, gone):
    """``propagate -o``: every comment of the input whose key is still written is in the output,
    in the same order; the values are the solve's (the written file propagates on as the JSON
    said, item 0) and each number reads back as a number."""
    src = EXAMPLES / source
    out = tmp_path / "out.yaml"
    obj = json.loads(run("propagate", src, "--set", change, "--json", "-o", out).stdout)
    before, after = src.read_text(), out.read_text()
    lost = [c for c in _comments(before) if c not in _comments(after)]
    assert all(any(g in line for g in gone) for line in before.splitlines() for c in lost if c in line), lost
    kept = [c for c in _comments(after) if c in _comments(before)]
    assert kept == [c for c in _comments(before) if c not in lost] and len(kept) >= 10
    assert _comments(after) == kept  # nothing invented
    again = json.loads(run("assemble", out, "--json").stdout)
    for name, where in obj["hardpoints"].items():  # the same pose, whichever coordinates say it
        assert again["hardpoints"][name] == pytest.approx(where, abs=1e-9), name
    joint = change.split(".")[0]
    assert again["coordinates"][joint] == pytest.approx(obj["coordinates"][joint], abs=1e-12)


def test_workbench_model_keeps_the_comments_and_numbers_read_back(tmp_path):
    from kinprop import load_model, propagate
    from kinprop.io.loader import parse_text
    from kinprop.io.writer import commented_text, dump_model_like

    src = EXAMPLES / "mcpherson.yaml"
    prop = propagate(load_model(src), {"RS.length": 0.21})
    out = tmp_path / "model.yaml"
    dump_model_like(prop.after, out, src)  # what GET /api/model.yaml sends
    assert _comments(out.read_text()) == _comments(src.read_text())
    assert load_model(out).design["RS.length"] == 0.21
    # YAML 1.1 (the loader) reads 1e-05 as text: small and huge floats are written as numbers
    text = commented_text("# c\na: 1  # one\nb: [1, 2]\n", {"a": 1e-05, "b": [3e20, -2.5e-300]})
    assert parse_text(text) == {"a": 1e-05, "b": [3e20, -2.5e-300]} and "# one" in text and "# c" in text
