"""Joint library and registry ``{name: joint type}``."""

from __future__ import annotations

from kinprop.joints.base import JointType
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


def joint_type(name: str) -> JointType:
    """Look up a joint type by name or alias; ``KeyError`` lists the known names."""
    key = ALIASES.get(name, name)
    if key not in REGISTRY:
        raise KeyError(f"unknown joint type {name!r}; known: {', '.join(sorted(REGISTRY))}")
    return REGISTRY[key]


__all__ = ["ALIASES", "REGISTRY", "JointType", "joint_type"]
