"""Building the kernel cache once after installation: ``python -m kinprop.cli.warmup``.

The first command-line run with an empty kernel cache (kinprop.jit) runs its job uncompiled
and starts this module in a background process, which compiles every kernel entry point
(single solves, batches serial and threaded, sequences, poses, sensitivities, the statics and
their rates) into the cache and then writes the cache's completion marker; later runs load the
compiled kernels. A lock file keeps concurrent first runs from starting more than one build.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from rich.console import Console

#: a build older than this (seconds) is taken as dead (its lock is removed)
STALE_LOCK = 600.0


def _lock() -> Path:
    from kinprop.jit import cache_dir

    return cache_dir() / "building.lock"


def start_background_build() -> bool:
    """Start the cache build in a detached process unless one is running; True if started."""
    lock = _lock()
    lock.parent.mkdir(parents=True, exist_ok=True)
    if lock.exists() and time.time() - lock.stat().st_mtime > STALE_LOCK:
        lock.unlink(missing_ok=True)
    try:
        fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
    except FileExistsError:
        return False
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_DISABLE_JIT"} | {"KINPROP_JIT": "on"}
    proc = subprocess.Popen(
        [sys.executable, "-m", "kinprop.cli.warmup", "--lock", str(lock)],
        env=env,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    os.write(fd, f"{proc.pid}\n".encode())
    os.close(fd)
    return True


def announce() -> None:
    """Say once, on stderr, when this run does not use compiled kernels or compiles them."""
    from kinprop import jit

    if jit.is_warm():
        return
    err = Console(stderr=True, highlight=False)
    compiled = jit.wanted() == "compiled"  # known without choosing (and importing numba) now
    if not compiled and jit.MODE == "auto":
        if start_background_build():
            err.print("kinprop: first run of this version: its kernels are being compiled in the background "
                      "(about a minute, once); this run uses them uncompiled.", soft_wrap=True)  # fmt: skip
    elif compiled:
        err.print("kinprop: first run of this version: compiling the kernels this command needs "
                  "(up to a minute, once) ...", soft_wrap=True)  # fmt: skip


def _statics_rates(model: Any, engine: Any) -> None:
    """Compile the statics' rates (design derivatives) and the reduced stiffness."""
    from kinprop.analysis.statics import input_columns, model_laws
    from kinprop.engine.statics import PointForces, reduced_stiffness
    from kinprop.engine.statics_rates import design_rates

    st = engine.state_of(model)
    loads = PointForces.empty()
    cols, _ = input_columns(engine, model.mechanism.inputs)
    laws, held = model_laws(model, engine, st)
    design_rates(engine, st, loads, [engine.n_coordinates], cols, laws, held)
    if cols:
        reduced_stiffness(engine, st, loads, cols, laws)


def build() -> None:
    """Compile every kernel entry point into the cache and write its completion marker."""
    import numpy as np

    import kinprop as kp
    from kinprop.analysis import output_names
    from kinprop.jit import warm_marker
    from kinprop.resources import examples_dir

    for name, change in (("slider_crank.yaml", {"J12.s_j": [-2.8, 0.2, 0.1]}), ("stewart.yaml", {"L3.length": 0.52})):
        model = kp.load_model(examples_dir() / name)
        engine = kp.compile(model)
        kp.propagate(model, change, engine=engine)
        kp.mobility(model)
        assembled = kp.assemble(model, engine=engine).after
        kp.statics(assembled, engine=engine)  # the statics' compiled call
        _statics_rates(assembled, engine)  # their rates' compiled call and the reduced stiffness
        sol = engine.propagate(change, ("q", "s"))
        engine.kinematics(sol.state)
        engine.retract(sol.state, np.zeros(engine.n_columns))
        batch = engine.stack([engine.reference] * 2)
        engine.solve_batch(batch, threads=False)
        engine.solve_batch(batch, threads=True)
        q = engine.target(f"{model.mechanism.joints[0].name}.q")
        if q.group == "q" and q.size == 1:
            engine.solve_sequence(engine.reference, [q.key], np.array([[0.0]]) + engine.get(engine.reference, q.key))
        kp.evaluate_outputs(model, output_names(model, engine)[:1], engine=engine)  # the compiled outputs
    warm_marker().parent.mkdir(parents=True, exist_ok=True)
    warm_marker().write_text(f"kinprop kernels compiled {time.strftime('%Y-%m-%d %H:%M:%S')}\n")


def main(argv: list[str]) -> int:
    lock = Path(argv[argv.index("--lock") + 1]) if "--lock" in argv else None
    try:
        build()
    finally:
        if lock is not None:
            lock.unlink(missing_ok=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
