"""Model builders for tests and benchmarks: Stewart 6-UPS platforms, stacks of them, RSSR.

All are built with the public model API (:class:`~kinprop.model.Body`, ``Joint``,
``Mechanism``, ``Design``, ``Model``) in metres and radians, assembled at the nominal pose.

Stewart legs come in two equivalent forms (``legs=``):

* ``"distance"`` (default): the platform hangs on a ``free`` tree joint (7 coordinates:
  translation and Euler parameters, relative to its base) and each leg is a ``distance`` cut
  joint ``|P - B| = l`` — 7 unknowns, 7 equations per module. A leg change is a change of
  ``Lk.length``.
* ``"ups"``: each leg is a universal joint on the base, a cylinder body, a translational joint
  (the leg length is its coordinate ``Pk.q``) and a piston body with a ``spherical-point`` cut
  to the platform — 19 unknowns, 19 equations per module. A leg change is a change of ``Pk.q``.

Both give the same platform pose; ``benchmarks/`` measures the first to be about three times
faster to re-assemble.
"""

from __future__ import annotations

import math

import numpy as np

from kinprop.model import Body, Design, Joint, Mechanism, Model
from kinprop.model.design import as_coordinates
from kinprop.spatial import Array

#: nominal Stewart geometry (metres): base / platform radius, height, half-angle of pairs
STEWART = {
    "base_radius": 0.5,
    "platform_radius": 0.3,
    "height": 0.6,
    "base_half_angle": 0.2,
    "platform_half_angle": 0.5,
}


def stewart_hardpoints(
    base_radius: float = 0.5,
    platform_radius: float = 0.3,
    base_half_angle: float = 0.2,
    platform_half_angle: float = 0.5,
) -> tuple[Array, Array]:
    """Base points ``a_k`` (base frame) and platform points ``b_k`` (platform frame), (6, 3) each.

    Leg k joins ``a_k`` to ``b_k``; the pairs sit at 0, 120, 240 degrees, the platform pairs
    rotated by 60 degrees so the legs cross over.
    """
    a = np.zeros((6, 3))
    b = np.zeros((6, 3))
    for k in range(6):
        c, sgn = k // 2, (1 if k % 2 else -1)
        ta = 2 * np.pi * c / 3 + sgn * base_half_angle
        tb = 2 * np.pi * c / 3 + sgn * (np.pi / 3 - platform_half_angle)
        a[k] = base_radius * np.cos(ta), base_radius * np.sin(ta), 0.0
        b[k] = platform_radius * np.cos(tb), platform_radius * np.sin(tb), 0.0
    return a, b


def _frame_with_x(u: Array) -> Array:
    """Rotation whose x axis is ``u`` and whose z axis is horizontal (universal joint frame)."""
    x = u / np.linalg.norm(u)
    z = np.cross([0.0, 0.0, 1.0], x)
    z = z / np.linalg.norm(z)
    y = np.cross(z, x)
    return np.column_stack([x, y, z])


#: translational joint frame on the cylinder: its slide axis z'' is the cylinder's x axis
_SLIDE_ALONG_X = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])


def _module(
    prefix: str,
    base: str,
    platform: str,
    a: Array,
    b: Array,
    height: float,
    legs: str,
    bodies: list[Body],
    joints: list[Joint],
    design: dict[str, object],
    coords: dict[str, Array],
) -> None:
    bodies.append(Body(platform, points=(("centre", (0.0, 0.0, 0.0)),)))
    free = f"{prefix}F"
    joints.append(Joint(free, "free", base, platform, cut=False))
    coords[free] = np.array([0.0, 0.0, height, 1.0, 0.0, 0.0, 0.0])
    top = b + np.array([0.0, 0.0, height])
    for k in range(6):
        length = float(np.linalg.norm(top[k] - a[k]))
        if legs == "distance":
            name = f"{prefix}L{k + 1}"
            joints.append(Joint(name, "distance", base, platform, frozenset({"s_i", "s_j", "length"})))
            design[f"{name}.s_i"], design[f"{name}.s_j"], design[f"{name}.length"] = a[k], b[k], length
            continue
        cyl, pis = f"{prefix}cyl{k + 1}", f"{prefix}piston{k + 1}"
        u, p, s = f"{prefix}U{k + 1}", f"{prefix}P{k + 1}", f"{prefix}S{k + 1}"
        bodies += [Body(cyl), Body(pis)]
        joints.append(Joint(u, "universal", base, cyl, frozenset({"s_i", "C_i"}), cut=False))
        design[f"{u}.s_i"], design[f"{u}.C_i"] = a[k], _frame_with_x(top[k] - a[k])
        coords[u] = np.zeros(2)
        joints.append(Joint(p, "translational", cyl, pis, frozenset({"C_i"}), cut=False))
        design[f"{p}.C_i"] = _SLIDE_ALONG_X
        coords[p] = np.array([length])
        joints.append(Joint(s, "spherical-point", pis, platform, frozenset({"s_j"})))
        design[f"{s}.s_j"] = b[k]


def stewart_stack(K: int = 1, legs: str = "distance", **geometry: float) -> Model:
    """K Stewart modules in series: module k's base is module k-1's platform.

    Names: bodies ``base``, ``M1``..``MK`` (platforms); per module ``Mk_F`` (free joint),
    ``Mk_L1``..``Mk_L6`` (distance legs) or ``Mk_U*``, ``Mk_P*``, ``Mk_S*`` (UPS legs).
    ``geometry`` overrides :data:`STEWART`.
    """
    if legs not in ("distance", "ups"):
        raise ValueError(f"legs must be 'distance' or 'ups', found {legs!r}")
    g = {**STEWART, **geometry}
    a, b = stewart_hardpoints(g["base_radius"], g["platform_radius"], g["base_half_angle"], g["platform_half_angle"])
    bodies: list[Body] = [Body("base", fixed=True)]
    joints: list[Joint] = []
    design: dict[str, object] = {}
    coords: dict[str, Array] = {}
    below = "base"
    for k in range(1, K + 1):
        plat = f"M{k}"
        # the platform of one module is the base of the next: its base points sit on it
        _module(f"M{k}_", below, plat, a, b, g["height"], legs, bodies, joints, design, coords)
        below = plat
    mech = Mechanism(tuple(bodies), tuple(joints), name=f"stewart stack K={K} ({legs})")
    return Model(mech, Design(design), as_coordinates(coords))


def stewart(legs: str = "distance", **geometry: float) -> Model:
    """One 6-UPS Stewart platform (a stack of one; joints ``M1_F``, ``M1_L1``..``M1_L6``)."""
    return stewart_stack(1, legs, **geometry)


def leg_addresses(model: Model) -> list[str]:
    """The leg-length addresses of a Stewart model built here (``.length`` or ``P*.q``)."""
    out = []
    for j in model.mechanism.joints:
        if j.jtype.has_length:  # a distance leg
            out.append(f"{j.name}.length")
        elif j.jtype.n_coordinates == 1 and not j.jtype.angle_indices:  # a sliding leg (translational)
            out.append(f"{j.name}.q")
    return out


#: RSSR geometry (metres): crank radius, rocker pivot, rocker radius
RSSR = {"crank": 0.1, "pivot": (0.35, 0.05, 0.15), "rocker": 0.3}


def rssr_rocker_point(phi: float | Array, pivot: Array, rocker: float) -> Array:
    """Rocker ball centre for rocker angle ``phi``: the rocker turns about the global y axis."""
    phi = np.asarray(phi, dtype=float)
    return np.asarray(pivot) + rocker * np.stack([np.sin(phi), np.zeros_like(phi), np.cos(phi)], axis=-1)


def rssr_crank_point(theta: float | Array, crank: float) -> Array:
    """Crank ball centre for crank angle ``theta``: the crank turns about the global z axis."""
    theta = np.asarray(theta, dtype=float)
    return crank * np.stack([np.cos(theta), np.sin(theta), np.zeros_like(theta)], axis=-1)


def rssr(theta: float = 0.0, phi: float = 0.3, **geometry: object) -> Model:
    """Spatial RSSR four-bar: crank revolute (global z) - coupler (distance) - rocker revolute (global y).

    Joints ``crank`` (revolute, ``crank.q`` is the input angle), ``rocker`` (revolute,
    ``rocker.q`` the output) and ``coupler`` (distance cut joint, ``coupler.length``). The
    coupler length is chosen so that ``(theta, phi)`` is assembled. Input-output equation:
    ``|crank_point(theta) - rocker_point(phi)|^2 = coupler.length^2``.
    """
    g = {**RSSR, **geometry}
    pivot = np.asarray(g["pivot"], dtype=float)
    crank, rocker = float(g["crank"]), float(g["rocker"])  # type: ignore[arg-type]
    length = float(np.linalg.norm(rssr_crank_point(theta, crank) - rssr_rocker_point(phi, pivot, rocker)))
    bodies = (
        Body("ground", fixed=True),
        Body("crank", points=(("ball", (crank, 0.0, 0.0)),)),
        Body("rocker", points=(("ball", (rocker, 0.0, 0.0)),)),
    )
    joints = (
        Joint("crank", "revolute", "ground", "crank", frozenset({"s_i"})),
        Joint("rocker", "revolute", "ground", "rocker", frozenset({"s_i", "C_i"})),
        Joint("coupler", "distance", "crank", "rocker", frozenset({"s_i", "s_j", "length"})),
    )
    # rocker joint frame: z'' = global y; x'' = global z, so the rocker x axis at phi is (sin, 0, cos)
    C_rocker = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    design = Design(
        {
            "crank.s_i": np.zeros(3),
            "rocker.s_i": pivot,
            "rocker.C_i": C_rocker,
            "coupler.s_i": np.array([crank, 0.0, 0.0]),
            "coupler.s_j": np.array([rocker, 0.0, 0.0]),
            "coupler.length": length,
        }
    )
    coords = as_coordinates({"crank": np.array([theta]), "rocker": np.array([phi])})
    return Model(Mechanism(bodies, joints, name="spatial RSSR four-bar"), design, coords)


def closed_chain_yaml(n: int) -> str:
    """A planar chain of ``n`` revolute links (bent into an arc) closed to the ground by one
    distance joint whose length is the actual tip distance: assembled, mobility n - 1."""
    L = 1.0 / n
    q = [0.0] + [0.5 / n] * (n - 1)  # a gentle arc, so the closing distance is not radial
    lines = ["kinprop: 1", f"name: chain {n}", "units: {length: m, angle: rad}", "bodies:"]
    lines.append("  ground: {fixed: true, position: [0, 0, 0]}")
    lines += [f"  b{k}: {{}}" for k in range(n)]
    lines.append("joints:")
    theta = np.cumsum(q)
    tip = np.array([L * np.cos(theta).sum(), L * np.sin(theta).sum()])
    for k in range(n):
        parent = "ground" if k == 0 else f"b{k - 1}"
        lines.append(
            f"  R{k}: {{type: revolute, bodies: [{parent}, b{k}], s_i: [{0 if k == 0 else L}, 0, 0], q: [{q[k]!r}]}}"
        )
    lines.append(
        f"  D: {{type: distance, bodies: [b{n - 1}, ground], s_i: [{L}, 0, 0], s_j: [0.3, 0, 0],"
        f" length: {math.dist(tip, (0.3, 0.0))!r}}}"
    )
    return "\n".join(lines) + "\n"


__all__ = [
    "closed_chain_yaml",
    "leg_addresses",
    "rssr",
    "rssr_crank_point",
    "rssr_rocker_point",
    "stewart",
    "stewart_hardpoints",
    "stewart_stack",
]
