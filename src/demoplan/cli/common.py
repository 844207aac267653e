"""What every command shares: the typer application, the two consoles,
errors to exit codes, progress, and the options several commands take."""

from __future__ import annotations

import logging
import math
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any

import typer
from typer.core import TyperGroup

from demoplan import __version__
from demoplan.cli.consoles import TextConsole as _TextConsole
from demoplan.cli.consoles import plain_text as plain_text  # re-exported: the commands use it
from demoplan.errors import (
    DemoplanError,
    error_line,
)
from demoplan.fileio import (
    os_error,
)

COMMANDS = (
    "learn",
    "show",
    "solve",
    "pddl",
    "plan",
    "problem",
    "export",
    "run",
    "evaluate",
    "calibrate",
    "perceive",
    "segment",
    "import",
    "experiments",
    "studio",
)
"""The commands in the order ``--help`` lists them: the pipeline's order,
whatever order their modules are imported in."""


class _PipelineOrder(TyperGroup):
    def list_commands(self, ctx: Any) -> list[str]:
        names = super().list_commands(ctx)
        return sorted(names, key=lambda n: COMMANDS.index(n) if n in COMMANDS else len(COMMANDS))


app = typer.Typer(
    name="demoplan",
    cls=_PipelineOrder,
    help="Learn pick-and-place task models from human demonstrations and plan them in new scenes.",
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
)


stdout = _TextConsole(soft_wrap=False, emoji=False, width=None if sys.stdout.isatty() else 140)
stderr = _TextConsole(stderr=True, soft_wrap=True, emoji=False)


@contextmanager
def reported_errors() -> Iterator[None]:
    """Turn a demoplan error into one line on stderr and its exit code. The
    warnings a command logged are printed when it succeeds and dropped when it
    fails: a failure is its one line (an error supersedes what led to it)."""
    try:
        yield
    except DemoplanError as exc:
        _HELD.discard()
        stderr.print(error_line(exc), markup=False, highlight=False)
        raise typer.Exit(exc.exit_code) from None
    except OSError as exc:  # a file system refusal no reader foresaw: still one line
        _HELD.discard()
        if exc.filename is None:  # printing failed: stdout full, or its reader gone
            raise  # demoplan.cli.launcher.main names standard output
        sys.stderr.write(error_line(os_error(exc)) + "\n")
        raise typer.Exit(1) from None
    except KeyboardInterrupt as exc:  # Ctrl-C or SIGTERM: exit 130 / 143 (docs/cli.md)
        from demoplan.frontends.interrupts import interrupted_by_signal, interrupted_exit_code

        _HELD.discard()
        if interrupted_by_signal():
            raise  # demoplan.cli.launcher.main reports it, once
        sys.stderr.write("demoplan: interrupted\n")
        raise typer.Exit(interrupted_exit_code(exc)) from None
    else:
        _HELD.print_held()


class _HeldWarnings(logging.Handler):
    """Warnings logged while a command runs, held until it ends (without
    ``--verbose``; with it every record is printed as it comes)."""

    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.records: list[logging.LogRecord] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.records.append(record)

    def print_held(self) -> None:
        """Print the held warnings on stderr, in the order they came, each once
        (a scene checked for every candidate goal would repeat its warning)."""
        for line in dict.fromkeys(self.format(record) for record in self.records):
            sys.stderr.write(line + "\n")
        self.records.clear()

    def discard(self) -> None:
        """Forget the held warnings (``release``/``acquire`` are the handler's lock)."""
        self.records.clear()


class _PrintableFormatter(logging.Formatter):
    """A log line with its control characters escaped (:func:`~demoplan.wording.printable`):
    a warning naming an object read from a file never drives the terminal."""

    def formatMessage(self, record: logging.LogRecord) -> str:  # noqa: N802 (logging's name)
        from demoplan.wording import printable

        return printable(super().formatMessage(record))


_HELD = _HeldWarnings()
_LOG_FORMAT = "demoplan: %(levelname)s: %(message)s"


@contextmanager
def working(text: str) -> Iterator[None]:
    """A progress bar on stderr while long work runs (learning: objects done;
    perception: colour regions done), on a terminal only; it goes when done."""
    if not stderr.is_terminal:
        yield
        return
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn

    from demoplan.budget import reporting_progress

    with Progress(
        TextColumn(text),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("{task.fields[what]}"),
        console=stderr,
        transient=True,
    ) as bar:
        task = bar.add_task(text, total=None, what="")

        def update(what: str, done: int, total: int) -> None:
            bar.update(task, completed=done, total=total, what=what)

        with reporting_progress(update):
            yield


def _version(value: bool) -> None:
    if value:
        stdout.print(f"demoplan {__version__}", markup=False)
        raise typer.Exit()


@app.callback()
def _main(
    version: Annotated[
        bool, typer.Option("--version", callback=_version, is_eager=True, help="Print the version.")
    ] = False,
    verbose: Annotated[
        bool, typer.Option("--verbose", "-v", help="Log progress to stderr.")
    ] = False,
) -> None:
    from demoplan.cli.clock import mark_command_start

    mark_command_start()
    _HELD.discard()
    if verbose:
        shown = logging.StreamHandler(sys.stderr)
        shown.setFormatter(_PrintableFormatter(_LOG_FORMAT))
        logging.basicConfig(level=logging.INFO, handlers=[shown], force=True)
    else:  # warnings are printed when the command ends (reported_errors)
        _HELD.setFormatter(_PrintableFormatter(_LOG_FORMAT))
        logging.basicConfig(level=logging.WARNING, handlers=[_HELD], force=True)
    # Warnings of the libraries (NumPy overflow, shapely, MuJoCo) never reach the
    # terminal as raw text: bad numbers are refused with our one-line errors
    # before they get that far, and what is left is harmless; --verbose logs them.
    logging.captureWarnings(True)
    logging.getLogger("py.warnings").setLevel(logging.INFO if verbose else logging.CRITICAL)


def print_json(data: Any) -> None:
    from demoplan.wording import json_document

    sys.stdout.write(json_document(data))


FRAME_OPTION = typer.Option(
    help="ROS 2 bags: the world frame TF frames are composed to (default: the TF tree's root).",
    show_default=False,
)
OBJECTS_OPTION = typer.Option(
    help="The objects to keep: names or glob patterns, comma-separated ('cup,plate', "
    "'obj_*'). Default: every object; in a TF tree, every frame without children.",
    show_default=False,
)
LANDMARKS_OPTION = typer.Option(
    help="Pose streams: tracked frames that are landmarks (a tray, a box), not objects: "
    "names or glob patterns, comma-separated; each one's rest pose is the "
    "demonstration's landmark.",
    show_default=False,
)
OBJECTS_FILE_HELP = "JSON/YAML file {objects: {NAME: {shape, size}}} (a demonstration's 'objects')"


class Units(StrEnum):
    """Units of length of a CSV pose stream's positions (``--units``)."""

    m = "m"
    cm = "cm"
    mm = "mm"


UNITS_OPTION = typer.Option(
    help="CSV streams: the unit of x,y,z (converted to metres); a '# units: mm' line "
    "above the header says it too, and the two must agree. Default: the file's, else "
    "metres, and a stream whose positions no room holds in metres is refused.",
    show_default=False,
)


def say(text: str) -> None:
    """A message on stdout: plain text, one line however long (scripts read it)."""
    stdout.print(text, markup=False, highlight=False, soft_wrap=True)


def xyz_text(position: Any, decimals: int) -> str:
    return "(" + ", ".join(f"{v:.{decimals}f}" for v in position) + ")"


class SearchName(StrEnum):
    """Search strategies of ``demoplan solve`` (demoplan.planning.search.SEARCHES)."""

    astar = "astar"
    bfs = "bfs"


GroundedOption = Annotated[
    bool,
    typer.Option(
        "--grounded",
        help="Write grounded STRIPS (one action per grasp and put-down) for pyperplan and "
        "planners without quantifiers.",
    ),
]


ModelArgument = Annotated[
    Path, typer.Argument(metavar="MODEL", help="A task model written by 'learn'.")
]
SceneArgument = Annotated[
    Path, typer.Argument(metavar="SCENE", help="The scene at run time (demoplan/scene-1).")
]


def bounded_number(low: float, high: float = math.inf, *, expected: str) -> Callable[[str], float]:
    """typer's ``parser=`` of a float option taken from ``low`` to ``high``, both
    included (the option's ``min`` and ``max``, which its help shows): a value
    outside says what was given and what is ``expected`` — NaN, an infinity,
    zero, a negative number each by name. typer's own range check answered
    ``--px-per-m nan`` with "Input should be less than or equal to 10000000"."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise typer.BadParameter(f"{text!r} is not a number; {expected} expected") from None
        if low <= value <= high:
            return value
        why = _out_of_range(value, low, high)
        raise typer.BadParameter(f"{plain_text(text)} {why}; {expected} expected")

    return parse


def _out_of_range(value: float, low: float, high: float) -> str:
    if math.isnan(value):
        return "is not a number (NaN)"
    if math.isinf(value):
        return "is infinite" if value > 0 else "is minus infinity"
    if value > high:
        return f"is above {high:,.0f}" if high.is_integer() else f"is above {high:g}"
    if value == 0:
        return "is zero"
    return "is negative" if value < 0 <= low else f"is below {low:,g}"


TIMEOUT_EXPECTED = "seconds, 0 or more (inf: no limit),"


def planning_timeout(what: str) -> Any:
    """The ``--timeout`` option of a planning command (``solve``, ``plan``,
    ``run``, ``export bt``): ``what`` its seconds are for; the default it names
    is read from :data:`~demoplan.cli.clock.DEFAULT_TIMEOUT`, never typed."""
    from demoplan.cli.clock import DEFAULT_TIMEOUT

    return typer.Option(
        "--timeout",
        min=0.0,
        parser=bounded_number(0.0, expected=TIMEOUT_EXPECTED),
        show_default=False,
        help=f"{what} [default: {DEFAULT_TIMEOUT:g}] ('inf': no limit).",
    )


ClutterOption = Annotated[
    bool,
    typer.Option(help="Allow objects the model never saw (they get no goal; moved if in the way)."),
]
FreespaceOption = Annotated[
    int | None,
    typer.Option(
        "--freespace",
        min=0,
        max=50,
        help="Free-space spots to generate when the scene gives none (default 3).",
    ),
]


class CollisionSource(StrEnum):
    """Where the planner's collision facts come from."""

    rule = "rule"
    simulation = "simulation"


CollisionsOption = Annotated[
    CollisionSource,
    typer.Option(
        "--collisions",
        help="Collision facts from the geometric finger rule (§V.B) or from the arm of "
        "--sim arm posed in MuJoCo (§IV.C's path planner); simulation also reports where "
        "the two disagree.",
    ),
]


def geometry_settings(
    freespace: int | None, collisions: CollisionSource = CollisionSource.rule
) -> Any:
    """The scene geometry's settings for --freespace and --collisions
    (:func:`demoplan.commands.settings.geometry_settings`)."""
    from demoplan.commands.settings import geometry_settings as settings_for

    return settings_for(freespace, collisions.value)


def stream_options(
    frame: str | None,
    objects: str | None,
    units: Units | None,
    landmarks: str | None,
    objects_file: Path | None,
) -> Any:
    """How pose streams are read, from --frame, --objects, --units, --landmarks
    and --objects-file (:class:`demoplan.segmentation.streams.StreamOptions`)."""
    from demoplan.segmentation.streams import StreamOptions
    from demoplan.segmentation.types import parse_object_patterns

    return StreamOptions(
        frame=frame,
        objects=parse_object_patterns(objects),
        units=None if units is None else units.value,
        landmarks=parse_object_patterns(landmarks) or (),
        objects_file=objects_file,
    )


class PerceptionName(StrEnum):
    """How ``demoplan run`` observes the world."""

    state = "state"
    camera = "camera"


class SimName(StrEnum):
    """Worlds of ``demoplan run``."""

    kinematic = "kinematic"
    mujoco = "mujoco"
    arm = "arm"


def count_of(n: int, noun: str) -> str:
    plural = noun + ("es" if noun.endswith("sh") else "s")
    return f"{n} {noun if n == 1 else plural}"
