"""Solving a planning problem (paper §IV.C): the searches, and why there is no plan.

Two searches, chosen by name from :data:`SEARCHES`:

- ``bfs`` — :func:`~demoplan.planning.bfs.breadth_first_search`, the paper's
  method and our reference;
- ``astar`` — the default: the *anytime* phases of :data:`PHASES` in turn,
  each with a share of the time left, ending with A* over moves
  (:class:`~demoplan.planning.astar.AStar`) with the admissible bounds of
  :mod:`demoplan.planning.bounds`.

Each phase is a function ``(compiled problem, bounds, clock, findings) ->
plan | None``: a plan ends the search (it is proved shortest, or the phase
is the last); None hands on to the next phase, with what the phase found —
a plan not yet proved shortest, a larger lower bound — in :class:`Findings`.
Every phase runs on its part of the one clock the search was given
(:meth:`~demoplan.budget.Clock.part`: a share of the time, every other limit
kept).

:func:`solve` turns the result into a :class:`~demoplan.planning.problem.Plan`
or raises NoPlanError (exit 3) / LimitReachedError (exit 4);
:func:`explain_unsolvable` finds the reasons that need no search.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import partial
from typing import NamedTuple, NoReturn

from demoplan.errors import LimitReachedError, NoPlanError
from demoplan.graphs import find_cycle
from demoplan.planning.astar import AStar, astar_search
from demoplan.planning.bfs import breadth_first_search
from demoplan.planning.bounds import DEAD_END, LowerBounds, Move
from demoplan.planning.budget import Budget, Clock, SearchOutcome
from demoplan.planning.compiled import Compiled, compile_problem
from demoplan.planning.greedy import greedy_moves
from demoplan.planning.parts import (
    PartsResult,
    needs_moves,
    object_groups,
    parts_plan,
    solve_by_parts,
)
from demoplan.planning.plateau import plateau_moves
from demoplan.planning.problem import Action, Plan, Problem
from demoplan.planning.tight import TightResult, searched_plan, tight_plan

__all__ = [
    "PHASES",
    "SEARCHES",
    "Budget",
    "Findings",
    "Phase",
    "SearchOutcome",
    "astar_search",
    "breadth_first_search",
    "explain_unsolvable",
    "plan_by_parts",
    "solve",
    "solve_part",
    "solve_within",
]


def explain_unsolvable(
    problem: Problem, compiled: Compiled | None = None, clock: Clock | None = None
) -> list[str]:
    """Reasons, where they can be shown without search, why no plan exists
    (``compiled``: the problem already compiled; ``clock``: read as it goes,
    LimitReachedError once the time is up — the pairs of goal places grow
    with the square of the objects)."""
    c = compiled or compile_problem(problem, clock)

    def check() -> None:
        if clock is not None:
            clock.check(
                f"looking for reasons there is no plan ({len(c.objects)} objects), "
                "before any search"
            )

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
    check()
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
    check()
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
        if not obj % 64:
            check()
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

    ``astar`` runs the phases of :data:`PHASES` in turn, sharing the budget:
    a tight plan (or its refutation), a greedy first plan, what the tight
    phase left open searched further, a dive for a plan
    as long as the bound, groups that never meet solved apart, weighted A*
    passes that shorten the plan, and A* over moves for the proof.

    A plan as long as a proven lower bound, or A* finding a plan or running
    out of states, proves the plan shortest; the budget ending first leaves
    it unproved, returned with ``optimal`` False and the lower bound reached.
    With ``optimal``, only a proved plan is returned (else LimitReachedError).
    ``bfs`` is the paper's exact search. NoPlanError (exit 3) says why there
    is no plan; LimitReachedError (exit 4) which limit stopped a search with
    no plan.
    """
    return solve_within(problem, search, Clock(budget), optimal=optimal)


def solve_within(problem: Problem, search: str, clock: Clock, *, optimal: bool = False) -> Plan:
    """:func:`solve` on a clock already running (a command's, or its share of
    one): the compilation and the checks for reasons without search count
    against it too."""
    return _solve(problem, search, clock, optimal, _MIN_GREEDY_SECONDS)


def solve_part(problem: Problem, clock: Clock) -> Plan:
    """:func:`solve` for a part of a bigger problem (:mod:`~demoplan.planning.parts`):
    the clock is kept to the letter — the first plan's search gets no more
    time than is left, since a part without a plan only means the parts give
    no plan."""
    return _solve(problem, "astar", clock, False, 0.0)


def plan_by_parts(
    problem: Problem, groups: Sequence[Sequence[str]], clock: Clock, c: Compiled
) -> PartsResult:
    """:func:`~demoplan.planning.parts.solve_by_parts` with each part solved
    by this planner (:func:`solve_part`)."""
    return solve_by_parts(problem, groups, clock, c, solve_part)


@dataclass(frozen=True, slots=True)
class _Request:
    """What the caller of :func:`solve` asked for, besides the problem."""

    clock: Clock
    optimal: bool  # only a plan proved shortest will do
    first_plan: Clock  # the clock, with at least the first plan's minimum from the start


def _solve(
    problem: Problem, search: str, clock: Clock, optimal: bool, first_plan_seconds: float
) -> Plan:
    """:func:`solve`, where the work up to the first plan (compiling, the reasons
    without search, the first plan's search) gets at least ``first_plan_seconds``."""
    if search not in SEARCHES:
        raise ValueError(f"unknown search {search!r}; one of {sorted(SEARCHES)}")
    first_plan = clock.at_least(first_plan_seconds)
    c = compile_problem(problem, first_plan)  # once, for every phase
    reasons = explain_unsolvable(problem, c, first_plan)
    if reasons:
        raise NoPlanError("no plan: " + "; ".join(reasons))
    started = time.perf_counter()
    return SEARCHES[search](problem, c, _Request(clock, optimal, first_plan), started)


def _breadth_first(problem: Problem, c: Compiled, request: _Request, started: float) -> Plan:
    """``--search bfs``: the paper's exact search, over primitive actions."""
    outcome = breadth_first_search(problem, request.clock, c)
    seconds = time.perf_counter() - started
    if outcome.actions is not None:
        return _plan(outcome.actions, outcome, seconds, "bfs")
    _raise_without_plan(outcome, seconds, None)


@dataclass(slots=True)
class Findings:
    """What the phases so far have established, handed from one to the next."""

    problem: Problem
    request: _Request
    started: float  # time.perf_counter() when the search started
    bound: int  # a proven lower bound, in actions: no plan is shorter
    plan: tuple[Action, ...] | None = None  # the best plan found so far
    found_by: str = ""  # the phase that found it
    tight: TightResult | None = None  # what the tight phase found, where it ran

    def elapsed(self) -> float:
        """Seconds since the search started."""
        return time.perf_counter() - self.started

    def offer(self, actions: tuple[Action, ...], found_by: str) -> None:
        """Keep ``actions`` if it is the first plan or shorter than the best."""
        if self.plan is None or len(actions) < len(self.plan):
            self.plan, self.found_by = actions, found_by

    def proved(self) -> Plan | None:
        """The best plan, if it is as long as the bound (so shortest)."""
        if self.plan is None or len(self.plan) > self.bound:
            return None
        return Plan(self.plan, seconds=self.elapsed(), search=self.found_by, bound=self.bound)

    def shortest(self, moves: list[Move], c: Compiled, search: str) -> Plan:
        """``moves``, as long as the bound: a plan proved shortest."""
        return Plan(_actions(c, moves), seconds=self.elapsed(), search=search, bound=self.bound)


Phase = Callable[[Compiled, LowerBounds, Clock, "Findings"], Plan | None]
"""One phase of the anytime search: given the compiled problem, its bounds,
its part of the search's clock and what the phases before it found, a plan
that ends the search, or None (what it found is in the :class:`Findings`)."""


def _actions(c: Compiled, moves: list[Move]) -> tuple[Action, ...]:
    return tuple(action for move in moves for action in c.move_actions(*move))


def tight_phase(c: Compiled, bounds: LowerBounds, clock: Clock, findings: Findings) -> Plan | None:
    """A plan as long as the feedback bound, from an order of the moves of its
    rigid shape — shortest at once — or the proof that there is none, which
    raises the bound by a move (:func:`~demoplan.planning.tight.tight_plan`)."""
    tight = tight_plan(bounds, c.start, c.start_reached, clock)
    findings.tight = tight
    if tight.moves is not None:
        return findings.shortest(tight.moves, c, "tight")
    if tight.refuted:
        findings.bound += 2
    return None


def orders_phase(c: Compiled, bounds: LowerBounds, clock: Clock, findings: Findings) -> Plan | None:
    """Once there is a first plan, what the tight phase left open, with more
    work (:func:`~demoplan.planning.tight.searched_plan`): after a refutation,
    a plan one move longer; where an order of the moves existed but its fixed
    play-out did not, a search over the orders. Either is as long as the
    bound, so shortest."""
    tight = findings.tight
    if tight is None or not (tight.refuted or tight.ordered):
        return None
    moves = searched_plan(bounds, c.start, c.start_reached, clock, tight.refuted)
    return None if moves is None else findings.shortest(moves, c, "tight")


def greedy_phase(c: Compiled, bounds: LowerBounds, clock: Clock, findings: Findings) -> Plan | None:
    """A first plan fast, by greedy best-first search on the guidance
    (:func:`~demoplan.planning.greedy.greedy_moves`): it may take all the time
    left, and never less than what the request's ``first_plan`` clock leaves (an
    easy problem must not go without a plan for want of a few milliseconds)."""
    least = findings.request.first_plan.remaining()
    if least is not None and not math.isinf(least):  # no deadline: the phase's share
        clock = clock.at_least(least)
    moves = greedy_moves(c, bounds, clock)
    if moves is not None:
        findings.offer(_actions(c, moves), "greedy")
    return None


def dive_phase(c: Compiled, bounds: LowerBounds, clock: Clock, findings: Findings) -> Plan | None:
    """A plan as long as the root bound, so shortest, by a depth-first dive
    (:func:`~demoplan.planning.plateau.plateau_moves`; finding none proves nothing)."""
    found = plateau_moves(c, bounds, clock, findings.bound // 2)
    return None if found is None else findings.shortest(found, c, "plateau")


def parts_phase(c: Compiled, bounds: LowerBounds, clock: Clock, findings: Findings) -> Plan | None:
    """Where the objects fall into two or more groups that never meet and need
    moves, the groups solved one by one (:mod:`~demoplan.planning.parts`): a
    plan, and a lower bound that adds up."""
    problem = findings.problem
    groups = object_groups(problem, c, clock)
    if sum(needs_moves(c, g) for g in groups) <= 1:
        return None
    parts = plan_by_parts(problem, groups, clock, c)
    by_parts = parts_plan(parts, findings.elapsed())
    if by_parts is not None and by_parts.optimal:
        return by_parts
    findings.bound = max(findings.bound, parts.bound)
    if parts.actions is not None:
        findings.offer(parts.actions, "parts")
    return None


def improve_phase(
    c: Compiled, bounds: LowerBounds, clock: Clock, findings: Findings, *, weight: float
) -> Plan | None:
    """A shorter plan by weighted A* on the greedy guidance with ``weight``
    (LAMA's way of improving its first plan), where there is a plan not yet
    proved shortest."""
    if findings.plan is None or len(findings.plan) <= findings.bound:
        return None
    upper = len(findings.plan) // 2
    better = greedy_moves(c, bounds, clock, weight=weight, upper=upper)
    if better is not None:
        findings.offer(_actions(c, better), "greedy")
    return None


def astar_phase(c: Compiled, bounds: LowerBounds, clock: Clock, findings: Findings) -> Plan:
    """A* over moves (:class:`~demoplan.planning.astar.AStar`) with the rest of
    the budget, dropping every state whose bound reaches the best plan's
    length: a plan it finds is shortest, and so is the best plan when it runs
    out of states. Otherwise the best plan unproved (not with ``optimal``), or
    LimitReachedError / NoPlanError."""
    incumbent = findings.plan
    if incumbent is None:  # no plan yet: whether there is one at all (exit 3 or 4)
        clock = clock.at_least(_MIN_PROOF_SECONDS)
    outcome = AStar(c, bounds, clock).run(None if incumbent is None else len(incumbent) // 2)
    seconds = findings.elapsed()
    name = "astar" if incumbent is None else f"{findings.found_by}+astar"
    if outcome.actions is not None:
        return _plan(outcome.actions, outcome, seconds, name)
    if incumbent is not None:
        if outcome.exhausted:  # nothing shorter exists
            return _plan(incumbent, outcome, seconds, name)
        if not findings.request.optimal:
            bound = max(outcome.bound, findings.bound)
            return _plan(incumbent, outcome, seconds, name, optimal=False, bound=bound)
    _raise_without_plan(outcome, seconds, incumbent)


class PhaseRow(NamedTuple):
    """A row of :data:`PHASES`."""

    name: str
    run: Phase
    share: float | None  # of the time left when it starts; None: the whole budget left
    bounded: bool = False
    """Its own work is bounded (a count of choices and nodes): without a
    deadline it runs to its end rather than for a share of
    :data:`_UNBOUNDED_SECONDS`, so that its outcome does not hang on the
    machine's speed."""


_WEIGHTS = (3.0, 2.0, 1.5)
"""Weights of the weighted-A* passes that shorten the first plan."""
_IMPROVE_SHARE = 0.2
"""Each pass may take this share of the time left."""


PHASES: list[PhaseRow] = [
    PhaseRow("tight", tight_phase, 0.25, bounded=True),
    PhaseRow("greedy", greedy_phase, 1.0),
    PhaseRow("orders", orders_phase, 0.3, bounded=True),
    PhaseRow("plateau", dive_phase, 0.3),
    PhaseRow("parts", parts_phase, 0.4),
    *(
        PhaseRow(f"improve w={weight:g}", partial(improve_phase, weight=weight), _IMPROVE_SHARE)
        for weight in _WEIGHTS
    ),
    PhaseRow("astar", astar_phase, None),
]
"""The phases of ``--search astar``, in order: name, function, share of the
time left when the phase starts (None: A*, which has the rest of the budget
with its limits of expansions and states). After each phase, a best plan as
long as the bound is returned, proved shortest. docs/planning.md describes
them."""


def _anytime(problem: Problem, c: Compiled, request: _Request, started: float) -> Plan:
    """``--search astar``: the :data:`PHASES` in turn, until one gives the plan."""
    bounds = LowerBounds(c)
    clock = request.clock
    root = 2 * bounds.estimate(c.start, c.start_reached)
    if root >= 2 * DEAD_END:  # A* proves it: no state to expand
        outcome = AStar(c, bounds, clock).run()
        _raise_without_plan(outcome, time.perf_counter() - started, None)
    findings = Findings(problem, request, started, root)
    for phase in PHASES:
        plan = phase.run(c, bounds, _phase_clock(clock, phase), findings)
        if plan is None:  # what the phase found may prove the best plan shortest
            plan = findings.proved()
        if plan is not None:
            return plan
    raise AssertionError("the last phase (A*) always answers")


SEARCHES: dict[str, Callable[[Problem, Compiled, _Request, float], Plan]] = {
    "astar": _anytime,
    "bfs": _breadth_first,
}
"""What runs for each ``--search``: the anytime :data:`PHASES`, or the paper's
breadth-first search."""


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


_MIN_GREEDY_SECONDS = 0.2
"""The work up to the first plan (compiling the problem, the reasons without
search, the first plan's search) gets at least this long from the start of
:func:`solve`, even where the budget is spent before it starts (a slow
start-up on a loaded machine): an easy problem must not go without a plan for
want of a few milliseconds."""


_MIN_PROOF_SECONDS = 0.2
"""A* (the last phase, the one that proves there is no plan) gets at least
this long when no phase before it found a plan, even where the budget is
spent before it starts: a goal proved unreachable in a few states is
reported so (exit 3), not as out of time."""


def _phase_clock(clock: Clock, phase: PhaseRow) -> Clock:
    """The clock of ``phase``: its share of the time left on ``clock``, every
    other limit kept (no share: ``clock`` itself); with no deadline (none, or
    ``--timeout inf``) a share of :data:`_UNBOUNDED_SECONDS`, so that an early
    phase cannot take forever before the exact search — none for a phase whose
    work is bounded."""
    if phase.share is None:
        return clock
    return clock.part(phase.share, None if phase.bounded else _UNBOUNDED_SECONDS)


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
