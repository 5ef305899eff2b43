"""``kinprop vehicle``: a vehicle file's parameters and each axle's anti geometry, roll centre,
roll steer and camber and steering ratio (:func:`kinprop.io.vehicle.vehicle_summary`)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.table import Table

from kinprop.cli.app import app, handles_user_errors, out, print_json


def _num(x: Any, digits: int = 6) -> str:
    if x is None:
        return "-"
    if isinstance(x, str):
        return x
    return "0" if x == 0 else f"{x:.{digits}g}" if math.isfinite(x) else str(x)


@app.command(name="vehicle")
@handles_user_errors
def vehicle_cmd(
    file: Annotated[Path, typer.Argument(help="vehicle file (YAML or JSON): two axle files, the vehicle's parameters")],
    as_json: Annotated[bool, typer.Option("--json", help="print one JSON object instead of tables")] = False,
) -> None:
    """Vehicle report: wheelbase, CG height, brake and drive split, and each axle's anti geometry, roll
    centre, roll steer and camber and steering ratio."""
    from kinprop.io.vehicle import load_vehicle, vehicle_summary

    s = vehicle_summary(load_vehicle(file))
    if as_json:
        print_json(s)
        return
    unit = s["units"]["length"]
    head = Table(title=s["name"], title_justify="left", show_header=False)
    head.add_column("parameter")
    head.add_column("value", justify="right")
    head.add_row(f"wheelbase [{unit}]", _num(s["wheelbase"]))
    head.add_row(f"CG height [{unit}]", _num(s["cg_height"]))
    head.add_row("brake front share", _num(s["brake_front"]))
    head.add_row("drive front share", _num(s["drive_front"]))
    head.add_row("brakes / drive", f"{s['brakes']} / {s['drive']}")
    head.add_row(f"rack travel per turn [{unit}]", _num(s["rack_travel_per_turn"]))
    out.print(head)
    axles = Table(title="axles (left wheel; roll steer and camber of the left / right wheel)", title_justify="left")
    for c in ("quantity", "unit", "front", "rear"):
        axles.add_column(c, justify="left" if c in ("quantity", "unit") else "right")
    f, r = s["front"], s["rear"]
    rows = [("track", unit, "track"), ("anti-dive", "%", "anti_dive"), ("anti-lift", "%", "anti_lift"),
            ("anti-squat", "%", "anti_squat"), ("roll-centre height", unit, "roll_centre_height")]  # fmt: skip
    for label, u, key in rows:
        axles.add_row(label, u, _num(f.get(key)), _num(r.get(key)))
    for label, key in (("roll steer", "roll_steer"), ("roll camber", "roll_camber")):
        pair = [" / ".join(_num(a[key][a["wheels"][side]], 4) for side in ("left", "right")) for a in (f, r)]
        axles.add_row(label, "deg/deg", *pair)
    axles.add_row("steering ratio", "deg/deg", _num(f["steering_ratio"], 4), _num(r["steering_ratio"], 4))
    out.print(axles)
    out.print(f"front: {f['source']}\nrear: {r['source']}")
