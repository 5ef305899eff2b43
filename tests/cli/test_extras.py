"""Optional extras fail clearly (issue 11, item 4).

Every command runs in a fresh process in which the optional libraries cannot be imported (a
``sitecustomize`` meta-path hook makes ``import pandas`` and the others raise
ModuleNotFoundError, exactly as on a plain ``pip install kinprop``). Each command either works
or prints one ``error:`` line naming the extra to install, exit 2 — never a traceback.
"""

from __future__ import annotations

import os

import pytest
from cli_run import one_error_line, run_kinprop

HOOK = '''
import sys
BLOCKED = set({blocked!r})


class _NotInstalled:
    """Pretend the optional extras are not installed."""

    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in BLOCKED:
            raise ModuleNotFoundError(f"No module named {{name!r}}", name=name)
        return None


sys.meta_path.insert(0, _NotInstalled())
'''

ALL_EXTRAS = ["pandas", "pyarrow", "matplotlib", "plotly", "dask", "distributed"]
SET = "J12.s_j=-2.8,0.2,0.1"

#: (arguments, None when the command must work, else the extra its error line names)
COMMANDS = [
    (["check", "{ex}/fourbar.yaml"], None),
    (["assemble", "{ex}/fourbar.yaml", "-o", "{tmp}/a.yaml"], None),
    (["propagate", "{ex}/slider_crank.yaml", "--set", SET, "--csv", "{tmp}/p.csv", "--json"], None),
    (["sensitivity", "{ex}/slider_crank.yaml", "--wrt", "J12.s_j", "--of", "J01.q", "--of", "hardpoint:J12.i"], None),
    (["sensitivity", "{ex}/slider_crank.yaml", "--wrt", "J12.s_j", "--json"], None),
    (["tolerance", "{ex}/fourbar.yaml", "--tolerance", "B.s_i[0]=5e-4", "--of", "O4.q"], None),
    (["convert", "{ex}/slider_crank.yaml", "--to", "hardpoints"], None),
    (["paper", "--table", "table4"], None),
    (["propagate", "{ex}/slider_crank.yaml", "--set", SET, "--plot", "{tmp}/p.png"], "plot"),
    (["propagate", "{ex}/slider_crank.yaml", "--set", SET, "--plot", "{tmp}/p.html"], "plot"),
    (["plot", "{ex}/fourbar.yaml", "-o", "{tmp}/f.png"], "plot"),
    (["plot", "{ex}/fourbar.yaml", "-o", "{tmp}/f.html"], "plot"),
    (["sweep", "{ex}/fourbar.yaml", "--drive", "O2=0:360:4"], "data"),
    (["study", "{ex}/fourbar.yaml", "--vary", "B.s_i[0]=0.39:0.41", "--samples", "4", "-o", "{tmp}/s"], "data"),
    (["tolerance", "{ex}/fourbar.yaml", "--tolerance", "B.s_i[0]=5e-4", "--of", "O4.q", "--mc", "10"], "data"),
]


def _env(tmp_path, blocked: list[str]) -> dict[str, str]:
    hook = tmp_path / "hook"
    hook.mkdir(exist_ok=True)
    (hook / "sitecustomize.py").write_text(HOOK.format(blocked=blocked))
    return {"PYTHONPATH": os.pathsep.join(p for p in (str(hook), os.environ.get("PYTHONPATH")) if p)}


def test_hook_blocks_the_extras(tmp_path) -> None:
    """The hook itself: pandas cannot be imported under it (else the test below proves nothing)."""
    import subprocess
    import sys

    p = subprocess.run(
        [sys.executable, "-c", "import pandas"], capture_output=True, text=True, env=_env(tmp_path, ALL_EXTRAS)
    )
    assert p.returncode == 1 and "ModuleNotFoundError: No module named 'pandas'" in p.stderr


@pytest.mark.parametrize(("args", "extra"), COMMANDS, ids=[" ".join(c[0][:1] + c[0][-2:]) for c in COMMANDS])
def test_command_without_extras(args, extra, examples, tmp_path) -> None:
    argv = [a.format(ex=examples, tmp=tmp_path) for a in args]
    p = run_kinprop(*argv, env=_env(tmp_path, ALL_EXTRAS), timeout=120)
    if extra is None:
        assert p.returncode == 0, p.stderr[-3000:]
        assert "Traceback" not in p.stderr
    else:
        line = one_error_line(p)
        assert f"pip install 'kinprop[{extra}]'" in line, line
        assert not (tmp_path / "s").exists()


def test_dask_scheduler_needs_the_dask_extra(examples, tmp_path) -> None:
    argv = ["study", examples / "fourbar.yaml", "--vary", "B.s_i[0]=0.39:0.41", "-o", tmp_path / "s"]
    p = run_kinprop(*argv, "--scheduler", "tcp://127.0.0.1:1", env=_env(tmp_path, ["dask", "distributed"]))
    assert "pip install 'kinprop[dask]'" in one_error_line(p)


def test_no_compile_notice_before_a_missing_extra(examples, tmp_path) -> None:
    """``kinprop sweep`` without pandas, on a first run (empty kernel cache): the one line says
    which extra to install; nothing announces a minute of compiling first (issue 19 item 11)."""
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k not in ("KINPROP_JIT", "NUMBA_DISABLE_JIT")}
    env |= _env(tmp_path, ALL_EXTRAS) | {"KINPROP_CACHE_DIR": str(tmp_path / "cache")}
    cmd = [sys.executable, "-m", "kinprop", "sweep", str(examples / "fourbar.yaml"), "--drive", "O2=0:360:4"]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=120, env=env)  # the entry point: __main__
    line = one_error_line(p)
    assert "pip install 'kinprop[data]'" in line and "compil" not in p.stderr
