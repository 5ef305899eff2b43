"""Camber and toe versus wheel travel of examples/double_wishbone.yaml, before and after
raising the upper arm's inner pivot axis by 10 mm (propagated with free q).

Run from the repository root: ``python examples/double_wishbone_curves.py [OUT.png]``
(default docs/img/double_wishbone_curves.png).
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import numpy as np

from kinprop import SingularityWarning, assemble, load_model, propagate
from kinprop.analysis.sensitivity import output_sensitivity
from kinprop.analysis.sweep import sweep
from kinprop.plot.curves import plot_curves

HERE = Path(__file__).resolve().parent
TRAVEL = 50.0  # mm, each way
OUTPUTS = ["wheel_centre_dz", "camber", "toe"]


def curves(out: Path) -> None:
    model = assemble(load_model(HERE / "double_wishbone.yaml")).after
    # the lower arm angle that gives +-TRAVEL (plus a margin) at the design position
    rate = output_sensitivity(model, ["wheel_centre_dz"], ["LCA.q"]).iloc[0, 0]  # mm per deg (model units)
    q = 1.3 * TRAVEL / rate  # degrees, the file's angle unit
    drive = [f"LCA={-q:.4f}:{q:.4f}:104"]
    before = sweep(model, drive, outputs=OUTPUTS, tol=1e-9).frame
    s = np.array(model.design["UCA.s_i"])
    s[2] += 10.0  # raise the upper arm's inner pivot axis (both pivots) by 10 mm
    changed = propagate(model, {"UCA.s_i": s}, ("q",))
    changed.result.raise_for_status()
    after = sweep(changed.after, drive, outputs=OUTPUTS, tol=1e-9).frame
    frames = {
        "before (Chrono HMMWV hardpoints)": before[before["wheel_centre_dz"].abs() <= TRAVEL + 1e-9],
        "after: upper inner pivots +10 mm z": after[after["wheel_centre_dz"].abs() <= TRAVEL + 1e-9],
    }
    plot_curves(
        frames,
        "wheel_centre_dz",
        ["camber", "toe"],
        units={"wheel_centre_dz": "mm", "camber": "deg", "toe": "deg"},
        title="Front double wishbone: camber and toe vs wheel travel (left wheel, ISO 8855)",
        swap_axes=True,
        path=out,
    )
    for label, f in frames.items():
        lo, hi = f.iloc[0], f.iloc[-1]
        print(
            f"{label}: travel {lo['wheel_centre_dz']:.1f} .. {hi['wheel_centre_dz']:.1f} mm, "
            f"camber {lo['camber']:.3f} .. {hi['camber']:.3f} deg, toe {lo['toe']:.3f} .. {hi['toe']:.3f} deg"
        )
    print(f"wrote {out}")


if __name__ == "__main__":
    warnings.simplefilter("ignore", SingularityWarning)
    curves(Path(sys.argv[1]) if len(sys.argv) > 1 else HERE.parent / "docs" / "img" / "double_wishbone_curves.png")
