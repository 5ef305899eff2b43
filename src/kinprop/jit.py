"""The one compiler switch: numba's ``njit`` with kinprop's options and an on-disk cache.

Compiled kernels are cached in a per-user cache directory (``KINPROP_CACHE_DIR``, else the
platform's user cache dir, e.g. ``~/.cache/kinprop/numba``), in one folder per version of the
kernel sources, never next to the installed sources, which may be read-only. The same source
runs uncompiled (plain Python) when ``NUMBA_DISABLE_JIT=1``: one implementation either way.
"""

from __future__ import annotations

import hashlib
import os
from functools import partial
from pathlib import Path

import platformdirs

#: packages whose sources are compiled into the kernels
_KERNEL_SOURCES = ("spatial.py", "jit.py", "joints", "constraints", "kinematics", "solver")


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


os.environ["NUMBA_CACHE_DIR"] = os.environ.get("KINPROP_NUMBA_CACHE_DIR") or str(cache_dir())

import numba  # noqa: E402  (after the cache directory is set)

numba.config.CACHE_DIR = os.environ["NUMBA_CACHE_DIR"]

#: ``@njit``: compiled, cached on disk, numpy's floating-point error model, GIL released
njit = partial(numba.njit, cache=True, error_model="numpy", nogil=True)
prange = numba.prange
get_num_threads = numba.get_num_threads

__all__ = ["cache_dir", "get_num_threads", "njit", "prange"]
