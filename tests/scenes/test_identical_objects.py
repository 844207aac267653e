"""Identical objects: learned as roles, planned with a free choice of instance,
executed with instances that may swap roles (docs/learning.md and
docs/planning.md, "Identical objects").

The tasks are generated (tests/support/identical_families.py) with what was meant per
seat, slot or level, so every assertion checks the learned roles against that
truth, whatever the instances were called. Plans are checked against an
independent count (each object away from its target moves at least once) and
against planning every binding on its own (the branch and bound must find the
least of them).
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from demoplan.budget import Clock
from demoplan.commands.inputs import load_inputs
from demoplan.execution.executor import ExecutionSettings, execute
from demoplan.execution.kinematic import KinematicWorld
from demoplan.learning.learner import learn, update
from demoplan.model import Demonstration, Pose, Step, TaskModel
from demoplan.planning.search import Budget
from demoplan.scenes.binding import Binding, bind_model, role_bindings
from demoplan.scenes.plan import ScenePlan, plan_in_scene, solve_candidate
from demoplan.scenes.prepared import prepare
from demoplan.scenes.problems import build_problem, pose_of
from demoplan.scenes.scene import Scene
from demoplan.segmentation.streams import StreamOptions
from demoplan.segmentation.synthetic import stream_from_demonstration
from demoplan.segmentation.writers import write_csv
from tests.support.identical_families import (
    SEATS,
    TABLE_TYPES,
    Taught,
    cups_into_tray,
    cups_scene,
    table_for_two,
    table_scene,
    tower_scene,
    tower_with_two_reds,
)
from tests.support.learning_families import shifted_scene_family

UNLIMITED = Budget(timeout=math.inf)

# Per type, the instance letters in seat order: shuffled between the demonstrations.
TABLE_ORDERS = [
    {"plate": (0, 1), "fork": (1, 0), "knife": (0, 1), "glass": (1, 0)},
    {"plate": (1, 0), "fork": (0, 1), "knife": (1, 0), "glass": (1, 0)},
    {"plate": (0, 1), "fork": (0, 1), "knife": (1, 0), "glass": (0, 1)},
]


def _place_of_role(taught: Taught, model: TaskModel) -> dict[str, int]:
    """Each role's seat (slot, level) by the generator's truth: the same in every
    demonstration, or the role mixes places and the assertion fails."""
    places: dict[str, int] = {}
    for role in model.roles:
        seen = {taught.truth[d][name] for d, name in enumerate(role.instances) if name}
        assert len(seen) == 1, f"{role.name} is filled at places {seen}"
        places[role.name] = seen.pop()
    return places


def _grasped(plan: ScenePlan) -> list[str]:
    return [a.object for a in plan.chosen.plan.actions if a.kind == "GRASP"]


def _shortest_over_bindings(model: TaskModel, scene: Scene) -> int:
    """The oracle: every binding planned alone (optimally), the least length."""
    prepared = prepare(model, scene)
    lengths = []
    for task in prepared.bindings:
        for candidate in task.candidates:
            outcome = solve_candidate(build_problem(prepared.scene, candidate), Clock(UNLIMITED))
            assert outcome.plan is None or outcome.plan.optimal
            if outcome.plan is not None:
                lengths.append(len(outcome.plan))
    return min(lengths)


@pytest.fixture(scope="module")
def table() -> tuple[Taught, TaskModel]:
    taught = table_for_two(np.random.default_rng(3), TABLE_ORDERS)
    return taught, learn(taught.demonstrations)


def test_a_table_for_two_learns_one_state_per_role(table: tuple[Taught, TaskModel]) -> None:
    taught, model = table
    types = model.object_types()
    assert sorted(types[s.object] for s in model.states) == sorted(TABLE_TYPES * 2)
    assert len({s.object for s in model.states}) == 8  # one state per role
    places = _place_of_role(taught, model)
    for state in model.states:
        kind = types[state.object]
        if kind == "plate":
            assert state.position.reference is None
            seat = SEATS[places[state.object]]
            assert math.dist(state.position.value[:2], seat) < 0.02
        else:  # relative to the plate of its own seat
            reference = state.position.reference
            assert reference is not None and types[reference] == "plate"
            assert places[reference] == places[state.object], state


def test_a_table_for_two_is_laid_moving_each_object_once(table: tuple[Taught, TaskModel]) -> None:
    _, model = table
    scene = table_scene(np.random.default_rng(5), {k: (1, 0) for k in TABLE_TYPES})
    result = plan_in_scene(model, prepare(model, scene), clock=Clock(UNLIMITED))
    grasped = _grasped(result)
    assert sorted(grasped) == sorted(obj.name for obj in scene.objects)  # each once
    assert len(grasped) == len(set(grasped)) == 8
    assert result.optimal and result.bound == 16
    assert result.chosen.bindings_weighed == 16  # 2!⁴ ways to fill the roles


def test_the_choice_of_instances_is_the_shortest_over_all_bindings(
    table: tuple[Taught, TaskModel],
) -> None:
    """A plate already at a seat keeps it: the binding matters, and branch and
    bound finds the binding planning every one of them alone finds."""
    _, model = table
    scene = table_scene(np.random.default_rng(6), {k: (0, 1) for k in TABLE_TYPES})
    seated = next(s for s in model.states if s.object == "plate#2")
    plate = next(o for o in scene.objects if o.name == "plate-a")
    objects = tuple(
        replace(o, pose=Pose(seated.position.value, o.pose.orientation)) if o is plate else o
        for o in scene.objects
    )
    scene = replace(scene, objects=objects)
    result = plan_in_scene(model, prepare(model, scene), clock=Clock(UNLIMITED))
    assert "plate-a" not in _grasped(result)
    assert result.chosen.binding.renaming["plate#2"] == "plate-a"
    assert result.optimal
    assert len(result.chosen.plan) == _shortest_over_bindings(model, scene) == 14


def test_a_tower_with_two_identical_reds_is_built_in_the_shortest_plan() -> None:
    taught = tower_with_two_reds([False, True])
    model = learn(taught.demonstrations)
    places = _place_of_role(taught, model)
    assert sorted(places.values()) == [0, 1]  # red#1, red#2: the lower and the upper red
    lower = min(places, key=places.__getitem__)
    states = {s.object: s for s in model.states}
    assert (
        states[lower].position.value[2]
        < states[max(places, key=places.__getitem__)].position.value[2]
    )
    for seed in range(4):
        scene = tower_scene(np.random.default_rng(seed))
        result = plan_in_scene(model, prepare(model, scene), clock=Clock(UNLIMITED))
        assert result.optimal
        assert len(result.chosen.plan) == _shortest_over_bindings(model, scene) == 8
        report = execute(
            model, prepare(model, scene, clutter=True), KinematicWorld(prepare(model, scene).scene)
        )
        assert report.success, report.reason
        heights = sorted(
            (report.final.poses[name].position[2], name)
            for name in ("blue", "red-x", "red-y", "green")
        )
        assert [name[:3] for _, name in heights] == ["blu", "red", "red", "gre"]


def _slot_positions(model: TaskModel, scene: Scene) -> list[tuple[float, float]]:
    prepared = prepare(model, scene)
    return [s.pose.position[:2] for s in prepared.candidates[0].subtasks]


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    x=st.floats(0.35, 0.55),
    y=st.floats(-0.15, 0.15),
    yaw=st.floats(-180, 180),
    names=st.permutations(["cup-x", "cup-y", "cup-z"]),
)
def test_three_identical_cups_fill_each_slot_of_a_turned_tray_once(
    x: float, y: float, yaw: float, names: list[str]
) -> None:
    taught = cups_into_tray(np.random.default_rng(11), [(0, 1, 2), (2, 0, 1), (1, 2, 0)])
    model = learn(taught.demonstrations)
    assert sorted(_place_of_role(taught, model).values()) == [0, 1, 2]
    scene = cups_scene((x, y, yaw), names)
    result = plan_in_scene(model, prepare(model, scene), clock=Clock(UNLIMITED))
    assert len(result.chosen.plan) == 6 and result.optimal
    report = execute(
        model, prepare(model, scene, clutter=True), KinematicWorld(prepare(model, scene).scene)
    )
    assert report.success, report.reason
    slots = _slot_positions(model, scene)
    filled = [
        min(range(3), key=lambda i: math.dist(report.final.poses[n].position[:2], slots[i]))
        for n in names
    ]
    assert sorted(filled) == [0, 1, 2]  # each slot once
    for name, slot in zip(names, filled, strict=True):
        assert math.dist(report.final.poses[name].position[:2], slots[slot]) < 0.005


class _LandsInAnotherSlot(KinematicWorld):
    """The first cup put down lands in the last slot instead of its own."""

    def __init__(self, scene: Scene, spot: Pose):
        super().__init__(scene)
        self.spot = spot
        self.landed = False

    def put_down(self, obj: str, pose: Pose) -> None:
        if not self.landed and self.held == obj:
            self.landed = True
            pose = self.spot
        super().put_down(obj, pose)


def test_a_cup_that_lands_in_another_slot_takes_that_role() -> None:
    """Replanning weighs the bindings again: the cup standing in slot 3 fills
    slot 3's role, and another cup goes to its slot — 4 actions left, not 6."""
    taught = cups_into_tray(np.random.default_rng(11), [(0, 1, 2), (2, 0, 1), (1, 2, 0)])
    model = learn(taught.demonstrations)
    scene = cups_scene((0.45, 0.05, 30.0))
    prepared = prepare(model, scene)
    first = plan_in_scene(model, prepared, clock=Clock(UNLIMITED)).chosen
    assert first.plan is not None
    put_downs = [a for a in first.plan.actions if a.kind == "PUT_DOWN"]
    last_slot = pose_of(first.problem.location(put_downs[-1].location))
    world = _LandsInAnotherSlot(prepared.scene, last_slot)
    report = execute(model, prepared, world, ExecutionSettings(budget=UNLIMITED))
    assert report.success and report.replans == 1
    assert len(report.actions) == len(first.plan) == 6  # no action lost to the slip


# -- names do not matter ---------------------------------------------------------------


def _renamed(demo: Demonstration, renaming: dict[str, str]) -> Demonstration:
    def name(old: str) -> str:
        return renaming.get(old, old)

    return replace(
        demo,
        steps=tuple(Step(name(s.object), s.pose) for s in demo.steps),
        objects=tuple((name(n), g) for n, g in demo.objects),
        initial=tuple((name(n), p) for n, p in demo.initial),
        types=tuple((name(n), t) for n, t in demo.types),
    )


def _learned_structure(model: TaskModel) -> tuple[object, ...]:
    return (model.states, model.sequences, model.constraints, model.goals)


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_renaming_instances_changes_neither_the_roles_nor_the_plan_length(
    table: tuple[Taught, TaskModel], data: st.DataObject
) -> None:
    taught, model = table
    demos = []
    for demo in taught.demonstrations:
        renaming = {}
        for kind in TABLE_TYPES:
            letters = data.draw(st.permutations("ab"))
            renaming |= {f"{kind}-{a}": f"{kind}-{b}" for a, b in zip("ab", letters, strict=True)}
        demos.append(_renamed(demo, renaming))
    renamed = learn(demos)
    assert _learned_structure(renamed) == _learned_structure(model)
    scene = table_scene(np.random.default_rng(5), {k: (1, 0) for k in TABLE_TYPES})
    swap = data.draw(st.permutations([o.name for o in scene.objects if o.kind == "plate"]))
    objects = tuple(
        replace(o, name=swap[["plate-b", "plate-a"].index(o.name)]) if o.kind == "plate" else o
        for o in scene.objects
    )
    first = plan_in_scene(model, prepare(model, scene), clock=Clock(UNLIMITED)).chosen.plan
    second = plan_in_scene(
        renamed, prepare(renamed, replace(scene, objects=objects)), clock=Clock(UNLIMITED)
    ).chosen.plan
    assert first is not None and second is not None and len(first) == len(second)


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**31), n_objects=st.integers(2, 5), n_demos=st.integers(2, 5))
def test_with_every_type_distinct_the_model_is_todays(
    seed: int, n_objects: int, n_demos: int
) -> None:
    """Each object declared of a type of its own (named otherwise): the model
    is the one learned without types, its roles named like the types."""
    family = shifted_scene_family(np.random.default_rng(seed), n_objects, n_demos)
    plain = learn(family.demos)
    typed_demos = [
        replace(demo, types=tuple((name, f"kind-{name}") for name in demo.moved_objects))
        for demo in family.demos
    ]
    typed = learn(typed_demos)
    assert len(typed.roles) == n_objects
    assert {r.name: r.instances for r in typed.roles} == {
        f"kind-{name}": tuple(name for _ in typed_demos) for name in typed_demos[0].moved_objects
    }
    back = Binding(tuple(sorted((r.name, r.instances[0] or r.name) for r in typed.roles)))
    assert _learned_structure(bind_model(typed, back)) == _learned_structure(plain)


def test_a_scene_with_too_few_instances_names_the_type() -> None:
    taught = cups_into_tray(np.random.default_rng(11), [(0, 1, 2), (2, 0, 1)])
    model = learn(taught.demonstrations)
    scene = cups_scene((0.45, 0.05, 0.0), ("cup-x", "cup-y", "cup-z"))
    scene = replace(scene, objects=scene.objects[:2])
    with pytest.raises(
        Exception, match=r"3 objects of type 'cup' .*the scene has 2 \(cup-x, cup-y\)"
    ):
        role_bindings(model, scene)


def test_pose_streams_carry_the_types_of_their_objects_file(tmp_path: Path) -> None:
    """Two tracked towers (CSV) whose identical reds are named differently, and
    an objects file declaring their type: ``learn`` of the streams gives the
    roles the demonstration files give."""
    taught = tower_with_two_reds([False, True])
    files = []
    for index, demo in enumerate(taught.demonstrations):
        stream = stream_from_demonstration(demo, rng=index, noise_m=0.0005, noise_deg=0.1)
        files.append(tmp_path / f"tower-{index + 1}.csv")
        write_csv(stream, files[-1])
    geometry = dict(taught.demonstrations[0].objects)
    objects = {
        name: {"shape": g.shape, "size": list(g.size)} | ({"type": "red"} if "red" in name else {})
        for name, g in geometry.items()
    }
    objects_file = tmp_path / "objects.json"
    objects_file.write_text(json.dumps({"objects": objects}))
    demos = load_inputs(files, stream=StreamOptions(objects_file=objects_file))
    assert [dict(d.types) for d in demos] == [{"red-a": "red", "red-b": "red"}] * 2
    model = learn(demos)
    assert _place_of_role(taught, model) == {"red#1": 0, "red#2": 1}


def test_a_teacher_constraint_may_name_a_type_or_a_role(table: tuple[Taught, TaskModel]) -> None:
    taught, model = table
    types = model.object_types()
    by_type = learn(taught.demonstrations, require=["glass<fork"])
    states = {s.id: s.object for s in by_type.states}
    required = set(by_type.teacher_constraints)
    glasses = [i for i, o in states.items() if types[o] == "glass"]
    forks = [i for i, o in states.items() if types[o] == "fork"]
    assert required == {(g, f) for g in glasses for f in forks}
    by_role = learn(taught.demonstrations, require=["plate#2<plate#1"])
    ids = {s.object: s.id for s in by_role.states}
    assert by_role.teacher_constraints == ((ids["plate#2"], ids["plate#1"]),)


def test_update_learns_the_roles_again_from_the_instances(table: tuple[Taught, TaskModel]) -> None:
    """``learn --update`` renames the roles back to the instances that filled
    them and learns from all demonstrations: the same model as learning them
    at once."""
    taught, _ = table
    first = learn(taught.demonstrations[:2])
    updated = update(first, taught.demonstrations[2:])
    at_once = learn(taught.demonstrations)
    assert _learned_structure(updated) == _learned_structure(at_once)
    assert updated.roles == at_once.roles


@pytest.mark.parametrize("typed", [False, True])
def test_a_scene_object_named_as_a_role_needs_its_type(tmp_path: Path, typed: bool) -> None:
    """``red#1`` names the first red role: a scene object may carry that name only
    as an instance of its type, as in demonstration files."""
    from demoplan.errors import InputError
    from demoplan.scenes.scene import load_scene

    red = {"position": [0.3, 0.1, 0.0], "size": [0.04, 0.04, 0.04]}
    document = {
        "format": "demoplan/scene-1",
        "objects": {"red#1": red | ({"type": "red"} if typed else {}), "blue": dict(red)},
    }
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(document))
    if typed:
        assert load_scene(path).object("red#1").type == "red"
    else:
        with pytest.raises(InputError, match=r"objects\.red#1: '#' names a role of a type"):
            load_scene(path)
