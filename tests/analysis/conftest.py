"""Fixtures for the analysis tests: assembled examples, a McPherson strut with a wheel."""

from __future__ import annotations

import pytest
from analysis_helpers import EXAMPLES, MCPHERSON_WHEEL, solved, with_points

from kinprop import Model


@pytest.fixture(scope="session")
def slider_crank() -> Model:
    m = solved(EXAMPLES / "slider_crank.yaml")
    return with_points(m, "rod", {"mid": (-1.414, 0.1, 0.05)})


@pytest.fixture(scope="session")
def mcpherson() -> Model:
    return with_points(solved(EXAMPLES / "mcpherson.yaml"), "wheel", MCPHERSON_WHEEL)


@pytest.fixture(scope="session")
def double_wishbone() -> Model:
    # lengths in mm: the distance row d.d - l^2 is ~1e5 mm^2, so its rounding floor is ~3e-11
    return solved(EXAMPLES / "double_wishbone.yaml", tol=1e-9)
