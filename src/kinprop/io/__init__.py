"""Model files: schema, validation, loading, writing.

``load_model`` and ``model_from_data`` (:mod:`kinprop.io.files`) dispatch to the importers
(:mod:`kinprop.imports`), which themselves build on :mod:`kinprop.io.hardpoints`; they are
exported lazily (PEP 562) so that importing either package first works.
"""

from __future__ import annotations

import importlib
from typing import Any

from kinprop.io.hardpoints import model_to_hardpoints
from kinprop.io.loader import parse_text
from kinprop.io.writer import atomic_write, dump_model, model_to_data

_LAZY = {"load_model": "kinprop.io.files", "model_from_data": "kinprop.io.files"}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'kinprop.io' has no attribute {name!r}")


__all__ = [
    "atomic_write",
    "dump_model",
    "load_model",
    "model_from_data",
    "model_to_data",
    "model_to_hardpoints",
    "parse_text",
]
