"""Units at the user boundary: the library works in radians; files and the CLI may use degrees."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from kinprop.engine import compile as compile_engine
from kinprop.model import Model, parse_address
from kinprop.propagation.hardpoints import is_global


def angle_indices(model: Model, joint: str) -> list[int]:
    """Indices of a joint's coordinates that are angles (tree joints only)."""
    if joint not in compile_engine(model.mechanism).topology.tree_joints:
        return []
    return list(model.mechanism.joint(joint).jtype.angle_indices)


def changes_to_internal(model: Model, changes: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Convert coordinate values given in the model's angle unit (``deg``) to radians.

    Only ``JOINT.q`` / ``JOINT.q[k]`` angle components change; design variables are unitless
    here (lengths stay in the model's length unit).
    """
    if model.units.get("angle") != "deg":
        return dict(changes)
    out: dict[str, np.ndarray] = {}
    for text, value in changes.items():
        v = np.array(value, dtype=float)
        if is_global(text.split("[")[0]):  # global points and axes: model length unit, no angles
            out[text] = v
            continue
        addr = parse_address(text)
        if addr.field == "q" and addr.joint in model.mechanism._joints:
            idx = angle_indices(model, addr.joint)
            if addr.index is None:
                v.ravel()[[i for i in idx if i < v.size]] = np.radians(v.ravel()[[i for i in idx if i < v.size]])
            elif addr.index in idx:
                v = np.radians(v)
        out[text] = v
    return out
