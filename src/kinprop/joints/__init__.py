"""Joint library: registry ``{name: joint type}`` and the compiled dispatch by type code.

To add a joint type: write its module (tree form: ``placement``/``motion`` kernels and a
``CODE``; cut form: a tuple of basic constraints), add an instance to ``REGISTRY`` and, for a
tree joint, one branch to :func:`placement` and :func:`motion` below. Nothing else changes.
"""

from __future__ import annotations

from kinprop.jit import kernel
from kinprop.joints import composite, cylindrical, prismatic, revolute, spherical, universal
from kinprop.joints.base import JointType, no_motion, no_placement
from kinprop.joints.basic import DistanceJoint, Dot1Joint, Dot2Joint, SphericalPoint
from kinprop.joints.composite import (
    Free,
    RevoluteSpherical,
    SphericalTranslational,
    TranslationalDistance,
)
from kinprop.joints.cylindrical import Cylindrical
from kinprop.joints.fixed import Fixed
from kinprop.joints.prismatic import Prismatic
from kinprop.joints.revolute import Revolute
from kinprop.joints.spherical import Spherical
from kinprop.joints.universal import Universal

REGISTRY: dict[str, JointType] = {
    jt.name: jt
    for jt in (
        Revolute(),
        Prismatic(),
        Cylindrical(),
        Universal(),
        Spherical(),
        Fixed(),
        Free(),
        SphericalTranslational(),
        RevoluteSpherical(),
        TranslationalDistance(),
        Dot1Joint(),
        Dot2Joint(),
        SphericalPoint(),
        DistanceJoint(),
    )
}

#: accepted short names
ALIASES = {
    "prismatic": "translational",
    "R": "revolute",
    "P": "translational",
    "C": "cylindrical",
    "U": "universal",
    "S": "spherical",
    "ball": "spherical",
    "weld": "fixed",
    "S-T": "spherical-translational",
    "R-S": "revolute-spherical",
    "T-D": "translational-distance",
    "S-S": "distance",
}


@kernel
def placement(code, q, A, d):
    """``A''(q)``, ``d''(q)`` of a tree joint of type ``code``, written into ``A``, ``d``."""
    if code == revolute.CODE:
        revolute.placement(q, A, d)
    elif code == prismatic.CODE:
        prismatic.placement(q, A, d)
    elif code == cylindrical.CODE:
        cylindrical.placement(q, A, d)
    elif code == universal.CODE:
        universal.placement(q, A, d)
    elif code == spherical.CODE:
        spherical.placement(q, A, d)
    elif code == composite.ST_CODE:
        composite.st_placement(q, A, d)
    elif code == composite.FREE_CODE:
        composite.free_placement(q, A, d)
    else:
        no_placement(q, A, d)


@kernel
def motion(code, q, A, d, dd, H):
    """``dd''/dq``, ``H''`` (3 x n) of a tree joint of type ``code`` at its placement ``A``, ``d``."""
    if code == revolute.CODE:
        revolute.motion(q, A, d, dd, H)
    elif code == prismatic.CODE:
        prismatic.motion(q, A, d, dd, H)
    elif code == cylindrical.CODE:
        cylindrical.motion(q, A, d, dd, H)
    elif code == universal.CODE:
        universal.motion(q, A, d, dd, H)
    elif code == spherical.CODE:
        spherical.motion(q, A, d, dd, H)
    elif code == composite.ST_CODE:
        composite.st_motion(q, A, d, dd, H)
    elif code == composite.FREE_CODE:
        composite.free_motion(q, A, d, dd, H)
    else:
        no_motion(q, A, d, dd, H)


def joint_type(name: str) -> JointType:
    """Look up a joint type by name or alias; ``KeyError`` lists the known names."""
    key = ALIASES.get(name, name)
    if key not in REGISTRY:
        raise KeyError(f"unknown joint type {name!r}; known: {', '.join(sorted(REGISTRY))}")
    return REGISTRY[key]


__all__ = ["ALIASES", "REGISTRY", "JointType", "joint_type", "motion", "placement"]
