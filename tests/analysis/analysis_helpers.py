"""Helpers of the analysis tests: assembled examples, named points, re-solve finite differences."""

from __future__ import annotations

import dataclasses
import warnings
from pathlib import Path

import numpy as np

from kinprop import Model, SingularityWarning, assemble, load_model, propagate
from kinprop.analysis.metrics import WheelSpec
from kinprop.model import Mechanism

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

#: McPherson wheel points (wheel body frame, m): the paper gives no wheel, so these are made up
#: for the tests — a wheel centre below and outboard of the strut, spin axis along +y.
MCPHERSON_WHEEL = {
    "wheel_centre": (0.0, 0.15, -0.1),
    "spin_axis": (0.0, 1.15, -0.1),
    "contact_patch": (0.0, 0.15, -0.4),
}
#: steering axis of the McPherson: strut top mount (on the chassis) to the lower ball joint
MCPHERSON_STEER = {"wheel": WheelSpec(steering_axis=("hardpoint:ST.i", "hardpoint:RS.j"))}


def solved(path: Path, tol: float = 1e-12) -> Model:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SingularityWarning)
        prop = assemble(load_model(path), tol=tol)
    assert prop.converged, prop.result.message
    return prop.after


def with_points(model: Model, body: str, points: dict[str, tuple[float, float, float]]) -> Model:
    """The model with named points added to ``body`` (a new, frozen mechanism)."""
    mech = model.mechanism
    bodies = tuple(
        dataclasses.replace(b, points=b.points + tuple(points.items())) if b.name == body else b for b in mech.bodies
    )
    return dataclasses.replace(model, mechanism=Mechanism(bodies, mech.joints, mech.name))


def resolve_fd(
    model: Model,
    f,
    column: str,
    h: float,
    free=("q",),
    weights=None,
    tol: float = 1e-10,
) -> np.ndarray:
    """Central difference of ``f`` over full re-solves (``propagate``) with design column
    ``column`` (``KEY[k]`` or a scalar ``KEY``) moved by ``+-h``."""
    key, _, idx = column.partition("[")
    base = np.array(model.design[key], dtype=float)
    vals = []
    for sign in (1.0, -1.0):
        v = base.copy()
        if idx:
            v.flat[int(idx[:-1])] += sign * h
        else:
            v = v + sign * h
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", SingularityWarning)
            prop = propagate(model, {key: v}, free, weights=weights, tol=tol)
        assert prop.converged, prop.result.message
        vals.append(f(prop.after))
    return (vals[0] - vals[1]) / (2.0 * h)
