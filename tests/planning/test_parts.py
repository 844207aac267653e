"""Solving group by group (demoplan.planning.parts): the groups' bound never
exceeds the shortest plan (BFS), a plan proved by parts is as long as BFS's,
and a table of independent swaps is proved without searching the whole."""

from __future__ import annotations

import dataclasses

import pytest
from hypothesis import HealthCheck, assume, given, settings

from demoplan.errors import NoPlanError
from demoplan.planning.bfs import breadth_first_search
from demoplan.planning.budget import Budget, Clock
from demoplan.planning.compiled import compile_problem
from demoplan.planning.parts import object_groups
from demoplan.planning.problem import Problem, Subgoal
from demoplan.planning.search import explain_unsolvable, plan_by_parts, solve
from demoplan.planning.strips import validate
from tests.planning.test_search import small_problems


def renamed(problem: Problem, tag: str) -> Problem:
    """The same problem with every name tagged (two of them never meet)."""

    def n(name: str) -> str:
        return f"{name}{tag}"

    return Problem.create(
        objects=[n(o) for o in problem.objects],
        locations=[n(loc) for loc in problem.locations],
        grasps=[n(g) for g in problem.grasps],
        allowed=[(n(o), n(g)) for o, g in problem.allowed],
        collisions=[(n(a), n(b), n(g)) for a, b, g in problem.collisions],
        initial=[(n(o), n(loc)) for o, loc in problem.initial],
        goal=[(n(o), n(loc)) for o, loc in problem.goal],
        freespace=[n(loc) for loc in problem.freespace],
        exclusions=[(n(a), n(b)) for a, b in problem.exclusions],
        accepts=[(n(loc), n(o)) for loc, o in problem.accepts],
        subgoals=[Subgoal(n(s.id), n(s.object), n(s.location)) for s in problem.subgoals],
        precedences=[(n(a), n(b)) for a, b in problem.precedences],
    )


def together(a: Problem, b: Problem) -> Problem:
    return Problem.create(
        objects=[*a.objects, *b.objects],
        locations=[*a.locations, *b.locations],
        grasps=[*a.grasps, *b.grasps],
        allowed=[*a.allowed, *b.allowed],
        collisions=[*a.collisions, *b.collisions],
        initial=[*a.initial, *b.initial],
        goal=[*a.goal, *b.goal],
        freespace=[*a.freespace, *b.freespace],
        exclusions=[*a.exclusions, *b.exclusions],
        accepts=[*a.accepts, *b.accepts],
        subgoals=[*a.subgoals, *b.subgoals],
        precedences=[*a.precedences, *b.precedences],
    )


def unstacked(problem: Problem) -> Problem:
    return dataclasses.replace(problem, supports=frozenset())


@given(small_problems(), small_problems())
@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
def test_two_problems_that_never_meet_are_solved_as_parts(first: Problem, second: Problem) -> None:
    """Two random small problems side by side: two groups (or more); the parts'
    bound is at most BFS's length, and solve's plan is as long as BFS's, valid,
    and proved shortest whenever parts claim it."""
    a, b = renamed(unstacked(first), "a"), renamed(unstacked(second), "b")
    whole = together(a, b)
    assume(len(whole.objects) <= 4)
    reference = breadth_first_search(whole, Clock(Budget(max_nodes=200_000)))
    assume(reference.actions is not None or reference.exhausted)
    groups = object_groups(whole, compile_problem(whole))
    assert sorted(o for g in groups for o in g) == sorted(whole.objects)
    assert len(groups) >= 2 and all(len({o[-1] for o in g}) == 1 for g in groups)
    parts = plan_by_parts(whole, groups, Clock(Budget(timeout=5.0)), compile_problem(whole))
    if reference.actions is None:  # no plan at all: the parts find none either
        assert parts.actions is None
        return
    assert parts.bound <= len(reference.actions)
    if parts.actions is not None:
        validate(whole, parts.actions)
        assert len(parts.actions) >= len(reference.actions)
    if explain_unsolvable(whole):  # refused without search (a start that breaks an
        # exclusion, whose goal BFS finds already holding): solve says why, exit 3
        with pytest.raises(NoPlanError):
            solve(whole, budget=Budget())
        return
    plan = solve(whole, budget=Budget())  # the proof must not race the clock
    validate(whole, plan.actions)
    assert plan.optimal and len(plan) == len(reference.actions)


def swapped_pairs(pairs: int) -> Problem:
    """``pairs`` pairs of objects far apart, each on the other's goal spot with a
    spare spot of its own; grasping at one spot of a pair is blocked by an
    object on the other."""
    objects, locations, initial, goal, allowed = [], [], [], [], []
    for k in range(pairs):
        a, b = f"a{k}", f"b{k}"
        objects += [a, b]
        locations += [f"p{k}", f"q{k}", f"s{k}"]
        initial += [(a, f"p{k}"), (b, f"q{k}")]
        goal += [(a, f"q{k}"), (b, f"p{k}")]
        allowed += [(a, "g"), (b, "g")]
    return Problem.create(
        objects=objects,
        locations=locations,
        grasps=["g"],
        allowed=allowed,
        initial=initial,
        goal=goal,
        collisions=[(f"p{k}", f"q{k}", "g") for k in range(pairs)],
    )


def test_independent_swaps_are_proved_part_by_part() -> None:
    """Six such pairs: six groups, each needing what BFS finds for one pair
    alone (it must park one object on another pair's spare spot: its own
    three spots deadlock);
    proved shortest by the parts without a search of the whole (whose state
    space is the product of the pairs')."""
    problem = swapped_pairs(6)
    keep = {"a0", "b0"}  # one pair, with every spot of the table to park on
    pair = dataclasses.replace(
        problem,
        objects=("a0", "b0"),
        allowed=frozenset(x for x in problem.allowed if x[0] in keep),
        initial=tuple(x for x in problem.initial if x[0] in keep),
        goal=tuple(x for x in problem.goal if x[0] in keep),
    )
    one = breadth_first_search(pair).actions
    assert one is not None
    assert len(object_groups(problem, compile_problem(problem))) == 6
    plan = solve(problem, budget=Budget())  # the proof must not race the clock
    validate(problem, plan.actions)
    assert plan.optimal and plan.search == "parts" and len(plan) == 6 * len(one)
