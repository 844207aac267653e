"""``demoplan perceive`` of one image: its options, a lean parser and its output,
shared by the launcher (:mod:`demoplan.cli.launcher`) and the typer command.

The command's perception takes a fraction of a second on a photograph; typer,
click and pydantic would add about as much again at every start
(docs/perception.md "Timing"). A plain, non-interactive invocation of its
common forms — one IMAGE with ``--px-per-m``/``--origin``, ``--side``,
``--camera`` or ``--markers``, and ``--json``, ``-o``, ``--plot``,
``--timeout`` — is parsed here with :mod:`argparse` and run with perception and
rich's table alone imported. Anything else (``--help``, ``--sequence``,
``--before``, ``--colours``, a value typer would refuse) is declined and goes
to typer, so usage errors and help come from one place; both paths print the
same table, JSON and one-line errors with the same exit codes (tested).
"""

from __future__ import annotations

import math
import sys
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from demoplan.budget import PERCEPTION_TIMEOUT
from demoplan.cli.lean_parser import DeclinedError, LeanParser

if TYPE_CHECKING:
    from rich.console import Console
    from rich.table import Table

    from demoplan.commands.perception import Perceived
    from demoplan.perception.blocks import Rejection

__all__ = [
    "PERCEIVE_OPTIONS",
    "PerceiveOptions",
    "blocks_table",
    "parse_perceive_options",
    "print_perceived",
    "rejections_line",
    "run_perceive",
]

PERCEIVE_OPTIONS = (
    "--px-per-m",
    "--origin",
    "--camera",
    "--markers",
    "--json",
    "--output",
    "--side",
    "--timeout",
    "--plot",
)
"""Options of ``demoplan perceive`` the lean path parses (the test checks typer's match)."""

PX_PER_M_RANGE = (1e-3, 1e7)
"""``--px-per-m``'s range in the typer command; outside it typer words the error."""
SIDE_MIN = 1e-4
"""``--side``'s least value in the typer command."""


@dataclass(frozen=True, slots=True)
class PerceiveOptions:
    """What ``demoplan perceive IMAGE`` was asked to do (one image, no ``--sequence``)."""

    image: Path
    px_per_m: float | None = None
    origin: tuple[float, float] | None = None
    camera: Path | None = None
    markers: Path | None = None
    json_output: bool = False
    output: Path | None = None
    side: tuple[float, ...] = ()
    """The blocks' sides given (``--side``, repeatable): none, one or several."""
    timeout: float = PERCEPTION_TIMEOUT
    plot: Path | None = None


def _number(text: str) -> float:
    """A float as click reads one (``float()``); anything else is declined."""
    return float(text)


def parse_perceive_options(args: Sequence[str]) -> PerceiveOptions | None:
    """Options of ``demoplan perceive ARGS``, or None when typer should handle them:
    an option this parser does not know, a value typer would refuse, ``--help``,
    ``--`` or an argument starting with ``-`` where a value is expected."""
    if any(arg in ("-h", "--help", "--") for arg in args):
        return None
    parser = LeanParser(prog="demoplan perceive", add_help=False, allow_abbrev=False)
    parser.add_argument("image", type=Path)
    parser.add_argument("--px-per-m", type=_number, default=None)
    parser.add_argument("--origin", type=_number, nargs=2, default=None)
    parser.add_argument("--camera", type=Path, default=None)
    parser.add_argument("--markers", type=Path, default=None)
    parser.add_argument("--json", dest="json_output", action="store_true")
    parser.add_argument("--output", "-o", type=Path, default=None)
    parser.add_argument("--side", type=_number, action="append", default=None)
    parser.add_argument("--timeout", type=_number, default=PERCEPTION_TIMEOUT)
    parser.add_argument("--plot", type=Path, default=None)
    try:
        parsed = parser.parse_args(list(args))
    except DeclinedError:
        return None
    px_per_m: float | None = parsed.px_per_m
    side: tuple[float, ...] = tuple(parsed.side or ())
    timeout: float = parsed.timeout
    low, high = PX_PER_M_RANGE
    if (
        (px_per_m is not None and not low <= px_per_m <= high)  # also refuses NaN
        or not all(one >= SIDE_MIN and math.isfinite(one) for one in side)
        or not timeout >= 0.0
    ):
        return None  # typer's range checks word the usage error
    origin = (parsed.origin[0], parsed.origin[1]) if parsed.origin is not None else None
    return PerceiveOptions(
        parsed.image,
        px_per_m,
        origin,
        parsed.camera,
        parsed.markers,
        parsed.json_output,
        parsed.output,
        side,
        timeout,
        parsed.plot,
    )


def run_perceive(options: PerceiveOptions) -> int:
    """Perceive, print the table (or the JSON) on stdout; return the exit code
    (docs/cli.md). A file system refusal without a file name (stdout full, its
    reader gone) and Ctrl-C reach the launcher's ``main``, as from typer."""
    from demoplan.cli.clock import mark_command_start
    from demoplan.commands.perception import perceive
    from demoplan.errors import DemoplanError, error_line
    from demoplan.fileio import os_error

    mark_command_start()
    _silence_library_warnings()
    try:
        found = perceive(
            options.image,
            options.px_per_m,
            options.origin,
            camera=options.camera,
            markers=options.markers,
            side=options.side or None,
            timeout=options.timeout,
            output=options.output,
            plot=options.plot,
            rejections=options.plot is not None,  # shown only with --plot
        )
        if options.json_output:
            from demoplan.wording import json_document

            sys.stdout.write(json_document(found.document))
        else:
            from demoplan.cli.consoles import TextConsole

            console = TextConsole(soft_wrap=False, emoji=False, width=140)  # stdout: no terminal
            print_perceived(console, found, options.image, options.plot)
    except DemoplanError as exc:
        sys.stderr.write(error_line(exc) + "\n")
        return exc.exit_code
    except OSError as exc:
        if exc.filename is None:  # printing failed: the launcher names standard output
            raise
        sys.stderr.write(error_line(os_error(exc)) + "\n")
        return 1
    return 0


def _silence_library_warnings() -> None:
    """As the typer application does without ``--verbose``: Python warnings of
    the libraries (NumPy overflow) go to a log nobody prints."""
    import logging

    logging.captureWarnings(True)
    logging.getLogger("py.warnings").setLevel(logging.CRITICAL)


def print_perceived(console: Console, found: Perceived, image: Path, plot: Path | None) -> None:
    """``perceive``'s output on ``console``: the table of the blocks, where the
    scale came from, and with ``plot`` the line of the regions rejected."""
    from demoplan.cli.consoles import plain_text

    console.print(blocks_table(found, image.name))
    console.print(f"scale from {found.scale}", markup=False, highlight=False, soft_wrap=True)
    if plot is not None:
        line = rejections_line(found.rejected, plot, found.specks)
        console.print(plain_text(line), highlight=False)


def blocks_table(found: Perceived, image_name: str) -> Table:
    """The blocks found, a row each; a type column only where a colour repeats."""
    from rich.table import Table

    table = Table(title=f"Blocks in {image_name}", title_justify="left")
    types = {n: o.get("type") for n, o in found.document["objects"].items()}
    typed = any(types.values())
    names = ("name", "type") if typed else ("name",)
    for column in (*names, "x [m]", "y [m]", "z [m]", "yaw [deg]", "side [m]"):
        table.add_column(column, justify="left" if column in names else "right")
    for name, b in found.blocks.items():
        table.add_row(
            name,
            *((types[name] or "",) if typed else ()),
            f"{b.x:.4f}",
            f"{b.y:.4f}",
            f"{b.z:.3f}",
            f"{b.yaw:.1f}",
            f"{b.side:.4f}",
        )
    return table


NOUNS = {"side face": "side faces", "side face or shadow": "side faces or shadows"}
"""Reasons for a rejection that are nouns, and their plurals."""


def rejections_line(rejected: Sequence[Rejection], plot: Path, specks: int = 0) -> str:
    """``3 regions rejected: 2 side faces, 1 too small (drawn in overlay.png)``: most
    first, ties in the order of the alphabet (the same line on every run); with
    ``specks``, how many of them the overlay does not draw."""
    from demoplan.wording import plural

    counts = Counter(r.reason for r in rejected)
    reasons = ", ".join(
        plural(n, why, NOUNS[why]) if why in NOUNS else f"{n} {why}"
        for why, n in sorted(counts.items(), key=lambda item: (-item[1], item[0]))
    )
    but = f"; {plural(specks, 'speck')} not drawn" if specks else ""
    return (
        f"{plural(len(rejected), 'region')} rejected{': ' if reasons else ''}{reasons} "
        f"(drawn in {plot.name}{but})"
    )
