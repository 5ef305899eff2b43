"""Propagation to targets on examples/double_wishbone.yaml: camber gain and bump steer set
by moving two hardpoints (the upper ball joint and the tie rod's inner point), then the
before/after camber and toe curves from an ordinary sweep of each design.

Run from the repository root: ``python examples/double_wishbone_targets.py [OUT.png]``
(default double_wishbone_targets.png in the current directory). docs/guide/targets.md explains it.
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import numpy as np

from kinprop import SingularityWarning, assemble, load_model
from kinprop.analysis.sensitivity import output_sensitivity
from kinprop.analysis.sweep import sweep
from kinprop.analysis.targets import propagate_targets
from kinprop.plot.curves import plot_curves

HERE = Path(__file__).resolve().parent
TRAVEL = 50.0  # mm, each way
OUTPUTS = ["wheel_centre_dz", "camber", "toe"]
TARGETS = [
    "camber@travel=0mm=0deg",  # keep the static camber
    "camber@travel=50mm=-2deg",  # more camber gain in bump ...
    "camber@travel=-50mm=1.5deg",  # ... and in rebound
    "toe@travel=0mm=0deg",  # keep the static toe
    "slope:toe@travel=-50..50mm=0deg/m",  # no bump steer over +-50 mm
]
FREE = ["hardpoint:UBJ", "hardpoint:TR.i"]


def curves(model, drive):
    f = sweep(model, drive, outputs=OUTPUTS, tol=1e-9).frame
    return f[f["wheel_centre_dz"].abs() <= TRAVEL + 1e-9]


def main(out: Path) -> None:
    model = assemble(load_model(HERE / "double_wishbone.yaml")).after
    tp = propagate_targets(model, TARGETS, FREE)
    print(tp.result.message)
    for row in tp.table():
        print(f"  {row['target']:<38} before {row['before']:+.5f}  achieved {row['achieved']:+.5f} {row['unit']}")
    for k, d in tp.hardpoint_moves().items():
        print(f"  {k:<6} moves by [{d[0]:+.3f}, {d[1]:+.3f}, {d[2]:+.3f}] mm, |d| = {np.linalg.norm(d):.3f} mm")
    static = tp.configuration_names.index("travel:upright=0")
    for key, (a, b) in tp.joint_positions(static).items():
        if np.linalg.norm(b - a) > 1e-6:
            print(f"  at 0 mm travel {key:<6} [{a[0]:.3f}, {a[1]:.3f}, {a[2]:.3f}] -> [{b[0]:.3f}, {b[1]:.3f}, "
                  f"{b[2]:.3f}] mm ({np.linalg.norm(b - a):.3f} mm)")  # fmt: skip
    rate = output_sensitivity(model, ["wheel_centre_dz"], ["LCA.q"]).iloc[0, 0]  # mm per deg (model units)
    q = 1.3 * TRAVEL / rate  # degrees
    drive = [f"LCA={-q:.4f}:{q:.4f}:104"]
    frames = {"before (Chrono HMMWV hardpoints)": curves(model, drive),
              "after: targets met (UBJ, tie-rod inner moved)": curves(tp.after, drive)}  # fmt: skip
    for label, f in frames.items():
        lo, hi = f.iloc[0], f.iloc[-1]
        print(f"{label}: camber {lo['camber']:+.3f} .. {hi['camber']:+.3f} deg, toe {lo['toe']:+.4f} .. "
              f"{hi['toe']:+.4f} deg over {lo['wheel_centre_dz']:.1f} .. {hi['wheel_centre_dz']:.1f} mm")  # fmt: skip
    plot_curves(
        frames,
        "wheel_centre_dz",
        ["camber", "toe"],
        units={"wheel_centre_dz": "mm", "camber": "deg", "toe": "deg"},
        title="Double wishbone to targets: camber gain and zero bump steer (left wheel, ISO 8855)",
        swap_axes=True,
        path=out,
    )
    print(f"wrote {out}")


if __name__ == "__main__":
    warnings.simplefilter("ignore", SingularityWarning)
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("double_wishbone_targets.png"))
