"""Command-line interface. Each command lives in its own module and registers on ``app``.

The ``kinprop`` command enters through :mod:`kinprop.__main__`, which chooses how the
kernels run before this package (and the library) is imported.
"""

from kinprop.cli import check, convert, examples, paper, plot, sensitivity, solve, sweep  # noqa: F401  (registers commands)
from kinprop.cli import importer as _importer  # noqa: F401  (kinprop import)
from kinprop.cli import loads as _loads  # noqa: F401  (kinprop loads)
from kinprop.cli import serve as _serve  # noqa: F401  (kinprop serve)
from kinprop.cli import study as _study  # noqa: F401  (kinprop study, kinprop tolerance)
from kinprop.cli.app import app


def main() -> None:
    app(prog_name="kinprop")


__all__ = ["app", "main"]
