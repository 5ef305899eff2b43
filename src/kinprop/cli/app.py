"""The ``kinprop`` command-line application: shared options, loading and exit codes.

Exit codes: 0 success, 1 the solver did not converge, 2 invalid input.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from functools import wraps
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
import typer
from rich.console import Console
from rich.markup import escape

from kinprop.errors import AddressError, ModelError
from kinprop.io import load_model
from kinprop.model import Model

EXIT_OK, EXIT_NOT_CONVERGED, EXIT_INVALID = 0, 1, 2

app = typer.Typer(
    name="kinprop",
    help="Kinematic design propagation in closed-loop mechanisms (Zou, Abdel-Malek & Wang 1997).",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
out = Console(highlight=False)
err = Console(stderr=True, highlight=False)

F = TypeVar("F", bound=Callable[..., Any])


def fail(lines: list[str] | str, code: int = EXIT_INVALID) -> None:
    """Print one line per problem on stderr and exit with ``code``."""
    for line in [lines] if isinstance(lines, str) else lines:
        err.print(f"[red]error:[/red] {escape(line)}", markup=True, soft_wrap=True)
    raise typer.Exit(code)


def handles_user_errors(fn: F) -> F:
    """Turn model/address errors into one stderr line per problem and exit code 2."""

    @wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return fn(*args, **kwargs)
        except ModelError as exc:
            fail([str(p) for p in exc.problems])
        except (AddressError, ValueError) as exc:
            fail(str(exc.args[0]) if exc.args else str(exc))

    return wrapper  # type: ignore[return-value]


#: model files larger than this show a progress line on a terminal while they load
PROGRESS_BYTES = 512 * 1024


def load_model_cli(path: Path) -> Model:
    """:func:`kinprop.io.load_model`, with a live status line on stderr for a large file.

    A 20,000-body model takes a few seconds to parse, validate and cut into a tree; a terminal
    user sees what is happening (a pipe or CI log gets nothing extra)."""
    try:
        size = path.stat().st_size
    except OSError:
        size = 0
    if size < PROGRESS_BYTES or not err.is_terminal:
        return load_model(path)
    with err.status(f"loading {escape(str(path))} ({size / 1e6:.1f} MB): parsing, validating, building the tree"):
        model = load_model(path)
    err.print(
        f"loaded {escape(str(path))}: {len(model.mechanism.bodies)} bodies, {len(model.mechanism.joints)} joints",
        highlight=False,
    )
    return model


def parse_assignment(text: str) -> tuple[str, np.ndarray]:
    """``ADDRESS=v1,v2,...`` -> (address, values)."""
    if "=" not in text:
        raise AddressError(f"--set {text!r}: expected ADDRESS=VALUE (e.g. J12.s_j=-2.8,0.2,0.1)")
    addr, _, value = text.partition("=")
    try:
        nums = np.array([float(x) for x in value.replace(";", ",").split(",") if x.strip()], dtype=float)
    except ValueError:
        raise AddressError(f"--set {text!r}: values must be comma-separated numbers") from None
    if nums.size == 0:
        raise AddressError(f"--set {text!r}: no value given")
    return addr.strip(), nums


def parse_weight(text: str) -> tuple[str, float]:
    addr, nums = parse_assignment(text)
    if nums.size != 1:
        raise AddressError(f"--weight {text!r}: expected one number")
    return addr, float(nums[0])


def print_json(obj: Any) -> None:
    sys.stdout.write(json.dumps(obj, allow_nan=True) + "\n")
