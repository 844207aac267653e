"""Ctrl-C and SIGTERM, the same way in every command (docs/cli.md: exit 130 /
143): the handlers :func:`demoplan.cli.launcher.main` installs, and what the CLI
asks when a command was stopped. Kept apart from the launcher so that the
typer application can use it without importing the launcher back.
"""

from __future__ import annotations

import sys
from typing import Any

__all__ = [
    "INTERRUPTED_EXIT",
    "TERMINATED_EXIT",
    "Terminated",
    "interrupted_by_signal",
    "interrupted_exit_code",
    "on_signal",
    "quiet_after_signal",
    "redeliver_lost_signal",
    "signals_received",
]


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised like Ctrl-C so that every command stops the same way."""


INTERRUPTED_EXIT = 130  # 128 + SIGINT, as a shell reports a job Ctrl-C stopped
TERMINATED_EXIT = 143  # 128 + SIGTERM


def interrupted_exit_code(exc: KeyboardInterrupt) -> int:
    """The exit code of a command stopped by ``exc`` (docs/cli.md)."""
    return TERMINATED_EXIT if isinstance(exc, Terminated) else INTERRUPTED_EXIT


signals_received: list[int] = []  # SIGINT / SIGTERM, in the order they came


def on_signal(signum: int, frame: object) -> None:
    """Ctrl-C or SIGTERM: remember it (a library may catch the exception and
    exit in its own way — typer turns Ctrl-C into a silent exit 130) and stop."""
    import signal

    signals_received.append(signum)
    raise Terminated if signum == signal.SIGTERM else KeyboardInterrupt


def redeliver_lost_signal(unraisable: Any) -> None:
    """``sys.unraisablehook``: a signal whose exception arrived where Python cannot
    raise it (a weakref callback inside an import lock, a ``__del__``) is
    neither reported with a traceback nor lost — a timer delivers it again a
    few milliseconds later, after the hook has returned, so that the command
    stops at the next line of ordinary code. Other unraisable exceptions go to
    Python's own report."""
    import signal

    if isinstance(unraisable.exc_value, KeyboardInterrupt) and signals_received:
        signum = signals_received[-1]
        signal.signal(signal.SIGALRM, lambda _number, frame: on_signal(signum, frame))
        signal.setitimer(signal.ITIMER_REAL, 0.005)
        return
    sys.__unraisablehook__(unraisable)


def quiet_after_signal(hook: Any) -> Any:
    """``sys.excepthook`` that says nothing once a signal has arrived. A C
    extension interrupted while it loads (shapely's, importing NumPy through
    the C API) prints the interrupted import through ``sys.excepthook`` before
    it fails with "initialization failed"; the command's one line,
    ``demoplan: interrupted``, already says what happened. Before a signal,
    ``hook`` reports as it would."""

    def quiet(exc_type: Any, exc: Any, tb: Any) -> None:
        if not signals_received:
            hook(exc_type, exc, tb)

    return quiet


def interrupted_by_signal() -> bool:
    """Whether ``main`` stopped the command on a signal (it reports it once)."""
    return bool(signals_received)
