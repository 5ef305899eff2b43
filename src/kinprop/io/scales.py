"""Warnings for numbers that are valid but implausible in the declared unit (issue 19 item 5).

A file that declares ``length: m`` but holds millimetre numbers, or a tyre radius given in
millimetres to a metre model, loads and solves; the results are then off by 1000 without a
word. These checks compare sizes with the model's length scale ``L``, the median size of its
positions, points and lengths (:func:`length_sizes`), and warn (they never refuse):

* ``L`` against the declared unit: a metre model with ``L`` above :data:`METRE_MAX` (a
  mechanism hundreds of metres across) or a millimetre model with ``L`` below
  :data:`MM_MIN` (under a millimetre) probably has the other unit's numbers;
* a wheel's loaded radius (its ``contact_patch`` point's distance from the spin axis) and
  every link ``length`` more than :data:`RATIO` times larger or smaller than ``L``.

:func:`warn_scales` issues each as a :class:`~kinprop.errors.UnitsWarning`: ``load_model`` and
``import_model`` call it, so the Python API warns as the CLI does (the CLI prints each as one
``warning:`` line).
"""

from __future__ import annotations

import warnings

import numpy as np

from kinprop.analysis.metrics import wheel_bodies
from kinprop.errors import UnitsWarning
from kinprop.model import Model

#: a metre model whose median length is above this (m) probably holds millimetres
METRE_MAX = 20.0
#: a millimetre model whose median length is below this (mm) probably holds metres
MM_MIN = 0.5
#: a radius or link length this many times larger or smaller than the length scale is suspect
RATIO = 100.0


def length_sizes(model: Model) -> list[float]:
    """Sizes of the model's fixed-body positions, named points, s' vectors and lengths (non-zero)."""
    mech = model.mechanism
    sizes = [float(np.linalg.norm(b.position)) for b in mech.bodies if b.fixed]
    sizes += [float(np.linalg.norm(v)) for b in mech.bodies for _, v in b.points]
    for j in mech.joints:
        for f in ("s_i", "s_j", "length"):
            if f in j.fields:
                sizes.append(float(np.linalg.norm(model.design[f"{j.name}.{f}"])))
    return [s for s in sizes if s > 0 and np.isfinite(s)]


def scale_warnings(model: Model) -> list[str]:
    """One line per implausible size (empty when the numbers fit the declared unit)."""
    sizes = length_sizes(model)
    if not sizes:
        return []
    unit = model.units.get("length", "m")
    L = float(np.median(sizes))
    out = []
    if unit == "m" and L > METRE_MAX:
        out.append(
            f"units: the model's lengths (median {L:.4g} m) look like millimetres, but the file declares "
            "length: m; every result would be 1000 times too large"
        )
    elif unit == "mm" and L < MM_MIN:
        out.append(f"units: the model's lengths (median {L:.4g} mm) look like metres, but the file declares length: mm")
    mech = model.mechanism
    for wheel in wheel_bodies(model):
        pts = {k: np.asarray(v, dtype=float) for k, v in mech.body(wheel).points}
        if "contact_patch" not in pts:
            continue
        a = pts["spin_axis"] - pts["wheel_centre"]
        a /= np.linalg.norm(a)
        v = pts["contact_patch"] - pts["wheel_centre"]
        radius = float(np.linalg.norm(v - (v @ a) * a))
        if radius > RATIO * L or radius * RATIO < L:
            out.append(
                f"units: wheel {wheel!r}: loaded radius {radius:.4g} {unit} is {radius / L:.3g} times the model's "
                f"length scale ({L:.4g} {unit}); is it in {unit}?"
            )
    for j in mech.joints:
        if "length" in j.fields:
            length = float(model.design[f"{j.name}.length"])
            if length > RATIO * L or length * RATIO < L:
                out.append(
                    f"units: joints.{j.name}.length = {length:.4g} {unit} is {length / L:.3g} times the model's "
                    f"length scale ({L:.4g} {unit}); is it in {unit}?"
                )
    return out


def warn_scales(model: Model, source: object, stacklevel: int = 2) -> None:
    """One :class:`~kinprop.errors.UnitsWarning` ``"SOURCE: ..."`` per line of
    :func:`scale_warnings`; ``stacklevel`` counts from the caller of this function."""
    for line in scale_warnings(model):
        warnings.warn(f"{source}: {line}", UnitsWarning, stacklevel=stacklevel + 1)


__all__ = ["length_sizes", "scale_warnings", "warn_scales"]
