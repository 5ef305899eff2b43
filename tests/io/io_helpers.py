"""Shared helpers of the io tests: comparing two models' hardpoints."""

from __future__ import annotations

from typing import Any

import numpy as np

from kinprop.io.hardpoints import model_to_hardpoints
from kinprop.model import Model


def _numbers(tree: Any, prefix: str = "") -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    if isinstance(tree, dict):
        for k, v in tree.items():
            out.update(_numbers(v, f"{prefix}.{k}" if prefix else str(k)))
    elif isinstance(tree, list) and tree and not any(isinstance(x, (str, dict, bool)) for x in tree):
        out[prefix] = np.array(tree, dtype=float)  # a vector or a matrix
    elif isinstance(tree, float):
        out[prefix] = np.array([tree])
    return out


def hardpoint_numbers(data: dict[str, Any]) -> dict[str, np.ndarray]:
    """Every point, axis and length of a hardpoint file's bodies and joints, keyed by location
    (not the coordinates ``q`` of the configuration they describe)."""
    numbers = _numbers({"bodies": data["bodies"], "joints": data["joints"]})
    return {k: v for k, v in numbers.items() if not k.endswith(".q")}


def hardpoint_difference(a: Model | dict[str, Any], b: Model | dict[str, Any]) -> float:
    """Largest absolute difference between two models' (or files') hardpoints; same keys required.
    Models are compared at their poses (re-zeroed), files as written."""
    na = hardpoint_numbers(a if isinstance(a, dict) else model_to_hardpoints(a, keep_coordinates=False))
    nb = hardpoint_numbers(b if isinstance(b, dict) else model_to_hardpoints(b, keep_coordinates=False))
    assert na.keys() == nb.keys(), set(na) ^ set(nb)
    return max(float(np.max(np.abs(na[k] - nb[k]))) for k in na)
