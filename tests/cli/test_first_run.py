"""First run with an empty kernel cache (issue 9, start-up): a one-shot command answers
uncompiled at once, says so once, and builds the cache in the background; the uncompiled and
compiled kernels are one implementation and give the same numbers."""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from cli_run import invoke_kinprop, run_kinprop_cases

from kinprop.jit import JIT, kernel_version

ROOT = Path(__file__).resolve().parents[2]
SLIDER = ["propagate", ROOT / "examples" / "slider_crank.yaml", "--set", "J12.s_j=-2.8,0.2,0.1", "--free", "q"]


def _auto_env(cache: Path) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("KINPROP_JIT", "NUMBA_DISABLE_JIT")}
    return env | {"KINPROP_CACHE_DIR": str(cache)}


def _run(env: dict[str, str], *args: object) -> subprocess.CompletedProcess[str]:
    cmd = [sys.executable, "-m", "kinprop", *map(str, args)]  # the command's entry: kinprop.__main__
    return subprocess.run(cmd, capture_output=True, text=True, timeout=300, env=env)


def test_first_run_answers_uncompiled_and_builds_the_cache_in_the_background(tmp_path):
    env = _auto_env(tmp_path / "cache")
    t0 = time.perf_counter()
    p = _run(env, *SLIDER, "--json")
    elapsed = time.perf_counter() - t0
    assert p.returncode == 0, p.stderr
    assert "compiled in the background" in p.stderr and "uncompiled" in p.stderr
    locks = list((tmp_path / "cache").glob("*/building.lock"))
    assert len(locks) == 1, "one background build started"
    pid = int(locks[0].read_text().split()[0])
    try:
        again = _run(env, *SLIDER, "--json")  # a second first run does not start a second build
        assert again.returncode == 0 and "background" not in again.stderr
        assert json.loads(again.stdout) == json.loads(p.stdout)
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(pid, signal.SIGKILL)
    if not JIT:
        pytest.skip("this test process runs the kernels uncompiled (KINPROP_JIT)")
    compiled = invoke_kinprop(*SLIDER, "--json")  # this process compiles (KINPROP_JIT=on)
    assert compiled.returncode == 0, compiled.stderr
    a, b = json.loads(p.stdout), json.loads(compiled.stdout)
    assert a["coordinates"].keys() == b["coordinates"].keys()
    for joint, q in a["coordinates"].items():
        assert q == pytest.approx(b["coordinates"][joint], abs=1e-12), joint
    print(f"first run (uncompiled) {elapsed:.2f} s")


def test_a_complete_cache_is_used_without_a_note(tmp_path):
    cache = tmp_path / "cache"
    folder = cache / kernel_version()
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "complete").write_text("test\n")  # what kinprop.cli.warmup writes when it is done
    # the compiled kernels themselves: the test session's (compiled once, not again for this test)
    env = _auto_env(cache) | {"KINPROP_NUMBA_CACHE_DIR": os.environ["NUMBA_CACHE_DIR"]}
    p = _run(env, *SLIDER)
    assert p.returncode == 0 and p.stderr == "", p.stderr
    assert not list(cache.glob("*/building.lock"))


def test_a_larger_model_loads_the_compiled_kernels_from_a_complete_cache(tmp_path):
    """Under ``auto`` one solve of a model above ``kinprop.jit.SMALL_MODEL`` joint coordinates
    (a 25-link chain) uses the compiled kernels of a complete cache: numba is imported, nothing
    is announced, no build is started, and the answer is the uncompiled one."""
    from kinprop.builders import closed_chain_yaml
    from kinprop.jit import SMALL_MODEL

    if not JIT:
        pytest.skip("this test process runs the kernels uncompiled (KINPROP_JIT)")
    chain = tmp_path / "chain.yaml"
    chain.write_text(closed_chain_yaml(SMALL_MODEL + 5))
    cache = tmp_path / "cache"
    folder = cache / kernel_version()
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "complete").write_text("test\n")
    env = _auto_env(cache) | {"KINPROP_NUMBA_CACHE_DIR": os.environ["NUMBA_CACHE_DIR"]}
    args = ["propagate", chain, "--set", "D.length=0.6", "--free", "q", "--json"]
    p = subprocess.run([sys.executable, "-X", "importtime", "-m", "kinprop", *map(str, args)], capture_output=True,
                       text=True, timeout=300, env=env)  # fmt: skip
    assert p.returncode == 0, p.stderr[-2000:]
    lines = p.stderr.splitlines()
    modules = {line.rsplit("|", 1)[-1].strip() for line in lines if line.startswith("import time:")}
    assert "numba" in modules
    assert not [line for line in lines if not line.startswith("import time:")], p.stderr[-2000:]
    assert not list(cache.glob("*/building.lock"))
    off = _run(_auto_env(cache) | {"KINPROP_JIT": "off"}, *args)
    assert off.returncode == 0, off.stderr
    _close(json.loads(p.stdout), json.loads(off.stdout))


#: commands whose JSON must not depend on whether the kernels are compiled
UNCOMPILED = [
    ["check", ROOT / "examples" / "mcpherson.yaml", "--json"],
    ["propagate", ROOT / "examples" / "stewart.yaml", "--set", "L3.length=0.53", "--json"],
    ["propagate", ROOT / "examples" / "fourbar.yaml", "--set", "O2.q=75", "--json"],
]


@pytest.fixture(scope="module")
def uncompiled() -> list[subprocess.CompletedProcess[str]]:
    """:data:`UNCOMPILED`, all in one process that runs the kernels as Python (KINPROP_JIT=off)."""
    return run_kinprop_cases(UNCOMPILED, timeout=300, env={"KINPROP_JIT": "off"})


@pytest.mark.parametrize("k", range(len(UNCOMPILED)), ids=[f"{c[0]} {c[1].stem}" for c in UNCOMPILED])
def test_uncompiled_kernels_give_the_compiled_numbers(k, uncompiled):
    if not JIT:
        pytest.skip("this test process runs the kernels uncompiled (KINPROP_JIT)")
    off = uncompiled[k]
    on = invoke_kinprop(*UNCOMPILED[k])  # this process: compiled
    assert off.returncode == on.returncode == 0, (off.stderr, on.stderr)
    a, b = json.loads(off.stdout), json.loads(on.stdout)
    _close(a, b)


def _close(a, b, path="") -> None:
    if isinstance(a, dict):
        assert a.keys() == b.keys(), path
        for k in a:
            _close(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list):
        assert len(a) == len(b), path
        for k, (x, y) in enumerate(zip(a, b, strict=True)):
            _close(x, y, f"{path}[{k}]")
    elif isinstance(a, float):
        assert a == pytest.approx(b, rel=1e-9, abs=1e-12), path
    else:
        assert a == b, path
