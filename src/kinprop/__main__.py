"""``python -m kinprop`` and the ``kinprop`` command.

First chooses how the kernels run (``KINPROP_JIT``, :mod:`kinprop.jit`), before any kernel is
imported: one-shot commands use ``auto`` (compiled when the kernel cache is complete, else
uncompiled while the cache is built in the background: a first run never waits for a compile
it does not need; ``propagate`` and ``assemble`` of a small model run uncompiled, which is
faster than importing numba and loading the cache); commands that solve many variants
compile. A ``KINPROP_JIT`` already set is the user's choice and is kept.
"""

from __future__ import annotations

import os
import sys
from importlib.util import find_spec

#: commands whose work is many solves: compiling first pays for itself
BATCH_COMMANDS = frozenset({"sweep", "study", "tolerance", "serve"})
#: commands that solve one model once (``kinprop.jit.one_solve``)
ONE_SOLVE_COMMANDS = frozenset({"propagate", "assemble"})
#: the optional libraries a batch command cannot start without (its extra): when one is
#: missing the command says which extra to install, and nothing is announced before that
NEEDS = {"sweep": ("pandas",), "study": ("pandas", "pyarrow"), "serve": ("fastapi",)}


def _has(module: str) -> bool:
    try:
        return find_spec(module) is not None
    except (ImportError, ValueError):
        return False


def main() -> None:
    command = next((a for a in sys.argv[1:] if not a.startswith("-")), "")
    # ``kinprop``, ``--help``, ``--version`` and ``COMMAND --help`` run no kernel: they import
    # neither numba nor the library (kinprop.cli loads a command's module when it runs)
    answers_only = not command or "--help" in sys.argv[1:]
    if "KINPROP_JIT" not in os.environ and not answers_only:
        os.environ["KINPROP_JIT"] = "on" if command in BATCH_COMMANDS else "auto"
        if all(_has(m) for m in NEEDS.get(command, ())):
            from kinprop.cli.warmup import announce

            announce()
    if command in ONE_SOLVE_COMMANDS and not answers_only:  # read by the rule of ``auto``
        from kinprop import jit

        jit.one_solve = True
    from kinprop.cli import main as cli_main

    cli_main()


if __name__ == "__main__":
    main()
