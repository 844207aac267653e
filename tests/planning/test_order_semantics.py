"""The taught order honoured physically (docs/planning.md "Planning"): no object put down
on its place before its predecessors are reached, no move that ends where it
started — in the search, the validator (strips), the PDDL export and the
executor's notion of "reached"."""

from __future__ import annotations

from pathlib import Path

import pytest

from demoplan.documents.demonstrations import load_demonstrations
from demoplan.learning import learn
from demoplan.model import TaskModel
from demoplan.planning.problem import Action, Problem, Subgoal
from demoplan.planning.search import astar_search, breadth_first_search, solve
from demoplan.planning.strips import InvalidPlanError, Rules, validate
from demoplan.scenes.plan import plan_in_scene
from demoplan.scenes.prepared import prepare
from demoplan.scenes.problems import SceneProblem
from demoplan.scenes.scene import load_scene
from tests.support.helpers import EXAMPLES

KIT = EXAMPLES / "kitting"
SCENE = KIT / "scene-manual-on-motor.json"


@pytest.fixture(scope="module", params=[(), ("cable<screws",)], ids=["taught", "teacher"])
def kit_model(request: pytest.FixtureRequest) -> TaskModel:
    return learn(load_demonstrations([KIT / "demonstrations.json"]), require=request.param)


def order_broken(problem: SceneProblem, actions: tuple[Action, ...]) -> list[str]:
    """Put-downs on a state's target before every predecessor state's object
    stands at its own target, checked on the scene's labels and targets (not
    through the planner's subgoal bookkeeping), and moves that end where they
    started."""
    subgoals = {s.id: s for s in problem.problem.subgoals}
    before = {sid: {a for a, b in problem.problem.precedences if b == sid} for sid in subgoals}
    at = dict(problem.problem.initial)
    # A state counts where its object stands at the start (docs/planning.md, strips docstring).
    done = {sid for sid, s in subgoals.items() if at[s.object] == s.location}
    broken = []
    taken_from = ""
    for action in actions:
        if action.kind == "GRASP":
            taken_from = action.location
            del at[action.object]
            continue
        if action.location == taken_from:
            broken.append(f"{action.object} put back where it was taken from")
        at[action.object] = action.location
        for sid, s in subgoals.items():
            if s.object == action.object and s.location == action.location and sid not in done:
                missing = before[sid] - done
                if missing:
                    broken.append(f"{action.object} on {sid} before {sorted(missing)}")
                done.add(sid)
    return broken


def test_the_kit_parks_the_manual_until_its_predecessors_are_in(kit_model: TaskModel) -> None:
    scene = load_scene(SCENE)
    chosen = plan_in_scene(kit_model, prepare(kit_model, scene)).chosen
    validate(chosen.problem.problem, chosen.plan.actions)
    actions = chosen.plan.actions
    assert order_broken(chosen.problem, actions) == []
    validate(chosen.problem.problem, actions)
    # The manual lies on the motor: it is lifted off first and parked, and put on
    # the pcb only as the last move — the same 6 moves as the plan that broke the order.
    manual_moves = [a for a in actions if a.object == "manual" and a.kind == "PUT_DOWN"]
    assert len(manual_moves) == 2
    assert actions[-1].object == "manual"
    assert len(actions) == 12
    if "cable<screws" in kit_model.settings.require:
        order = [a.object for a in actions if a.kind == "PUT_DOWN"]
        assert order.index("cable") < order.index("screws")


def two_step_problem() -> Problem:
    """b must be put at l3 after a is at l2; b starts at l1, a at l0; one spare spot."""
    return Problem.create(
        objects=["a", "b"],
        locations=["l0", "l1", "l2", "l3", "spare"],
        grasps=["g"],
        allowed=[("a", "g"), ("b", "g")],
        initial=[("a", "l0"), ("b", "l1")],
        goal=[("a", "l2"), ("b", "l3")],
        subgoals=[Subgoal("A", "a", "l2"), Subgoal("B", "b", "l3")],
        precedences=[("A", "B")],
    )


def test_a_put_down_on_a_place_before_its_predecessor_is_refused() -> None:
    problem = two_step_problem()
    early = [Action("GRASP", "b", "l1", "g"), Action("PUT_DOWN", "b", "l3", "g")]
    with pytest.raises(InvalidPlanError, match="subgoal B, which must wait for A"):
        validate(problem, early)
    plan = solve(problem)
    assert [str(a) for a in plan.actions] == [
        "GRASP a l0 g",
        "PUT_DOWN a l2 g",
        "GRASP b l1 g",
        "PUT_DOWN b l3 g",
    ]


def test_a_move_that_ends_where_it_started_is_refused() -> None:
    problem = two_step_problem()
    null = [Action("GRASP", "a", "l0", "g"), Action("PUT_DOWN", "a", "l0", "g")]
    with pytest.raises(InvalidPlanError, match="a move must end elsewhere"):
        validate(problem, null)


def test_an_object_found_in_place_is_not_moved_for_the_order() -> None:
    """b already stands at its place while its predecessor A is missing: B counts
    as reached (the decision documented in demoplan.planning.strips), so only a
    moves — for both searches and for the executor's bookkeeping."""
    problem = Problem.create(
        objects=["a", "b"],
        locations=["l0", "l2", "l3"],
        grasps=["g"],
        allowed=[("a", "g"), ("b", "g")],
        initial=[("a", "l0"), ("b", "l3")],
        goal=[("a", "l2"), ("b", "l3")],
        subgoals=[Subgoal("A", "a", "l2"), Subgoal("B", "b", "l3")],
        precedences=[("A", "B")],
    )
    assert Rules(problem).start().reached == {"B"}
    for search in (astar_search, breadth_first_search):
        actions = search(problem).actions
        assert actions is not None
        assert [str(a) for a in actions] == ["GRASP a l0 g", "PUT_DOWN a l2 g"]


def test_an_objects_own_earlier_visit_still_counts() -> None:
    """b stands at the place of its second visit, but has not made its first:
    the second does not count at the start, so b goes to l1 and comes back."""
    problem = Problem.create(
        objects=["b"],
        locations=["l0", "l1"],
        grasps=["g"],
        allowed=[("b", "g")],
        initial=[("b", "l0")],
        goal=[("b", "l0")],
        subgoals=[Subgoal("B1", "b", "l1"), Subgoal("B2", "b", "l0")],
        precedences=[("B1", "B2")],
    )
    assert Rules(problem).start().reached == frozenset()
    plan = solve(problem)
    assert [str(a) for a in plan.actions] == [
        "GRASP b l0 g",
        "PUT_DOWN b l1 g",
        "GRASP b l1 g",
        "PUT_DOWN b l0 g",
    ]


def test_kitting_cli_plan_and_run_keep_the_order(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from demoplan.cli import app

    runner = CliRunner()
    model = tmp_path / "kit.json"
    learned = runner.invoke(
        app, ["learn", str(KIT / "demonstrations.json"), "-o", str(model), "--json"]
    )
    assert learned.exit_code == 0, learned.output
    run = runner.invoke(app, ["run", str(model), str(SCENE), "--json"])
    assert run.exit_code == 0, run.output
    import json

    report = json.loads(run.stdout)
    assert report["success"] and report["replans"] == 0
    put_downs = [a for a in report["actions"] if a[0] == "PUT_DOWN"]
    assert [a[1] for a in put_downs][-1] == "manual"
