"""``kinprop serve``: the browser workbench (needs ``pip install kinprop[serve]``)."""

from __future__ import annotations

import socket
import threading
import webbrowser
from pathlib import Path
from typing import Annotated

import typer

from kinprop.cli.app import app, fail, handles_user_errors, out
from kinprop.io import load_model


@app.command(name="serve")
@handles_user_errors
def serve_cmd(
    model: Annotated[Path, typer.Argument(help="model file (YAML or JSON)")],
    host: Annotated[str, typer.Option("--host", help="address to bind (default: this machine only)")] = "127.0.0.1",
    port: Annotated[int, typer.Option("--port", help="TCP port")] = 8000,
    open_browser: Annotated[bool, typer.Option("--open", help="open the page in the default browser")] = False,
    assemble_first: Annotated[
        bool, typer.Option("--assemble/--no-assemble", help="assemble the model (free: q) when loading it")
    ] = True,
) -> None:
    """Start the design-propagation workbench in the browser (edit, propagate, sweep, undo)."""
    try:
        from kinprop.serve import create_app, serve
    except ImportError as exc:
        fail(f"kinprop serve needs the optional dependencies: pip install 'kinprop[serve]' ({exc})")
    m = load_model(model)
    if not 0 < port < 65536:
        raise ValueError(f"--port {port}: expected 1..65535")
    with socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET) as probe:
        try:
            probe.bind((host, port))
        except OSError as exc:
            fail(f"--host {host} --port {port}: cannot listen there ({exc.strerror or exc})")
    application = create_app(m, str(model), assemble_first=assemble_first)
    url = f"http://{'[' + host + ']' if ':' in host else host}:{port}/"
    out.print(f"kinprop workbench for {model}: {url}  (Ctrl-C to stop)", soft_wrap=True)
    if open_browser:
        threading.Timer(1.0, webbrowser.open, args=(url,)).start()
    serve(application, host, port)
