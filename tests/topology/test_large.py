"""Topology of large models: loops equal to a brute-force reference, deep chains (issue 11, item 9).

The old topology walked each cut joint's chain to the root (O(K * depth)): a 2,000-body chain
with a cut joint per body took ~8 s and 20,000 bodies more than two minutes. The junction is now
found by walking up from both bodies only until they meet. The times are measured by
benchmarks/large_models.py (no timed assertions here).
"""

from __future__ import annotations

import itertools
import json
import subprocess
import sys
from pathlib import Path

import networkx as nx
import pytest

from kinprop.builders import closed_chain_yaml
from kinprop.model import Body, Joint, Mechanism
from kinprop.topology import WORLD, build_topology
from random_mechanisms import suite_mechanisms


def reference_loops(mech: Mechanism) -> dict[str, tuple[str, tuple[str, ...], tuple[str, ...]]]:
    """Junction and paths of every cut joint from networkx's own tree algorithms (independent)."""
    topo = build_topology(mech)
    T = nx.DiGraph()
    T.add_node(WORLD)
    for b in mech.bodies:
        if b.fixed:
            T.add_edge(WORLD, b.name)
    for t in topo.tree:
        T.add_edge(t.parent, t.child, joint=t.joint)
    out = {}
    for name in topo.cut_joints:
        j = mech.joint(name)
        lca = nx.lowest_common_ancestor(T, j.body_i, j.body_j)

        def down(b: str, lca: str = lca) -> tuple[str, ...]:
            path = nx.shortest_path(T, lca, b)
            return tuple(T.edges[u, v]["joint"] for u, v in itertools.pairwise(path) if "joint" in T.edges[u, v])

        out[name] = (lca, down(j.body_i), down(j.body_j))
    return out


@pytest.mark.parametrize("rm", suite_mechanisms(12), ids=lambda rm: f"seed{rm.seed}")
def test_loops_match_networkx_lca(rm) -> None:
    mech = rm.model.mechanism
    topo = build_topology(mech)
    ref = reference_loops(mech)
    assert {lp.cut_joint: (lp.junction, lp.path_i, lp.path_j) for lp in topo.loops} == ref


def ladder(n: int) -> Mechanism:
    """A serial chain of ``n`` revolute bodies with a distance joint from every body to the one
    two links back (n - 2 short loops, at depths up to n)."""
    bodies = [Body("ground", fixed=True)] + [Body(f"b{k}") for k in range(n)]
    joints = [
        Joint(f"R{k}", "revolute", "ground" if k == 0 else f"b{k - 1}", f"b{k}", frozenset({"s_i"})) for k in range(n)
    ]
    joints += [Joint(f"D{k}", "distance", f"b{k - 2}", f"b{k}", frozenset({"length"})) for k in range(2, n)]
    return Mechanism(tuple(bodies), tuple(joints), "ladder")


def test_deep_ladder_topology() -> None:
    """20,000 bodies and 19,998 cut joints at depth up to 20,000: each loop is 2 tree joints long."""
    mech = ladder(20_000)
    topo = build_topology(mech)
    assert len(topo.loops) == 19_998
    lp = {lp.cut_joint: lp for lp in topo.loops}["D15000"]
    assert (lp.junction, lp.path_i, lp.path_j, lp.case) == ("b14998", (), ("R14999", "R15000"), 2)


def test_check_of_a_long_chain(tmp_path: Path) -> None:
    """Load + ``kinprop check`` of a 2,000-body chain in a fresh process: one loop through every
    body, rank 1, mobility = the Gruebler count (20,000 bodies: benchmarks/large_models.py)."""
    n = 2_000
    path = tmp_path / "chain.yaml"
    path.write_text(closed_chain_yaml(n))
    code = f"from kinprop.cli import app\napp(['check', {str(path)!r}, '--json'])\n"
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr[-2000:]
    obj = json.loads(p.stdout)
    assert len(obj["bodies"]) == n + 1 and obj["cut_joints"] == ["D"]
    assert obj["loops"][0]["junction"] == "ground" and len(obj["loops"][0]["path_i"]) == n
    # one distance row on n angles: rank 1, mobility n - 1 = the Gruebler count
    assert (obj["n_coordinates"], obj["rank"], obj["mobility"], obj["gruebler"]) == (n, 1, n - 1, n - 1)
    assert obj["assembled"] and obj["residual"] < 1e-9
