"""The dive for a plan as long as the start's bound (planning/plateau.py)."""

from __future__ import annotations

from hypothesis import HealthCheck, given, settings

from demoplan.planning.bfs import breadth_first_search
from demoplan.planning.bounds import LowerBounds
from demoplan.planning.budget import Budget, Clock
from demoplan.planning.compiled import compile_problem
from demoplan.planning.plateau import plateau_moves
from demoplan.planning.problem import Problem
from demoplan.planning.strips import validate
from tests.planning.test_search import small_problems


@given(small_problems())
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
def test_a_plan_the_dive_finds_is_valid_and_shortest(problem: Problem) -> None:
    c = compile_problem(problem)
    bounds = LowerBounds(c)
    root = bounds.estimate(c.start, c.start_reached)
    moves = plateau_moves(c, bounds, Clock(Budget(timeout=5)), root)
    if moves is None:
        return
    reference = breadth_first_search(problem)
    assert reference.actions is not None
    validate(problem, [a for move in moves for a in c.move_actions(*move)])
    assert 2 * len(moves) == len(reference.actions)


def test_the_dive_stops_at_its_state_limit(hard_parking: Problem) -> None:
    # A crowded draw the dive cannot finish (tests/data/hard-parking.xml):
    # it gives up at the states it may keep.
    c = compile_problem(hard_parking)
    bounds = LowerBounds(c)
    root = bounds.estimate(c.start, c.start_reached)
    entered = []
    estimate = bounds.estimate

    def counted(positions: tuple[int, ...], reached: int) -> int:
        entered.append(positions)
        return estimate(positions, reached)

    bounds.estimate = counted  # type: ignore[method-assign]
    assert plateau_moves(c, bounds, Clock(Budget(max_states=200)), root) is None
    assert 0 < len(entered) <= 200  # each state entered is bounded once
