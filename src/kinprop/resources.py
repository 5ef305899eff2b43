"""Files shipped with kinprop: the example models (also the paper's two mechanisms).

In a source checkout they are the repository's ``examples/``; an installed wheel carries a
copy as package data in ``kinprop/examples/`` (setup.py copies it at build time), so
``kinprop paper`` works after a plain ``pip install .``.
"""

from __future__ import annotations

from pathlib import Path

_PACKAGE = Path(__file__).resolve().parent


def examples_dir() -> Path:
    """The directory of the example model files (package data first, then the checkout)."""
    shipped = _PACKAGE / "examples"
    if shipped.is_dir():
        return shipped
    checkout = _PACKAGE.parents[1] / "examples"
    if checkout.is_dir():
        return checkout
    raise FileNotFoundError(f"kinprop's example models are missing: looked in {shipped} and {checkout}")


__all__ = ["examples_dir"]
