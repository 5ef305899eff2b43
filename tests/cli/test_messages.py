"""Messages a new user met (issue 19 item 9): each names the file or option the user gave,
exits 2, and says what to do.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from cli_run import invoke_kinprop, one_error_line
from typer.testing import CliRunner

from kinprop.cli import app

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def test_yaml_syntax_error_names_the_file_and_line(tmp_path):
    bad = tmp_path / "syn.yaml"
    bad.write_text("kinprop: 1\nname: x\nunits: {length: m\n  angle: rad}\n")
    line = one_error_line(invoke_kinprop("check", bad))
    assert line.startswith(f"error: {bad}: line 4, column ") and "unicode string" not in line


def test_unknown_input_names_the_file(tmp_path):
    text = (EXAMPLES / "double_wishbone_hardpoints.yaml").read_text()
    bad = tmp_path / "inp.yaml"
    bad.write_text(text.replace("inputs: [LCA]", "inputs: [NOPE]"))
    r = CliRunner().invoke(app, ["check", str(bad)])
    assert r.exit_code == 2
    assert f"{bad}: inputs[0]: unknown joint 'NOPE'" in r.stderr


def test_unwritable_output_names_the_output_not_a_temporary(tmp_path):
    target = Path("/proc/kinprop-out.yaml")
    r = CliRunner().invoke(app, ["assemble", str(EXAMPLES / "fourbar.yaml"), "-o", str(target)])
    assert r.exit_code == 2, r.output
    assert str(target) in r.stderr and ".tmp" not in r.stderr


@pytest.mark.parametrize(
    ("model", "change", "held"),
    [("double_wishbone_hardpoints.yaml", "UCA.q=5", "LCA"), ("fourbar.yaml", "O4.q=90", "O2")],
)
def test_a_coordinate_tied_to_a_held_input_is_refused_up_front(model, change, held):
    """The 1-dof mechanism's only freedom is taken by the held input: the second coordinate
    cannot move; the message says which input holds it and how to free it, and freeing it works."""
    r = CliRunner().invoke(app, ["propagate", str(EXAMPLES / model), "--set", change])
    assert r.exit_code == 2, r.output
    assert f"not independent while {held} is held" in r.stderr and f"--free q --free {held}.q" in r.stderr
    r = CliRunner().invoke(app, ["propagate", str(EXAMPLES / model), "--set", change, "--free", "q", "--free",
                                 f"{held}.q"])  # fmt: skip
    assert r.exit_code == 0, r.output
