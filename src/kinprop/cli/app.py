"""The ``kinprop`` command-line application: shared options, loading and exit codes.

Exit codes: 0 success, 1 the solver did not converge, 2 invalid input.

The commands are loaded lazily: this module imports typer and rich only, and a command's
module (with the library and numba under it) is imported when that command runs or its own
``--help`` is asked for; ``kinprop --help`` lists :data:`COMMANDS` and ``kinprop --version``
reads the package metadata (benchmarks/cold_start.py).
"""

from __future__ import annotations

import importlib
import json
import math
import signal
import sys
import threading
from collections.abc import Callable
from functools import wraps
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, NoReturn, TypeVar

import typer
from rich.console import Console, ConsoleDimensions
from rich.table import Table
from rich.text import Text
from typer.core import TyperGroup

try:  # typer >= 0.20 carries its own copy of click; its exceptions are the ones raised
    from typer import _click as click
except ImportError:  # pragma: no cover - older typer on the real click
    import click  # type: ignore[no-redef]

from kinprop.errors import AddressError, ModelError

if TYPE_CHECKING:
    from kinprop.model import Model

EXIT_OK, EXIT_NOT_CONVERGED, EXIT_INVALID, EXIT_INTERRUPTED = 0, 1, 2, 130
#: the exit status after SIGTERM (128 + 15, the shell's convention)
EXIT_TERMINATED = 143

#: optional modules -> the extra that installs them (``pip install 'kinprop[EXTRA]'``)
EXTRAS = {
    "pandas": "data",
    "pyarrow": "data",
    "matplotlib": "plot",
    "plotly": "plot",
    "dask": "dask",
    "distributed": "dask",
}


#: every command, in the order ``kinprop --help`` lists them, a session's order (look at a
#: model, solve it, analyse it, share it, other tools' files, the paper): the module that defines it (on
#: ``app``) and its one-line help, the first paragraph of its docstring (tests/cli/test_startup.py
#: checks both against the commands themselves)
COMMANDS: dict[str, tuple[str, str]] = {
    "examples": (
        "kinprop.cli.examples",
        "List the example models (the paper's mechanisms and more), or copy them to a directory.",
    ),
    "check": ("kinprop.cli.check", "Mechanism report: structure, loops, counts, mobility and redundant constraints."),
    "plot": ("kinprop.cli.plot", "Draw a 3D stick figure of a model (PNG or interactive HTML)."),
    "assemble": (
        "kinprop.cli.solve",
        "Solve for the joint coordinates from the model's estimates (with freedom left: the assembly closest to them).",
    ),
    "propagate": (
        "kinprop.cli.solve",
        "Change design variables and re-assemble, moving only the free variables; with --target, find the "
        "smallest change of the --free design variables meeting the targets.",
    ),
    "sweep": ("kinprop.cli.sweep", "Drive joint coordinates over a range; each step is solved from the previous one."),
    "sensitivity": (
        "kinprop.cli.sensitivity",
        "Derivatives of outputs (default: the free variables) with respect to design variables.",
    ),
    "tolerance": (
        "kinprop.cli.study",
        "Linearised output standard deviations from design-variable tolerances (sensitivity matrix).",
    ),
    "study": (
        "kinprop.cli.study",
        "Run a design study: every variant re-assembled, inputs and results streamed to Parquet.",
    ),
    "loads": (
        "kinprop.cli.loads",
        "Joint reactions, member forces (tension positive), spring and damper forces (positive pushing apart) "
        "and the efforts that hold the inputs, at the model's assembled pose.",
    ),
    "vehicle": (
        "kinprop.cli.vehicle",
        "Vehicle report: wheelbase, CG height, brake and drive split, and each axle's anti geometry, roll centre, "
        "roll steer and camber and steering ratio.",
    ),
    "report": (
        "kinprop.cli.report",
        "Write a self-contained HTML report: the global hardpoints and the default curves.",
    ),
    "serve": (
        "kinprop.cli.serve",
        "Start the design-propagation workbench in the browser (edit, propagate, sweep, undo).",
    ),
    "import": ("kinprop.cli.importer", "Read another tool's mechanism file and write it as a kinprop model file."),
    "convert": (
        "kinprop.cli.convert",
        "Convert a model between frame style (s', C, q) and hardpoint style (global points and axes), or write "
        "it as a kinematic MuJoCo MJCF file (--to mjcf; at the model's coordinates).",
    ),
    "paper": ("kinprop.cli.paper", "Reproduce the paper's Table 4 (slider-crank) and Table 1 (McPherson strut)."),
}


def load_commands(names: list[str] | None = None) -> None:
    """Import the modules of ``names`` (default: every module of :mod:`kinprop.cli`, so a
    command missing from :data:`COMMANDS` still registers), which register them on ``app``."""
    if names is not None:
        for name in names:
            importlib.import_module(COMMANDS[name][0])
        return
    import pkgutil

    import kinprop.cli

    for mod in pkgutil.iter_modules(kinprop.cli.__path__):
        if mod.name not in ("warmup",):  # run as a script (python -m kinprop.cli.warmup)
            importlib.import_module(f"kinprop.cli.{mod.name}")


class _Group(TyperGroup):
    """The command group, with usage errors as one ``error:`` line and SIGTERM as Ctrl-C,
    loading each command's module when the command is used.

    Click's usage errors (unknown option, bad integer, missing argument) would print a
    boxed, multi-line panel; here they get the same one-line ``error:`` form, exit 2, as
    every other invalid input. SIGTERM (``timeout``, a cancelled CI job) raises
    KeyboardInterrupt, so the interrupt paths (finished rows kept, partial files removed)
    run for it too."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        return list(COMMANDS)

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        if cmd_name not in self.commands:
            load_commands([cmd_name] if cmd_name in COMMANDS else None)
            for info in app.registered_commands:
                name = info.name or typer.main.get_command_name(info.callback.__name__)  # type: ignore[union-attr]
                if name == cmd_name:
                    self.commands[name] = typer.main.get_command_from_info(
                        info, pretty_exceptions_short=app.pretty_exceptions_short, rich_markup_mode=app.rich_markup_mode
                    )
        return self.commands.get(cmd_name)

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        """The command list from :data:`COMMANDS`, without importing any command."""
        limit = formatter.width - 6 - max(map(len, COMMANDS))
        rows = [(name, click.utils.make_default_short_help(text, limit)) for name, (_, text) in COMMANDS.items()]
        with formatter.section("Commands"):
            formatter.write_dl(rows)

    def main(self, *args: Any, standalone_mode: bool = True, **kwargs: Any) -> Any:
        if not standalone_mode:
            return super().main(*args, standalone_mode=False, **kwargs)
        previous = _sigterm_as_interrupt()
        try:
            rv = super().main(*args, standalone_mode=False, **kwargs)
        except click.exceptions.NoArgsIsHelpError as exc:
            exc.show()
            sys.exit(exc.exit_code)
        except click.exceptions.UsageError as exc:
            where = f"kinprop {exc.ctx.info_name}: " if exc.ctx is not None and exc.ctx.parent is not None else ""
            hint = f" (see {exc.ctx.command_path} --help)" if exc.ctx is not None else ""
            _error_line(f"{where}{exc.format_message()}{hint}")
            sys.exit(EXIT_INVALID)
        except click.exceptions.ClickException as exc:
            _error_line(exc.format_message())
            sys.exit(exc.exit_code)
        except (typer.Abort, KeyboardInterrupt, SystemError) as exc:
            if not isinstance(exc, typer.Abort) and not is_interrupt(exc):
                raise
            err.print("interrupted")
            sys.exit(interrupt_status(exc))
        finally:
            if previous is not None:
                signal.signal(signal.SIGTERM, previous)
        sys.exit(rv if isinstance(rv, int) else 0)


def is_interrupt(exc: BaseException | None) -> bool:
    """Whether ``exc`` is a KeyboardInterrupt (Ctrl-C, or SIGTERM routed to it), also when the
    signal arrived inside a C callback (numba unpickling a constant), which Python reports
    as a SystemError caused by the KeyboardInterrupt."""
    seen = 0
    while exc is not None and seen < 20:
        if isinstance(exc, KeyboardInterrupt):
            return True
        exc, seen = exc.__cause__ or exc.__context__, seen + 1
    return False


class Terminated(KeyboardInterrupt):
    """SIGTERM, routed to the interrupt paths; the command then exits 143, not 130."""


def interrupt_status(exc: BaseException | None) -> int:
    """Exit status of an interrupt: 143 after SIGTERM, 130 after Ctrl-C (also when the
    signal reached us wrapped, see :func:`is_interrupt`)."""
    seen = 0
    while exc is not None and seen < 20:
        if isinstance(exc, Terminated):
            return EXIT_TERMINATED
        exc, seen = exc.__cause__ or exc.__context__, seen + 1
    return EXIT_INTERRUPTED


def _raise_interrupt(signum: int, frame: Any) -> None:
    raise Terminated


def _sigterm_as_interrupt() -> Any:
    """Route SIGTERM to KeyboardInterrupt (main thread only); returns the previous handler."""
    if threading.current_thread() is not threading.main_thread():
        return None
    return signal.signal(signal.SIGTERM, _raise_interrupt)


#: ``--free`` and ``--weight``, shared by every command that solves
FreeOption = Annotated[
    list[str] | None,
    typer.Option("--free", metavar="GROUP|ADDRESS", help="groups (q s C l coef inputs) or addresses; default q"),
]
HoldOption = Annotated[
    list[str] | None,
    typer.Option(
        "--hold",
        metavar="JOINT",
        help="hold JOINT's coordinates as a declared input is held (repeat; --free JOINT.q frees it again)",
    ),
]
WeightOption = Annotated[
    list[str] | None, typer.Option("--weight", metavar="ADDRESS=W", help="ADDRESS_OR_GROUP=W: larger moves more")
]

app = typer.Typer(
    name="kinprop",
    help="Kinematic design propagation in closed-loop mechanisms (Zou, Abdel-Malek & Wang 1997).",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    cls=_Group,
    rich_markup_mode=None,
)


def _print_version(value: bool) -> None:
    if value:
        from importlib.metadata import PackageNotFoundError, version

        try:
            text = version("kinprop")
        except PackageNotFoundError:  # pragma: no cover - running from an uninstalled checkout
            from kinprop import __version__ as text
        out.print(f"kinprop {text}")
        raise typer.Exit()


@app.callback()
def _root(
    show_version: Annotated[
        bool, typer.Option("--version", callback=_print_version, is_eager=True, help="print the version and exit")
    ] = False,
) -> None:
    """Kinematic design propagation in closed-loop mechanisms (Zou, Abdel-Malek & Wang 1997)."""


class _Console(Console):
    """A rich console that prints user text literally (no markup, no ``:emoji:`` codes) and,
    when not writing to a terminal, never wraps or truncates: a pipe gets whole lines."""

    @property
    def size(self) -> ConsoleDimensions:
        size = Console.size.fget(self)  # type: ignore[attr-defined]
        return size if self.is_terminal else ConsoleDimensions(PIPE_WIDTH, size.height)

    @size.setter
    def size(self, new_size: tuple[int, int]) -> None:
        Console.size.fset(self, new_size)  # type: ignore[attr-defined]

    def print(self, *objects: Any, **kwargs: Any) -> None:
        """As :meth:`rich.console.Console.print`; to a pipe a table's title is its own line
        (rich would wrap a title longer than the table to the table's width)."""
        if objects and not self.is_terminal:
            for k, obj in enumerate(objects):
                if isinstance(obj, Table) and obj.title is not None:
                    title, obj.title = obj.title, None
                    super().print(title, soft_wrap=True)
                    super().print(*objects[k : k + 1], **kwargs)
                    obj.title = title
                else:
                    super().print(obj, **kwargs)
            return
        super().print(*objects, **kwargs)


#: the line width when output goes to a pipe or file (tables are only as wide as their cells)
PIPE_WIDTH = 100_000
out = _Console(highlight=False, markup=False, emoji=False)
err = _Console(stderr=True, highlight=False, markup=False, emoji=False)

F = TypeVar("F", bound=Callable[..., Any])


def _error_line(line: str) -> None:
    err.print(Text.assemble(("error:", "red"), " ", line), soft_wrap=True)


def fail(lines: list[str] | str, code: int = EXIT_INVALID) -> NoReturn:
    """Print one ``error: ...`` line per problem on stderr and exit with ``code``."""
    for line in [lines] if isinstance(lines, str) else lines:
        _error_line(line)
    raise typer.Exit(code)


def missing_extra(exc: ImportError) -> str | None:
    """The one-line message for an optional module that is not installed, else None."""
    name = (getattr(exc, "name", None) or "").split(".")[0]
    extra = EXTRAS.get(name)
    if extra is None:
        return None
    return f"this command needs {name}, which is not installed: pip install 'kinprop[{extra}]'"


def require(module: str) -> None:
    """Import an optional module now, so a missing extra is reported before any work."""
    importlib.import_module(module)


def require_plot(path: Path) -> None:
    """The plotting library a plot file needs: plotly for ``.html``, matplotlib otherwise."""
    require("plotly" if path.suffix.lower() == ".html" else "matplotlib")


def handles_user_errors(fn: F) -> F:
    """Turn every invalid input into one ``error:`` line per problem on stderr and exit 2:
    model and address errors, bad values, unwritable outputs, and a missing optional extra."""

    @wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return fn(*args, **kwargs)
        except ModelError as exc:
            fail([str(p) for p in exc.problems])
        except (AddressError, ValueError) as exc:
            fail(str(exc.args[0]) if exc.args else str(exc))
        except ImportError as exc:
            msg = missing_extra(exc)
            if msg is None:
                raise
            fail(msg)
        except OSError as exc:
            if exc.filename is None:
                raise
            fail(f"{exc.filename}: {exc.strerror or exc}")

    return wrapper  # type: ignore[return-value]


#: model files larger than this show a progress line on a terminal while they load
PROGRESS_BYTES = 512 * 1024


def load_model_cli(path: Path) -> Model:
    """:func:`kinprop.io.load_model`, with a live status line on stderr for a large file.

    A 20,000-body model takes a few seconds to parse, validate and cut into a tree; a terminal
    user sees what is happening (a pipe or CI log gets nothing extra)."""
    import warnings

    from kinprop.errors import UnitsWarning
    from kinprop.io.points import JointPointWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", JointPointWarning)
        warnings.simplefilter("always", UnitsWarning)
        model = _load_model_cli(path)
    for w in caught:  # a declared point off its joint (issue 20), a size implausible in its unit: one line each
        if issubclass(w.category, (JointPointWarning, UnitsWarning)):
            err.print(f"warning: {w.message}", soft_wrap=True, markup=False, highlight=False)
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return model


def _load_model_cli(path: Path) -> Model:
    from kinprop.io import load_model

    try:
        size = path.stat().st_size
    except OSError:
        size = 0
    if size < PROGRESS_BYTES or not err.is_terminal:
        model = load_model(path)
    else:
        with err.status(f"loading {path} ({size / 1e6:.1f} MB): parsing, validating, building the tree"):
            model = load_model(path)
        mech = model.mechanism
        err.print(f"loaded {path}: {len(mech.bodies)} bodies, {len(mech.joints)} joints", soft_wrap=True)
    return model


def warn_scales(model: Model, source: object) -> None:
    """One ``warning:`` line per number implausible in the declared unit (:mod:`kinprop.io.scales`)."""
    from rich.markup import escape

    from kinprop.io.scales import scale_warnings

    for line in scale_warnings(model):
        err.print(escape(f"warning: {source}: {line}"), soft_wrap=True)


def json_safe(obj: Any) -> Any:
    """``obj`` with every non-finite float (NaN, +-Infinity) replaced by None: strict JSON."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    if hasattr(obj, "tolist") and type(obj).__module__ == "numpy":  # an array or a numpy scalar
        return json_safe(obj.tolist())
    return obj


def json_text(obj: Any) -> str:
    """Strict JSON (RFC 8259): non-finite numbers become null, never bare NaN/Infinity."""
    return json.dumps(json_safe(obj), allow_nan=False)


def print_json(obj: Any) -> None:
    sys.stdout.write(json_text(obj) + "\n")
