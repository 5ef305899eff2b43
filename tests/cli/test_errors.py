"""Every error is a located one-liner with exit 2, checked before work starts; JSON is strict;
user text is printed literally (issue 11, item 6)."""

from __future__ import annotations

import json
import shutil

import pytest
from cli_run import invoke_kinprop, one_error_line, run_kinprop

FOURBAR_TOL = ["tolerance", "{ex}/fourbar.yaml", "--tolerance", "B.s_i[0]=5e-4", "--of", "O4.q"]

#: (arguments, text the one error line must contain: the option and the value at fault)
BAD = [
    (["sweep", "{ex}/fourbar.yaml", "--drive", "O2=0:360:4", "--out", "point:coupler.Q"], "point:coupler.Q"),
    (["sweep", "{ex}/fourbar.yaml", "--drive", "O2=0:360:4", "--out", "O9.q"], "O9.q"),
    (["sweep", "{ex}/fourbar.yaml", "--drive", "O2=0:360:4", "--x", "O4.q"], "--x"),
    (["sweep", "{ex}/fourbar.yaml", "--drive", "O2=0:360:4", "--tol", "nan"], "--tol nan"),
    (["sweep", "{ex}/fourbar.yaml", "--drive", "O2=0:360:4", "-o", "{tmp}/x.txt"], "-o"),
    (["propagate", "{ex}/fourbar.yaml", "--tol", "-1"], "--tol -1"),
    (["propagate", "{ex}/fourbar.yaml", "--max-iter", "-5"], "--max-iter -5"),
    (["propagate", "{ex}/fourbar.yaml", "--set", "O2.q=70", "--free", "O2.q"], "--free 'O2.q'"),
    (["propagate", "{ex}/fourbar.yaml", "--set", "O2.q=70", "--set", "O2.q=80"], "already given"),
    (["propagate", "{ex}/fourbar.yaml", "--set", "B.s_i=0.4,0,0", "--set", "B.s_i[0]=0.5"], "already given"),
    (["propagate", "{ex}/fourbar.yaml", "--bogus"], "No such option: --bogus"),
    (["propagate", "{ex}/fourbar.yaml", "--max-iter", "x"], "--max-iter"),
    (["propagate"], "Missing argument"),
    (["propagate", "{ex}/fourbar.yaml", "-o", "{tmp}"], "-o"),
    (["propagate", "{ex}/fourbar.yaml", "--csv", "{tmp}"], "is a directory"),
    (["propagate", "{ex}/fourbar.yaml", "-o", "/nonexistent-kinprop/dir/out.yaml"], "does not exist"),
    (["propagate", "{ex}/fourbar.yaml", "--plot", "{tmp}/x.gif"], "--plot"),
    (
        ["study", "{ex}/fourbar.yaml", "--vary", "B.s_i[0]=0.39:0.41", "--vary", "B.s_i[0]=0.3:0.5", "-o", "{tmp}/s"],
        "already varied",
    ),
    (["study", "{ex}/fourbar.yaml", "--vary", "B.s_i[0]=0.39:0.41", "--method", "sobol", "-o", "{tmp}/s"], "--method"),
    ([*FOURBAR_TOL, "--mc", "-3"], "--mc -3"),
    ([*FOURBAR_TOL, "--tolerance", "B.s_i[0]=1e-3"], "already given"),
    (["sensitivity", "{ex}/fourbar.yaml", "--wrt", "B.s_i", "--weight", "q=0"], "--weight"),
    (["check", "{tmp}/missing.yaml"], "missing.yaml"),
    (["convert", "{ex}/fourbar.yaml", "--to", "frames", "-o", "{tmp}/x.txt"], "-o"),
    (["plot", "{ex}/fourbar.yaml", "-o", "{tmp}/x.gif"], "-o"),
    (["paper", "--table", "table9"], "--table 'table9'"),
    (["examples", "--copy", "{ex}"], "would overwrite"),
]


@pytest.mark.parametrize(("args", "needle"), BAD, ids=[" ".join(a[0][3:6]) or a[0][0] for a in BAD])
def test_bad_option_is_one_located_line(args, needle, examples, tmp_path) -> None:
    argv = [a.format(ex=examples, tmp=tmp_path) for a in args]
    line = one_error_line(invoke_kinprop(*argv))  # in this process: what it prints, its exit code
    assert needle in line, line
    assert not (tmp_path / "s").exists()


def _strict(text: str) -> object:
    def refuse(name: str) -> None:
        raise AssertionError(f"bare {name} in JSON")

    return json.loads(text, parse_constant=refuse)


def test_json_has_no_nan_or_infinity(examples) -> None:
    """With nothing free (the fourbar has no lengths) the singular-value ratio is NaN: it is null in JSON."""
    p = invoke_kinprop("propagate", examples / "fourbar.yaml", "--set", "O2.q=70", "--free", "l", "--json")
    assert p.returncode == 1, p.stderr
    obj = _strict(p.stdout)
    assert obj["status"] == "no_free"
    assert obj["continuation"]["singularity_ratio"] is None
    for args in (
        ["propagate", examples / "double_wishbone.yaml", "--set", "TR.length=5000", "--json"],
        # past its toggles the double rocker cannot follow: failed steps (NaN values) in the JSON
        ["sweep", examples / "fourbar_double_rocker.yaml", "--drive", "O2=0:360:4", "--json"],
    ):
        p = invoke_kinprop(*args)
        assert p.returncode == 1, p.stderr
        _strict(p.stdout)


def test_user_text_is_printed_literally(examples, tmp_path) -> None:
    """Paths and names with rich markup or emoji codes are printed as written."""
    weird = tmp_path / "[red]x :smile: [bold]"
    weird.mkdir()
    model = weird / "m[i].yaml"
    shutil.copy(examples / "fourbar.yaml", model)
    out = weird / "[green]out.yaml"
    p = invoke_kinprop("assemble", model, "-o", out)
    assert p.returncode == 0, p.stderr
    assert f"wrote {out}" in p.stdout
    assert f"assemble {model}" in p.stdout.replace("\n", "")
    line = one_error_line(invoke_kinprop("check", weird / "[b]missing :smile:.yaml"))
    assert "[b]missing :smile:.yaml" in line and "😄" not in line


def test_piped_output_is_not_wrapped(examples) -> None:
    """Output to a pipe: whole lines, no wrapping at 80 columns, no colour codes."""
    p = run_kinprop("propagate", examples / "double_wishbone.yaml", "--set", "TR.length=5000")
    assert p.returncode == 1
    message = [x for x in p.stdout.splitlines() if x.startswith("the change cannot be assembled")]
    assert len(message) == 1 and "singular value there" in message[0]
    assert "\x1b[" not in p.stdout + p.stderr
