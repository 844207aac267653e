"""Solving a problem part by part, where its objects fall into groups that
never meet: a proof of optimality that A* over the whole problem cannot
afford, because the plateaus of independent groups multiply.

Groups (:func:`object_groups`): two objects belong together when a location
one of them starts on, must end on or must visit is the same as, blocks, is
blocked by or overlaps one of the other's, or when a precedence links their
subgoals.

- **A lower bound** (:func:`parts_bound`): each group alone — the problem
  with the other objects taken away — is a relaxation of the whole. Taking
  an object away only removes what could block a move (no supports: a
  problem that stacks is not split), and drops precedences to it, which
  only allows more. A plan for the whole, restricted to a group's objects,
  is a plan for that group alone, and every move moves one object, so the
  shortest plans of the groups add up to a lower bound of the whole.
- **A plan** (:func:`solve_by_parts`): the groups one after another in the
  whole problem, each solved with the other objects standing still and the
  goal places of the groups still to come reserved for their owners; the
  concatenation is checked by the plain rules (:mod:`~demoplan.planning.strips`).

When the plan is as long as the bound, it is shortest.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence

from demoplan.errors import LimitReachedError, NoPlanError
from demoplan.planning.budget import Clock
from demoplan.planning.compiled import Compiled
from demoplan.planning.problem import Action, Plan, Problem

__all__ = [
    "PartsResult",
    "SolvePart",
    "needs_moves",
    "object_groups",
    "parts_plan",
    "solve_by_parts",
]

SolvePart = Callable[[Problem, Clock], Plan]
"""How a part is solved: a plan within the clock, or NoPlanError (none
exists) / LimitReachedError (none found in time) — the planner's own
:func:`~demoplan.planning.search.solve_part`, passed in by the caller."""

_NO_PLAN_FOR_PART = (NoPlanError, LimitReachedError)
"""What :data:`SolvePart` raises for a part without a plan: then no plan, or
no bound, comes from that part."""


@dataclasses.dataclass(frozen=True, slots=True)
class PartsResult:
    """A plan for the whole problem made group by group (None: none found in
    time, or its check failed), and the proven lower bound (actions) the
    groups give, or 0."""

    actions: tuple[Action, ...] | None
    bound: int


def object_groups(problem: Problem, c: Compiled, clock: Clock | None = None) -> list[list[str]]:
    """The objects in groups that never meet (see the module docstring), in
    the problem's order; one group when the problem stacks (supports), or
    when ``clock``'s time is up before the pairs are weighed (nothing split)."""
    if problem.supports:
        return [list(problem.objects)]
    index = {name: k for k, name in enumerate(c.locations)}
    relevant: dict[int, set[int]] = {}
    for obj, start in enumerate(c.start):
        places = {start}
        if c.goal[obj] >= 0:
            places.add(c.goal[obj])
        places |= {c.subgoal_location[s] for s in c.subgoals_of[obj]}
        relevant[obj] = places
    touching: dict[int, int] = {}  # location → mask of locations it meets
    for la, lb, _ in problem.collisions:
        a, b = index[la], index[lb]
        touching[a] = touching.get(a, 0) | 1 << b
        touching[b] = touching.get(b, 0) | 1 << a
    for la, lb in problem.exclusions:
        a, b = index[la], index[lb]
        touching[a] = touching.get(a, 0) | 1 << b
        touching[b] = touching.get(b, 0) | 1 << a
    parent = list(range(len(c.objects)))

    def find(x: int) -> int:
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    own = {obj: sum(1 << p for p in places) for obj, places in relevant.items()}
    masks = dict(own)
    for obj, places in relevant.items():
        for place in places:
            masks[obj] |= touching.get(place, 0)
    for a in range(len(c.objects)):
        if clock is not None and not a % 64 and clock.expired():
            return [list(problem.objects)]
        for b in range(a + 1, len(c.objects)):
            if masks[a] & own[b] or masks[b] & own[a]:
                parent[find(a)] = find(b)
    owner = {s.id: c.objects.index(s.object) for s in problem.subgoals}
    for before, after in problem.precedences:
        parent[find(owner[before])] = find(owner[after])
    groups: dict[int, list[str]] = {}
    for obj, name in enumerate(c.objects):
        groups.setdefault(find(obj), []).append(name)
    return list(groups.values())


def needs_moves(c: Compiled, group: Sequence[str]) -> bool:
    """Whether some object of ``group`` is off its goal or has a subgoal to reach."""
    return _movers(c, group) > 0


def _movers(c: Compiled, group: Sequence[str]) -> int:
    """How many objects of ``group`` are off their goals or have a subgoal to reach."""
    return sum(c.must_move(c.objects.index(name)) for name in group)


def solve_by_parts(
    problem: Problem,
    groups: Sequence[Sequence[str]],
    clock: Clock,
    c: Compiled,
    solve_part: SolvePart,
) -> PartsResult:
    """A plan group by group and the bound of the groups alone (module
    docstring), within ``clock`` (its limits of expansions and states hold in
    each part's searches), each part solved by ``solve_part``: each
    group's two searches share the time left in proportion to the objects it
    must move (a group with none gets no time of its own: its plan is empty),
    so the groups solved quickly leave their time to the others."""
    # Here, not at the top: only a problem in parts needs the plain rules, and
    # `demoplan solve` starts faster without them.
    from demoplan.planning.strips import InvalidPlanError, validate

    weights = [_movers(c, group) for group in groups]
    bound = 0
    bound_proved = True
    state = dict(problem.initial)
    owners: dict[str, set[str]] = {}
    for obj, location in problem.goal:
        owners.setdefault(obj, set()).add(location)
    for subgoal in problem.subgoals:
        owners.setdefault(subgoal.object, set()).add(subgoal.location)
    actions: list[Action] = []
    planned = True
    for k, group in enumerate(groups):
        if clock.expired():  # out of time: no plan and no bound from the parts
            return PartsResult(None, 0)
        share = weights[k] / (2 * max(1, sum(weights[k:])))  # of the time left, per search
        alone = _alone(problem, group)
        try:
            relaxed = solve_part(alone, clock.part(share))
        except _NO_PLAN_FOR_PART:  # no plan for a part, or out of time: no bound from it
            bound_proved = False
        else:
            bound += len(relaxed) if relaxed.optimal else relaxed.bound
        if not planned:
            continue
        later = [o for g in groups[k + 1 :] for o in g]
        try:
            part = solve_part(_in_turn(problem, group, state, later, owners), clock.part(share))
        except _NO_PLAN_FOR_PART:  # the part has no plan with the others standing still
            planned = False
            continue
        actions += part.actions
        for action in part.actions:
            if action.kind == "PUT_DOWN":
                state[action.object] = action.location
    if not planned:
        return PartsResult(None, bound if bound_proved else 0)
    try:
        validate(problem, actions)
    except InvalidPlanError:
        return PartsResult(None, bound if bound_proved else 0)
    return PartsResult(tuple(actions), bound if bound_proved else 0)


def parts_plan(result: PartsResult, seconds: float) -> Plan | None:
    """The plan of ``result`` as a :class:`Plan` (proved shortest when as long as
    the bound), or None."""
    if result.actions is None:
        return None
    optimal = len(result.actions) <= result.bound
    return Plan(
        result.actions,
        seconds=seconds,
        search="parts",
        optimal=optimal,
        bound=len(result.actions) if optimal else result.bound,
    )


def _alone(problem: Problem, group: Sequence[str]) -> Problem:
    """The problem with only ``group``'s objects (a relaxation of it)."""
    keep = set(group)
    return dataclasses.replace(
        _only_goals_of(problem, keep),
        objects=tuple(o for o in problem.objects if o in keep),
        initial=tuple(x for x in problem.initial if x[0] in keep),
        # A place that took only objects now gone takes any: a relaxation too.
        accepts=frozenset(a for a in problem.accepts if a[1] in keep),
    )


def _in_turn(
    problem: Problem,
    group: Sequence[str],
    state: dict[str, str],
    later: Sequence[str],
    owners: dict[str, set[str]],
) -> Problem:
    """``group``'s turn in the whole problem: every object where it stands now,
    only ``group``'s may move, only its goals count, and the places the
    ``later`` groups must reach take none of ``group``'s objects."""
    accepts = set(problem.accepts)
    for obj in later:
        accepts |= {(location, obj) for location in owners.get(obj, ())}
    return dataclasses.replace(
        _only_goals_of(problem, set(group)),
        initial=tuple((o, state[o]) for o in problem.objects),
        accepts=frozenset(accepts),
    )


def _only_goals_of(problem: Problem, keep: set[str]) -> Problem:
    """``problem`` where only the objects in ``keep`` may be grasped and only
    their goals, subgoals and the precedences among those count."""
    subgoals = tuple(s for s in problem.subgoals if s.object in keep)
    ids = {s.id for s in subgoals}
    return dataclasses.replace(
        problem,
        allowed=frozenset(a for a in problem.allowed if a[0] in keep),
        goal=tuple(x for x in problem.goal if x[0] in keep),
        subgoals=subgoals,
        precedences=frozenset(p for p in problem.precedences if p[0] in ids and p[1] in ids),
        reached=frozenset(r for r in problem.reached if r in ids),
    )
