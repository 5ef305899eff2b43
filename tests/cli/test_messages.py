"""Messages a new user met (issue 19 item 9): each names the file or option the user gave,
exits 2, and says what to do.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from cli_run import one_error_line, run_kinprop
from typer.testing import CliRunner

from kinprop.cli import app

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def test_yaml_syntax_error_names_the_file_and_line(tmp_path):
    bad = tmp_path / "syn.yaml"
    bad.write_text("kinprop: 1\nname: x\nunits: {length: m\n  angle: rad}\n")
    line = one_error_line(run_kinprop("check", bad))
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


def test_sub_step_wording_states_the_per_sub_step_cap(tmp_path):
    """A change no sub-step can solve (the crank moved with only the coupler angle free): the
    message counts the iterations of all sub-steps and names the cap each had, the --max-iter
    given (not "1000 iterations" beside a default of 50). The counts are the solve's own."""
    import re

    import kinprop as kp

    assembled = kp.propagate(kp.load_model(EXAMPLES / "fourbar.yaml"), {}).after
    sol = kp.propagate(assembled, {"O2.q": [70.0]}, free=("A.q",), max_iter=7).result
    assert not sol.converged
    path = tmp_path / "assembled.yaml"
    kp.dump_model(assembled, path)
    r = CliRunner().invoke(app, ["propagate", str(path), "--set", "O2.q=70", "--free", "A.q", "--max-iter", "7",
                                 "--no-continuation", "-q"])  # fmt: skip
    assert r.exit_code == 1, r.output
    m = re.search(r"not converged after (\d+) iterations in all \((\d+) sub-steps of the change, each allowed "
                  r"--max-iter 7\)", r.stdout)  # fmt: skip
    assert m, r.stdout
    iterations, substeps = int(m[1]), int(m[2])
    assert substeps > 1 and substeps * 7 >= iterations > 7  # more than one sub-step's cap, none above its own
    assert m[0] in sol.message and sol.iterations == iterations  # the Python API's solve says the same
