"""Force arrows of a load case (``kinprop loads --plot``): the loads applied to the bodies, the
rods' axial forces and the elements' forces on their body-j ends (red: tension, blue:
compression), and the other joints' reactions on their body j (grey), drawn over the model's
stick figure (:mod:`kinprop.plot.static`).

Every arrow is the force (the model's force unit) on the body it is drawn at, from that
point, scaled so that the largest is a quarter of the scene's size (the scale is printed in
the title); a couple has no arrow.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from kinprop.analysis.statics import Statics, applied_points
from kinprop.model.loads import LoadCase
from kinprop.spatial import Array

#: arrow kind -> (colour, legend text)
FORCE_STYLE = {
    "applied": ("#e7298a", "applied load"),
    "tension": ("#d62728", "tension (rod, element)"),
    "compression": ("#1f77b4", "compression (rod, element)"),
    "reaction": ("#555555", "joint reaction on body j"),
}
#: the largest arrow's length as a fraction of the scene's size
ARROW_FRACTION = 0.25


@dataclass(frozen=True)
class ForceArrow:
    """A force ``force`` (model force unit) acting at ``origin`` (global), of ``kind``
    (:data:`FORCE_STYLE`), named ``label``."""

    label: str
    kind: str
    origin: Array
    force: Array


def force_arrows(s: Statics, case: LoadCase | None) -> list[ForceArrow]:
    """The arrows of a statics record (module docstring); NaN (undetermined) forces are left out."""
    out = []
    st = s.state
    pf = applied_points(s.model, s.engine, np.array(st.r), np.array(st.A), case)
    names = s.model.mechanism.body_names
    count: dict[str, int] = {}
    for k in range(pf.body.shape[0]):
        body = names[pf.body[k]]
        if pf.radius is not None and pf.radius[k] > 0:
            label = f"{body} wheel"  # the wheel force at its contact point
        else:
            count[body] = count.get(body, 0) + 1
            label = f"{body} load {count[body]}"  # forces, then weights, in the case's order
        if np.linalg.norm(pf.F[k]) > 0:
            out.append(ForceArrow(label, "applied", pf.P[k], pf.F[k]))
    for k, j in enumerate(s.model.mechanism.joints):
        F = st.at_point[k, 1, :3]
        if np.isnan(F).any():
            continue
        if j.name in s.member_forces:
            kind = "tension" if s.member_forces[j.name] > 0 else "compression"
        else:
            kind = "reaction"
        out.append(ForceArrow(j.name, kind, st.P[k, 1], F))
    for k, e in enumerate(s.model.elements):
        f = float(st.element_force[k])
        Pi, Pj = st.element_ends[k]
        if f != 0.0:
            u = (Pj - Pi) / np.linalg.norm(Pj - Pi)
            out.append(ForceArrow(e.name, "compression" if f > 0 else "tension", Pj, f * u))
    return out


def arrow_scale(arrows: Sequence[ForceArrow], size: float) -> float:
    """Length per force unit: the largest arrow :data:`ARROW_FRACTION` of ``size``."""
    big = max((float(np.linalg.norm(a.force)) for a in arrows), default=0.0)
    return ARROW_FRACTION * size / big if big > 0 else 0.0


__all__ = ["ARROW_FRACTION", "FORCE_STYLE", "ForceArrow", "arrow_scale", "force_arrows"]
