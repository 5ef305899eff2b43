"""The workbench's HTTP application: the page, its static files and the JSON API under ``/api/``.

The API answers with the CLI's JSON contracts, built by the same functions (:mod:`kinprop.io.commands`):

* ``GET /api/check`` — ``kinprop check --json`` of the session's current model;
* ``POST /api/propagate`` — ``kinprop propagate --json`` for ``{"set", "free", "weights", ...}``
  from the current model; a converged change becomes the current model (one undo step), a
  failed one is reported and not applied;
* ``POST /api/sweep`` — ``kinprop sweep --json``; ``POST /api/sensitivity`` —
  ``kinprop sensitivity --json`` (both leave the current model as it is);
* ``POST /api/undo``, ``/api/redo``, ``/api/reset``; ``GET /api/model.yaml``,
  ``/api/results.json``, ``/api/results.csv`` (downloads); ``GET /api/state`` (the page's view).

Invalid requests get HTTP 422 ``{"errors": [...]}`` with the CLI's exit-2 messages (one per
problem); malformed JSON gets 400. A session is named by the ``X-Kinprop-Session`` header
(or the ``session`` query parameter), ``default`` without one.
"""

from __future__ import annotations

import json
import tempfile
import time
import warnings
from collections.abc import Callable
from importlib import resources
from pathlib import Path
from typing import Annotated, Any

from fastapi import FastAPI, Header, Query, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, HTMLResponse, Response
from fastapi.staticfiles import StaticFiles
from pydantic import BaseModel, ConfigDict, Field

from kinprop.analysis.mobility import mobility
from kinprop.analysis.sensitivity import RESIDUAL_WARN
from kinprop.analysis.sweep import sweep
from kinprop.engine.units import changes_to_internal
from kinprop.errors import AddressError, ModelError, SingularityWarning
from kinprop.io.arguments import parse_assignment, parse_weight
from kinprop.io.commands import (
    check_json,
    check_x,
    comparison_csv,
    propagate_json,
    sensitivities,
    sensitivity_json,
    solve_propagation,
    sweep_inputs,
    sweep_json,
)
from kinprop.io.writer import dump_model_like, file_style
from kinprop.model import Model
from kinprop.plot.report import report_html, slider_joints
from kinprop.propagation import assemble
from kinprop.serve.session import Session, Sessions
from kinprop.serve.views import state_json, status_text

STATIC = resources.files("kinprop.serve") / "static"
SESSION_HEADER = "X-Kinprop-Session"

Value = float | list[float] | str
#: the session, from the header or (download links) the query
Sid = Annotated[str | None, Header(alias=SESSION_HEADER)]
QSid = Annotated[str | None, Query(alias="session")]


class PropagateRequest(BaseModel):
    """``kinprop propagate``'s options: ``set`` values in the model's units (degrees for
    angle coordinates when the file says so), as a number, a list or ``"x,y,z"``."""

    model_config = ConfigDict(extra="forbid")
    set: dict[str, Value] = Field(default_factory=dict)
    free: list[str] = Field(default_factory=lambda: ["q"])
    weights: dict[str, float] | None = None
    tol: float = 1e-10
    max_iter: int = 50
    continuation: bool | None = None


class SweepRequest(BaseModel):
    """``kinprop sweep``'s options: ``drive`` as ``JOINT=START:STOP:STEPS`` strings."""

    model_config = ConfigDict(extra="forbid")
    drive: list[str]
    set: dict[str, Value] = Field(default_factory=dict)
    free: list[str] = Field(default_factory=lambda: ["q"])
    out: list[str] | None = None
    tol: float = 1e-10
    max_iter: int = 50
    continuation: bool = False
    baseline: bool = False
    #: the abscissa of the curves (``kinprop sweep --x``): a drive, a coordinate or an output
    x: str | None = None


class SensitivityRequest(BaseModel):
    """``kinprop sensitivity``'s options."""

    model_config = ConfigDict(extra="forbid")
    wrt: list[str]
    of: list[str] | None = None
    free: list[str] = Field(default_factory=lambda: ["q"])
    weights: dict[str, float] | None = None
    tol: float = 1e-10


def json_response(obj: Any, status: int = 200, headers: dict[str, str] | None = None) -> Response:
    """The object as the CLI prints it (``json.dumps``, NaN allowed)."""
    return Response(json.dumps(obj, allow_nan=True), status, headers, media_type="application/json")


def errors(lines: list[str], status: int = 422) -> Response:
    return json_response({"errors": lines}, status)


def _assignments(values: dict[str, Value], option: str = "--set") -> list[str]:
    """``{address: value}`` as the CLI's ``ADDRESS=VALUE`` texts (same parsing, same messages)."""
    out = []
    for addr, v in values.items():
        if isinstance(v, list):
            text = ",".join(repr(float(x)) for x in v)
        elif isinstance(v, float | int):
            text = repr(float(v))
        else:
            text = v
        out.append(f"{addr}={text}")
    return out


def _changes(model: Model, values: dict[str, Value]) -> dict[str, Any]:
    return changes_to_internal(model, dict(parse_assignment(s) for s in _assignments(values)))


def _weights(values: dict[str, float] | None) -> dict[str, float] | None:
    if not values:
        return None
    return dict(parse_weight(s) for s in _assignments(dict(values), "--weight"))


def _caught(fn: Callable[[], Any]) -> tuple[Any, list[str]]:
    """``fn()`` and the distinct singularity warnings it raised (the CLI's ``warning:`` lines)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", SingularityWarning)
        out = fn()
    return out, list(dict.fromkeys(str(w.message) for w in caught if issubclass(w.category, SingularityWarning)))


def create_app(model: Model, label: str | None = None, *, assemble_first: bool = True) -> FastAPI:
    """The workbench for ``model`` (sessions start from it, assembled first unless told not)."""
    label = label or model.source or model.mechanism.name
    start_note: list[str] = []
    start_json: dict | None = None
    start_prop = None
    if assemble_first:
        (prop, _, _), notes = _caught(
            lambda: solve_propagation(model, {}, ("q",), tol=1e-10, max_iter=50, weights=None, continuation=None)
        )
        start_prop, start_json, start_note = prop, propagate_json(prop), notes
        if prop.converged:
            model = prop.after
        else:
            start_note.append(f"{label}: cannot assemble the model: {prop.result.message}; shown as given")
    sessions = Sessions(model)
    sliders = slider_joints(model)
    source = model.source if model.source and Path(model.source).is_file() else None
    hardpoint_style = source is not None and file_style(source)[0] == "hardpoints"
    start_line = status_text({}, start_json) if start_json is not None else "loaded: the coordinates as given"
    app = FastAPI(title="kinprop workbench", docs_url="/api/docs", openapi_url="/api/openapi.json", redoc_url=None)
    app.state.sessions = sessions

    @app.middleware("http")
    async def server_timing(request: Request, call_next: Callable[[Request], Any]) -> Response:
        """``Server-Timing: app;dur=MS``: the time spent in the application (benchmarks, devtools)."""
        t0 = time.perf_counter()
        response = await call_next(request)
        response.headers["Server-Timing"] = f"app;dur={(time.perf_counter() - t0) * 1e3:.3f}"
        return response

    def session(sid: str | None, q: str | None) -> Session:
        s = sessions.get(sid or q or "default")
        if not s.notes:
            s.notes[id(s.start)] = start_line
        if s.result_json is None and start_json is not None and not s.undo_stack:
            s.result, s.result_json, s.warnings = start_prop, start_json, list(start_note)
        return s

    @app.exception_handler(ModelError)
    async def _model_error(_: Request, exc: ModelError) -> Response:
        return errors([str(p) for p in exc.problems])

    @app.exception_handler(AddressError)
    @app.exception_handler(ValueError)
    async def _address_error(_: Request, exc: Exception) -> Response:
        return errors([str(exc.args[0]) if exc.args else str(exc)])

    @app.exception_handler(RequestValidationError)
    async def _invalid(_: Request, exc: RequestValidationError) -> Response:
        lines, status = [], 422
        for e in exc.errors():
            loc = ".".join(str(x) for x in e.get("loc", ()))
            found = e.get("input")
            if e.get("type") == "json_invalid":
                status = 400
                lines.append(f"request body: invalid JSON ({e.get('ctx', {}).get('error', e.get('msg'))})")
            elif e.get("loc") == ("body",) and not isinstance(found, dict):
                status = 400
                text = found.decode("utf-8", "replace") if isinstance(found, bytes) else str(found)
                lines.append(f"request body: expected a JSON object, found {text[:80]!r}")
            else:
                shown = json.dumps(found, default=str)[:80] if found is not None and not isinstance(found, dict) else ""
                lines.append(f"{loc}: {e.get('msg')}" + (f", found {shown}" if shown else ""))
        return errors(lines, status)

    # --- the page ---------------------------------------------------------------------------

    @app.get("/", include_in_schema=False)
    def index() -> HTMLResponse:
        return HTMLResponse((STATIC / "index.html").read_text(encoding="utf-8"))

    @app.get("/static/plotly.min.js", include_in_schema=False)
    def plotly_js() -> FileResponse:
        """plotly.js as shipped inside the installed ``plotly`` Python package (no CDN)."""
        path = resources.files("plotly") / "package_data" / "plotly.min.js"
        return FileResponse(str(path), media_type="text/javascript")

    app.mount("/static", StaticFiles(directory=str(STATIC)), name="static")

    @app.get("/api/state")
    def state(sid: Sid = None, q: QSid = None) -> Response:
        s = session(sid, q)
        with s.lock:
            return json_response(state_json(s, label, sliders, hardpoint_style))

    # --- the CLI's contracts ----------------------------------------------------------------

    @app.get("/api/check")
    def check(sid: Sid = None, q: QSid = None) -> Response:
        """``kinprop check --json`` of the current model."""
        m = session(sid, q).model
        obj = check_json(m, mobility(m), "the model's coordinates as given")
        obj["model"] = label
        return json_response(obj)

    @app.post("/api/propagate")
    def propagate_route(req: PropagateRequest, sid: Sid = None, q: QSid = None) -> Response:
        """``kinprop propagate --json`` from the current model; applied when converged."""
        s = session(sid, q)
        with s.lock:
            m = s.model
            changes = _changes(m, req.set)
            weights = _weights(req.weights)
            (prop, res, newton_ran), notes = _caught(
                lambda: solve_propagation(
                    m,
                    changes,
                    tuple(req.free),
                    tol=req.tol,
                    max_iter=req.max_iter,
                    weights=weights,
                    continuation=req.continuation,
                )
            )
            obj = propagate_json(prop, res, newton_ran)
            applied = obj["status"] == "converged"
            if applied:
                s.apply(prop, status_text(req.set, obj))
            s.result, s.result_json, s.warnings = prop, obj, notes
        headers = {"X-Kinprop-Applied": str(applied).lower(), "X-Kinprop-Warnings": json.dumps(notes)}
        return json_response(obj, headers=headers)

    @app.post("/api/sweep")
    def sweep_route(req: SweepRequest, sid: Sid = None, q: QSid = None) -> Response:
        """``kinprop sweep --json`` from the current model (which stays as it is)."""
        m = session(sid, q).model
        drives, changes = sweep_inputs(m, req.drive, _assignments(req.set), req.baseline)
        if req.x is not None:
            check_x(m, drives, req.out, req.x)
        kw = {"free": tuple(req.free), "outputs": req.out, "tol": req.tol, "max_iter": req.max_iter}
        (res, base), _ = _caught(
            lambda: (
                sweep(m, drives, changes=changes, continuation=req.continuation, units="solver", **kw),
                sweep(m, drives, continuation=req.continuation, **kw) if req.baseline else None,
            )
        )
        return json_response(sweep_json(res, base, x=req.x))

    @app.post("/api/sensitivity")
    def sensitivity_route(req: SensitivityRequest, sid: Sid = None, q: QSid = None) -> Response:
        """``kinprop sensitivity --json`` at the current model (assembled first, as the CLI does)."""
        m = session(sid, q).model
        weights = _weights(req.weights)
        prop, _ = _caught(lambda: assemble(m, tol=req.tol))
        r = prop.result
        if not r.converged:
            return errors([f"{label}: cannot assemble the model before differentiating: {r.message}"], 409)
        sens = sensitivities(prop.after, req.wrt, req.of, tuple(req.free), weights)
        obj = sensitivity_json(label, sens, tuple(req.free), weights, r)
        headers = {}
        if r.residual_history[0] > RESIDUAL_WARN:
            headers["X-Kinprop-Note"] = f"not assembled (||Phi|| = {r.residual_history[0]:.3g}); assembled first"
        return json_response(obj, headers=headers)

    # --- history and downloads --------------------------------------------------------------

    def _history(s: Session, ok: bool, what: str) -> Response:
        if not ok:
            return errors([f"nothing to {what}"], 409)
        return json_response({"undo": len(s.undo_stack), "redo": len(s.redo_stack)})

    @app.post("/api/undo")
    def undo(sid: Sid = None, q: QSid = None) -> Response:
        s = session(sid, q)
        with s.lock:
            return _history(s, s.undo(), "undo")

    @app.post("/api/redo")
    def redo(sid: Sid = None, q: QSid = None) -> Response:
        s = session(sid, q)
        with s.lock:
            return _history(s, s.redo(), "redo")

    @app.post("/api/reset")
    def reset(sid: Sid = None, q: QSid = None) -> Response:
        s = session(sid, q)
        with s.lock:
            s.reset()
            return _history(s, True, "reset")

    def _attachment(name: str) -> dict[str, str]:
        return {"Content-Disposition": f'attachment; filename="{name}"'}

    stem = Path(label).stem or "model"

    @app.get("/api/model.yaml")
    def model_yaml(sid: Sid = None, q: QSid = None) -> Response:
        """The current model as ``kinprop propagate -o MODEL.yaml`` writes it (full precision, the
        input file's style)."""
        m = session(sid, q).model
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "model.yaml"
            dump_model_like(m, path, source)  # a hardpoint-style input comes back hardpoint style
            text = path.read_text(encoding="utf-8")
        return Response(text, media_type="application/yaml", headers=_attachment(f"{stem}.yaml"))

    @app.get("/api/report.html")
    def report(sid: Sid = None, q: QSid = None) -> Response:
        """``kinprop report`` of the current model: one self-contained HTML file."""
        text = report_html(session(sid, q).model, f"kinprop report: {label}")
        return Response(text, media_type="text/html", headers=_attachment(f"{stem}-report.html"))

    @app.get("/api/results.json")
    def results_json(sid: Sid = None, q: QSid = None) -> Response:
        """The last propagation's ``kinprop propagate --json``."""
        s = session(sid, q)
        if s.result_json is None:
            return errors(["no propagation yet"], 404)
        return json_response(s.result_json, headers=_attachment(f"{stem}-results.json"))

    @app.get("/api/results.csv")
    def results_csv(sid: Sid = None, q: QSid = None) -> Response:
        """The last propagation's ``kinprop propagate --csv`` (before/after of every variable)."""
        s = session(sid, q)
        if s.result is None:
            return errors(["no propagation yet"], 404)
        if not s.result.converged:
            return errors(["not writing results.csv: the solve did not converge"], 409)
        return Response(comparison_csv(s.result), media_type="text/csv", headers=_attachment(f"{stem}-results.csv"))

    return app
