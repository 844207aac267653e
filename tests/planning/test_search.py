"""The planner: the paper's example, and A* against breadth-first search."""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from demoplan.errors import LimitReachedError, NoPlanError
from demoplan.planning.bounds import LowerBounds
from demoplan.planning.compiled import compile_problem
from demoplan.planning.problem import Problem, Subgoal
from demoplan.planning.search import (
    Budget,
    astar_search,
    breadth_first_search,
    solve,
)
from demoplan.planning.strips import InvalidPlanError, validate
from demoplan.planning.xml import load_problem
from tests.support.helpers import EXAMPLES
from tests.support.planning_families import (
    CROWDED_FAMILIES,
    blocks_problem,
    parking_problem,
    table_problem,
)

PAPER_PLAN = [
    "GRASP box loc264 grasp6",
    "PUT_DOWN box freespace1 grasp6",
    "GRASP food loc15 grasp2",
    "PUT_DOWN food loc264 grasp2",
    "GRASP fork loc10 grasp1",
    "PUT_DOWN fork loc35 grasp1",
    "GRASP cup loc22 grasp4",
    "PUT_DOWN cup loc293 grasp4",
]


def three_objects() -> Problem:
    """A toy task without file parsing: swap a and b through free space; c blocks a's grasp."""
    return Problem.create(
        objects=["a", "b", "c"],
        locations=["l1", "l2", "l3", "free1", "free2"],
        grasps=["g1", "g2"],
        allowed=[("a", "g1"), ("b", "g1"), ("b", "g2"), ("c", "g2")],
        collisions=[("l1", "l3", "g1")],
        initial=[("a", "l1"), ("b", "l2"), ("c", "l3")],
        goal=[("a", "l2"), ("b", "l1")],
        freespace=["free1", "free2"],
    )


@pytest.mark.parametrize("search", ["astar", "bfs"])
def test_the_papers_example_gives_an_eight_action_plan(search: str) -> None:
    problem = load_problem(EXAMPLES / "planning" / "paper-example.xml")
    plan = solve(problem, search)
    assert len(plan) == 8
    validate(problem, plan.actions)
    if search == "bfs":  # the paper's own method finds the paper's plan
        assert [str(a) for a in plan.actions] == PAPER_PLAN


def test_toy_problem_needs_the_blocker_and_a_detour() -> None:
    problem = three_objects()
    plan = solve(problem)
    validate(problem, plan.actions)
    # c must leave l3 (it blocks a's only grasp), a and b swap through free space.
    assert len(plan) == 2 * 4
    assert len(solve(problem, "bfs")) == len(plan)


def test_the_validator_rejects_a_plan_that_breaks_a_collision() -> None:
    problem = three_objects()
    plan = solve(problem).actions
    without_c = [a for a in plan if a.object != "c"]  # a is grasped while c blocks it
    with pytest.raises(InvalidPlanError, match="c at l3 is in the way"):
        validate(problem, without_c)


def test_interchangeable_free_space_is_used_but_not_searched_twice() -> None:
    problem = table_problem(7, 3, n_freespace=6)
    few = table_problem(7, 3, n_freespace=3)
    plan = solve(problem)
    validate(problem, plan.actions)
    assert len(plan) <= len(solve(few))


def test_limits_stop_the_search_with_exit_code_4() -> None:
    problem = table_problem(7, 2)  # one object must be parked: a few states are expanded
    outcome = astar_search(problem, Budget(max_nodes=2))
    assert outcome.actions is None and outcome.limit == "--max-nodes 2"
    with pytest.raises(LimitReachedError, match="max-nodes 2") as caught:
        solve(problem, "bfs", budget=Budget(max_nodes=2))
    assert caught.value.exit_code == 4
    assert "at least" in str(caught.value)


def test_an_unproved_plan_comes_with_its_bound_or_exit_4_when_proof_is_demanded() -> None:
    # a crowded grid with stacked caps (the tight phase finds no plan): a plan of 82
    # actions, a bound of 72, no proof in 50 nodes
    problem = parking_problem(20, 2, **CROWDED_FAMILIES["crowded-stacks"])
    # The first plan (greedy, 0.6 s here) gets most of the 6 s: room for a loaded
    # machine; the proof is refused by the node limit, not the clock.
    plan = solve(problem, budget=Budget(max_nodes=50, timeout=6))
    validate(problem, plan.actions)
    assert not plan.optimal and plan.bound < len(plan)
    assert plan.bound >= 2 * LowerBounds(compile_problem(problem)).estimate(
        *(compile_problem(problem).start, 0)
    )
    with pytest.raises(LimitReachedError, match="not proved shortest"):
        solve(problem, budget=Budget(max_nodes=50, timeout=6), optimal=True)


def test_an_object_that_must_move_without_a_grasp_is_the_reason() -> None:
    problem = Problem.create(
        objects=["a"],
        locations=["l1", "l2"],
        grasps=["g"],
        allowed=[],
        initial=[("a", "l1")],
        goal=[("a", "l2")],
    )
    with pytest.raises(NoPlanError, match="a must move but allows no grasp") as caught:
        solve(problem)
    assert caught.value.exit_code == 3


def test_objects_that_block_each_other_for_good_are_the_reason() -> None:
    # b's only grasp at l2 is blocked by a at l1; a can never move (no grasp) -> no plan.
    problem = Problem.create(
        objects=["a", "b"],
        locations=["l1", "l2", "l3"],
        grasps=["g"],
        allowed=[("b", "g")],
        collisions=[("l2", "l1", "g")],
        initial=[("a", "l1"), ("b", "l2")],
        goal=[("b", "l3")],
    )
    with pytest.raises(NoPlanError, match="b must move but can never be grasped"):
        solve(problem)
    assert breadth_first_search(problem).exhausted


def test_an_exhausted_search_says_how_many_states_it_tried() -> None:
    # Swap two objects with nowhere to park one of them.
    problem = Problem.create(
        objects=["a", "b"],
        locations=["l1", "l2"],
        grasps=["g"],
        allowed=[("a", "g"), ("b", "g")],
        initial=[("a", "l1"), ("b", "l2")],
        goal=[("a", "l2"), ("b", "l1")],
    )
    with pytest.raises(NoPlanError, match="exhausted after"):
        solve(problem)
    assert breadth_first_search(problem).exhausted


@st.composite
def small_problems(draw: st.DrawFn) -> Problem:
    """Random small problems with every kind of fact, for checking A* against BFS."""
    n_objects = draw(st.integers(1, 3))
    n_locations = draw(st.integers(n_objects + 1, n_objects + 3))
    objects = [f"o{i}" for i in range(n_objects)]
    locations = [f"l{i}" for i in range(n_locations)]
    grasps = ["g1", "g2"]
    allowed = [(o, g) for o in objects for g in grasps if draw(st.booleans()) or g == "g1"]
    starts = draw(st.permutations(locations))[:n_objects]
    goals = draw(st.permutations(locations))[:n_objects]
    goal = [(o, g) for o, g in zip(objects, goals, strict=True) if draw(st.booleans())]
    pairs = [(a, b) for a in locations for b in locations if a != b]
    collisions = draw(
        st.lists(st.tuples(st.sampled_from(pairs), st.sampled_from(grasps)), max_size=6)
    )
    supports = draw(st.lists(st.sampled_from(pairs), max_size=1))
    exclusions = draw(st.lists(st.sampled_from(pairs), max_size=1))
    mentioned = {x for (a, b), _ in collisions for x in (a, b)} | {
        x for pair in supports + exclusions for x in pair
    }
    freespace = [loc for loc in locations if loc not in mentioned and draw(st.booleans())]
    subgoals: list[Subgoal] = []
    precedences: list[tuple[str, str]] = []
    if draw(st.booleans()):
        for k in range(draw(st.integers(1, 3))):
            subgoals.append(
                Subgoal(f"S{k}", draw(st.sampled_from(objects)), draw(st.sampled_from(locations)))
            )
        for later in range(1, len(subgoals)):  # acyclic: earlier before later
            for earlier in range(later):
                if draw(st.booleans()):
                    precedences.append((f"S{earlier}", f"S{later}"))
    accepts: list[tuple[str, str]] = []
    if draw(st.booleans()):  # a location that takes only some objects
        place = draw(st.sampled_from(locations))
        needed = {o for o, loc in zip(objects, starts, strict=True) if loc == place}
        needed |= {o for o, loc in goal if loc == place}
        needed |= {s.object for s in subgoals if s.location == place}
        others = [o for o in objects if o not in needed]
        if others:
            needed |= set(draw(st.lists(st.sampled_from(others), max_size=1)))
        accepts = [(place, o) for o in sorted(needed)]
    return Problem.create(
        objects=objects,
        locations=locations,
        grasps=grasps,
        allowed=allowed,
        collisions=[(a, b, g) for (a, b), g in collisions],
        initial=list(zip(objects, starts, strict=True)),
        goal=goal,
        freespace=freespace,
        supports=supports,
        exclusions=exclusions,
        accepts=accepts,
        subgoals=subgoals,
        precedences=precedences,
    )


@given(small_problems())
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
def test_astar_plans_are_exactly_as_long_as_bfs_plans(problem: Problem) -> None:
    reference = breadth_first_search(problem)
    ours = astar_search(problem)
    if reference.actions is None:
        assert reference.exhausted
        assert ours.actions is None and ours.exhausted
        return
    assert ours.actions is not None
    assert len(ours.actions) == len(reference.actions)
    validate(problem, ours.actions)
    validate(problem, reference.actions)


@given(small_problems())
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
def test_every_bound_stays_below_the_moves_left_along_a_shortest_plan(problem: Problem) -> None:
    # Admissibility checked state by state: at every state of a shortest plan
    # (BFS), the heuristic and the feedback-set bound are at most the moves left.
    shortest = breadth_first_search(problem).actions
    if shortest is None:
        return
    c = compile_problem(problem)
    bounds = LowerBounds(c)
    positions, reached = list(c.start), c.start_reached
    moves_left = len(shortest) // 2
    for k in range(0, len(shortest) + 1, 2):
        state = tuple(positions)
        assert bounds.estimate(state, reached) <= moves_left
        assert bounds.feedback(state, reached) <= moves_left
        if k == len(shortest):
            break
        put = shortest[k + 1]
        obj, target = c.objects.index(put.object), c.locations.index(put.location)
        positions[obj] = target
        reached = c.put_down(obj, target, reached)
        moves_left -= 1


def test_the_feedback_bound_sees_a_swap_a_three_cycle_and_distractors() -> None:
    # parking problems are drawn with cycles of two or three objects on each
    # other's goals and distractors on goal places: each cycle needs one parking
    # move and each distractor one move, which the bound counts at the start.
    for seed in range(4):
        problem = parking_problem(8, seed)
        c = compile_problem(problem)
        cycled = sum(
            1
            for obj, at in enumerate(c.start)
            if c.goal[obj] >= 0 and at in c.goal and c.goal.index(at) != obj
        )
        distractors = sum(1 for goal in c.goal if goal < 0)
        bound = LowerBounds(c).feedback(c.start, c.start_reached)
        needs = sum(1 for obj, at in enumerate(c.start) if 0 <= c.goal[obj] != at)
        # at least one parking move per cycle (cycles have 2 or 3 members)
        assert bound >= needs + distractors + -(-cycled // 3)
        plan = solve(problem, budget=Budget())  # any plan will do: no clock to race
        assert len(plan) >= 2 * bound


@pytest.mark.parametrize("n", [3, 5, 7])
@pytest.mark.parametrize("make", [table_problem, blocks_problem])
def test_generated_problems_match_bfs(make: object, n: int) -> None:
    problem = make(n, n)  # type: ignore[operator]
    plan = solve(problem)
    validate(problem, plan.actions)
    if n <= 5:
        assert len(solve(problem, "bfs")) == len(plan)


def test_goals_that_block_each_others_last_put_down_are_the_reason() -> None:
    # a's only grasp at la collides with lb and b's at lb with la: whichever
    # object is put down last cannot be.
    problem = Problem.create(
        objects=["a", "b"],
        locations=["sa", "sb", "la", "lb"],
        grasps=["g"],
        allowed=[("a", "g"), ("b", "g")],
        collisions=[("la", "lb", "g"), ("lb", "la", "g")],
        initial=[("a", "sa"), ("b", "sb")],
        goal=[("a", "la"), ("b", "lb")],
    )
    with pytest.raises(NoPlanError, match="the last of them put down cannot be"):
        solve(problem)
    assert breadth_first_search(problem).exhausted
    assert astar_search(problem).exhausted


def pyramid_with_a_stacked_start() -> Problem:
    """t stands on b at the start, but t's goal (the top) needs b's goal below it."""
    return Problem.create(
        objects=["b", "c", "t"],
        locations=["left", "right", "top", "s1", "s2", "s3", "free"],
        grasps=["g"],
        allowed=[("b", "g"), ("c", "g"), ("t", "g")],
        supports=[("top", "left"), ("top", "right"), ("s2", "s1")],
        initial=[("b", "s1"), ("t", "s2"), ("c", "s3")],
        goal=[("b", "left"), ("c", "right"), ("t", "top")],
        freespace=["free"],
    )


def test_a_cycle_of_precedences_counts_a_second_move() -> None:
    # t must leave b before b can move, and b must be at its goal before t can
    # be put on top: t is parked once, 4 moves; the heuristic sees it at the start.
    problem = pyramid_with_a_stacked_start()
    plan = solve(problem)
    validate(problem, plan.actions)
    assert len(plan) == 2 * 4 == len(solve(problem, "bfs"))
    c = compile_problem(problem)
    assert LowerBounds(c).estimate(c.start, c.start_reached) == 4


def test_final_places_that_overlap_are_reported() -> None:
    problem = Problem.create(
        objects=["a", "b"],
        locations=["l1", "l2", "g1", "g2"],
        grasps=["g"],
        allowed=[("a", "g"), ("b", "g")],
        initial=[("a", "l1"), ("b", "l2")],
        goal=[("a", "g1"), ("b", "g2")],
        exclusions=[("g1", "g2")],
    )
    with pytest.raises(NoPlanError, match="a and b cannot both stand at their final places"):
        solve(problem)


def test_an_infinite_budget_gives_each_phase_a_finite_share() -> None:
    """--timeout inf is no deadline: the early phases get a share of the
    unbounded default, as with no timeout — not inf * share, which let a
    phase run forever before the exact search."""
    import math

    from demoplan.planning.budget import Budget, Clock
    from demoplan.planning.search import _UNBOUNDED_SECONDS, PHASES, _phase_clock

    greedy = next(p for p in PHASES if p.name == "greedy")
    tight = next(p for p in PHASES if p.name == "tight")
    assert greedy.share is not None
    for budget in (Budget(), Budget(timeout=math.inf)):
        left = _phase_clock(Clock(budget), greedy).remaining()
        assert left is not None and 0 < left <= greedy.share * _UNBOUNDED_SECONDS
        # its work bounded, the tight phase runs to its end: no machine-speed path
        assert _phase_clock(Clock(budget), tight).remaining() is None
