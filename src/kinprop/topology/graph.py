"""Topology: body-joint multigraph, spanning tree, cut joints and loops (sections 2, 4).

The spanning tree is a minimum spanning tree of the multigraph in which fixed bodies hang from
a virtual world node, joints the user asked to cut and cut-only joint types are left out, and a
tree joint costs its number of coordinates — so joints with the fewest constraint rows
(spherical before universal before revolute) are the ones cut, as in the paper's slider-crank.
Joints marked ``cut: false`` and joints named by a coupling (their coordinate is a variable of
the coupling row) are kept in the tree. Each cut joint closes a loop whose junction body is the
lowest common ancestor of its two bodies: case 1 when the pair is still joined by a tree joint,
case 2 otherwise (eqs. 44-51).
"""

from __future__ import annotations

from dataclasses import dataclass

import networkx as nx

from kinprop.errors import ModelError, Problem
from kinprop.model.mechanism import Mechanism

WORLD = "__world__"


@dataclass(frozen=True)
class TreeJoint:
    joint: str
    parent: str
    child: str
    #: True when the joint's body_j is the parent (the joint is traversed j -> i)
    reversed: bool


@dataclass(frozen=True)
class Loop:
    cut_joint: str
    body_i: str
    body_j: str
    junction: str
    #: tree joints from the junction down to body_i / body_j
    path_i: tuple[str, ...]
    path_j: tuple[str, ...]
    case: int


@dataclass(frozen=True)
class Topology:
    """Derived once from a Mechanism; parent-before-child order of moving bodies."""

    order: tuple[str, ...]
    tree: tuple[TreeJoint, ...]
    cut_joints: tuple[str, ...]
    loops: tuple[Loop, ...]
    parent_joint: dict[str, str]

    @property
    def tree_joints(self) -> tuple[str, ...]:
        return tuple(t.joint for t in self.tree)


def _loop_paths(
    body_i: str, body_j: str, parent: dict[str, str], depth: dict[str, int], parent_joint: dict[str, str]
) -> tuple[str, tuple[str, ...], tuple[str, ...]]:
    """Junction (lowest common ancestor) and the tree joints from it down to each body.

    Walks up from the deeper body until both meet, so the work is the length of the two
    paths (the loop's own size), not the depth of the tree. Fixed bodies have no parent
    joint: a loop between two fixed bases meets at WORLD."""
    a, b = body_i, body_j
    up_i: list[str] = []
    up_j: list[str] = []
    while depth[a] > depth[b]:
        up_i.append(a)
        a = parent[a]
    while depth[b] > depth[a]:
        up_j.append(b)
        b = parent[b]
    while a != b:
        up_i.append(a)
        up_j.append(b)
        a, b = parent[a], parent[b]
    return (
        a,
        tuple(parent_joint[x] for x in reversed(up_i) if x in parent_joint),
        tuple(parent_joint[x] for x in reversed(up_j) if x in parent_joint),
    )


def build_topology(mech: Mechanism) -> Topology:
    """Spanning tree, cut joints and loops; raises :class:`ModelError` naming unreachable bodies."""
    G = nx.MultiGraph()
    G.add_node(WORLD)
    G.add_nodes_from(mech.body_names)
    for b in mech.bodies:
        if b.fixed:
            G.add_edge(WORLD, b.name, key=f"{WORLD}:{b.name}", weight=-1.0)
    n = max(len(mech.joints), 1)
    keep = mech.coupled_joints
    for k, j in enumerate(mech.joints):
        jt = j.jtype
        if j.cut is True or not jt.tree:
            continue
        forced = j.cut is False or j.name in keep
        G.add_edge(j.body_i, j.body_j, key=j.name, weight=jt.n_coordinates + k / (10.0 * n) - (1000 if forced else 0))
    T = nx.minimum_spanning_tree(G, weight="weight", algorithm="kruskal")
    tree_keys = {key for _, _, key in T.edges(keys=True)}

    problems: list[Problem] = []
    reach = nx.node_connected_component(T, WORLD)
    full = nx.MultiGraph()
    full.add_nodes_from(mech.body_names)
    full.add_edges_from((j.body_i, j.body_j) for j in mech.joints)
    fixed = {b.name for b in mech.bodies if b.fixed}
    grounded: set[str] = set()
    if len(reach) - 1 < len(mech.body_names):  # reach holds WORLD
        for comp in nx.connected_components(full):
            if comp & fixed:
                grounded |= comp
    for b in mech.body_names:
        if b in reach:
            continue
        if b not in grounded:
            problems.append(Problem(f"bodies.{b}", "not connected to a fixed body by any joint"))
        else:
            problems.append(
                Problem(
                    f"bodies.{b}",
                    "reachable from a fixed body only through cut-only joints "
                    "(distance, dot, R-S, T-D) or joints marked cut; add a tree joint (e.g. 'free')",
                )
            )
    for j in mech.joints:
        if j.cut is False and j.name not in tree_keys:
            problems.append(Problem(f"joints.{j.name}.cut", "marked as a tree joint but it closes a loop"))
    for c in mech.couplings:
        for k, name in enumerate((c.joint_a, c.joint_b)):
            if name not in tree_keys and mech.joint(name).cut is not False:
                problems.append(
                    Problem(
                        f"couplings.{c.name}.joints[{k}]",
                        f"joint {name!r} must be a tree joint to be coupled, but it closes a loop of other "
                        "tree-only or coupled joints",
                    )
                )
    if problems:
        raise ModelError(problems)

    # orient the tree from the world (BFS: parent before child)
    joints = {j.name: j for j in mech.joints}
    parent: dict[str, str] = {}
    depth: dict[str, int] = {WORLD: 0}
    parent_joint: dict[str, str] = {}
    tree: list[TreeJoint] = []
    order: list[str] = []
    for u, v, key in nx.edge_bfs(T, WORLD):
        depth[v] = depth[u] + 1
        if u == WORLD:
            parent[v] = WORLD
            continue
        j = joints[key]
        parent[v] = u
        parent_joint[v] = key
        tree.append(TreeJoint(key, u, v, reversed=(j.body_j == u)))
        order.append(v)

    loops = []
    cut = [j.name for j in mech.joints if j.name not in tree_keys]
    for name in cut:
        j = joints[name]
        junction, pi, pj = _loop_paths(j.body_i, j.body_j, parent, depth, parent_joint)
        case = 1 if (len(pi) + len(pj) == 1) else 2
        loops.append(Loop(name, j.body_i, j.body_j, junction, pi, pj, case))
    return Topology(tuple(order), tuple(tree), tuple(cut), tuple(loops), parent_joint)
