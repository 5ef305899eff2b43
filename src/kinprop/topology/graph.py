"""Topology: body-joint multigraph, spanning tree, cut joints and loops (sections 2, 4).

The spanning tree is a minimum spanning tree of the multigraph in which fixed bodies hang from
a virtual world node, joints the user asked to cut and cut-only joint types are left out, and a
tree joint costs its number of coordinates — so joints with the fewest constraint rows
(spherical before universal before revolute) are the ones cut, as in the paper's slider-crank.
Joints marked ``cut: false`` and joints named by a coupling (their coordinate is a variable of
the coupling row) are kept in the tree. Each cut joint closes a loop whose junction body is the
lowest common ancestor of its two bodies: case 1 when the pair is still joined by a tree joint,
case 2 otherwise (eqs. 44-51).

The graph work is Kruskal's spanning tree and connected components by union-find (plain
Python: the results scipy's ``csgraph`` gives, without importing scipy); the tree is then
oriented from the world breadth first, each body's children in the order the spanning tree took
their joints (cheapest first).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

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


def _root(parent: list[int], a: int) -> int:
    """Union-find root of ``a`` (path halving)."""
    while parent[a] != a:
        parent[a] = parent[parent[a]]
        a = parent[a]
    return a


def connected_components(n_nodes: int, u: np.ndarray, v: np.ndarray) -> tuple[int, np.ndarray]:
    """Connected components of the undirected graph with edges ``u[k] - v[k]``: their count
    and each node's label, components numbered in the order of their lowest node (scipy's
    ``csgraph.connected_components`` numbering)."""
    parent = list(range(n_nodes))
    for a, b in zip(np.asarray(u).tolist(), np.asarray(v).tolist(), strict=True):
        ra, rb = _root(parent, a), _root(parent, b)
        if ra != rb:
            parent[max(ra, rb)] = min(ra, rb)  # a root is its component's lowest node so far
    label = np.empty(n_nodes, dtype=np.int32)
    count = 0
    for a in range(n_nodes):
        r = _root(parent, a)
        if r == a:
            label[a], count = count, count + 1
        else:
            label[a] = label[r]  # r < a: labelled already
    return count, label


def _spanning_tree(n_nodes: int, edges: list[tuple[int, int, str, float]]) -> dict[int, list[tuple[int, str]]]:
    """Minimum spanning forest of a multigraph given as ``(u, v, key, weight)`` edges with
    distinct weights (so the forest is unique; Kruskal's): each node's tree neighbours with the
    joining edge's key, cheapest edge first. Of parallel edges only the cheapest can be a tree
    edge."""
    best: dict[tuple[int, int], tuple[float, str]] = {}
    for u, v, key, w in edges:
        pair = (min(u, v), max(u, v))
        if u != v and (pair not in best or w < best[pair][0]):
            best[pair] = (w, key)
    adjacent: dict[int, list[tuple[int, str]]] = {k: [] for k in range(n_nodes)}
    parent = list(range(n_nodes))
    for (a, b), (_, key) in sorted(best.items(), key=lambda item: item[1]):
        ra, rb = _root(parent, a), _root(parent, b)
        if ra != rb:
            parent[ra] = rb
            adjacent[a].append((b, key))
            adjacent[b].append((a, key))
    return adjacent


def build_topology(mech: Mechanism) -> Topology:
    """Spanning tree, cut joints and loops; raises :class:`ModelError` naming unreachable bodies."""
    names = [WORLD, *mech.body_names]
    node = {b: k for k, b in enumerate(names)}
    # fixed bodies hang from the world by edges below every joint's (in file order: weights distinct)
    edges = [(0, node[b.name], f"{WORLD}:{b.name}", -1.0 + k / 10.0 / len(names))
             for k, b in enumerate(mech.bodies) if b.fixed]  # fmt: skip
    n = max(len(mech.joints), 1)
    keep = mech.coupled_joints
    for k, j in enumerate(mech.joints):
        jt = j.jtype
        if j.cut is True or not jt.tree:
            continue
        forced = j.cut is False or j.name in keep
        w = jt.n_coordinates + k / (10.0 * n) - (1000 if forced else 0)
        edges.append((node[j.body_i], node[j.body_j], j.name, w))
    adjacent = _spanning_tree(len(names), edges)

    # orient the tree from the world, breadth first (parent before child)
    parent: dict[str, str] = {}
    depth: dict[str, int] = {WORLD: 0}
    tree_edges: list[tuple[str, str, str]] = []  # (parent, child, joint)
    queue = deque([0])
    while queue:
        u = queue.popleft()
        for v, key in adjacent[u]:
            if names[v] in depth:
                continue
            depth[names[v]] = depth[names[u]] + 1
            parent[names[v]] = names[u]
            tree_edges.append((names[u], names[v], key))
            queue.append(v)
    reach = set(depth)
    tree_keys = {key for *_, key in tree_edges}

    problems: list[Problem] = []
    grounded: set[str] = set()
    if len(reach) - 1 < len(mech.body_names):  # reach holds WORLD
        ij = np.array([(node[j.body_i], node[j.body_j]) for j in mech.joints], dtype=np.int64).reshape(-1, 2)
        _, label = connected_components(len(names), ij[:, 0], ij[:, 1])
        fixed = {label[node[b.name]] for b in mech.bodies if b.fixed}
        grounded = {b for b in mech.body_names if label[node[b]] in fixed}
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

    joints = {j.name: j for j in mech.joints}
    parent_joint: dict[str, str] = {}
    tree: list[TreeJoint] = []
    order: list[str] = []
    for u, v, key in tree_edges:
        if u == WORLD:
            continue
        j = joints[key]
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
