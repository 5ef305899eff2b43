"""The one compiler switch: numba's ``njit`` with kinprop's options and an on-disk cache.

Compiled kernels are cached in a per-user cache directory (``KINPROP_CACHE_DIR``, else the
platform's user cache dir, e.g. ``~/.cache/kinprop/numba``), in one folder per version of the
kernel sources, never next to the installed sources, which may be read-only. The same source
runs uncompiled (plain Python) when ``NUMBA_DISABLE_JIT=1``: one implementation either way.

``KINPROP_JIT`` chooses: ``on`` (the default: compile on first use), ``off`` (never compile),
``auto`` (what the command line uses for one-shot jobs): compiled when the cache holds a
complete build (:func:`is_warm`), else uncompiled for this process, while the cache is built
in the background (``kinprop.cli.warmup``), so a first run never waits for a compile.
"""

from __future__ import annotations

import hashlib
import os
from functools import partial
from pathlib import Path

import platformdirs

#: packages whose sources are compiled into the kernels
_KERNEL_SOURCES = (
    "spatial.py",
    "jit.py",
    "joints",
    "constraints",
    "kinematics",
    "solver",
    "engine/outputs.py",
    "engine/statics_kernels.py",
)


def kernel_version() -> str:
    """Hash of the kernel sources. numba invalidates a cached function only when its own file
    changes, not when a function it calls does; one cache folder per source version does."""
    root = Path(__file__).parent
    h = hashlib.sha256()
    for name in _KERNEL_SOURCES:
        p = root / name
        for f in sorted(p.rglob("*.py")) if p.is_dir() else [p]:
            h.update(f.read_bytes())
    return h.hexdigest()[:16]


def cache_dir() -> Path:
    """Where compiled kernels are kept (created on first use), one folder per kernel version."""
    env = os.environ.get("KINPROP_CACHE_DIR")
    base = Path(env) if env else Path(platformdirs.user_cache_dir("kinprop")) / "numba"
    return base / kernel_version()


def warm_marker() -> Path:
    """Written by the warm-up (``kinprop.cli.warmup``) once every entry point is compiled."""
    return cache_dir() / "complete"


def is_warm() -> bool:
    """Whether the kernel cache holds a complete build of this version of the kernels."""
    return warm_marker().exists()


#: how this process runs the kernels: ``on``, ``off`` or ``auto`` (see the module docstring)
MODE = os.environ.get("KINPROP_JIT", "on").lower()
if MODE not in ("on", "off", "auto"):
    raise ValueError(f"KINPROP_JIT must be on, off or auto, found {MODE!r}")
_UNCOMPILED = MODE == "off" or (MODE == "auto" and not is_warm())

os.environ["NUMBA_CACHE_DIR"] = os.environ.get("KINPROP_NUMBA_CACHE_DIR") or str(cache_dir())

import numba  # noqa: E402  (after the cache directory is set)
import numba.core.cpu  # noqa: E402
from numba.np.linalg import _LAPACK, F_INT_nptype  # noqa: E402

numba.config.CACHE_DIR = os.environ["NUMBA_CACHE_DIR"]
if _UNCOMPILED:  # before any kernel is decorated; never exported to child processes
    numba.config.DISABLE_JIT = True

#: ``@njit``: compiled, cached on disk, numpy's floating-point error model, GIL released
njit = partial(numba.njit, cache=True, error_model="numpy", nogil=True)

#: ``@kernel``: an ``@njit`` function that allocates nothing and only reads and writes the arrays
#: it is given, compiled without numba's reference counting (its ``_nrt=False`` option). Every
#: view it takes (``R[j, 0]``, ``Phi[row0:]``, ``ws[k]``) is borrowed from its caller, so counting
#: references is pure cost: two atomic calls per view, two thirds of an ``evaluate`` (measured:
#: 3.1 us -> 1.0 us per Stewart evaluation, benchmarks/). A kernel that allocates fails to
#: compile ("NRT required"), so the rule is checked by the compiler. Numba versions without the
#: option get a plain ``@njit`` (same results, slower).
kernel = partial(njit, _nrt=False) if hasattr(numba.core.cpu.CPUTargetOptions, "_nrt") else njit
#: ``@inlined``: a ``@kernel`` with one call site in the solve loop, inlined into its caller when
#: that is compiled (numba's ``inline="always"``). Numba passes every array as its seven to
#: nine fields, so a call with the tables and the workspace moves hundreds of arguments
#: (measured: 0.12 us of an empty ``evaluate``; inlining forward kinematics and the twists
#: saves 0.08 us of 0.92 per Stewart evaluation).
inlined = partial(kernel, inline="always")
#: LAPACK's ``dgelsd`` (the SVD least-squares solver of ``numpy.linalg.lstsq``) as numba binds it
#: for its own ``lstsq``: an external symbol of numba's helper library, so kernels that call it
#: stay allocation-free and cacheable; ``LAPACK_INT`` is the integer type of its ``rank`` output.
GELSD = _LAPACK().numba_ez_gelsd(numba.types.float64)
LAPACK_INT = F_INT_nptype
prange = numba.prange
set_parallel_chunksize = numba.set_parallel_chunksize
#: False when numba's compiler is switched off (``NUMBA_DISABLE_JIT=1``): the kernels run as Python
JIT = not numba.config.DISABLE_JIT
get_num_threads = numba.get_num_threads

__all__ = [
    "GELSD",
    "JIT",
    "LAPACK_INT",
    "MODE",
    "cache_dir",
    "get_num_threads",
    "inlined",
    "is_warm",
    "kernel",
    "njit",
    "prange",
    "set_parallel_chunksize",
    "warm_marker",
]
