"""The command clock, which the lean launcher (:mod:`demoplan.cli.launcher`)
and the typer application share: a planning command's time budget counts
from the start of the ``demoplan`` process, so that the whole command answers
within it."""

from __future__ import annotations

import time

from demoplan.budget import PLANNING_SECONDS, Budget

__all__ = [
    "DEFAULT_TIMEOUT",
    "command_budget",
    "mark_command_start",
    "mark_process_start",
    "restart_process_clock",
]

DEFAULT_TIMEOUT = PLANNING_SECONDS
"""Seconds a planning command may take by default, counted from its start (docs/cli.md)."""

_command_started = time.monotonic()
"""When the current command started: the import of this module, for the
``demoplan`` executable (so a time budget bounds the whole process, start-up
included); each invocation of the typer app in a longer-lived process (tests,
notebooks) restarts it (:func:`mark_command_start`)."""
_started_by_main = False


def mark_process_start() -> None:
    """The executable's own command: its clock runs from the process start."""
    global _started_by_main
    _started_by_main = True


def restart_process_clock() -> None:
    """The process starts now: for a process forked from one that imported this
    module earlier (the tests' fork server, tests/support/forkserver.py), whose
    command's clock should run from the fork, as a new process's would."""
    global _command_started
    _command_started = time.monotonic()


def mark_command_start() -> None:
    """A command starts now — unless it is the one :func:`main` started, whose
    clock has been running since the process began."""
    global _command_started, _started_by_main
    if _started_by_main:
        _started_by_main = False
        return
    _command_started = time.monotonic()


def command_budget(max_nodes: int | None, timeout: float | None) -> Budget:
    """The budget of a planning command: ``timeout`` seconds (default
    :data:`DEFAULT_TIMEOUT`) from the start of the process."""
    seconds = DEFAULT_TIMEOUT if timeout is None else timeout
    # The search stops a little before the end, to leave time to write the answer
    # and tear down what it built.
    margin = min(_ANSWER_SECONDS, seconds / 8)
    return Budget(max_nodes, timeout=seconds, deadline=_command_started + seconds - margin)


_ANSWER_SECONDS = 0.25
