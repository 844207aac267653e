"""Solving a planning problem (paper §IV.C): the searches, and why there is no plan.

Two searches, chosen by name from :data:`SEARCHES`:

- ``bfs`` — :func:`~demoplan.planning.bfs.breadth_first_search`, the paper's
  method and our reference;
- ``astar`` — :func:`~demoplan.planning.astar.astar_search`, the default: A*
  over moves with the admissible bounds of :mod:`demoplan.planning.bounds`.

:func:`solve` turns a search's :class:`~demoplan.planning.budget.SearchOutcome`
into a :class:`~demoplan.planning.problem.Plan` or raises NoPlanError (exit 3)
/ LimitReachedError (exit 4); :func:`explain_unsolvable` finds the reasons
that need no search.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from demoplan.errors import LimitReachedError, NoPlanError
from demoplan.graphs import find_cycle
from demoplan.planning.astar import astar_search
from demoplan.planning.bfs import breadth_first_search
from demoplan.planning.budget import Budget, SearchOutcome
from demoplan.planning.compiled import compile_problem
from demoplan.planning.problem import Plan, Problem

__all__ = [
    "SEARCHES",
    "Budget",
    "SearchOutcome",
    "astar_search",
    "breadth_first_search",
    "explain_unsolvable",
    "solve",
]


SEARCHES: dict[str, Callable[[Problem, Budget], SearchOutcome]] = {
    "astar": astar_search,
    "bfs": breadth_first_search,
}


def explain_unsolvable(problem: Problem) -> list[str]:
    """Reasons, where they can be shown without search, why no plan exists."""
    c = compile_problem(problem)
    reasons = []
    finals: dict[int, int] = {}
    for obj, goal in enumerate(c.goal):
        if goal < 0:
            continue
        if goal in finals:
            first, second = c.objects[finals[goal]], c.objects[obj]
            reasons.append(f"{first} and {second} must both end at {c.locations[goal]}")
        finals[goal] = obj
    for obj, name in enumerate(c.objects):
        needs_move = (c.goal[obj] >= 0 and c.goal[obj] != c.start[obj]) or any(
            not c.start_reached >> s & 1 for s in c.subgoals_of[obj]
        )
        if needs_move and not c.grasps_of[obj]:
            reasons.append(f"{name} must move but allows no grasp")
    frozen = c.frozen(c.start)
    stuck = [c.objects[o] for o, loc in enumerate(c.start) if frozen >> loc & 1]
    must_move = [
        c.objects[o]
        for o, loc in enumerate(c.start)
        if frozen >> loc & 1
        and (
            (c.goal[o] >= 0 and c.goal[o] != loc)
            or any(not c.start_reached >> s & 1 for s in c.subgoals_of[o])
        )
    ]
    if must_move:
        reasons.append(
            f"{', '.join(must_move)} must move but can never be grasped: "
            f"{', '.join(stuck)} block every grasp of one another where they stand"
        )
    unmovable = c.never_placed()
    must_place = [
        c.objects[o]
        for o, loc in enumerate(c.start)
        if unmovable >> o & 1
        and c.grasps_of[o]
        and (c.goal[o] != loc or any(not c.start_reached >> s & 1 for s in c.subgoals_of[o]))
    ]
    if must_place:
        circle = [c.objects[o] for o in range(len(c.objects)) if unmovable >> o & 1]
        reasons.append(
            f"{', '.join(must_place)} must be put down at places where every grasp "
            f"collides with another final place of {', '.join(circle)}: "
            "the last of them put down cannot be"
        )
    for obj, goal in enumerate(c.goal):
        for other in range(obj + 1, len(c.goal)):
            place = c.goal[other]
            if goal >= 0 and place >= 0 and c.exclusive[goal] >> place & 1:
                reasons.append(
                    f"{c.objects[obj]} and {c.objects[other]} cannot both stand at their final "
                    f"places: {c.locations[goal]} and {c.locations[place]} overlap"
                )
    cycle = find_cycle(problem.precedences)
    if cycle:
        reasons.append(f"subgoals must come before themselves: {' < '.join(cycle)}")
    return reasons


def solve(
    problem: Problem,
    search: str = "astar",
    budget: Budget = Budget(),
) -> Plan:
    """A shortest plan, or NoPlanError (with the reason) / LimitReachedError."""
    if search not in SEARCHES:
        raise ValueError(f"unknown search {search!r}; one of {sorted(SEARCHES)}")
    reasons = explain_unsolvable(problem)
    if reasons:
        raise NoPlanError("no plan: " + "; ".join(reasons))
    started = time.perf_counter()
    outcome = SEARCHES[search](problem, budget)
    seconds = time.perf_counter() - started
    if outcome.actions is not None:
        return Plan(outcome.actions, outcome.expanded, outcome.generated, seconds, search)
    if outcome.limit:
        raise LimitReachedError(
            f"{outcome.limit} reached after expanding {outcome.expanded} states "
            f"({outcome.generated} generated, {seconds:.2f} s) with no plan yet"
            + (f"; every plan needs at least {outcome.bound} actions" if outcome.bound else "")
        )
    raise NoPlanError(
        f"no plan: search space exhausted after {outcome.expanded} states "
        "(every reachable arrangement tried)"
    )
