"""Couplings in model files: the ``couplings`` section, read and written in the file's units.

A coupling ties the coordinate of a driven joint ``a`` to that of a joint ``b``
(:class:`kinprop.model.Coupling`, MuJoCo's ``<equality><joint>``)::

    couplings:
      GEAR:
        joints: [A, B]          # q_A - q_A0 = c0 + c1 (q_B - q_B0) + ... + c4 (q_B - q_B0)^4
        coef: [0, 2]            # c0..c4; 1 to 5 numbers, the missing ones are 0
        q0: [0, 0]              # optional offsets q_A0, q_B0 (default 0)

In the file every number is in the model's units: ``q0`` in each joint's unit and ``c_k`` in
``[q_A] / [q_B]^k`` (degrees for a revolute in a ``deg`` model, the length unit for a slide).
Inside (solver units, radians) ``c_k = c_k,file * f_A / f_B^k`` with ``f = pi/180`` for an
angle in a degree model, else 1 (:func:`coef_factors`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from kinprop.constraints.coupling import N_COEF
from kinprop.engine.units import coef_factors
from kinprop.errors import Problem
from kinprop.model import Coupling, Joint, Model
from kinprop.spatial import Array


def build_couplings(
    specs: Mapping[str, Any], joints: Mapping[str, Joint], deg: bool, file: str
) -> tuple[tuple[Coupling, ...], dict[str, Array], list[Problem]]:
    """Couplings, their coefficients (design values ``NAME.coef``, solver units) and the
    problems of the file's ``couplings`` section (coefficient count; the joints are checked
    by :func:`kinprop.model.mechanism.validate_couplings`)."""
    out: list[Coupling] = []
    values: dict[str, Array] = {}
    problems: list[Problem] = []
    for name, c in specs.items():
        a, b = c.joints
        if not 1 <= len(c.coef) <= N_COEF:
            text = f"expected 1 to {N_COEF} coefficients c0..c4, found {len(c.coef)}"
            problems.append(Problem(f"couplings.{name}.coef", text, file))
            continue
        F, fa, fb = coef_factors(joints.get(a), joints.get(b), deg)
        coef = np.zeros(N_COEF)
        coef[: len(c.coef)] = c.coef
        q0 = c.q0 if c.q0 is not None else (0.0, 0.0)
        values[f"{name}.coef"] = coef * F
        out.append(Coupling(name, a, b, float(q0[0]) * fa, float(q0[1]) * fb))
    return tuple(out), values, problems


def couplings_to_data(model: Model, shift: Mapping[str, float] | None = None) -> dict[str, Any]:
    """The ``couplings`` section of ``model`` in its units (empty: no couplings). ``shift``
    (solver units) is subtracted from the offsets, for a file whose coordinates are zero at
    the model's current ones (hardpoint style): ``q0 - shift``."""
    mech = model.mechanism
    deg = model.units.get("angle") == "deg"
    out: dict[str, Any] = {}
    for c in mech.couplings:
        F, fa, fb = coef_factors(mech.joint(c.joint_a), mech.joint(c.joint_b), deg)
        coef = np.asarray(model.design[f"{c.name}.coef"], float) / F
        spec: dict[str, Any] = {"joints": [c.joint_a, c.joint_b], "coef": coef.tolist()}
        qa0 = c.q_a0 - (shift or {}).get(c.joint_a, 0.0)
        qb0 = c.q_b0 - (shift or {}).get(c.joint_b, 0.0)
        if qa0 != 0.0 or qb0 != 0.0:
            spec["q0"] = [qa0 / fa, qb0 / fb]
        out[c.name] = spec
    return out


__all__ = ["build_couplings", "coef_factors", "couplings_to_data"]
