"""The one compiler switch: numba's ``njit`` with kinprop's options and an on-disk cache.

Compiled kernels are cached in a per-user cache directory (``KINPROP_CACHE_DIR``, else the
platform's user cache dir, e.g. ``~/.cache/kinprop/numba``), never next to the installed
sources, which may be read-only. ``NUMBA_CACHE_DIR`` set by the user wins. The same source
runs uncompiled (plain Python) when ``NUMBA_DISABLE_JIT=1``: one implementation either way.
"""

from __future__ import annotations

import os
from functools import partial
from pathlib import Path

import platformdirs


def cache_dir() -> Path:
    """Where compiled kernels are kept (created on first use)."""
    env = os.environ.get("NUMBA_CACHE_DIR") or os.environ.get("KINPROP_CACHE_DIR")
    return Path(env) if env else Path(platformdirs.user_cache_dir("kinprop")) / "numba"


os.environ.setdefault("NUMBA_CACHE_DIR", str(cache_dir()))

import numba  # noqa: E402  (after the cache directory is set)

numba.config.CACHE_DIR = os.environ["NUMBA_CACHE_DIR"]

#: ``@njit``: compiled, cached on disk, numpy's floating-point error model, GIL released
njit = partial(numba.njit, cache=True, error_model="numpy", nogil=True)
prange = numba.prange
get_num_threads = numba.get_num_threads

__all__ = ["cache_dir", "get_num_threads", "njit", "prange"]
