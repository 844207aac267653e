"""The ``demoplan`` executable: a lean path for ``demoplan solve``, typer for the rest.

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
"""

from __future__ import annotations

import argparse
import errno
import os
import sys
import time
from collections.abc import Callable, Sequence
from contextlib import AbstractContextManager, nullcontext
from dataclasses import dataclass
from pathlib import Path
from typing import Any

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

DEFAULT_TIMEOUT = 2.0
"""Seconds a planning command may take by default, counted from its start (SPEC §4)."""

_command_started = time.monotonic()
"""When the current command started: the import of this module, for the
``demoplan`` executable (so a time budget bounds the whole process, start-up
included); each invocation of the typer app in a longer-lived process (tests,
notebooks) restarts it (:func:`mark_command_start`)."""
_started_by_main = False


def mark_command_start() -> None:
    """A command starts now — unless it is the one :func:`main` started, whose
    clock has been running since the process began."""
    global _command_started, _started_by_main
    if _started_by_main:
        _started_by_main = False
        return
    _command_started = time.monotonic()


@dataclass(frozen=True)
class SolveOptions:
    """What ``demoplan solve`` was asked to do."""

    problem: Path
    json_output: bool = False
    search: str = "astar"
    max_nodes: int | None = None
    timeout: float | None = None  # None: DEFAULT_TIMEOUT
    optimal: bool = False


class _DeclinedError(Exception):
    """The lean parser leaves this command line to typer."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # type: ignore[override]
        raise _DeclinedError(message)


def parse_solve_options(args: Sequence[str]) -> SolveOptions | None:
    """Options of ``demoplan solve ARGS``, or None when typer should handle them."""
    if any(arg in ("-h", "--help") for arg in args):
        return None
    parser = _Parser(prog="demoplan solve", add_help=False, allow_abbrev=False)
    parser.add_argument("problem", type=Path)
    parser.add_argument("--json", dest="json_output", action="store_true")
    from demoplan.planning.search import SEARCHES  # needed next anyway, to solve

    parser.add_argument("--search", choices=tuple(SEARCHES), default="astar")
    parser.add_argument("--max-nodes", type=int, default=None)
    parser.add_argument("--timeout", type=float, default=None)
    parser.add_argument("--optimal", action="store_true")
    try:
        parsed = parser.parse_args(list(args))
    except _DeclinedError:
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


def command_budget(max_nodes: int | None, timeout: float | None) -> Any:
    """The :class:`~demoplan.planning.budget.Budget` of a planning command:
    ``timeout`` seconds (default :data:`DEFAULT_TIMEOUT`) from the start of the
    process, so that the whole command answers within it."""
    from demoplan.planning.budget import Budget

    seconds = DEFAULT_TIMEOUT if timeout is None else timeout
    # The search stops a little before the end, to leave time to write the answer
    # and tear down what it built.
    margin = min(_ANSWER_SECONDS, seconds / 8)
    return Budget(max_nodes, timeout=seconds, deadline=_command_started + seconds - margin)


_ANSWER_SECONDS = 0.25


def solve_text(
    options: SolveOptions, spinner: Callable[[str], AbstractContextManager[object]] | None = None
) -> tuple[str, str]:
    """Read the problem, solve it and render the plan (the paper's format, or its
    JSON) and the line for stderr saying whether it is proved shortest;
    ``spinner(text)`` wraps the search (a terminal's status line). Raises
    :class:`~demoplan.errors.DemoplanError`. Both ``solve`` paths use this."""
    from demoplan.planning.problem import format_plan, optimality_line, plan_to_json
    from demoplan.planning.search import solve
    from demoplan.planning.xml import load_problem

    started = time.perf_counter()
    problem = load_problem(options.problem)
    read_seconds = time.perf_counter() - started
    budget = command_budget(options.max_nodes, options.timeout)
    with spinner(f"Searching ({options.search}) for a plan…") if spinner else nullcontext():
        plan = solve(problem, options.search, budget, optimal=options.optimal)
    note = f"demoplan: {optimality_line(plan)}\n"
    if options.json_output:
        import json

        data = plan_to_json(plan, read_seconds)
        return json.dumps(data, indent=2, ensure_ascii=False, allow_nan=False) + "\n", note
    return format_plan(plan), note


def run_solve(options: SolveOptions) -> int:
    """Solve, print the plan (or its JSON) on stdout; return the exit code (SPEC §4)."""
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
    sys.stdout.write(text)
    sys.stderr.write(note)
    return 0


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised like Ctrl-C so that every command stops the same way."""


INTERRUPTED_EXIT = 130  # 128 + SIGINT, as a shell reports a job Ctrl-C stopped
TERMINATED_EXIT = 143  # 128 + SIGTERM


def interrupted_exit_code(exc: KeyboardInterrupt) -> int:
    """The exit code of a command stopped by ``exc`` (SPEC §4)."""
    return TERMINATED_EXIT if isinstance(exc, Terminated) else INTERRUPTED_EXIT


_signals_received: list[int] = []  # SIGINT / SIGTERM, in the order they came


def _on_signal(signum: int, frame: object) -> None:
    """Ctrl-C or SIGTERM: remember it (a library may catch the exception and
    exit in its own way — typer turns Ctrl-C into a silent exit 130) and stop."""
    import signal

    _signals_received.append(signum)
    raise Terminated if signum == signal.SIGTERM else KeyboardInterrupt


def _redeliver_lost_signal(unraisable: Any) -> None:
    """``sys.unraisablehook``: a signal whose exception arrived where Python cannot
    raise it (a weakref callback inside an import lock, a ``__del__``) is
    neither reported with a traceback nor lost — a timer delivers it again a
    few milliseconds later, after the hook has returned, so that the command
    stops at the next line of ordinary code. Other unraisable exceptions go to
    Python's own report."""
    import signal

    if isinstance(unraisable.exc_value, KeyboardInterrupt) and _signals_received:
        signum = _signals_received[-1]
        signal.signal(signal.SIGALRM, lambda _number, frame: _on_signal(signum, frame))
        signal.setitimer(signal.ITIMER_REAL, 0.005)
        return
    sys.__unraisablehook__(unraisable)


def interrupted_by_signal() -> bool:
    """Whether ``main`` stopped the command on a signal (it reports it once)."""
    return bool(_signals_received)


def main() -> None:
    """Entry point of the ``demoplan`` command."""
    import signal

    global _started_by_main
    _started_by_main = True
    # Ctrl-C raises KeyboardInterrupt even where the process was started with
    # SIGINT ignored (a background job of a script); SIGTERM does the same.
    signal.signal(signal.SIGINT, _on_signal)
    signal.signal(signal.SIGTERM, _on_signal)
    sys.unraisablehook = _redeliver_lost_signal
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
            if not _signals_received:
                sys.stdout.flush()  # here, where a full disk or a closed pipe is caught
    except KeyboardInterrupt:
        if not _signals_received:  # raised without a signal (a test, a debugger)
            _signals_received.append(signal.SIGINT)
    except Exception as exc:
        if not _signals_received:
            if not isinstance(exc, OSError):
                raise
            # stdout full (> /dev/full) or its reader gone (| head)
            _drop_stdout()
            sys.stderr.write(f"demoplan: error: standard output: {_stdout_reason(exc)}\n")
            raise SystemExit(1) from None
        # else the signal surfaced as another error: a C extension interrupted
        # while it loads reports "ImportError: initialization failed"
    # The command is over: a signal now would only turn a finished command's
    # exit into Python's own KeyboardInterrupt report.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    if _signals_received:
        # Every command stops the same way, wherever the signal found it.
        _drop_stdout()
        sys.stderr.write("demoplan: interrupted\n")
        terminated = signal.SIGTERM in _signals_received
        raise SystemExit(TERMINATED_EXIT if terminated else INTERRUPTED_EXIT)
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
    """Run the command; its exit code. Usage errors are one line (SPEC §4)."""
    args = sys.argv[1:]
    if args[:1] == ["solve"] and not sys.stderr.isatty():
        options = parse_solve_options(args[1:])
        if options is not None:
            sys.stdout.flush()
            return run_solve(options)
    from demoplan.cli import app

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
    sys.stderr.write(f"demoplan: error: {name}: {message}{hint}\n")
    return int(exc.exit_code) if exc.exit_code else 1


if __name__ == "__main__":  # pragma: no cover
    main()
