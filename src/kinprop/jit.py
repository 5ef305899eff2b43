"""The one compiler switch: numba's ``njit`` with kinprop's options and an on-disk cache.

Compiled kernels are cached in a per-user cache directory (``KINPROP_CACHE_DIR``, else the
platform's user cache dir, e.g. ``~/.cache/kinprop/numba``), in one folder per version of the
kernel sources, never next to the installed sources, which may be read-only.

The decorators (:data:`kernel`, :data:`inlined`, :func:`njit`) do not compile anything, nor
import numba: they register the function, and the process chooses how every kernel runs at
the first kernel call (:func:`bind`, once): compiled by numba (imported then), or the same
source run as plain Python ("uncompiled"): one implementation either way. Binding rewrites, in every
loaded ``kinprop`` module, the names of the registered kernels (and :data:`COMPILED`,
:data:`GELSD`, :data:`LAPACK_INT`) to what runs, so that compiled kernels call
compiled kernels; a kernel held elsewhere forwards its calls.

``KINPROP_JIT`` chooses: ``on`` (the default: compiled), ``off`` (never compiled; also
``NUMBA_DISABLE_JIT=1``), ``auto`` (what the command line uses for one-shot commands):
uncompiled for one solve (:data:`one_solve`: ``propagate``, ``assemble``) of a model with at
most :data:`SMALL_MODEL` joint coordinates, which is faster than importing numba and loading
the cache; otherwise compiled when the cache holds a complete build (:func:`is_warm`), else
uncompiled for this process, while the cache is built in the background
(``kinprop.cli.warmup``), so a first run never waits for a compile.
"""

from __future__ import annotations

import hashlib
import os
import sys
import threading
from collections.abc import Callable
from functools import cache, partial
from pathlib import Path
from typing import Any

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


@cache
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
if os.environ.get("NUMBA_DISABLE_JIT", "0").strip() not in ("", "0"):
    MODE = "off"
#: under ``auto``: a one-solve job of a model with at most this many joint coordinates runs
#: uncompiled (every shipped example has at most 18; measured in docs/performance.md)
SMALL_MODEL = 20
#: set by the command line for the one-solve commands (``propagate``, ``assemble``)
one_solve = False
_model_size: int | None = None  # the largest model compiled so far (joint coordinates)

os.environ["NUMBA_CACHE_DIR"] = os.environ.get("KINPROP_NUMBA_CACHE_DIR") or str(cache_dir())

# what the kernels see; rewritten by :func:`bind` (here and in every module that imported them)
#: whether the kernels are compiled (a constant to the compiled code)
COMPILED = False
#: LAPACK's ``dgelsd`` (the SVD least-squares solver of ``numpy.linalg.lstsq``) as numba binds it
#: for its own ``lstsq``: an external symbol of numba's helper library, so kernels that call it
#: stay allocation-free and cacheable (None uncompiled: ``numpy.linalg.lstsq`` is called)
GELSD: Any = None
#: the integer type of ``dgelsd``'s ``rank`` output
LAPACK_INT: Any = "int32"

_bound: str | None = None  # None (not chosen yet), "python" or "compiled"
_binding = threading.RLock()  # the first kernel calls of two threads choose once
_KERNELS: list[_Kernel] = []


class _Kernel:
    """A kernel before the process has chosen how kernels run: forwards to what runs."""

    def __init__(self, py_func: Callable[..., Any], options: dict[str, Any]) -> None:
        self.py_func = py_func
        self.options = options
        self.target: Callable[..., Any] | None = None
        self.__name__ = py_func.__name__
        self.__qualname__ = py_func.__qualname__
        self.__module__ = py_func.__module__
        self.__doc__ = py_func.__doc__
        self.__wrapped__ = py_func

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        if self.target is None:
            bind()
        return self.target(*args, **kwargs)  # type: ignore[misc]

    def __getattr__(self, name: str) -> Any:  # numba's attributes (``targetoptions`` ..): bind first
        if name.startswith("__") or name in ("target", "py_func", "options"):
            raise AttributeError(name)
        if self.target is None:
            bind()
        return getattr(self.target, name)

    def __repr__(self) -> str:
        return f"<kinprop kernel {self.__module__}.{self.__qualname__} ({_bound or 'not bound yet'})>"


def njit(func: Callable[..., Any] | None = None, **options: Any) -> Any:
    """``@njit``: compiled, cached on disk, numpy's floating-point error model, GIL released
    (``@njit(parallel=True)`` passes numba options)."""
    if func is None:
        return partial(njit, **options)
    k = _Kernel(func, options)
    with _binding:
        _KERNELS.append(k)
        if _bound is None:
            return k
        k.target = _runnable(k, _bound)
    return k.target  # a module imported after the choice holds what runs


#: ``@kernel``: an ``@njit`` function that allocates nothing and only reads and writes the arrays
#: it is given, compiled without numba's reference counting (its ``_nrt=False`` option). Every
#: view it takes (``R[j, 0]``, ``Phi[row0:]``, ``ws[k]``) is borrowed from its caller, so counting
#: references is pure cost: two atomic calls per view, two thirds of an ``evaluate`` (measured:
#: 3.1 us -> 1.0 us per Stewart evaluation, benchmarks/). A kernel that allocates fails to
#: compile ("NRT required"), so the rule is checked by the compiler. Numba versions without the
#: option get a plain ``@njit`` (same results, slower).
kernel = partial(njit, _nrt=False)
#: ``@inlined``: a ``@kernel`` with one call site in the solve loop, inlined into its caller when
#: that is compiled (numba's ``inline="always"``). Numba passes every array as its seven to
#: nine fields, so a call with the tables and the workspace moves hundreds of arguments
#: (measured: 0.12 us of an empty ``evaluate``; inlining forward kinematics and the twists
#: saves 0.08 us of 0.92 per Stewart evaluation).
inlined = partial(kernel, inline="always")


@cache
def _numba() -> Any:
    """numba, imported (after the cache directory is set) and configured."""
    import numba
    import numba.core.cpu

    numba.config.CACHE_DIR = os.environ["NUMBA_CACHE_DIR"]
    return numba


def _runnable(k: _Kernel, how: str) -> Callable[..., Any]:
    if how == "python":
        return k.py_func
    numba = _numba()
    options = dict(k.options)
    if not hasattr(numba.core.cpu.CPUTargetOptions, "_nrt"):
        options.pop("_nrt", None)
    return numba.njit(cache=True, error_model="numpy", nogil=True, **options)(k.py_func)


def wanted() -> str:
    """``"compiled"`` or ``"python"``: the rule of the module docstring, for what is known now."""
    if MODE != "auto":
        return "compiled" if MODE == "on" else "python"
    if one_solve and _model_size is not None and _model_size <= SMALL_MODEL:
        return "python"
    return "compiled" if is_warm() else "python"


def bind(how: str | None = None) -> str:
    """Choose how the kernels run (default :func:`wanted`), once per process; returns the choice."""
    with _binding:
        if _bound is None:
            _bind(how or wanted())
    if how not in (None, _bound):
        raise RuntimeError(f"the kernels of this process already run {_bound}")
    return _bound  # type: ignore[return-value]


def _bind(how: str) -> None:
    global _bound, COMPILED, GELSD, LAPACK_INT
    old = {"COMPILED": COMPILED, "GELSD": GELSD, "LAPACK_INT": LAPACK_INT}
    if how == "compiled":
        numba = _numba()
        from numba.np.linalg import _LAPACK, F_INT_nptype

        COMPILED, GELSD, LAPACK_INT = True, _LAPACK().numba_ez_gelsd(numba.types.float64), F_INT_nptype
    new = {"COMPILED": COMPILED, "GELSD": GELSD, "LAPACK_INT": LAPACK_INT}
    swap: dict[int, Any] = {}
    for k in _KERNELS:
        k.target = swap[id(k)] = _runnable(k, how)
    for name, mod in list(sys.modules.items()):
        if (name != "kinprop" and not name.startswith("kinprop.")) or name == __name__ or mod is None:
            continue
        d = mod.__dict__
        for key, value in list(d.items()):
            if id(value) in swap:
                d[key] = swap[id(value)]
            elif key in old and value is old[key]:
                d[key] = new[key]
    _bound = how


def note_model(n_coordinates: int) -> None:
    """``kp.compile`` tells the size of each model before its first kernel call (read by the
    rule of ``auto`` when the first kernel call chooses)."""
    global _model_size
    _model_size = max(n_coordinates, _model_size or 0)


def num_threads() -> int:
    """Threads a batch is split over: numba's thread count (``NUMBA_NUM_THREADS``, default the
    cores), read from its configuration without starting numba's threading layer; 1 when the
    kernels run uncompiled (as Python they hold the GIL)."""
    return max(1, int(_numba().config.NUMBA_NUM_THREADS)) if bind() == "compiled" else 1


def __getattr__(name: str) -> Any:
    if name == "JIT":  # whether this process's kernels are compiled (chooses now if not chosen)
        return bind() == "compiled"
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "COMPILED",
    "GELSD",
    "LAPACK_INT",
    "MODE",
    "SMALL_MODEL",
    "bind",
    "cache_dir",
    "inlined",
    "is_warm",
    "kernel",
    "njit",
    "note_model",
    "num_threads",
    "wanted",
    "warm_marker",
]
