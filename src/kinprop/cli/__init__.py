"""Command-line interface. Each command lives in its own module and registers on ``app``.

:func:`main` first chooses how the kernels run (``KINPROP_JIT``, kinprop.jit): one-shot
commands use ``auto`` (compiled when the kernel cache is complete, else uncompiled while the
cache is built in the background: a first run never waits for a compile it does not need);
commands that solve many variants (``sweep``, ``study``, ``tolerance``, ``serve``) compile.
"""

from __future__ import annotations

import os
import sys
from typing import Any

#: commands whose work is many solves: compiling first pays for itself
BATCH_COMMANDS = frozenset({"sweep", "study", "tolerance", "serve"})


def main() -> None:
    command = next((a for a in sys.argv[1:] if not a.startswith("-")), "")
    if "KINPROP_JIT" not in os.environ:  # the user's choice wins (and is not announced)
        os.environ["KINPROP_JIT"] = "on" if command in BATCH_COMMANDS else "auto"
        from kinprop.cli import warmup

        warmup.announce()
    _app()(prog_name="kinprop")


def _app() -> Any:
    from kinprop.cli import check, convert, examples, importer, paper, plot, sensitivity, serve, solve, study, sweep  # noqa: F401  # noqa: F401  (each registers its commands)
    from kinprop.cli.app import app

    return app


def __getattr__(name: str) -> Any:
    if name == "app":
        return _app()
    raise AttributeError(f"module 'kinprop.cli' has no attribute {name!r}")


__all__ = ["app", "main"]
