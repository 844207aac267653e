"""Ctrl-C and SIGTERM, the same way in every command (docs/cli.md: exit 130 /
143): the handlers :func:`demoplan.cli.launcher.main` installs, and what the CLI
asks when a command was stopped. Shared by the front ends: the command
line (the typer application uses it without importing the launcher back) and
the studio's runs, which stop through the same handlers.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from types import CodeType
from typing import Any, TypeVar

__all__ = [
    "INTERRUPTED_EXIT",
    "TERMINATED_EXIT",
    "Terminated",
    "ignore_signals",
    "interrupted_by_signal",
    "interrupted_exit_code",
    "on_signal",
    "quiet_after_signal",
    "redeliver_lost_signal",
    "reports_signals",
    "signals_received",
    "stop_redelivery",
]


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised like Ctrl-C so that every command stops the same way."""


INTERRUPTED_EXIT = 130  # 128 + SIGINT, as a shell reports a job Ctrl-C stopped
TERMINATED_EXIT = 143  # 128 + SIGTERM


def interrupted_exit_code(exc: KeyboardInterrupt) -> int:
    """The exit code of a command stopped by ``exc`` (docs/cli.md)."""
    return TERMINATED_EXIT if isinstance(exc, Terminated) else INTERRUPTED_EXIT


signals_received: list[int] = []  # SIGINT / SIGTERM, in the order they came
_ended: list[bool] = []  # [True] once the command is over (ignore_signals)


REDELIVERY_SECONDS = 0.25
"""How soon a signal whose exception was swallowed is raised again."""

_reporters: set[CodeType] = set()  # the functions that report a signal: never redelivered into
_Function = TypeVar("_Function", bound=Callable[..., Any])


def on_signal(signum: int, frame: object) -> None:
    """Ctrl-C or SIGTERM: remember it (a library may catch the exception and
    exit in its own way — typer turns Ctrl-C into a silent exit 130) and stop.
    A timer raises it again if the exception is swallowed (:func:`_redeliver`).
    Once the command is over (:func:`ignore_signals`) the signal is ignored."""
    import signal

    if _ended:
        return
    signals_received.append(signum)
    _arm_redelivery(REDELIVERY_SECONDS)
    raise Terminated if signum == signal.SIGTERM else KeyboardInterrupt


def _arm_redelivery(seconds: float) -> None:
    import signal

    signal.signal(signal.SIGALRM, _redeliver)
    signal.setitimer(signal.ITIMER_REAL, seconds)


def _redeliver(_signum: int, frame: Any) -> None:
    """The redelivery timer: the signal's exception again, unless it is on its way.

    A library may swallow the exception: an extension module interrupted while
    it loads fails with ``ImportError``, which an optional import's ``except
    ImportError`` takes for a missing package, and the command ran on to its end.
    While a ``KeyboardInterrupt`` is being handled (a ``finally`` or ``__exit__``
    cleaning up as the command unwinds), the timer waits instead of cutting the
    cleanup short; in a reporting function (:func:`reports_signals`) it stops.
    """
    if frame is not None and frame.f_code in _reporters:
        return
    if isinstance(sys.exc_info()[1], KeyboardInterrupt):
        _arm_redelivery(REDELIVERY_SECONDS)
        return
    if signals_received:
        on_signal(signals_received[-1], frame)


def reports_signals(function: _Function) -> _Function:
    """Mark ``function`` as the one that reports a signal (a process's ``main``):
    the redelivery timer never raises inside it. It calls :func:`stop_redelivery`
    where it takes the exception (or finds a signal was received)."""
    _reporters.add(function.__code__)
    return function


def stop_redelivery() -> None:
    """No more redelivery: the signal has reached the function that reports it."""
    import signal

    signal.setitimer(signal.ITIMER_REAL, 0)
    signal.signal(signal.SIGALRM, signal.SIG_IGN)


def ignore_signals() -> None:
    """The command is over: SIGINT and SIGTERM are ignored from here on.

    A signal that had arrived before is in :data:`signals_received`, for the
    caller to report. One that arrives now finds the work done (the outputs in
    place, the answer printed) and the interpreter ending: there is nothing
    left to stop, and raising it would only turn a finished command's exit into
    a traceback. The first statement makes :func:`on_signal` ignore it, so that
    no moment is left between the two where a signal's exception escapes the
    caller: a signal whose handler runs inside ``signal.signal`` below (Python
    runs the pending ones before it changes a handler) or a redelivery timer
    firing meanwhile is ignored the same way."""
    _ended.append(True)
    import signal

    stop_redelivery()
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)


def redeliver_lost_signal(unraisable: Any) -> None:
    """``sys.unraisablehook``: a signal whose exception arrived where Python cannot
    raise it (a weakref callback inside an import lock, a ``__del__``) is
    neither reported with a traceback nor lost — the redelivery timer raises it
    again a few milliseconds later, after the hook has returned, so that the
    command stops at the next line of ordinary code. Other unraisable
    exceptions go to Python's own report."""
    if isinstance(unraisable.exc_value, KeyboardInterrupt) and signals_received:
        _arm_redelivery(0.005)
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
