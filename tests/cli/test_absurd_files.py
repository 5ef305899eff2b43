"""A model file with an absurd number is refused at load time (issue 19 item 6).

A point of 1e300 made ``kinprop check`` exit 0 with a numpy overflow warning and extra
degrees of freedom. Now: exit 2, one located line, nothing else on stderr; the limit is
1e6 times the file's length scale (the median size of its lengths), as for ``--set``.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from cli_run import one_error_line, run_kinprop

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.mark.parametrize(
    ("example", "old", "new", "location"),
    [
        ("fourbar.yaml", "s_i: [0.15, 0, 0]", "s_i: [1e300, 0, 0]", "joints.A.s_i"),
        ("double_wishbone_hardpoints.yaml", "point: [-35.56, 786.511, -118.11]", "point: [-35.56, 1e300, -118.11]",
         "joints.LBJ.point"),
        ("double_wishbone_hardpoints.yaml", "[223.266, 307.086, 0.0]", "[223.266, 307.086, 1e300]",
         "joints.LCA.pivots.front"),
    ],
)  # fmt: skip
def test_absurd_number_is_refused_at_load(tmp_path, example, old, new, location):
    text = (EXAMPLES / example).read_text()
    assert old in text
    bad = tmp_path / example
    bad.write_text(text.replace(old, new, 1))
    line = one_error_line(run_kinprop("check", bad))
    assert f"{bad}: {location}: 1e+300 is beyond 1e+06 times the model's length scale" in line
    assert "Warning" not in line and "site-packages" not in line


def test_the_limit_follows_the_file_unit(tmp_path):
    """The limit is 1e6 times the median size of the file's lengths, in the file's unit: a
    millimetre model (L of the order of 800 mm) accepts 7e8 mm and refuses 9e8 mm."""
    text = (EXAMPLES / "double_wishbone_hardpoints.yaml").read_text()
    ok = tmp_path / "ok.yaml"
    ok.write_text(text.replace("[223.266, 307.086, 0.0]", "[223.266, 307.086, 7e8]", 1))
    assert run_kinprop("check", ok).returncode == 0
    bad = tmp_path / "bad.yaml"
    bad.write_text(text.replace("[223.266, 307.086, 0.0]", "[223.266, 307.086, 9e8]", 1))
    line = one_error_line(run_kinprop("check", bad))
    limit = float(line.split("the limit is ")[1].split(")")[0])
    assert 7e8 < limit < 9e8
