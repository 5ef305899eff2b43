"""The signatures numba compiled into a kernel cache, per function, those with more than one
first: each extra signature of a kernel is a whole compile of it (and of what it inlines).

    python benchmarks/kernel_signatures.py [CACHE_DIR]

``CACHE_DIR``: a numba cache folder (default: this checkout's, ``kinprop.jit.cache_dir()``; a
test run with ``KINPROP_CACHE_DIR=DIR`` fills ``DIR/<kernel version>``). For each function the
arguments that differ between its signatures are printed, e.g. ``Literal[bool](True)`` against
``Literal[bool](False)``: a constant passed from another kernel is compiled once per value.
"""

from __future__ import annotations

import pickle
import sys
from pathlib import Path


def signatures(index: Path) -> list[tuple]:
    """The argument types of every overload a numba index file (``*.nbi``) lists."""
    with index.open("rb") as fh:
        pickle.load(fh)  # numba's version
        _, overloads = pickle.loads(fh.read())
    return [key[0] for key in overloads]


def differing(sigs: list[tuple]) -> list[str]:
    """``arg k: type, type`` for the arguments whose types differ between the signatures."""
    out = []
    for k, types in enumerate(zip(*sigs, strict=False)):
        if len({str(t) for t in types}) > 1:
            out.append(f"arg {k}: " + " | ".join(str(t) for t in types))
    return out


def main() -> int:
    if len(sys.argv) > 1:
        root = Path(sys.argv[1])
    else:
        from kinprop.jit import cache_dir

        root = cache_dir()
    rows = sorted(((signatures(f), f.stem.split("-")[0]) for f in root.rglob("*.nbi")), key=lambda r: -len(r[0]))
    for sigs, name in rows:
        print(f"{len(sigs)}  {name}")
        for line in differing(sigs) if len(sigs) > 1 else []:
            print(f"     {line[:300]}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
