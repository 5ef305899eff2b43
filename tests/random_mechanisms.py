"""Seeded random mechanisms for the finite-difference tests, built through the public API.

Everything here goes through ``kinprop.model`` (``Body``, ``Joint``, ``Mechanism``, ``Design``,
``Model``, ``as_coordinates``): random body-frame vectors s', random proper rotations C (via
``kinprop.spatial.exp_so3``), random coordinates (Euler parameters normalised, so that the
paper's tangent map ``H = 2E(p)`` is exact along tangent directions).

Shape of a generated mechanism:

* one fixed body ``G0`` (and optionally a second fixed body ``G1``) with a random global pose;
* moving bodies ``B1..Bn`` hung on a spanning tree of tree joints (``cut=False``), drawn in turn
  from :data:`TREE_TYPES`; about half of them are *reversed* (``body_j`` is the parent), and tree
  joints carry random ``s_i``/``s_j``/``C_i``/``C_j`` design variables on both sides;
* cut joints (``cut=True`` or cut-only types) of the requested types, each closing a loop of a
  requested kind:

  - ``"adjacent"``: the pair of a tree joint (case 1: still joined by that tree joint);
  - ``"branch"``:   two moving bodies not joined by a tree joint (case 2, junction a moving body or
    the fixed body);
  - ``"ground"``:   the fixed body ``G0`` and a body at depth >= 2 below it (case 2, junction = the
    fixed body);
  - ``"world"``:    a body below ``G0`` and a body below ``G1`` (case 2, two fixed bodies; the
    junction is the virtual world node).

``assembled=True`` chooses every cut joint's ``s_j``/``C_j`` (and length) so that the cut
constraints hold exactly at the generated coordinates.

``couplings=n`` adds up to ``n`` couplings ``C1..Cn`` between pairs of single-coordinate tree
joints (revolute, translational; either direction), with random coefficients c0..c4 and
offsets (drawn last, so the rest of a seed's mechanism is the same with or without them; with
``assembled=True`` each ``c0`` is chosen so that the coupling row holds).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from kinprop.engine import Engine as Assembly
from kinprop.joints import joint_type
from kinprop.model import Body, Coupling, Design, Joint, Mechanism, Model, as_coordinates
from kinprop.spatial import exp_so3, rot_x, rot_z

TREE_TYPES = (
    "revolute",
    "translational",
    "cylindrical",
    "universal",
    "spherical",
    "fixed",
    "spherical-translational",
    "free",
)
CUT_TYPES = (
    "revolute",
    "translational",
    "cylindrical",
    "universal",
    "spherical",
    "fixed",
    "spherical-translational",
    "revolute-spherical",
    "translational-distance",
    "dot-1",
    "dot-2",
    "spherical-point",
    "distance",
)
LOOP_KINDS = ("adjacent", "branch", "ground")
FRAME_FIELDS = ("s_i", "s_j", "C_i", "C_j")


# --- random numbers ------------------------------------------------------------------------------
def random_rotation(rng: np.random.Generator) -> np.ndarray:
    """A proper rotation ``exp(tilde(w))`` with ``w`` of random direction and angle in (0, pi)."""
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    return exp_so3(axis * rng.uniform(0.1, np.pi - 0.1))


def random_vector(rng: np.random.Generator, scale: float = 0.6) -> np.ndarray:
    return rng.normal(scale=scale, size=3)


def random_unit_quaternion(rng: np.random.Generator) -> np.ndarray:
    p = rng.normal(size=4)
    return p / np.linalg.norm(p)


def random_coordinates(type_name: str, rng: np.random.Generator, tree: bool = True) -> np.ndarray:
    """Random coordinates of a joint type: tree coordinates (angles in (-pi, pi), translations
    of order 1, unit Euler parameters) or, with ``tree=False``, its cut form's own coordinates."""
    jt = joint_type(type_name)
    if not tree:
        return rng.uniform(-1.0, 1.0, size=jt.n_cut_coordinates)
    q = rng.uniform(-1.0, 1.0, size=jt.n_coordinates)
    for k in jt.angle_indices:
        q[k] = rng.uniform(-np.pi, np.pi)
    if jt.euler is not None:
        q[jt.euler] = random_unit_quaternion(rng)
    return q


def assembled_cut_placement(
    type_name: str, rng: np.random.Generator, qc: np.ndarray
) -> tuple[np.ndarray, np.ndarray, float]:
    """``(A'', d'', length)``: a placement of joint frame j in joint frame i (and the joint's
    length) that satisfies the cut form of ``type_name`` exactly, with own coordinates ``qc``."""
    jt = joint_type(type_name)
    if jt.tree:
        App, dpp = jt.placement(random_coordinates(type_name, rng))
        return App, dpp, 0.0
    R = random_rotation(rng)
    d = random_vector(rng)
    if type_name == "revolute-spherical":
        d[2] = 0.0  # the ball stays in the revolute's plane, at the link length
        return R, d, float(np.linalg.norm(d))
    if type_name == "translational-distance":
        u, _ = jt.cut_offset(qc)
        return R, d, float(np.linalg.norm(d - u))
    if type_name == "dot-1":
        # z''_j perpendicular to z''_i
        return rot_z(rng.uniform(-np.pi, np.pi)) @ rot_x(np.pi / 2) @ rot_z(rng.uniform(-np.pi, np.pi)), d, 0.0
    if type_name == "dot-2":
        d[2] = 0.0
        return R, d, 0.0
    if type_name == "spherical-point":
        return R, np.zeros(3), 0.0
    if type_name == "distance":
        return R, d, float(np.linalg.norm(d))
    raise ValueError(f"no assembled placement for {type_name!r}")


# --- mechanisms ----------------------------------------------------------------------------------
@dataclass
class RandomMechanism:
    """A generated model with the plan that produced it (for failure messages)."""

    model: Model
    seed: int
    #: cut joint name -> requested loop kind
    loop_kinds: dict[str, str]

    @property
    def mechanism(self) -> Mechanism:
        return self.model.mechanism

    @property
    def design(self) -> Design:
        return self.model.design

    @property
    def coordinates(self):
        return self.model.coordinates

    def assembly(self) -> Assembly:
        return Assembly(self.mechanism)

    def describe(self) -> str:
        parts = [f"seed={self.seed}"]
        for j in self.mechanism.joints:
            parts.append(f"{j.name}:{j.type}({j.body_i}->{j.body_j}{', cut' if j.cut or not j.jtype.tree else ''})")
        return " ".join(parts)


def random_mechanism(
    seed: int,
    tree_types: Sequence[str] | None = None,
    cuts: Sequence[tuple[str, str]] = (),
    n_fixed: int = 1,
    reverse_probability: float = 0.5,
    field_probability: float = 0.7,
    assembled: bool = False,
    couplings: int = 0,
) -> RandomMechanism:
    """A random mechanism with one tree joint per entry of ``tree_types`` (one moving body each)
    and one cut joint per ``(type, loop kind)`` in ``cuts`` (see the module docstring).

    ``tree_types`` defaults to a random arrangement of every tree-capable type. Needs at least
    three tree joints for the ``branch``/``ground`` kinds, and ``n_fixed=2`` for ``world``.
    """
    rng = np.random.default_rng(seed)
    if tree_types is None:
        tree_types = [str(t) for t in rng.permutation(TREE_TYPES)]
    tree_types = list(tree_types)

    fixed_names = [f"G{k}" for k in range(n_fixed)]
    bodies = [
        Body(name, fixed=True, position=tuple(random_vector(rng)), orientation=tuple(map(tuple, random_rotation(rng))))
        for name in fixed_names
    ]
    parent: dict[str, str] = {}
    depth: dict[str, int] = dict.fromkeys(fixed_names, 0)
    root: dict[str, str] = {name: name for name in fixed_names}
    joints: list[Joint] = []
    design: dict[str, object] = {}
    coords: dict[str, np.ndarray] = {}

    def add_fields(name: str, type_name: str, always: Sequence[str] = ()) -> frozenset[str]:
        fields = [f for f in FRAME_FIELDS if f in always or rng.random() < field_probability]
        for f in fields:  # a fixed order: the draws must not depend on string hashing
            design[f"{name}.{f}"] = random_rotation(rng) if f.startswith("C") else random_vector(rng)
        fields = set(fields)
        if joint_type(type_name).has_length:
            fields.add("length")
            design[f"{name}.length"] = rng.uniform(0.5, 2.0)
        return frozenset(fields)

    moving: list[str] = []
    for k, type_name in enumerate(tree_types):
        child = f"B{k + 1}"
        if k == 0:
            par = "G0"
        elif k == 1:
            par = "B1"  # guarantees a body at depth 2 below G0
        elif n_fixed > 1 and k == 2:
            par = "G1"
        else:
            par = str(rng.choice(["G0", *moving]))
        bodies.append(Body(child))
        parent[child], depth[child], root[child] = par, depth[par] + 1, root[par]
        moving.append(child)
        name = f"T{k + 1}"
        reversed_ = bool(rng.random() < reverse_probability)
        bi, bj = (child, par) if reversed_ else (par, child)
        joints.append(Joint(name, type_name, bi, bj, add_fields(name, type_name), cut=False))
        coords[name] = random_coordinates(type_name, rng)

    adjacent = [(j.body_i, j.body_j) for j in joints]
    adjacent_set = {frozenset(p) for p in adjacent}
    loop_kinds: dict[str, str] = {}
    cut_specs: list[tuple[str, str, str, str]] = []
    for k, (type_name, kind) in enumerate(cuts):
        if kind == "adjacent":
            a, b = adjacent[rng.integers(len(adjacent))]
        elif kind == "branch":
            pairs = [(a, b) for a in moving for b in moving if a < b and frozenset((a, b)) not in adjacent_set]
            a, b = pairs[rng.integers(len(pairs))]
        elif kind == "ground":
            deep = [b for b in moving if depth[b] >= 2 and root[b] == "G0"]
            a, b = "G0", deep[rng.integers(len(deep))]
        elif kind == "world":
            left = [b for b in moving if root[b] == "G0"]
            right = [b for b in moving if root[b] == "G1"]
            a, b = left[rng.integers(len(left))], right[rng.integers(len(right))]
        else:
            raise ValueError(f"unknown loop kind {kind!r}")
        if rng.random() < 0.5:
            a, b = b, a
        name = f"K{k + 1}"
        loop_kinds[name] = kind
        cut_specs.append((name, type_name, a, b))

    for name, type_name, a, b in cut_specs:
        jt = joint_type(type_name)
        always = ("s_j", "C_j") if assembled else ()
        joints.append(Joint(name, type_name, a, b, add_fields(name, type_name, always), cut=True if jt.tree else None))
        if jt.n_cut_coordinates:
            coords[name] = random_coordinates(type_name, rng, tree=False)

    coupled: list[Coupling] = []
    single = [j.name for j in joints if j.cut is False and joint_type(j.type).n_coordinates == 1]
    for k in range(couplings if len(single) >= 2 else 0):
        a, b = (str(x) for x in rng.choice(single, size=2, replace=False))
        c = Coupling(f"C{k + 1}", a, b, float(rng.uniform(-0.5, 0.5)), float(rng.uniform(-0.5, 0.5)))
        coef = rng.normal(scale=0.7, size=5)
        if assembled:  # c0 such that the row holds at the generated coordinates
            x = coords[b][0] - c.q_b0
            coef[0] = coords[a][0] - c.q_a0 - sum(coef[m] * x**m for m in range(1, 5))
        design[f"{c.name}.coef"] = coef
        coupled.append(c)

    mech = Mechanism(tuple(bodies), tuple(joints), name=f"random-{seed}", couplings=tuple(coupled))
    model = Model(mech, Design(design), as_coordinates(coords))
    if assembled:
        model = _assemble_cuts(model, rng)
    return RandomMechanism(model, seed, loop_kinds)


def _assemble_cuts(model: Model, rng: np.random.Generator) -> Model:
    """Choose each cut joint's ``s_j``, ``C_j`` (and length) so that its constraints hold."""
    asm = Assembly(model.mechanism)
    kin = asm.kinematics(model.design, model.coordinates)
    updates: dict[str, object] = {}
    for name in asm.topology.cut_joints:
        j = model.mechanism.joint(name)
        jt = j.jtype
        qc = np.asarray(model.coordinates.get(name, np.zeros(0)))
        App, dpp, length = assembled_cut_placement(j.type, rng, qc)
        A_i, A_j = kin.A[j.body_i], kin.A[j.body_j]
        R_i = A_i @ model.design.value(name, "C_i")
        P_i = kin.r[j.body_i] + A_i @ model.design.value(name, "s_i")
        R_j, P_j = R_i @ App, P_i + R_i @ dpp
        updates[f"{name}.s_j"] = A_j.T @ (P_j - kin.r[j.body_j])
        updates[f"{name}.C_j"] = A_j.T @ R_j
        if jt.has_length:
            updates[f"{name}.length"] = length
    return model.with_state(model.design.replace(updates), model.coordinates)


def suite_mechanisms(count: int = 24, base_seed: int = 1000) -> list[RandomMechanism]:
    """``count`` mechanisms that together cover every tree type (forward and reversed) and every
    cut type in every loop kind, including two with two fixed bodies (``world`` loops)."""
    out: list[RandomMechanism] = []
    combos = [(t, kind) for t in CUT_TYPES for kind in LOOP_KINDS]
    rng = np.random.default_rng(base_seed)
    combos = [combos[k] for k in rng.permutation(len(combos))]
    for k in range(count - 2):
        seed = base_seed + k
        cuts = combos[k :: count - 2]
        tree = [TREE_TYPES[(k + m) % len(TREE_TYPES)] for m in range(4 + k % 3)]
        out.append(random_mechanism(seed, tree, cuts, couplings=k % 3))
    for k in range(2):
        seed = base_seed + count - 2 + k
        tree = [TREE_TYPES[(3 * k + m) % len(TREE_TYPES)] for m in range(5)]
        cuts = [
            (CUT_TYPES[(5 * k + m) % len(CUT_TYPES)], kind) for m, kind in enumerate(("world", "branch", "adjacent"))
        ]
        out.append(random_mechanism(seed, tree, cuts, n_fixed=2))
    return out


def assembled_set(count: int = 40) -> list[RandomMechanism]:
    """Seeds ``0 .. count-1``: five tree joints cycling through the tree types, two cut joints
    through the cut types and loop kinds, 0-2 couplings, assembled (the motion and statics
    tests' common set)."""
    return cycled_set(count, couplings=True)


def cycled_set(
    count: int, base: int = 0, tree_joints: int = 5, cut_stride: int = 3, couplings: bool = False
) -> list[RandomMechanism]:
    """``count`` assembled mechanisms, seeds ``base + i``: ``tree_joints`` tree joints cycling
    through the tree types from ``i``, two cut joints through the cut types (stride
    ``cut_stride``) and the loop kinds, ``i % 3`` couplings when ``couplings``."""
    return [
        random_mechanism(
            base + i,
            [TREE_TYPES[(i + m) % len(TREE_TYPES)] for m in range(tree_joints)],
            [(CUT_TYPES[(cut_stride * i + m) % len(CUT_TYPES)], LOOP_KINDS[(i + m) % 3]) for m in range(2)],
            assembled=True,
            couplings=i % 3 if couplings else 0,
        )
        for i in range(count)
    ]
