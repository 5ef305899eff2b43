"""The stopping rule reads the residual in metres (length rows times U, distance rows times
U^2, U the metres per model unit), below max(tol, 16 eps (U L)^2): a mechanism in mm and the
same mechanism in m meet the same accuracy at the default tolerance.

Before this rule, distance rows ``d.d - l^2`` in mm^2 of a double wishbone scaled to twice its
size stalled at ~1e-10 to 5e-10 (measured) against the default 1e-10 without converging.
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest

from kinprop import Design, Mechanism, Model, assemble, compile, load_model
from kinprop.analysis.points import joint_hardpoints
from kinprop.engine.engine import ROUNDOFF
from kinprop.propagation.propagate import roundoff_floor


def scaled(model: Model, s: float) -> Model:
    d = {k: (v if k.endswith(("C_i", "C_j")) else np.asarray(v) * s) for k, v in model.design.items()}
    bodies = tuple(
        replace(
            b, position=tuple(np.array(b.position) * s), points=tuple((n, tuple(np.array(p) * s)) for n, p in b.points)
        )
        for b in model.mechanism.bodies
    )
    return Model(
        Mechanism(bodies, model.mechanism.joints, model.mechanism.name), Design(d), model.coordinates, model.units
    )


@pytest.mark.parametrize("s", [2.0, 4.0])
def test_large_mm_models_converge_at_the_default_tolerance(examples, s) -> None:
    m = scaled(load_model(examples / "double_wishbone.yaml"), s)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # singularity warnings are beside the point here
        a = assemble(m)
    assert a.converged, a.result.message
    assert a.result.residual < 1e-10
    # the same mechanism in metres reaches the same accuracy
    in_m = replace(scaled(m, 1e-3), units={**m.units, "length": "m"})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        b = assemble(in_m)
    assert b.converged, b.result.message
    tr_mm = np.linalg.norm(np.subtract(*(joint_hardpoints(a.after)[k] for k in ("TR.j", "TR.i"))))
    tr_m = np.linalg.norm(np.subtract(*(joint_hardpoints(b.after)[k] for k in ("TR.j", "TR.i"))))
    assert tr_mm * 1e-3 == pytest.approx(tr_m, rel=1e-12)
    # the solved lengths hold to ~1e-13 of the model's scale
    hp = joint_hardpoints(a.after)
    d = np.linalg.norm(np.array(hp["TR.j"]) - np.array(hp["TR.i"]))
    assert d == pytest.approx(float(a.after.design["TR.length"]), rel=1e-13)


def test_metre_scale_models_keep_the_plain_tolerance(examples) -> None:
    for name in ("slider_crank.yaml", "mcpherson.yaml", "stewart.yaml"):
        m = load_model(examples / name)
        assert roundoff_floor(m) < 1e-12
        assert roundoff_floor(m) == pytest.approx(ROUNDOFF * np.finfo(float).eps * compile(m).length_scale ** 2)
