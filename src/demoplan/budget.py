"""A time budget for long computations other than search: learning (read
between cluster counts) and perception (read between colour regions).

Their cost grows with the data (placements × references × cluster counts;
regions × Hough candidates), and hostile data makes it minutes.
:func:`time_budget` sets a deadline for the code run inside it;
:func:`check_time` raises :class:`~demoplan.errors.LimitReachedError` (exit 4)
once it has passed, naming the option that raises it. Without a budget
nothing is checked. (The planner's searches have their own,
:mod:`demoplan.planning.budget`.)
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar

from demoplan.errors import LimitReachedError

__all__ = [
    "LEARNING_TIMEOUT",
    "PERCEPTION_TIMEOUT",
    "check_time",
    "report_progress",
    "reporting_progress",
    "time_budget",
]

_deadline: ContextVar[tuple[float, str] | None] = ContextVar("deadline", default=None)

LEARNING_TIMEOUT = 300.0
"""Seconds ``learn`` may take by default before it stops with exit 4 (docs/limits.md)."""
PERCEPTION_TIMEOUT = 60.0
"""Seconds ``perceive`` may take by default (docs/limits.md)."""


@contextmanager
def time_budget(seconds: float | None, message: str) -> Iterator[None]:
    """The work inside the block stops after ``seconds`` (None or inf: no limit)
    with ``message`` (what stopped and how to give it more)."""
    if seconds is None or math.isinf(seconds):
        yield
        return
    token = _deadline.set((time.monotonic() + seconds, message))
    try:
        yield
    finally:
        _deadline.reset(token)


def check_time() -> None:
    """Raise LimitReachedError if the current budget is spent."""
    budget = _deadline.get()
    if budget is not None and time.monotonic() > budget[0]:
        raise LimitReachedError(budget[1])


Progress = Callable[[str, int, int], None]  # (what, done, total)
_progress: ContextVar[Progress | None] = ContextVar("progress", default=None)


@contextmanager
def reporting_progress(callback: Progress | None) -> Iterator[None]:
    """Long work inside the block reports ``callback(what, done, total)`` as it
    goes (a progress bar in the command line; None: nothing)."""
    token = _progress.set(callback)
    try:
        yield
    finally:
        _progress.reset(token)


def report_progress(what: str, done: int, total: int) -> None:
    """Tell the current progress callback, if any, how far the work is."""
    callback = _progress.get()
    if callback is not None:
        callback(what, done, total)
