"""Fixtures of the workbench tests: a TestClient or a live server for an example model."""

from __future__ import annotations

import warnings
from collections.abc import Callable
from pathlib import Path

import pytest

pytest.importorskip("fastapi")
pytest.importorskip("uvicorn")

from workbench import Server

from kinprop import load_model
from kinprop.serve import create_app


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
def live_server(examples: Path) -> Callable[[str], Server]:
    """``live_server(name)``: a running server (context manager) for ``examples/NAME``."""

    def start(name: str) -> Server:
        path = examples / name
        return Server(create_app(load_model(path), f"examples/{name}"))

    return start
