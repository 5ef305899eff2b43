"""Command-line interface. Each command lives in its own module and registers on ``app``;
``app`` imports a command's module only when that command is used (:data:`COMMANDS`), so
``kinprop --help`` and ``--version`` do not import the library.

The ``kinprop`` command enters through :mod:`kinprop.__main__`, which chooses how the
kernels run before any command (and the library) is imported.
"""

from kinprop.cli.app import COMMANDS, app, load_commands


def main() -> None:
    app(prog_name="kinprop")


__all__ = ["COMMANDS", "app", "load_commands", "main"]
