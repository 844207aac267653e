"""The ``demoplan`` executable: lean paths for ``solve`` and ``perceive``, typer for the rest.

Importing typer, click, pydantic and rich costs about 0.4 s per process, twenty
times what solving a small problem takes. Programs that call ``demoplan solve``
once per problem (a benchmark harness, an executive replanning in a loop) pay
that on every call, so a plain, non-interactive ``solve`` invocation is parsed
here with :mod:`argparse` and run with nothing but the planner imported.
Anything else — another command, ``--help``, an option this parser does not
know or a value it would reject, an interactive terminal (which gets a
spinner) — goes to the typer application in :mod:`demoplan.cli`, so help
texts, usage errors and their exit codes come from one place. The two paths
print the same plan, the same JSON and the same one-line errors (tested).
``demoplan perceive`` of one image has its lean path in
:mod:`demoplan.cli.perceiving`, taken on the same terms.
"""

from __future__ import annotations

import errno
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from demoplan.cli.clock import mark_command_start, mark_process_start

# First: the command clock starts when this module is imported, at process start.
from demoplan.cli.lean_parser import DeclinedError, LeanParser
from demoplan.cli.solving import SolveOptions, solve_text
from demoplan.frontends.interrupts import (
    INTERRUPTED_EXIT,
    TERMINATED_EXIT,
    ignore_signals,
    on_signal,
    quiet_after_signal,
    redeliver_lost_signal,
    reports_signals,
    signals_received,
)

__all__ = [
    "SOLVE_OPTIONS",
    "SolveOptions",
    "main",
    "parse_solve_options",
    "run_solve",
    "solve_text",
]

SOLVE_OPTIONS = ("--json", "--search", "--max-nodes", "--timeout", "--optimal")
"""Options of ``demoplan solve`` the lean path parses (the test checks typer's match)."""


def parse_solve_options(args: Sequence[str]) -> SolveOptions | None:
    """Options of ``demoplan solve ARGS``, or None when typer should handle them."""
    if any(arg in ("-h", "--help") for arg in args):
        return None
    parser = LeanParser(prog="demoplan solve", add_help=False, allow_abbrev=False)
    parser.add_argument("problem", type=Path)
    parser.add_argument("--json", dest="json_output", action="store_true")
    from demoplan.planning.search import SEARCHES  # needed next anyway, to solve

    parser.add_argument("--search", choices=tuple(SEARCHES), default="astar")
    parser.add_argument("--max-nodes", type=int, default=None)
    parser.add_argument("--timeout", type=float, default=None)
    parser.add_argument("--optimal", action="store_true")
    try:
        parsed = parser.parse_args(list(args))
    except DeclinedError:
        return None
    max_nodes: int | None = parsed.max_nodes
    timeout: float | None = parsed.timeout
    if (max_nodes is not None and max_nodes < 1) or (
        timeout is not None and not timeout >= 0.0  # also refuses NaN
    ):
        return None  # typer's range checks word the usage error
    return SolveOptions(
        parsed.problem, parsed.json_output, parsed.search, max_nodes, timeout, parsed.optimal
    )


def run_solve(options: SolveOptions) -> int:
    """Solve, print the plan (or its JSON) on stdout; return the exit code (docs/cli.md)."""
    from demoplan.errors import DemoplanError, error_line
    from demoplan.fileio import os_error

    mark_command_start()
    try:
        text, note = solve_text(options)
    except DemoplanError as exc:
        sys.stderr.write(error_line(exc) + "\n")
        return exc.exit_code
    except OSError as exc:
        sys.stderr.write(error_line(os_error(exc)) + "\n")
        return 1
    from demoplan.wording import printable_lines

    sys.stdout.write(printable_lines(text))
    # The plan reaches stdout before the note reaches stderr: a full disk or a
    # closed pipe is then the command's one line (main), with no note before it.
    sys.stdout.flush()
    sys.stderr.write(printable_lines(note))
    return 0


@reports_signals
def main() -> None:
    """Entry point of the ``demoplan`` command."""
    import signal

    mark_process_start()
    # Ctrl-C raises KeyboardInterrupt even where the process was started with
    # SIGINT ignored (a background job of a script); SIGTERM does the same.
    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGTERM, on_signal)
    sys.unraisablehook = redeliver_lost_signal
    sys.excepthook = quiet_after_signal(sys.excepthook)  # before typer keeps it as its fallback
    # Started with stdout (or stderr) closed: what would be printed is dropped,
    # as if sent to /dev/null; a command whose job is a file still does it.
    if sys.stdout is None:
        sys.stdout = Path(os.devnull).open("w")  # noqa: SIM115 - for the whole process
    if sys.stderr is None:
        sys.stderr = Path(os.devnull).open("w")  # noqa: SIM115
    # A file name with bytes that are not UTF-8 is printed with escapes, not a
    # UnicodeEncodeError.
    for stream in (sys.stdout, sys.stderr):
        reconfigure = getattr(stream, "reconfigure", None)
        if reconfigure is not None:
            reconfigure(errors="backslashreplace")
    code = 1
    try:
        try:
            code = _dispatch()
        finally:
            if not signals_received:
                sys.stdout.flush()  # here, where a full disk or a closed pipe is caught
        # The work is done: a signal from here on is ignored (one that came
        # before, swallowed by a library or landing on this line, is reported
        # below all the same). Inside the try, so that none falls in between.
        ignore_signals()
    except KeyboardInterrupt:
        ignore_signals()
        if not signals_received:  # raised without a signal (a test, a debugger)
            signals_received.append(signal.SIGINT)
    except Exception as exc:
        ignore_signals()
        if not signals_received:
            if not isinstance(exc, OSError):
                raise
            # stdout full (> /dev/full) or its reader gone (| head)
            _drop_stdout()
            sys.stderr.write(f"demoplan: error: standard output: {_stdout_reason(exc)}\n")
            raise SystemExit(1) from None
        # else the signal surfaced as another error: a C extension interrupted
        # while it loads reports "ImportError: initialization failed"
    if signals_received:
        # Every command stops the same way, wherever the signal found it.
        _drop_stdout()
        sys.stderr.write("demoplan: interrupted\n")
        sys.stderr.flush()
        terminated = signal.SIGTERM in signals_received
        # At once: the command has unwound (outputs removed, locks released), and
        # the interpreter's own teardown (MuJoCo's GL contexts, matplotlib) can
        # take longer than the second a stopped command has.
        os._exit(TERMINATED_EXIT if terminated else INTERRUPTED_EXIT)
    # The interpreter's teardown collects the garbage of every module imported
    # (numba, llvmlite, SciPy, matplotlib: 0.3 s of perceive's 2 s of CPU) for
    # a process about to end: what exists now is left out of those collections.
    # Its ending is otherwise the same (atexit, threads, flushes, finalizers).
    import gc

    gc.freeze()
    raise SystemExit(code)


def _drop_stdout() -> None:
    """Point stdout at /dev/null, so that Python's flush at exit cannot fail again."""
    try:
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, sys.stdout.fileno())
        os.close(null)
    except (OSError, ValueError):
        pass


def _stdout_reason(exc: OSError) -> str:
    from demoplan.fileio import os_reason

    if exc.errno == errno.EPIPE:
        return "the pipe was closed by its reader"
    return os_reason(exc)


def _dispatch() -> int:
    """Run the command; its exit code. Usage errors are one line (docs/cli.md)."""
    args = sys.argv[1:]
    if args[:1] == ["solve"] and not sys.stderr.isatty():
        options = parse_solve_options(args[1:])
        if options is not None:
            sys.stdout.flush()
            return run_solve(options)
    # perceive's table is as wide as a terminal is: the lean path prints for
    # pipes and files only, typer's console for a terminal (and its progress bar)
    if args[:1] == ["perceive"] and not sys.stderr.isatty() and not sys.stdout.isatty():
        from demoplan.cli.perceiving import parse_perceive_options, run_perceive

        seen = parse_perceive_options(args[1:])
        if seen is not None:
            return run_perceive(seen)
    from demoplan.cli.application import app

    try:
        result = app(standalone_mode=False)
    except Exception as exc:  # click's (or typer's vendored click's) exceptions
        if not hasattr(exc, "format_message") or not hasattr(exc, "exit_code"):
            raise
        if type(exc).__name__ == "NoArgsIsHelpError":  # `demoplan` alone: the help
            exc.show()  # type: ignore[attr-defined]
            return int(exc.exit_code)
        return _usage_error(exc)
    return result if isinstance(result, int) else 0


def _usage_error(exc: Any) -> int:
    """A click usage error (or Abort) as one line naming the command."""
    context = getattr(exc, "ctx", None)
    command = context.command_path if context is not None else "demoplan"
    message = " ".join(str(exc.format_message()).split()).rstrip(".") or "aborted"
    hint = f"; see {command} --help" if type(exc).__name__ != "Abort" else ""
    name = command.removeprefix("demoplan").strip() or "demoplan"
    if context is not None and hint:
        hint += _recording_hint(context.info_name, sys.argv[2:])
    sys.stderr.write(f"demoplan: error: {name}: {message}{hint}\n")
    return int(exc.exit_code) if exc.exit_code else 1


_BAG_SUFFIXES = (".db3", ".mcap")


def _recording_hint(command: str | None, args: Sequence[str]) -> str:
    """`` (FILE: an HDF5 file: …)`` where a usage error's command line names a
    recording that command does not read as such — an HDF5 file anywhere but
    ``import``, a bag's SQLite or MCAP storage under another name —, so that
    the way to read it is said whatever else was wrong (``segment demo.hdf5``
    without ``-o``). Only regular files are looked at, their first bytes."""
    import stat

    from demoplan.fileio.reading import binary_container

    for arg in args:
        if arg.startswith("-"):
            continue
        try:
            if not stat.S_ISREG(Path(arg).stat().st_mode):
                continue
            with Path(arg).open("rb") as handle:
                head = handle.read(4104)
        except (OSError, ValueError):
            continue
        found = binary_container(head, arg)
        if found is None:
            continue
        kind, how = found
        if kind == "an HDF5 file" and command == "import":
            continue
        if kind != "an HDF5 file" and arg.lower().endswith(_BAG_SUFFIXES):
            continue
        from demoplan.fileio import display_path

        return f" ({display_path(arg)}: {kind}; {how})"
    return ""


if __name__ == "__main__":  # pragma: no cover
    main()
