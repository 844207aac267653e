"""Budgets: how long (and how far) a computation may run — one mechanism for
the planner's searches, learning and perception (docs/limits.md).

A :class:`Budget` names the limits (expanded states, seconds, an absolute
deadline, states kept); a :class:`Clock` tells the work when its budget is
spent. A search is handed its budget and reads its clock between expansions
(:mod:`demoplan.planning`). Learning (read between cluster counts) and
perception (read between colour regions) run inside :func:`time_budget`,
which puts a clock in a context variable; :func:`check_time` raises
:class:`~demoplan.errors.LimitReachedError` (exit 4) once it is spent,
naming the option that raises it. Their cost grows with the data
(placements × references × cluster counts; regions × Hough candidates), and
hostile data makes it minutes. Without a budget nothing is checked.
"""

from __future__ import annotations

import copy
import math
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass

from demoplan.errors import LimitReachedError

__all__ = [
    "LEARNING_TIMEOUT",
    "MAX_STATES",
    "PERCEPTION_TIMEOUT",
    "PLANNING_SECONDS",
    "Budget",
    "Clock",
    "ProgressCallback",
    "check_time",
    "default_budget",
    "report_progress",
    "reporting_progress",
    "time_budget",
]

PLANNING_SECONDS = 2.0
"""The time budget of a planning command and of each (re)planning of a run,
by default (docs/limits.md): the one place it is written — the CLI, the
command layer and :class:`~demoplan.execution.executor.ExecutionSettings`
take it from here."""

MAX_STATES = 2_000_000
"""States a search may keep by default (about 1–2 GB at 30 objects): beyond it
the search stops as at any other limit (exit 4), never with a MemoryError."""

LEARNING_TIMEOUT = 300.0
"""Seconds ``learn`` may take by default before it stops with exit 4 (docs/limits.md)."""
PERCEPTION_TIMEOUT = 60.0
"""Seconds ``perceive`` may take by default (docs/limits.md)."""


@dataclass(frozen=True, slots=True)
class Budget:
    """Limits of one computation (None: no limit): expanded states, seconds from
    its start, an absolute ``time.monotonic()`` deadline (a command's budget
    counted from its own start), and states kept in memory."""

    max_nodes: int | None = None
    timeout: float | None = None
    deadline: float | None = None
    max_states: int | None = MAX_STATES


def default_budget() -> Budget:
    """A planning command's budget when it is given none: :data:`PLANNING_SECONDS`."""
    return Budget(timeout=PLANNING_SECONDS)


class Clock:
    """Tells a computation when its budget is spent: started once, where the
    command starts, and handed down to every stage, which takes its share
    with :meth:`part` (every limit kept)."""

    def __init__(self, budget: Budget | None = None):
        budget = Budget() if budget is None else budget
        self.budget = budget
        deadlines = [] if budget.deadline is None else [budget.deadline]
        if budget.timeout is not None:
            deadlines.append(time.monotonic() + budget.timeout)
        self.deadline = min(deadlines) if deadlines else None

    @property
    def max_states(self) -> int:
        """States a computation under this clock may keep."""
        return MAX_STATES if self.budget.max_states is None else self.budget.max_states

    def expired(self) -> bool:
        """The time is up."""
        return self.deadline is not None and time.monotonic() > self.deadline

    def stop(self, expanded: int, states: int = 0) -> str | None:
        """Which limit is reached after ``expanded`` expansions with ``states``
        kept, if any (named as the option that raises it)."""
        if self.budget.max_nodes is not None and expanded >= self.budget.max_nodes:
            return f"--max-nodes {self.budget.max_nodes}"
        if self.budget.max_states is not None and states >= self.budget.max_states:
            return f"the memory limit of {self.budget.max_states} states"
        if self.expired():
            return self.time_limit()
        return None

    def time_limit(self) -> str:
        """The time limit, named as the option that raises it."""
        timeout = self.budget.timeout
        return f"--timeout {timeout:g} s" if timeout is not None else "the time budget"

    def check(self, where: str) -> None:
        """Raise LimitReachedError (exit 4) once the time is up, naming the
        limit and ``where`` the time ran out (work with no plan to show yet:
        compiling a problem, looking for reasons there is no plan)."""
        if self.expired():
            raise LimitReachedError(f"{self.time_limit()} reached {where}")

    def remaining(self) -> float | None:
        """Seconds left, if there is a deadline."""
        return None if self.deadline is None else max(0.0, self.deadline - time.monotonic())

    def part(self, fraction: float, unbounded: float | None = None) -> Clock:
        """This clock for a part of the work: ``fraction`` of the time left from
        now, every other limit (expansions, states) and the names of the limits
        as they are. Without a deadline (none, or an infinite one): a
        ``fraction`` of ``unbounded`` seconds where given, else no deadline."""
        clock = copy.copy(self)
        left = self.remaining()
        if left is None or math.isinf(left):
            left = unbounded
        clock.deadline = None if left is None else time.monotonic() + fraction * left
        return clock

    def at_least(self, seconds: float) -> Clock:
        """This clock, with at least ``seconds`` left from now (its limits of
        states and expansions as they are)."""
        clock = copy.copy(self)
        if clock.deadline is not None:
            clock.deadline = max(clock.deadline, time.monotonic() + seconds)
        return clock


_current: ContextVar[tuple[Clock, str] | None] = ContextVar("budget", default=None)


@contextmanager
def time_budget(seconds: float | Clock | None, message: str) -> Iterator[None]:
    """The work inside the block stops after ``seconds`` (None or inf: no limit;
    a :class:`Clock`: at its deadline — the command's own clock, not a second
    one) with ``message`` (what stopped and how to give it more; ``{where}`` in
    it: the work under way, as :func:`check_time` says it)."""
    clock = seconds if isinstance(seconds, Clock) else Clock(Budget(timeout=seconds))
    if clock.deadline is None or math.isinf(clock.deadline):
        yield
        return
    token = _current.set((clock, message))
    try:
        yield
    finally:
        _current.reset(token)


def check_time(where: str = "") -> None:
    """Raise LimitReachedError if the current budget is spent; ``where``: the
    work under way, put in place of ``{where}`` in the budget's message (where
    the time went)."""
    current = _current.get()
    if current is not None and current[0].expired():
        raise LimitReachedError(current[1].replace("{where}", where))


ProgressCallback = Callable[[str, int, int], None]
"""``callback(what, done, total)``: how far long work is (a progress bar in the
command line); one shape wherever work reports how far it is."""
_progress: ContextVar[ProgressCallback | None] = ContextVar("progress", default=None)


@contextmanager
def reporting_progress(callback: ProgressCallback | None) -> Iterator[None]:
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
