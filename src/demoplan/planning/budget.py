"""What a search is given and what it returns: :class:`Budget`, :class:`Clock`,
:class:`SearchOutcome` (shared by every search in :mod:`demoplan.planning`)."""

from __future__ import annotations

import time
from dataclasses import dataclass

from demoplan.planning.problem import Action

__all__ = [
    "MAX_STATES",
    "PLANNING_SECONDS",
    "Budget",
    "Clock",
    "SearchOutcome",
    "default_budget",
]

PLANNING_SECONDS = 2.0
"""The time budget of a planning command and of each (re)planning of a run,
by default (docs/limits.md): the one place it is written — the CLI, the
library (:mod:`demoplan.api`) and :class:`~demoplan.execution.executor.ExecutionSettings`
take it from here."""

MAX_STATES = 2_000_000
"""States a search may keep by default (about 1–2 GB at 30 objects): beyond it
the search stops as at any other limit (exit 4), never with a MemoryError."""


@dataclass(frozen=True, slots=True)
class Budget:
    """Limits of one search (None: no limit): expanded states, seconds from the
    start of the search, an absolute ``time.monotonic()`` deadline (a command's
    budget counted from its own start), and states kept in memory."""

    max_nodes: int | None = None
    timeout: float | None = None
    deadline: float | None = None
    max_states: int | None = MAX_STATES


@dataclass(frozen=True, slots=True)
class SearchOutcome:
    """What a search found: ``actions`` (None when there is no plan or a limit hit)."""

    actions: tuple[Action, ...] | None
    expanded: int
    generated: int
    exhausted: bool  # the whole reachable space was searched without finding a plan
    limit: str | None = None  # which budget stopped the search
    bound: int = 0  # proven lower bound on the plan length (in actions)
    optimal: bool = True  # the actions are proved shortest


class Clock:
    """Tells a search when its budget is spent."""

    def __init__(self, budget: Budget):
        self.budget = budget
        deadlines = [] if budget.deadline is None else [budget.deadline]
        if budget.timeout is not None:
            deadlines.append(time.monotonic() + budget.timeout)
        self.deadline = min(deadlines) if deadlines else None

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
            timeout = self.budget.timeout
            return f"--timeout {timeout:g} s" if timeout is not None else "the time budget"
        return None

    def remaining(self) -> float | None:
        """Seconds left, if there is a deadline."""
        return None if self.deadline is None else max(0.0, self.deadline - time.monotonic())


def default_budget() -> Budget:
    """A planning command's budget when it is given none: :data:`PLANNING_SECONDS`."""
    return Budget(timeout=PLANNING_SECONDS)
