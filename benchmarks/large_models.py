"""Benchmark: topology and ``kinprop check`` of 20,000-body models (the timings that
tests/topology/test_large.py used to assert; the tests check the answers).

(a) ``build_topology`` of a ladder: a serial chain of N revolute bodies with a distance joint
from every body to the one two links back (N - 2 short loops at depths up to N), CPU seconds
in this process (was ~8 s for 2,000 bodies before the linear junction search, target < 10 s
for 20,000); (b) load + ``kinprop check --json`` of an N-body chain closed by one distance joint,
in a fresh process (imports and the kernel cache load included): CPU and wall seconds
(target < 10 s CPU; was > 2 min).

    python benchmarks/large_models.py [--bodies N] [--repeats R]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from kinprop.builders import closed_chain_yaml
from kinprop.model import Body, Joint, Mechanism
from kinprop.topology import build_topology

TARGET_CPU = 10.0


def ladder(n: int) -> Mechanism:
    bodies = [Body("ground", fixed=True)] + [Body(f"b{k}") for k in range(n)]
    joints = [
        Joint(f"R{k}", "revolute", "ground" if k == 0 else f"b{k - 1}", f"b{k}", frozenset({"s_i"})) for k in range(n)
    ]
    joints += [Joint(f"D{k}", "distance", f"b{k - 2}", f"b{k}", frozenset({"length"})) for k in range(2, n)]
    return Mechanism(tuple(bodies), tuple(joints), "ladder")


def topology_cpu(n: int) -> float:
    mech = ladder(n)
    t0 = time.process_time()
    topo = build_topology(mech)
    cpu = time.process_time() - t0
    assert len(topo.loops) == n - 2
    return cpu


def check_cpu(n: int) -> tuple[float, float]:
    """(CPU, wall) seconds of load + ``kinprop check --json`` in a fresh process."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "chain.yaml"
        path.write_text(closed_chain_yaml(n))
        code = (
            "import sys, time\n"
            "from kinprop.cli import app\n"
            "t = time.process_time()\n"
            "try:\n"
            f'    app(["check", {str(path)!r}, "--json"])\n'
            "except SystemExit as e:\n"
            "    assert not e.code, e.code\n"
            "print(time.process_time() - t, file=sys.stderr)\n"
        )
        t0 = time.monotonic()
        p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
        wall = time.monotonic() - t0
    if p.returncode != 0:
        raise SystemExit(p.stderr[-2000:])
    return float(p.stderr.strip().splitlines()[-1]), wall


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bodies", type=int, default=20_000)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    topo = [topology_cpu(args.bodies) for _ in range(args.repeats)]
    checks = [check_cpu(args.bodies) for _ in range(args.repeats)]
    print(f"(a) build_topology, ladder of {args.bodies:,} bodies: {statistics.median(topo):.2f} s CPU median "
          f"(target < {TARGET_CPU:g} s)")  # fmt: skip
    print(f"(b) load + kinprop check, chain of {args.bodies:,} bodies: "
          f"{statistics.median(c for c, _ in checks):.2f} s CPU, {statistics.median(w for _, w in checks):.2f} s wall "
          f"median (target < {TARGET_CPU:g} s CPU)")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
