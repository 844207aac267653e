"""A first plan shortened by dropping the moves it can do without
(:func:`demoplan.planning.greedy.shorten`), checked by the STRIPS rules."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.budget import Budget, Clock
from demoplan.planning.bounds import LowerBounds
from demoplan.planning.compiled import compile_problem
from demoplan.planning.greedy import greedy_moves, shorten, valid_moves
from demoplan.planning.problem import Problem
from demoplan.planning.strips import validate
from tests.support.planning_families import PARKING_FAMILIES, parking_problem


def _swap_with_a_free_goal() -> Problem:
    """``a`` stands on ``b``'s goal; ``a``'s own goal is free from the start."""
    return Problem.create(
        objects=["a", "b"],
        locations=["a_goal", "b_goal", "b_start", "park"],
        grasps=["g"],
        allowed=[("a", "g"), ("b", "g")],
        collisions=[],
        initial=[("a", "b_goal"), ("b", "b_start")],
        goal=[("a", "a_goal"), ("b", "b_goal")],
        freespace=["park"],
    )


def test_a_parking_is_skipped_when_the_parked_object_s_goal_is_free() -> None:
    problem = _swap_with_a_free_goal()
    c = compile_problem(problem)
    at = {name: i for i, name in enumerate(c.locations)}
    a, b = c.objects.index("a"), c.objects.index("b")
    parked = [  # a must leave b's goal first, so waiting in its place is no plan
        (a, at["b_goal"], at["park"], c.grasps_of[a][0]),
        (b, at["b_start"], at["b_goal"], c.grasps_of[b][0]),
        (a, at["park"], at["a_goal"], c.grasps_of[a][0]),
    ]
    assert valid_moves(c, parked)
    straight = shorten(c, parked)
    assert [(c.objects[o], c.locations[t]) for o, _, t, _ in straight] == [
        ("a", "a_goal"),
        ("b", "b_goal"),
    ]


@settings(max_examples=25, deadline=None)
@given(
    family=st.sampled_from(sorted(PARKING_FAMILIES)),
    n_objects=st.integers(6, 20),
    seed=st.integers(0, 10_000),
)
def test_a_shortened_plan_is_valid_no_longer_and_has_no_move_left_to_drop(
    family: str, n_objects: int, seed: int
) -> None:
    problem = parking_problem(n_objects, seed, **PARKING_FAMILIES[family])
    c = compile_problem(problem)
    first = greedy_moves(c, LowerBounds(c), Clock(Budget(timeout=60.0)))  # a hang guard
    if first is None:
        return
    shorter = shorten(c, first)
    assert len(shorter) <= len(first)
    actions = [action for move in shorter for action in c.move_actions(*move)]
    validate(problem, actions)  # raises InvalidPlanError naming the first bad action
    assert shorten(c, shorter) == shorter
