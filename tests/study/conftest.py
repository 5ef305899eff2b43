"""Fixtures for the study and tolerance tests: an RSSR model file."""

from __future__ import annotations

import pytest

from kinprop.builders import rssr
from kinprop.io import dump_model


@pytest.fixture(scope="session")
def rssr_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("models") / "rssr.yaml"
    dump_model(rssr(theta=1.0), path)
    return path
