"""What a search is given and what it returns: the :class:`Budget` and its
:class:`Clock` (one mechanism with learning and perception:
:mod:`demoplan.budget`) and :class:`SearchOutcome` (shared by every search in
:mod:`demoplan.planning`)."""

from __future__ import annotations

from dataclasses import dataclass

from demoplan.budget import MAX_STATES, PLANNING_SECONDS, Budget, Clock, default_budget
from demoplan.planning.problem import Action

__all__ = [
    "MAX_STATES",
    "PLANNING_SECONDS",
    "Budget",
    "Clock",
    "SearchOutcome",
    "default_budget",
]


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
