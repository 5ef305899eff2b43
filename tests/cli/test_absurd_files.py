"""A model file with an absurd number is refused at load time (issue 19 item 6).

A point of 1e300 made ``kinprop check`` exit 0 with a numpy overflow warning and extra
degrees of freedom. Now: exit 2, one located line, nothing else on stderr; the limit is
1e6 times the file's length scale (the median size of its lengths), as for ``--set``. The
refusals run in a fresh process of their own (one for the three files: nothing else on
stderr, no numpy warning), the limit's two checks in the test process.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from cli_run import invoke_kinprop, one_error_line, run_kinprop_cases

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


#: (example, text, the absurd text that replaces it, the location the error line names)
CASES = [
    ("fourbar.yaml", "s_i: [0.15, 0, 0]", "s_i: [1e300, 0, 0]", "joints.A.s_i"),
    ("double_wishbone_hardpoints.yaml", "point: [-35.56, 786.511, -118.11]", "point: [-35.56, 1e300, -118.11]",
     "joints.LBJ.point"),
    ("double_wishbone_hardpoints.yaml", "[223.266, 307.086, 0.0]", "[223.266, 307.086, 1e300]",
     "joints.LCA.pivots.front"),
]  # fmt: skip


@pytest.fixture(scope="module")
def checked(tmp_path_factory) -> list[tuple[Path, subprocess.CompletedProcess[str]]]:
    """``kinprop check`` of each edited file, all in one fresh process."""
    files = []
    for k, (example, old, new, _) in enumerate(CASES):
        text = (EXAMPLES / example).read_text()
        assert old in text
        bad = tmp_path_factory.mktemp(f"absurd{k}") / example
        bad.write_text(text.replace(old, new, 1))
        files.append(bad)
    return list(zip(files, run_kinprop_cases([["check", f] for f in files]), strict=True))


@pytest.mark.parametrize("k", range(len(CASES)), ids=[f"{c[0]}-{c[3]}" for c in CASES])
def test_absurd_number_is_refused_at_load(checked, k):
    bad, p = checked[k]
    line = one_error_line(p)
    assert f"{bad}: {CASES[k][3]}: 1e+300 is beyond 1e+06 times the model's length scale" in line
    assert "Warning" not in line and "site-packages" not in line


def test_the_limit_follows_the_file_unit(tmp_path):
    """The limit is 1e6 times the median size of the file's lengths, in the file's unit: a
    millimetre model (L of the order of 800 mm) accepts 7e8 mm and refuses 9e8 mm."""
    text = (EXAMPLES / "double_wishbone_hardpoints.yaml").read_text()
    ok = tmp_path / "ok.yaml"
    ok.write_text(text.replace("[223.266, 307.086, 0.0]", "[223.266, 307.086, 7e8]", 1))
    assert invoke_kinprop("check", ok).returncode == 0
    bad = tmp_path / "bad.yaml"
    bad.write_text(text.replace("[223.266, 307.086, 0.0]", "[223.266, 307.086, 9e8]", 1))
    line = one_error_line(invoke_kinprop("check", bad))
    limit = float(line.split("the limit is ")[1].split(")")[0])
    assert 7e8 < limit < 9e8
