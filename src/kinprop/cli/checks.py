"""Option checks run before any work: every invalid option is one located ``error:`` line.

Each command validates its numbers, repeated assignments and output paths here, before it
loads the model or creates a file, so a bad option never costs a sweep or leaves a
half-created directory (issue 11, items 1 and 6).
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable, Sequence
from pathlib import Path

from kinprop.errors import AddressError
from kinprop.io.arguments import address_key as _key

#: upper bounds that keep one command's work and memory finite
MAX_ITER = 100_000
MAX_SAMPLES = 10_000_000


def check_tol(tol: float, option: str = "--tol") -> None:
    """A stopping tolerance is a positive finite number."""
    if not (math.isfinite(tol) and tol > 0):
        raise AddressError(f"{option} {tol!r}: expected a positive finite number (e.g. 1e-10)")


#: ``assemble``/``propagate``'s tolerance when no ``--tol`` is given: a true assembly
DEFAULT_TOL = 1e-10


def method_and_tol(method: str | None, tol: float | None) -> tuple[str, float]:
    """``--method`` and ``--tol`` of ``assemble``/``propagate`` (docs/analysis/weights.md): a
    method given is used (``least-change`` or ``paper``, ``kinprop.engine.METHODS``). Without
    one, a ``--tol`` given is the paper's stopping rule ``||Phi|| < TOL``, which defines the
    paper's iteration's end point, so it selects ``paper``; no ``--tol`` either: the least
    change (the closest assembly, which no tolerance defines) to :data:`DEFAULT_TOL`."""
    if method is not None and method not in ("least-change", "paper"):
        raise AddressError(f"--method {method!r}: expected least-change or paper")
    if tol is not None:
        check_tol(tol)
    return method or ("least-change" if tol is None else "paper"), DEFAULT_TOL if tol is None else tol


def check_int(option: str, value: int, low: int, high: int) -> None:
    """``low <= value <= high``."""
    if not low <= value <= high:
        raise AddressError(f"{option} {value}: expected an integer from {low} to {high:,}")


def check_set_not_free(changes: Iterable[str], free: Sequence[str] | None, option: str = "--set") -> None:
    """A changed variable is never free: naming it in --free too is a contradiction."""
    changes = list(changes)
    changed = {_key(a)[0]: a for a in changes}
    for f in free or []:
        base, _, comp = f.strip().partition("[")
        for a in changes if base.startswith("element:") else ():  # an element point or one component
            b, _, c = a.strip().partition("[")
            if b == base and (not c or not comp or c == comp):
                raise AddressError(f"--free {f!r}: {a} is also given by {option}; a changed variable is never free")
        if "." in f and _key(f)[0] in changed:
            raise AddressError(
                f"--free {f!r}: {changed[_key(f)[0]]} is also given by {option}; a changed variable is never free"
            )


def check_outputs(
    inputs: Sequence[Path | None], outputs: Sequence[tuple[str, Path | None]], directories: Sequence[str] = ()
) -> None:
    """Output paths that would destroy an input or each other, or cannot be written, are refused.

    ``outputs``: (option, path) pairs; options in ``directories`` name an output directory
    (``study -o``), the others a file. Nothing is created here: a missing parent directory is
    an error (not silently made), as is a path that is a directory, an input model, or the
    same file as another output.
    """
    ins = [(p, p.resolve()) for p in inputs if p is not None]
    taken: dict[Path, str] = {}
    for option, path in outputs:
        if path is None:
            continue
        where = f"{option} {str(path)!r}"
        real = path.resolve()
        for given, inp in ins:
            if real == inp or (path.exists() and given.exists() and os.path.samefile(path, given)):
                raise AddressError(f"{where}: is the input model {str(given)!r}; refusing to overwrite it")
        if real in taken:
            raise AddressError(f"{where}: the same file as {taken[real]}; give each output its own name")
        taken[real] = option
        if option in directories:
            if path.exists() and not path.is_dir():
                raise AddressError(f"{where}: exists and is not a directory")
        elif path.is_dir():
            raise AddressError(f"{where}: is a directory; expected a file name")
        parent = real.parent
        if not parent.is_dir():
            raise AddressError(f"{where}: the directory {str(parent)!r} does not exist")
        target = path if path.exists() else parent
        if not os.access(target, os.W_OK):
            raise AddressError(f"{where}: {str(target)!r} is not writable")


def check_suffix(option: str, path: Path | None, suffixes: Sequence[str]) -> None:
    """The output format follows the name: refuse an unknown suffix up front."""
    if path is not None and path.suffix.lower() not in suffixes:
        raise AddressError(f"{option} {str(path)!r}: expected a name ending in {' or '.join(suffixes)}")


__all__ = [
    "DEFAULT_TOL",
    "MAX_ITER",
    "MAX_SAMPLES",
    "check_int",
    "check_outputs",
    "check_set_not_free",
    "check_suffix",
    "check_tol",
    "method_and_tol",
]
