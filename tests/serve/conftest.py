"""Fixtures for the workbench tests: the app for an example model, the CLI runner."""

from __future__ import annotations

import json
import socket
import threading
import time
import warnings
from collections.abc import Iterator
from pathlib import Path

import pytest
from typer.testing import CliRunner

pytest.importorskip("fastapi")
pytest.importorskip("uvicorn")

from kinprop import load_model
from kinprop.cli import app as cli_app
from kinprop.serve import create_app

runner = CliRunner()


def cli(*args: object) -> tuple[int, str, str]:
    """``kinprop ARGS``: (exit code, stdout, stderr)."""
    r = runner.invoke(cli_app, [str(a) for a in args])
    return r.exit_code, r.stdout, r.stderr


def cli_json(*args: object) -> dict:
    code, out, err = cli(*args)
    assert out.strip(), f"exit {code}, no JSON on stdout; stderr: {err}"
    return json.loads(out)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Server:
    """uvicorn serving ``app`` in a thread on 127.0.0.1 (a free port)."""

    def __init__(self, app) -> None:
        import uvicorn

        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}/"
        self.server = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=self.port, log_level="warning"))
        self.thread = threading.Thread(target=self.server.run, daemon=True)

    def __enter__(self) -> Server:
        self.thread.start()
        deadline = time.monotonic() + 30
        while not self.server.started:
            if time.monotonic() > deadline or not self.thread.is_alive():
                raise RuntimeError("uvicorn did not start")
            time.sleep(0.02)
        return self

    def __exit__(self, *exc: object) -> None:
        self.server.should_exit = True
        self.thread.join(timeout=10)


@pytest.fixture
def make_client(examples: Path):
    """``make_client(name)``: a TestClient of a fresh workbench for ``examples/NAME``."""
    with warnings.catch_warnings():  # starlette's note about httpx's successor
        warnings.simplefilter("ignore")
        from fastapi.testclient import TestClient

    def make(name: str, **kw) -> TestClient:
        path = examples / name
        return TestClient(create_app(load_model(path), str(path), **kw))

    return make


@pytest.fixture
def live_server(examples: Path) -> Iterator:
    """``live_server(name)``: a running server (context manager) for ``examples/NAME``."""

    def start(name: str) -> Server:
        path = examples / name
        return Server(create_app(load_model(path), str(path)))

    return start
