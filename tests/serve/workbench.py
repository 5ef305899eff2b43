"""Helpers of the workbench tests: the CLI runner, a live uvicorn server, the browser check."""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import socket
import subprocess
import threading
import time
from pathlib import Path

import pytest
from typer.testing import CliRunner

from kinprop.cli import app as cli_app

ROOT = Path(__file__).resolve().parents[2]
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


def require_browser() -> str:
    """Debian's chromium and Playwright for Python. Under CI a missing chromium is installed
    once (scripts/install-test-deps.sh) and otherwise fails the test; outside CI it skips."""
    ci = bool(os.environ.get("CI"))
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None and ci:
        with contextlib.suppress(OSError, subprocess.SubprocessError):
            subprocess.run(["bash", str(ROOT / "scripts" / "install-test-deps.sh")], capture_output=True, timeout=1200)
        exe = shutil.which("chromium")
    missing = None if exe else "chromium is not installed (Debian package 'chromium'; run scripts/install-test-deps.sh)"
    if missing is None:
        try:
            import playwright.sync_api  # noqa: F401
        except ImportError:
            missing = "Playwright for Python is not installed (pip install 'kinprop[test]')"
    if missing:
        if ci:
            pytest.fail(f"{missing}: the browser test cannot run under CI", pytrace=False)
        pytest.skip(missing)
    return exe
