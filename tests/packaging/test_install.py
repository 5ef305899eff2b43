"""A real package (issue 11, item 5): the wheel built by ``pip wheel .`` carries the example
models, and an installed kinprop — outside the checkout, without the optional extras — runs
``kinprop paper``, ``kinprop --version`` and ``kinprop examples``.

The wheel is installed with ``pip install --no-deps --target`` and run with that directory
first on PYTHONPATH (the test environment supplies numpy, scipy, ...), from a working directory
outside the repository; a sitecustomize hook blocks the optional extras as in
tests/cli/test_extras.py.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
EXTRAS_HOOK = """
import sys
class _NotInstalled:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in {"pandas", "pyarrow", "matplotlib", "plotly", "dask", "distributed"}:
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
sys.meta_path.insert(0, _NotInstalled())
"""


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> tuple[Path, dict[str, str]]:
    tmp = tmp_path_factory.mktemp("install")
    wheels = tmp / "wheels"
    pip = [sys.executable, "-m", "pip", "--disable-pip-version-check", "-q"]
    p = subprocess.run([*pip, "wheel", str(ROOT), "--no-deps", "-w", str(wheels)], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr[-3000:]
    (wheel,) = wheels.glob("kinprop-*.whl")
    site = tmp / "site"
    p = subprocess.run(
        [*pip, "install", "--no-deps", "--target", str(site), str(wheel)], capture_output=True, text=True
    )
    assert p.returncode == 0, p.stderr[-3000:]
    hook = tmp / "hook"
    hook.mkdir()
    (hook / "sitecustomize.py").write_text(EXTRAS_HOOK)
    # the installed copy's kernels would be a cache of their own (numba keys it by the source
    # path): compiling them again would test numba, not the wheel; they run as Python here
    # (tests/cli/test_first_run.py checks that uncompiled and compiled give the same numbers)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(site), str(hook)]), "KINPROP_JIT": "off"}
    return site, env


def _run(installed, *args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    site, env = installed
    return subprocess.run([str(site / "bin" / "kinprop"), *args], capture_output=True, text=True, env=env, cwd=cwd,
                          timeout=300)  # fmt: skip


def test_installed_package_is_the_wheel(installed, tmp_path) -> None:
    site, env = installed
    code = "import kinprop, kinprop.resources as r; print(kinprop.__file__); print(r.examples_dir())"
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    module, examples = p.stdout.split()
    assert Path(module).is_relative_to(site) and Path(examples) == site / "kinprop" / "examples"
    shipped = sorted(x.name for x in (site / "kinprop" / "examples").iterdir() if x.is_file())
    assert shipped == sorted(x.name for x in (ROOT / "examples").iterdir() if x.suffix in (".yaml", ".py"))


def test_paper_version_and_examples_from_the_wheel(installed, tmp_path) -> None:
    p = _run(installed, "--version", cwd=tmp_path)
    assert p.returncode == 0 and p.stdout.strip() == "kinprop 0.1.0"
    p = _run(installed, "paper", "--json", cwd=tmp_path)
    assert p.returncode == 0, p.stderr[-3000:]
    assert '"agree": ' in p.stdout and "Traceback" not in p.stderr
    import json

    obj = json.loads(p.stdout)
    assert obj["agree"] == obj["total"] > 50
    p = _run(installed, "examples", "--copy", "examples", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "examples" / "mcpherson.yaml").read_text() == (ROOT / "examples" / "mcpherson.yaml").read_text()
    # the README's first command, from the copied examples
    p = _run(installed, "assemble", "examples/mcpherson.yaml", "-o", "assembled.yaml", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    p = _run(installed, "sweep", "examples/fourbar.yaml", "--drive", "O2=0:360:4", cwd=tmp_path)
    assert p.returncode == 2 and p.stderr.strip() == (
        "error: this command needs pandas, which is not installed: pip install 'kinprop[data]'"
    )
