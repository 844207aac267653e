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

import math
import time
from collections.abc import Callable
from typing import NoReturn

from demoplan.errors import LimitReachedError, NoPlanError
from demoplan.graphs import find_cycle
from demoplan.planning.astar import AStar, astar_search
from demoplan.planning.bfs import breadth_first_search
from demoplan.planning.bounds import DEAD_END, LowerBounds, Move
from demoplan.planning.budget import MAX_STATES, Budget, Clock, SearchOutcome
from demoplan.planning.compiled import Compiled, compile_problem
from demoplan.planning.greedy import greedy_moves
from demoplan.planning.parts import needs_moves, object_groups, parts_plan, plan_by_parts
from demoplan.planning.plateau import plateau_moves
from demoplan.planning.problem import Action, Plan, Problem
from demoplan.planning.tight import tight_plan

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


def explain_unsolvable(problem: Problem, compiled: Compiled | None = None) -> list[str]:
    """Reasons, where they can be shown without search, why no plan exists
    (``compiled``: the problem already compiled)."""
    c = compiled or compile_problem(problem)
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
        if c.must_move(obj) and not c.grasps_of[obj]:
            reasons.append(f"{name} must move but allows no grasp")
    frozen = c.frozen(c.start)
    stuck = [c.objects[o] for o, loc in enumerate(c.start) if frozen >> loc & 1]
    must_move = [
        c.objects[o] for o, loc in enumerate(c.start) if frozen >> loc & 1 and c.must_move(o)
    ]
    if must_move:
        reasons.append(
            f"{', '.join(must_move)} must move but can never be grasped: "
            f"{', '.join(stuck)} block every grasp of one another where they stand"
        )
    unmovable = c.never_placed()
    must_place = [
        c.objects[o]
        for o in range(len(c.objects))
        if unmovable >> o & 1 and c.grasps_of[o] and c.must_move(o)
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
    *,
    optimal: bool = False,
) -> Plan:
    """A plan for ``problem`` within ``budget``: shortest where it can be proved.

    ``astar`` is *anytime*, in phases that share the budget:

    0. where the start's bound has a rigid shape, a plan exactly that long is
       built from an order of the moves, or shown not to exist — the bound
       then grows by a move (:func:`~demoplan.planning.tight.tight_plan`);
    1. greedy best-first search (:func:`~demoplan.planning.greedy.greedy_moves`)
       finds a first plan fast (it may take the whole budget, and never less
       than 0.2 s);
    2. a depth-first dive (:func:`~demoplan.planning.plateau.plateau_moves`)
       looks for a plan as long as the start's lower bound — shortest;
    3. where the objects fall into groups that never meet, the groups are
       solved one by one (:mod:`~demoplan.planning.parts`): a plan, and a
       lower bound that adds up;
    4. weighted A* passes on the greedy guidance shorten the plan;
    5. A* looks for a shorter plan, dropping every state whose lower bound
       reaches the plan's length.

    A plan as long as a proven lower bound, or A* finding a plan or running
    out of states, proves the plan shortest; the budget ending first leaves
    it unproved, returned with ``optimal`` False and the lower bound reached.
    With ``optimal``, only a proved plan is returned (else LimitReachedError).
    ``bfs`` is the paper's exact search. NoPlanError (exit 3) says why there
    is no plan; LimitReachedError (exit 4) which limit stopped a search with
    no plan.
    """
    return _solve(problem, search, budget, optimal, _MIN_GREEDY_SECONDS)


def solve_part(problem: Problem, budget: Budget) -> Plan:
    """:func:`solve` for a part of a bigger problem (:mod:`~demoplan.planning.parts`):
    the budget is kept to the letter — the first plan's search gets no more
    time than is left, since a part without a plan only means the parts give
    no plan."""
    return _solve(problem, "astar", budget, False, 0.0)


def _solve(
    problem: Problem, search: str, budget: Budget, optimal: bool, first_plan_seconds: float
) -> Plan:
    """:func:`solve`, where the first plan's search gets at least ``first_plan_seconds``."""
    if search not in SEARCHES:
        raise ValueError(f"unknown search {search!r}; one of {sorted(SEARCHES)}")
    c = compile_problem(problem)  # once, for every phase
    reasons = explain_unsolvable(problem, c)
    if reasons:
        raise NoPlanError("no plan: " + "; ".join(reasons))
    started = time.perf_counter()
    if search == "bfs":
        outcome = breadth_first_search(problem, budget, c)
        seconds = time.perf_counter() - started
        if outcome.actions is not None:
            return _plan(outcome.actions, outcome, seconds, search)
        _raise_without_plan(outcome, seconds, None)
    bounds = LowerBounds(c)
    clock = Clock(budget)
    root = 2 * bounds.estimate(c.start, c.start_reached)
    if root >= 2 * DEAD_END:  # A* proves it: no state to expand
        outcome = AStar(c, bounds, clock).run()
        _raise_without_plan(outcome, time.perf_counter() - started, None)

    def elapsed() -> float:
        return time.perf_counter() - started

    def actions_of(moves: list[Move]) -> tuple[Action, ...]:
        return tuple(action for move in moves for action in c.move_actions(*move))

    # A plan as long as the feedback bound from an order of the moves, or
    # the proof that there is none (tight.py).
    ordering = Clock(Budget(timeout=_share(clock, _TIGHT_SHARE)))
    tight = tight_plan(bounds, c.start, c.start_reached, ordering)
    if tight.moves is not None:
        return Plan(actions_of(tight.moves), seconds=elapsed(), search="tight", bound=root)
    if tight.refuted:
        root += 2
    first = Budget(timeout=max(_share(clock, 1.0), first_plan_seconds))
    moves = greedy_moves(c, bounds, Clock(first))
    incumbent = None if moves is None else actions_of(moves)
    found_by = "greedy"  # the phase that found the incumbent
    if incumbent is not None and len(incumbent) <= root:  # as long as the bound: shortest
        return Plan(incumbent, seconds=elapsed(), search=found_by, bound=root)
    # A plan as long as the root bound is shortest: dive for one (plateau.py).
    dive = Clock(Budget(timeout=_share(clock, _PLATEAU_SHARE)))
    found = plateau_moves(c, bounds, dive, root // 2, budget.max_states or MAX_STATES)
    if found is not None:
        return Plan(actions_of(found), seconds=elapsed(), search="plateau", bound=root)
    groups = object_groups(problem, c)
    if sum(needs_moves(c, g) for g in groups) > 1:
        # Groups of objects that never meet: their shortest plans add up (parts.py).
        parts = plan_by_parts(problem, groups, Budget(timeout=_share(clock, _PARTS_SHARE)), c)
        by_parts = parts_plan(parts, elapsed())
        if by_parts is not None and by_parts.optimal:
            return by_parts
        root = max(root, parts.bound)
        if parts.actions is not None and (incumbent is None or len(parts.actions) < len(incumbent)):
            incumbent, found_by = parts.actions, "parts"
    # Shorter plans by weighted A* on the same guidance, while they come fast.
    for weight in _WEIGHTS:
        if incumbent is None or len(incumbent) <= root:
            break
        improve = Clock(Budget(timeout=_share(clock, _IMPROVE_SHARE)))
        better = greedy_moves(c, bounds, improve, weight=weight, upper=len(incumbent) // 2)
        if better is not None and 2 * len(better) < len(incumbent):
            incumbent, found_by = actions_of(better), "greedy"
    if incumbent is not None and len(incumbent) <= root:
        return Plan(incumbent, seconds=elapsed(), search=found_by, bound=root)
    outcome = AStar(c, bounds, clock).run(None if incumbent is None else len(incumbent) // 2)
    seconds = elapsed()
    name = "astar" if incumbent is None else f"{found_by}+astar"
    if outcome.actions is not None:
        return _plan(outcome.actions, outcome, seconds, name)
    if incumbent is not None:
        if outcome.exhausted:  # nothing shorter exists
            return _plan(incumbent, outcome, seconds, name)
        if not optimal:
            bound = max(outcome.bound, root)
            return _plan(incumbent, outcome, seconds, name, optimal=False, bound=bound)
    _raise_without_plan(outcome, seconds, incumbent)


def _plan(
    actions: tuple[Action, ...],
    outcome: SearchOutcome,
    seconds: float,
    search: str,
    *,
    optimal: bool = True,
    bound: int | None = None,
) -> Plan:
    return Plan(
        actions,
        expanded=outcome.expanded,
        generated=outcome.generated,
        seconds=seconds,
        search=search,
        optimal=optimal,
        bound=len(actions) if bound is None else bound,
    )


_UNBOUNDED_SECONDS = 10.0
"""The time the phases share when the budget sets none."""


_TIGHT_SHARE = 0.25
"""The share of the time left that ordering the moves of a plan as long as the
feedback bound may take."""


_PLATEAU_SHARE = 0.3
"""The share of the time left that the dive for a plan as long as the root
bound may take."""


_PARTS_SHARE = 0.4
"""The share of the time left that solving group by group may take (when the
objects fall into several groups that need moves)."""


_WEIGHTS = (3.0, 2.0, 1.5)
"""Weights of the weighted-A* passes that shorten the first plan."""
_IMPROVE_SHARE = 0.2
"""Each pass may take this share of the time left."""


_MIN_GREEDY_SECONDS = 0.2
"""The first plan's search gets at least this long, even where the budget is
spent before it starts (a slow start-up on a loaded machine): an easy problem
must not go without a plan for want of a few milliseconds."""


def _share(clock: Clock, share: float) -> float:
    """Seconds for a phase: ``share`` of the time left; with no deadline (none,
    or ``--timeout inf``) a share of :data:`_UNBOUNDED_SECONDS`, so that an
    early phase cannot take forever before the exact search."""
    left = clock.remaining()
    return share * (_UNBOUNDED_SECONDS if left is None or math.isinf(left) else left)


def _raise_without_plan(
    outcome: SearchOutcome, seconds: float, incumbent: tuple[Action, ...] | None
) -> NoReturn:
    if outcome.limit:
        found = (
            f"; a plan of {len(incumbent)} actions was found but not proved shortest"
            if incumbent is not None
            else " with no plan yet"
        )
        raise LimitReachedError(
            f"{outcome.limit} reached after expanding {outcome.expanded} states "
            f"({outcome.generated} generated, {seconds:.2f} s){found}"
            + (f"; every plan needs at least {outcome.bound} actions" if outcome.bound else "")
        )
    raise NoPlanError(
        f"no plan: search space exhausted after {outcome.expanded} states "
        "(every reachable arrangement tried)"
    )
