"""Topology: spanning tree, cut joints, loops."""

from kinprop.topology.graph import WORLD, Loop, Topology, TreeJoint, build_topology

__all__ = ["WORLD", "Loop", "Topology", "TreeJoint", "build_topology"]
