"""Shared fixtures: paths to the shipped examples and the paper."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

# command-line runs in tests compile (deterministic); tests/cli/test_first_run.py covers "auto"
os.environ.setdefault("KINPROP_JIT", "on")

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"


@pytest.fixture(scope="session")
def examples() -> Path:
    return EXAMPLES
