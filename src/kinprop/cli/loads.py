"""``kinprop loads``: joint reactions, member and element forces and input efforts of an
assembled model under a load case (:func:`kinprop.statics`)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.table import Table

from kinprop.analysis.metrics import wheel_bodies
from kinprop.analysis.statics import Statics, equilibrium, statics, wheel_rate
from kinprop.cli.app import (
    EXIT_NOT_CONVERGED,
    app,
    err,
    fail,
    handles_user_errors,
    load_model_cli,
    out,
    print_json,
    require_plot,
)
from kinprop.cli.checks import check_outputs, check_suffix
from kinprop.engine.units import from_solver_units
from kinprop.errors import AddressError
from kinprop.io.arguments import parse_assignment
from kinprop.io.writer import atomic_write, csv_text
from kinprop.model import Model
from kinprop.model.loads import LoadCase, PointLoad
from kinprop.propagation import assemble

#: a table entry below this fraction of the table's largest is shown as 0 (round-off)
ROUNDOFF = 1e-12


def _vec(text: str, option: str) -> tuple[str, tuple[float, float, float]]:
    key, v = parse_assignment(text, option)
    if v.size != 3:
        raise AddressError(f"{option} {text!r}: expected three numbers")
    return key, (float(v[0]), float(v[1]), float(v[2]))


def build_case(model: Model, name: str | None, wheels: list[str], forces: list[str], moments: list[str],
               gravity: str | None) -> LoadCase | None:  # fmt: skip
    """The named case of the model's ``loads:`` plus the loads given on the command line."""
    base = None
    if name is not None:
        if model.loads is None or name not in model.loads.cases:
            known = ", ".join(model.loads.cases) if model.loads is not None else ""
            raise AddressError(f"--load-case {name!r}: not a load case of the model; load cases: {known or 'none'}")
        base = model.loads.cases[name]
    if not (wheels or forces or moments or gravity):
        return base
    pts = list(base.forces) if base else []
    for text in forces:
        key, f = _vec(text, "--force")
        body, _, point = key.partition(".")
        if not point:
            raise AddressError(f"--force {text!r}: expected BODY.POINT=Fx,Fy,Fz (a named point of the body)")
        pts.append(PointLoad(body, point, force=f))
    for text in moments:
        body, mo = _vec(text, "--moment")
        pts.append(PointLoad(body, (0.0, 0.0, 0.0), moment=mo))
    wh = dict(base.wheels) if base else {}
    for text in wheels:
        body, fw = _vec(text, "--wheel")
        wh[body] = fw
    g = base.gravity if base else None
    if gravity is not None:
        _, g = _vec(f"g={gravity}", "--gravity")
    return LoadCase(name or "command line", tuple(pts), wh, g)


def statics_json(s: Statics) -> dict:
    reactions = {}
    for j, r in s.reactions.items():
        reactions[j] = {
            "bodies": list(r.bodies),
            "points": [p.tolist() for p in r.points],
            "force": [f.tolist() for f in r.force],
            "moment": [m.tolist() for m in r.moment],
            "local": r.local.tolist(),
            "undetermined": list(r.undetermined),
        }
    return {
        "model": s.model.mechanism.name,
        "case": s.case,
        "status": s.status,
        "message": s.message,
        "residual": s.residual,
        "units": s.units,
        "efforts": dict(s.efforts),
        "reactions": reactions,
        "member_forces": dict(s.member_forces),
        "element_forces": dict(s.element_forces),
        "element_lengths": dict(s.element_lengths),
        "undetermined": list(s.undetermined),
    }


def statics_csv(s: Statics) -> str:
    u = s.units
    rows = []
    for name in s.names():
        unit = u["moment"] if name.split(".")[-1].startswith("m") and name.startswith("reaction:") else u["force"]
        if name.startswith("effort:"):
            jt = s.model.mechanism.joint(name[len("effort:") :].split(".")[0]).jtype
            unit = u["moment"] if jt.angle_indices else u["force"]
        rows.append({"output": name, "unit": unit, "value": s.value(name)})
    return csv_text(["output", "unit", "value"], rows)


@app.command()
@handles_user_errors
def loads(
    model: Annotated[Path, typer.Argument(help="model file (YAML or JSON)")],
    load_case: Annotated[
        str | None, typer.Option("--load-case", help="a load case of the model's loads: section")
    ] = None,
    wheel: Annotated[
        list[str], typer.Option("--wheel", help="WHEEL=Fx,Fy,Fz: contact-patch force, ISO 8855 axes")
    ] = [],  # noqa: B006
    force: Annotated[
        list[str], typer.Option("--force", help="BODY.POINT=Fx,Fy,Fz: a force at a named point, global axes")
    ] = [],  # noqa: B006
    moment: Annotated[list[str], typer.Option("--moment", help="BODY=Mx,My,Mz: a couple on a body, global axes")] = [],  # noqa: B006
    gravity: Annotated[
        str | None, typer.Option("--gravity", help="gx,gy,gz in g (the weights of loads.masses)")
    ] = None,
    input_: Annotated[list[str], typer.Option("--input", help="held input (default: the model's inputs:)")] = [],  # noqa: B006
    json_out: Annotated[bool, typer.Option("--json", help="one JSON object on stdout")] = False,
    csv: Annotated[Path | None, typer.Option("--csv", help="write every load output as CSV")] = None,
    tol: Annotated[float, typer.Option("--tol", help="assembly tolerance before the statics")] = 1e-10,
    equilibrium_: Annotated[
        bool,
        typer.Option("--equilibrium", help="first find the pose where the springs hold the loads (inputs released)"),
    ] = False,
    plot: Annotated[
        Path | None,
        typer.Option(
            "--plot", help="draw the forces as arrows on the mechanism (.png or .html; red tension, blue compression)"
        ),
    ] = None,
) -> None:
    """Joint reactions, member forces (tension positive), spring and damper forces (positive
    pushing apart) and the efforts that hold the inputs, at the model's assembled pose.

    Forces in the model's force unit (units: {force: N}), moments in force x length.
    A redundant mechanism's undetermined reaction components are named and shown as nan.
    """
    check_suffix("--csv", csv, (".csv",))
    check_suffix("--plot", plot, (".png", ".html"))
    check_outputs([model], [("--csv", csv), ("--plot", plot)])
    if plot is not None:
        require_plot(plot)
    m = load_model_cli(model)
    case = build_case(m, load_case, wheel, force, moment, gravity)
    asm = assemble(m, tol=tol)
    if asm.result.status != "converged":
        fail(f"{model}: the model does not assemble ({asm.result.status}); no loads at an unassembled pose",
             EXIT_NOT_CONVERGED)  # fmt: skip
    at = asm.after
    eq = None
    if equilibrium_:
        eq = equilibrium(at, case, release=input_ or None)
        if not eq.converged:
            fail(f"{model}: no static equilibrium: {eq.message}", EXIT_NOT_CONVERGED)
        at = eq.model
    s = statics(at, case, inputs=input_ or None, reference=asm.after)
    if csv is not None and s.ok:
        atomic_write(csv, statics_csv(s))
    if plot is not None and s.ok:
        from kinprop.plot import render
        from kinprop.plot.forces import force_arrows

        title = f"{at.mechanism.name}: load case {s.case or '(elements only)'}"
        atomic_write(plot, render(plot, at, title=title, arrows=force_arrows(s, case), force_unit=s.units["force"]))
    rate = _wheel_rate(at, input_) if equilibrium_ else None
    if json_out:
        data = statics_json(s)
        if eq is not None:
            data["equilibrium"] = {"status": eq.status, "message": eq.message,
                                   "coordinates": {a: _model_value(at, a) for a in eq.released},
                                   "iterations": eq.iterations, "stable": eq.stable, "wheel_rate": rate}  # fmt: skip
        print_json(data)
    else:
        if eq is not None:
            pos = ", ".join(f"{a} = {_model_value(at, a):.6g}" for a in eq.released)
            out.print(
                f"equilibrium after {eq.iterations - 1} Newton step(s): {pos} ({'stable' if eq.stable else 'UNSTABLE'})"
            )
            if rate is not None:
                out.print(f"wheel rate at the wheel centre: {rate:.6g} {s.units['force']}/{s.units['length']}")
        _print(s)
    if not s.ok:
        err.print(f"error: {model}: {s.message}", soft_wrap=True, markup=False)
        raise typer.Exit(EXIT_NOT_CONVERGED)


def _model_value(model: Model, address: str) -> float:
    """A single input coordinate in the model's units."""
    return float(np.atleast_1d(from_solver_units(model, address, model.coordinates[address.split(".")[0]]))[0])


def _wheel_rate(model: Model, inputs: list[str]) -> float | None:
    """The wheel rate of the springs when the model has one wheel body and one input, else None."""
    if len(wheel_bodies(model)) != 1:
        return None
    try:
        return wheel_rate(model, inputs=inputs or None)
    except ValueError:
        return None


def _fmt(x: float, scale: float) -> str:
    """Six significant digits; round-off (below 1e-12 of the table's largest) shown as 0."""
    return "0" if abs(x) <= ROUNDOFF * scale else f"{x:.6g}"


def _print(s: Statics) -> None:
    u = s.units
    out.print(f"{s.model.mechanism.name}: load case {s.case or '(elements only)'}: {s.message}", soft_wrap=True)
    t = Table(title=f"joint reactions on body j, global axes ({u['force']}; {u['moment']} about the joint's point)")
    for c in ("joint", "on body", "fx", "fy", "fz", "|f|", "mx", "my", "mz"):
        t.add_column(c, justify="left" if c in ("joint", "on body") else "right")
    fs = max([float(np.nanmax(np.abs(r.force[1]), initial=0.0)) for r in s.reactions.values()] + [0.0])
    ms = max([float(np.nanmax(np.abs(r.moment[1]), initial=0.0)) for r in s.reactions.values()] + [0.0])
    for j, r in s.reactions.items():
        f, mo = r.force[1], r.moment[1]
        t.add_row(j, r.bodies[1], *(_fmt(x, fs) for x in (*f, float(np.linalg.norm(f)))), *(_fmt(x, ms) for x in mo))
    out.print(t)
    if s.member_forces or s.element_forces:
        t = Table(title=f"member forces (tension +) and element forces (pushing apart +), {u['force']}")
        t.add_column("name")
        t.add_column("kind")
        t.add_column("force", justify="right")
        for n, v in s.member_forces.items():
            t.add_row(n, "member", f"{v:.6g}")
        kinds = {e.name: e.kind for e in (*s.model.elements, *s.model.torsion_springs)}
        for n, v in s.element_forces.items():
            unit = f" {u['moment']}" if kinds[n] == "torsion" else ""
            t.add_row(n, kinds[n], f"{v:.6g}{unit}")
        out.print(t)
    for a, v in s.efforts.items():
        jt = s.model.mechanism.joint(a.split(".")[0]).jtype
        out.print(f"effort {a}: {v:.6g} {u['moment'] if jt.angle_indices else u['force']}")
    if s.undetermined:
        out.print(f"undetermined (redundant constraints): {', '.join(s.undetermined)}", soft_wrap=True)
