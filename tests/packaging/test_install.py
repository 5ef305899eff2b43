"""A real package (issue 11 item 5, issue 19 item 2): the wheel built by ``pip wheel .`` carries
the example models, and kinprop installed from it into a clean virtualenv — outside the
checkout — runs ``kinprop paper``, ``--version``, ``examples --copy``, the README's import and
Python snippet, and the import guide's commands, its sweep included.

The virtualenv is new (``python -m venv --without-pip``; the wheel goes in with this
interpreter's pip, ``--python VENV --no-deps``). Its dependencies are not downloaded again: a
``.pth`` file puts this test environment's site-packages *after* the virtualenv's own (numpy,
scipy, pandas, ... for the commands; a path line, so the editable checkout's own ``.pth`` there
is not read and ``import kinprop`` is the wheel's — the first test checks it). That keeps the
test under half a minute and off the network, and still proves what the issue asked: the
package's files, entry point and shipped examples, installed as a user installs them. Runs
"without the extras" add a sitecustomize hook that blocks them, as tests/cli/test_extras.py.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import sysconfig
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
def venv(tmp_path_factory) -> Path:
    """A new virtualenv with the wheel installed (and this environment's packages after its own)."""
    tmp = tmp_path_factory.mktemp("install")
    wheels = tmp / "wheels"
    pip = [sys.executable, "-m", "pip", "--disable-pip-version-check", "-q"]
    p = subprocess.run([*pip, "wheel", str(ROOT), "--no-deps", "-w", str(wheels)], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr[-3000:]
    (wheel,) = wheels.glob("kinprop-*.whl")
    env_dir = tmp / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(env_dir)], check=True)
    python = env_dir / "bin" / "python"
    clean = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}  # else pip sees the checkout's kinprop
    p = subprocess.run([*pip, "--python", str(python), "install", "--no-deps", str(wheel)], capture_output=True,
                       text=True, env=clean)  # fmt: skip
    assert p.returncode == 0, p.stderr[-3000:]
    own = subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"],
                         capture_output=True, text=True, check=True, env=clean).stdout.strip()  # fmt: skip
    assert any(Path(own).glob("kinprop-*.dist-info")), "the wheel is installed in the new virtualenv"
    Path(own, "zz_test_environment.pth").write_text(sysconfig.get_path("purelib") + "\n")
    return env_dir


def _env(venv: Path, extras: bool) -> dict[str, str]:
    """The user's environment: no PYTHONPATH (the checkout is not on it); without the extras, a
    hook that blocks them. The installed copy's kernels would be a cache of their own (numba
    keys it by the source path): compiling them again would test numba, not the wheel; they run
    as Python here (tests/cli/test_first_run.py checks that uncompiled and compiled agree)."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "KINPROP_JIT")}
    env |= {"KINPROP_JIT": "off", "PATH": f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}"}
    if not extras:
        hook = venv / "hook"
        hook.mkdir(exist_ok=True)
        (hook / "sitecustomize.py").write_text(EXTRAS_HOOK)
        env["PYTHONPATH"] = str(hook)
    return env


@pytest.fixture(scope="module")
def installed(venv) -> tuple[Path, dict[str, str]]:
    """The installed package without the optional extras: ``(venv, environment)``."""
    return venv, _env(venv, extras=False)


def _run(installed, *args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    venv, env = installed
    return subprocess.run([str(venv / "bin" / "kinprop"), *args], capture_output=True, text=True, env=env, cwd=cwd,
                          timeout=300)  # fmt: skip


def test_installed_package_is_the_wheel(installed, tmp_path) -> None:
    venv, env = installed
    code = "import kinprop, kinprop.resources as r; print(kinprop.__file__); print(r.examples_dir())"
    p = subprocess.run([str(venv / "bin" / "python"), "-c", code], capture_output=True, text=True, env=env,
                       cwd=tmp_path)  # fmt: skip
    assert p.returncode == 0, p.stderr
    module, examples = p.stdout.split()
    site = Path(module).parents[1]
    assert site.is_relative_to(venv) and Path(examples) == site / "kinprop" / "examples"
    shipped_dir = site / "kinprop" / "examples"
    shipped = sorted(x.relative_to(shipped_dir).as_posix() for x in shipped_dir.rglob("*")
                     if x.is_file() and "__pycache__" not in x.parts)  # fmt: skip
    want = sorted(x.relative_to(ROOT / "examples").as_posix() for x in (ROOT / "examples").rglob("*")
                  if x.is_file() and x.suffix in (".yaml", ".py", ".json", ".xml", ".md"))  # fmt: skip
    assert shipped == want and "chrono/DoubleWishbone.json" in shipped and "mjcf/robotiq_2f85_kinematic.xml" in shipped


def test_paper_version_and_examples_from_the_wheel(installed, tmp_path) -> None:
    p = _run(installed, "--version", cwd=tmp_path)
    assert p.returncode == 0 and p.stdout.strip() == "kinprop 0.1.0"
    p = _run(installed, "paper", "--json", cwd=tmp_path)
    assert p.returncode == 0, p.stderr[-3000:]
    assert '"agree": ' in p.stdout and "Traceback" not in p.stderr
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


def test_readme_and_import_guide_commands_from_the_wheel(installed, tmp_path) -> None:
    """Issue 19 item 2: after ``kinprop examples --copy examples`` from the wheel, the README's
    import and the import guide's commands (those without the optional extras) run."""
    p = _run(installed, "examples", "--copy", "examples", cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    for sub in ("chrono/DoubleWishbone.json", "chrono/MultiLink.json", "mjcf/cassie_left_leg_kinematic.xml"):
        assert (tmp_path / "examples" / sub).read_bytes() == (ROOT / "examples" / sub).read_bytes()
    commands = [
        ["import", "examples/chrono/DoubleWishbone.json", "-o", "dw.yaml"],  # README
        ["import", "examples/mjcf/robotiq_2f85_kinematic.xml", "-o", "robotiq.yaml"],
        [
            "sensitivity",
            "examples/chrono/DoubleWishbone.json",
            "--wrt",
            "UCA_U.s_j",
            "--wrt",
            "TIEROD.s_j",
            "--of",
            "camber",
            "--of",
            "toe",
            "--free",
            "UCA.q",
            "--free",
            "LCA_U.q",
        ],
        ["check", "dw.yaml", "--assemble"],
    ]
    for args in commands:
        p = _run(installed, *args, cwd=tmp_path)
        assert p.returncode == 0, (args, p.stderr[-3000:])
    assert (tmp_path / "dw.yaml").is_file() and (tmp_path / "robotiq.yaml").is_file()


def test_readme_snippet_and_guide_sweep_with_the_extras(venv, tmp_path) -> None:
    """With the extras (from the test environment): the README's Python snippet and the import
    guide's camber/toe sweep, as documented, from the examples the wheel copies out."""
    env = _env(venv, extras=True)
    run = dict(capture_output=True, text=True, env=env, cwd=tmp_path, timeout=300)
    p = subprocess.run([str(venv / "bin" / "kinprop"), "examples", "--copy", "examples"], **run)
    assert p.returncode == 0, p.stderr
    readme = (ROOT / "README.md").read_text()
    snippet = readme.split("```python\n", 1)[1].split("```", 1)[0]
    assert "import kinprop as kp" in snippet
    p = subprocess.run([str(venv / "bin" / "python"), "-c", snippet], **run)
    assert p.returncode == 0, p.stderr[-3000:]
    assert p.stdout.startswith("converged ")  # prop.result.status, as the README prints it
    guide = (ROOT / "docs/guide/importing.md").read_text()
    sweep = next(c for c in guide.split("```bash\n")[1:] if c.startswith("kinprop sweep examples/chrono"))
    argv = sweep.split("```", 1)[0].split("\nkinprop ")[0].replace("\\\n", " ").split()
    p = subprocess.run([str(venv / "bin" / "kinprop"), *argv[1:]], **run)
    assert p.returncode == 0, p.stderr[-3000:]
    assert "41 steps: 41 converged, 0 failed" in p.stdout and (tmp_path / "camber_toe.png").stat().st_size > 10_000
