"""Responsiveness of ``kinprop serve``: one hardpoint edit, the 3D scene and a 50-point camber curve.

For the McPherson strut (``examples/mcpherson.yaml``) and the double wishbone
(``examples/double_wishbone.yaml``), one edit is what the page does after a designer types a
new hardpoint coordinate:

1. ``POST /api/propagate`` — the edit (a hardpoint's z + 10 mm, free: q), re-assembled;
2. ``GET /api/state`` — the re-assembled model's 3D scene, design table and sliders;
3. ``POST /api/sweep`` — the camber curve, 50 points of the page's default drive.

Server time is the application's own ``Server-Timing`` (no network); the session is reset
between repeats (not timed), so every repeat makes the same edit. The McPherson file declares
no wheel, so a copy gets two named points on its wheel body (a wheel centre at the ball joint
and a spin axis along the paper's x, outboard at the assembled configuration) for the camber
metric; its curve drives the steering rack (TD), the double wishbone's the lower arm (LCA).

    .venv/bin/python benchmarks/serve_latency.py [--repeats 15]
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
import yaml

import kinprop as kp
from kinprop.analysis.points import snapshot
from kinprop.serve import create_app

ROOT = Path(__file__).resolve().parents[1]
TARGET_MS = 100.0


def mcpherson_with_wheel(tmp: Path) -> Path:
    """examples/mcpherson.yaml with wheel points on the wheel body (for the camber metric)."""
    src = ROOT / "examples" / "mcpherson.yaml"
    asm = kp.assemble(kp.load_model(src)).after
    A = snapshot(asm).A["wheel"]
    centre = np.asarray(asm.design["RS.s_j"], dtype=float)
    spin = centre + A.T @ np.array([1.0, 0.0, 0.0])  # the paper's x: outboard
    data = yaml.safe_load(src.read_text())
    data["bodies"]["wheel"] = {"points": {"wheel_centre": centre.tolist(), "spin_axis": spin.tolist()}}
    path = tmp / "mcpherson_wheel.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def server_ms(response) -> float:
    assert response.status_code == 200, response.text
    return float(response.headers["server-timing"].split("dur=")[1])


def bench(path: Path, address: str, dz: float, repeats: int) -> dict[str, list[float]]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from fastapi.testclient import TestClient
    client = TestClient(create_app(kp.load_model(path), str(path)))
    state = client.get("/api/state").json()
    row = next(v for v in state["variables"] if v["address"] == address)
    value = list(row["value"])
    value[2] += dz
    drive = state["drives"][0]
    lo, hi = drive["curve"]
    sweep_req = {"drive": [f"{drive['spec']}={lo}:{hi}:49"], "out": ["camber"]}
    times: dict[str, list[float]] = {k: [] for k in ("propagate", "state", "sweep", "total", "wall")}
    for k in range(repeats + 1):  # the first repeat warms up (imports, caches)
        client.post("/api/reset")
        t0 = time.perf_counter()
        r1 = client.post("/api/propagate", json={"set": {address: value}, "free": ["q"]})
        r2 = client.get("/api/state")
        r3 = client.post("/api/sweep", json=sweep_req)
        wall = (time.perf_counter() - t0) * 1e3
        assert r1.json()["status"] == "converged"
        rows = r3.json()["rows"]
        assert len(rows) == 50 and r3.json()["converged"] == 50, r3.json()["failed"]
        assert all(np.isfinite(r["camber"]) for r in rows)
        if k == 0:
            continue
        parts = [server_ms(r) for r in (r1, r2, r3)]
        for name, t in zip(("propagate", "state", "sweep"), parts, strict=True):
            times[name].append(t)
        times["total"].append(sum(parts))
        times["wall"].append(wall)
    return times


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=15)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        cases = [
            ("McPherson (ST.s_i z +10 mm; camber vs TD)", mcpherson_with_wheel(Path(tmp)), "ST.s_i", 0.010),
            (
                "double wishbone (UCA.s_i z +10 mm; camber vs LCA)",
                ROOT / "examples" / "double_wishbone.yaml",
                "UCA.s_i",
                10.0,
            ),
        ]
        print(f"server time per edit [ms], median (min-max) of {args.repeats} repeats; target {TARGET_MS:g} ms")
        head = (
            f"{'model':52s} {'propagate':>16s} {'state (3D)':>16s} {'sweep (50 pts)':>18s} {'total':>18s} {'wall':>9s}"
        )
        print(head)
        for name, path, address, dz in cases:
            t = bench(path, address, dz, args.repeats)

            def cell(v: list[float], w: int) -> str:
                return f"{statistics.median(v):.1f} ({min(v):.0f}-{max(v):.0f})".rjust(w)

            total = statistics.median(t["total"])
            print(
                f"{name:52s} {cell(t['propagate'], 16)} {cell(t['state'], 16)} {cell(t['sweep'], 18)} "
                f"{cell(t['total'], 18)} {statistics.median(t['wall']):9.1f}"
                + ("" if total < TARGET_MS else "  (over target)")
            )


if __name__ == "__main__":
    main()
