"""What a search is given and what it returns: :class:`Budget`, :class:`Clock`,
:class:`SearchOutcome` (shared by every search in :mod:`demoplan.planning`)."""

from __future__ import annotations

import time
from dataclasses import dataclass

from demoplan.planning.problem import Action

__all__ = ["Budget", "Clock", "SearchOutcome"]


@dataclass(frozen=True, slots=True)
class Budget:
    """Limits of one search: expanded states and wall-clock seconds (None: no limit)."""

    max_nodes: int | None = None
    timeout: float | None = None


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


# BFS state: object locations (-1 for the held one), held (object, grasp, where it


class Clock:
    """Tells a search when its budget is spent."""

    def __init__(self, budget: Budget):
        self.budget = budget
        self.deadline = None if budget.timeout is None else time.monotonic() + budget.timeout

    def stop(self, expanded: int) -> str | None:
        if self.budget.max_nodes is not None and expanded >= self.budget.max_nodes:
            return f"--max-nodes {self.budget.max_nodes}"
        if self.deadline is not None and time.monotonic() > self.deadline:
            return f"--timeout {self.budget.timeout:g} s"
        return None
