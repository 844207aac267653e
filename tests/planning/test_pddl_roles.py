"""The PDDL export with identical objects (demoplan.planning.pddl.Roles): the
planner, not the export, chooses which instance fills which role.

Fast Downward — an independent optimal planner (A* with LM-cut) — reads the
typed export that ``demoplan problem --pddl`` writes, binds the roles itself
and plans. Its optimal plan has one ``bind`` per instance and must have as
many moves as demoplan's branch and bound over the bindings
(demoplan.scenes.plan) and as the best of demoplan's own optimal plans of
every binding's problem, one by one; and its moves must be valid by
demoplan's rules (demoplan.planning.strips) under the binding it chose.
Data: the generated tasks of tests/support/identical_families.py (a table for two, a
tower with two reds, three cups into a tray) and a hypothesis family of
towers half built in scenes with two or three identical reds."""

from __future__ import annotations

import functools
import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from demoplan.budget import Clock
from demoplan.commands.planning import write_problem
from demoplan.errors import UsageError
from demoplan.learning.learner import learn
from demoplan.model import Pose, TaskModel
from demoplan.planning.pddl import Roles, plan_from_pddl, problem_to_pddl
from demoplan.planning.problem import Problem, Subgoal
from demoplan.planning.search import Budget, solve
from demoplan.planning.strips import validate
from demoplan.rotations import quat_from_yaw
from demoplan.scenes.plan import plan_in_scene
from demoplan.scenes.prepared import prepare
from demoplan.scenes.problems import build_problem
from demoplan.scenes.scene import Scene, SceneObject
from demoplan.scenes.table import surroundings_of
from tests.planning.test_pddl import fast_downward_plan, need_fast_downward
from tests.support.identical_families import (
    BLOCK,
    cups_into_tray,
    cups_scene,
    table_for_two,
    table_scene,
    tower_scene,
    tower_with_two_reds,
)

TABLE_ORDERS = [
    dict(plate=(0, 1), fork=(1, 0), knife=(0, 1), glass=(1, 0)),
    dict(plate=(1, 0), fork=(0, 1), knife=(1, 0), glass=(1, 0)),
    dict(plate=(0, 1), fork=(0, 1), knife=(1, 0), glass=(0, 1)),
]


@functools.cache
def table_model() -> TaskModel:
    return learn(table_for_two(np.random.default_rng(3), TABLE_ORDERS).demonstrations)


@functools.cache
def tower_model() -> TaskModel:
    return learn(tower_with_two_reds([False, True]).demonstrations)


@functools.cache
def cups_model() -> TaskModel:
    rng = np.random.default_rng(3)
    return learn(cups_into_tray(rng, [(0, 1, 2), (2, 0, 1), (1, 2, 0)]).demonstrations)


def families() -> list[tuple[str, TaskModel, Scene]]:
    rng = np.random.default_rng(5)
    return [
        ("table", table_model(), table_scene(rng, TABLE_ORDERS[0])),
        ("tower", tower_model(), tower_scene(rng)),
        ("cups", cups_model(), cups_scene((0.45, 0.1, 75.0))),
    ]


def exported(
    model: TaskModel, scene: Scene, folder: Path
) -> tuple[str, str, Problem, Roles | None]:
    """What ``demoplan problem MODEL SCENE --pddl -o FILE`` writes for goal 1:
    the domain and problem texts, the problem (one binding's) and its roles."""
    written = write_problem(model, scene, folder / "goal.pddl", pddl=True)
    problem_path, domain_path = written.files
    return (
        domain_path.read_text(),
        problem_path.read_text(),
        written.problem.problem,
        written.roles,
    )


def check_against_fast_downward(model: TaskModel, scene: Scene, folder: Path) -> int:
    """Fast Downward's optimal plan of the typed export against demoplan's
    plan of goal 1 over every binding; returns the plan's length."""
    domain, text, problem, roles = exported(model, scene, folder)
    assert roles is not None and roles.kinds
    status, names, _ = fast_downward_plan(domain, text)
    assert status == "SOLVED_OPTIMALLY" and names is not None
    actions, binding = plan_from_pddl(problem, names, roles)
    assert len(names) == len(actions) + len(roles.kinds)  # one bind per instance
    assert sorted(binding) == sorted(roles.filled.values())
    validate(roles.rebind(problem, binding), actions)

    result = plan_in_scene(model, prepare(model, scene), clock=Clock(Budget(timeout=300)))
    goal_1 = next(c for c in result.candidates if 0 in c.problem.candidate.demonstrations)
    assert goal_1.plan is not None and goal_1.plan.optimal
    assert len(actions) == len(goal_1.plan)
    return len(actions)


def binding_lengths(problem: Problem, roles: Roles, model: TaskModel, scene: Scene) -> list[int]:
    """demoplan's optimal plan length of goal 1 under each binding, one by one."""
    lengths = []
    for task in prepare(model, scene).bindings:
        plan = solve(roles.rebind(problem, task.binding.renaming), "astar", Budget(timeout=120))
        assert plan.optimal
        lengths.append(len(plan))
    return lengths


# --- the problems: one binding's facts hold under every binding --------------------------


@pytest.mark.parametrize("index", range(3), ids=["table", "tower", "cups"])
def test_every_binding_has_the_exported_problem_with_its_instances_in_the_roles(
    index: int, tmp_path: Path
) -> None:
    """The export writes one binding's facts with roles for instances: each
    binding's own problem, as demoplan builds it, must be that problem with
    its instances in the roles (the targets do not depend on the binding)."""
    _, model, scene = families()[index]
    _, _, problem, roles = exported(model, scene, tmp_path)
    assert roles is not None
    prepared = prepare(model, scene)
    around = surroundings_of(model, prepared.scene)
    assert len(prepared.bindings) > 1
    for task in prepared.bindings:
        built = build_problem(prepared.scene, task.candidates[0], surroundings=around).problem
        assert built == roles.rebind(problem, task.binding.renaming)


# --- Fast Downward against demoplan ---------------------------------------------------------


@pytest.mark.parametrize("index", range(3), ids=["table", "tower", "cups"])
def test_fast_downward_binds_and_plans_as_short_as_demoplan(index: int, tmp_path: Path) -> None:
    need_fast_downward()
    _, model, scene = families()[index]
    length = check_against_fast_downward(model, scene, tmp_path)
    _, _, problem, roles = exported(model, scene, tmp_path / "again")
    assert roles is not None
    assert length == min(binding_lengths(problem, roles, model, scene))


TOWER = (0.4, 0.1)
SPOTS = [(0.15, -0.25), (0.30, -0.35), (0.55, -0.25), (0.65, 0.30), (0.20, 0.30), (0.70, -0.05)]


def tower_start(reds: list[str], built: int, spots: list[int], yaws: list[float]) -> Scene:
    """blue, the reds and green; the first ``built`` levels of the tower
    (blue, then ``reds[0]``, then ``reds[1]``) already standing, the rest at
    ``spots``, turned by ``yaws``; reds[2], if any, a spare."""
    tower = ["blue", *reds[:2], "green"]
    objects = []
    scattered = iter(zip(spots, yaws, strict=False))
    for name in ["blue", *reds, "green"]:
        if name in tower[:built]:
            level = tower.index(name)
            pose = Pose((*TOWER, 0.04 * level), quat_from_yaw(0.0))
        else:
            spot, yaw = next(scattered)
            pose = Pose((*SPOTS[spot], 0.0), quat_from_yaw(yaw))
        kind = "red" if name.startswith("red") else None
        objects.append(SceneObject(name, pose, BLOCK, type=kind))
    return Scene(objects=tuple(objects), source="tower scene")


@st.composite
def tower_scenes(draw: st.DrawFn) -> Scene:
    count = draw(st.integers(2, 3))
    letters = draw(st.permutations("pqrs"))[:count]
    reds = [f"red-{letter}" for letter in letters]
    spots = draw(st.permutations(range(len(SPOTS))))
    yaws = draw(st.lists(st.sampled_from([0.0, 25.0, -40.0]), min_size=5, max_size=5))
    scene = tower_start(reds, draw(st.integers(0, 3)), spots, yaws)
    order = draw(st.permutations(range(len(scene.objects))))
    return replace(scene, objects=tuple(scene.objects[i] for i in order))


@settings(max_examples=5, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scene=tower_scenes())
def test_fast_downward_agrees_on_half_built_towers(scene: Scene) -> None:
    """Two or three identical reds (a spare), shuffled names and order, the
    tower standing up to some level with either red in it."""
    need_fast_downward()
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        check_against_fast_downward(tower_model(), scene, Path(folder))


def test_the_red_already_in_place_is_the_one_bound_to_it(tmp_path: Path) -> None:
    """blue and red-q stand as the tower's first two levels: binding red-q to
    the lower red's role saves its moves, so the bindings' plans differ and
    Fast Downward must find the shorter one."""
    need_fast_downward()
    scene = tower_start(["red-q", "red-p"], 2, [0, 1, 2], [0.0, 25.0, 0.0])
    domain, text, problem, roles = exported(tower_model(), scene, tmp_path)
    assert roles is not None
    # standing there, red-q reaches the lower red's subgoal once bound to its role
    assert "(:action bind-reaching" in domain
    assert re.search(r"\(start-reaches red-1 \S+ b\)", text)
    lengths = binding_lengths(problem, roles, tower_model(), scene)
    assert len(set(lengths)) > 1
    assert check_against_fast_downward(tower_model(), scene, tmp_path / "fd") == min(lengths)


def test_fast_downward_leaves_the_red_under_green_spare(tmp_path: Path) -> None:
    """Three reds, green standing on the first: every binding has the same
    lower bound, and the first binding (scene order) uses that red, which
    costs green two more moves than leaving it spare. The export of the
    first binding alone would be 2 moves too long; Fast Downward must bind
    the others."""
    need_fast_downward()
    flat = quat_from_yaw(0.0)
    scene = Scene(
        objects=(
            SceneObject("blue", Pose((*SPOTS[0], 0.0), flat), BLOCK),
            SceneObject("red-s", Pose((*SPOTS[1], 0.0), flat), BLOCK, type="red"),
            SceneObject("green", Pose((*SPOTS[1], 0.04), flat), BLOCK),
            SceneObject("red-p", Pose((*SPOTS[2], 0.0), flat), BLOCK, type="red"),
            SceneObject("red-q", Pose((*SPOTS[3], 0.0), flat), BLOCK, type="red"),
        ),
        source="tower scene",
    )
    _, _, problem, roles = exported(tower_model(), scene, tmp_path)
    assert roles is not None and "red-s" in roles.filled
    lengths = binding_lengths(problem, roles, tower_model(), scene)
    assert lengths[0] == min(lengths) + 2
    assert check_against_fast_downward(tower_model(), scene, tmp_path / "fd") == min(lengths)


def test_a_table_half_laid_binds_the_pieces_already_at_a_seat(tmp_path: Path) -> None:
    """plate-b stands at the second seat and knife-a beside it, where the
    model puts them: only the bindings that give them those roles save their
    moves: 2 for each of the 8 pieces, less the 2 in place, for demoplan and
    for Fast Downward."""
    need_fast_downward()
    model = table_model()
    states = {s.object: s for s in model.states}
    seat = states["plate#2"].position.value
    knife = next(
        s for s in model.states if s.position.reference == "plate#2" and "knife" in s.object
    )
    at = {
        "plate-b": (seat[0], seat[1], 0.0),
        "knife-a": (seat[0] + knife.position.value[0], seat[1] + knife.position.value[1], 0.0),
    }
    scene = table_scene(np.random.default_rng(8), TABLE_ORDERS[1])
    scene = replace(
        scene,
        objects=tuple(
            replace(o, pose=Pose(at[o.name], quat_from_yaw(0.0))) if o.name in at else o
            for o in scene.objects
        ),
    )
    length = check_against_fast_downward(model, scene, tmp_path)
    assert length == 12


# --- the text, and what it refuses ---------------------------------------------------------


def test_typed_export_declares_types_roles_and_binds(tmp_path: Path) -> None:
    domain, text, problem, roles = exported(cups_model(), cups_scene((0.45, 0.1, 75.0)), tmp_path)
    assert roles is not None
    assert "(:types item location grip subgoal - object\n    cup - item)" in domain
    assert "(:action bind\n" in domain
    assert "    cup-x cup-y cup-z cup-1 cup-2 cup-3 - cup\n" in text
    # the subgoals and the goal name roles, not instances
    for s in problem.subgoals:
        assert f"(subgoal-of {s.id.lower()} {roles.filled[s.object].replace('#', '-')} " in text
    assert "(located cup-x" not in text.split("(:goal")[1]
    for instance in roles.kinds:
        assert f"(bound {instance})" in text.split("(:goal")[1]


def test_a_model_without_roles_exports_as_before(tmp_path: Path) -> None:
    """The tower taught with untyped reds: every object of its own type, the
    export of the one problem there is, no binds."""
    taught = tower_with_two_reds([False, True]).demonstrations
    model = learn([replace(demo, types=()) for demo in taught])
    scene = tower_start(["red-a", "red-b"], 0, [0, 1, 2, 3], [0.0] * 4)
    untyped = replace(scene, objects=tuple(replace(o, type=None) for o in scene.objects))
    domain, text, problem, roles = exported(model, untyped, tmp_path)
    assert roles is None
    assert (domain, text) == problem_to_pddl(problem)
    assert "bind" not in domain and "(:types item location grip subgoal)" in domain


@pytest.mark.parametrize("index", [1, 2], ids=["tower", "cups"])
def test_the_grounded_export_with_roles_is_plain_strips_pyperplan_solves(
    index: int, tmp_path: Path
) -> None:
    """pyperplan (A* with h_max, optimal) reads the grounded export: its plan
    binds, is as long as Fast Downward's of the lifted one would be (the
    binding's optimum over all bindings), and valid under its binding."""
    pytest.importorskip("pyperplan", reason="pyperplan not installed (pip install -e '.[fd]')")
    from pyperplan.grounding import ground
    from pyperplan.heuristics.relaxation import hMaxHeuristic
    from pyperplan.pddl.parser import Parser
    from pyperplan.search import astar_search

    _, model, scene = families()[index]
    written = write_problem(model, scene, tmp_path / "goal.pddl", pddl=True, grounded=True)
    problem_path, domain_path = written.files
    problem, roles = written.problem.problem, written.roles
    assert roles is not None
    domain = domain_path.read_text()
    assert "(:requirements :strips)" in domain
    for keyword in ("forall", "exists", "when", " or ", "(not (plays", ":typing"):
        assert keyword not in domain
    assert "(:action bind__" in domain
    parser = Parser(str(domain_path), str(problem_path))
    task = ground(parser.parse_problem(parser.parse_domain()))
    plan = astar_search(task, hMaxHeuristic(task))
    assert plan is not None
    actions, binding = plan_from_pddl(problem, [op.name for op in plan], roles)
    assert len(plan) == len(actions) + len(roles.kinds)
    validate(roles.rebind(problem, binding), actions)
    assert len(actions) == min(binding_lengths(problem, roles, model, scene))


def test_fast_downward_reads_the_grounded_export_with_roles(tmp_path: Path) -> None:
    need_fast_downward()
    _, model, scene = families()[1]
    _, _, problem, roles = exported(model, scene, tmp_path)
    assert roles is not None
    status, names, _ = fast_downward_plan(*problem_to_pddl(problem, grounded=True, roles=roles))
    assert status == "SOLVED_OPTIMALLY" and names is not None
    actions, binding = plan_from_pddl(problem, names, roles)
    validate(roles.rebind(problem, binding), actions)
    assert len(actions) == min(binding_lengths(problem, roles, model, scene))


def test_targets_that_depend_on_the_binding_are_refused(tmp_path: Path) -> None:
    """A cup placed anywhere stays where its instance stands: a target per
    binding, which one PDDL problem cannot say."""
    model = cups_model()
    first = model.states[0]
    anywhere = replace(
        first, position=replace(first.position, anywhere=True, reference=None, value=(0, 0, 0))
    )
    model = replace(model, states=(anywhere, *model.states[1:]))
    scene = cups_scene((0.45, 0.1, 75.0))
    plan_in_scene(
        model, prepare(model, scene), clock=Clock(Budget(timeout=60))
    )  # demoplan plans it
    with pytest.raises(UsageError, match=rf"subgoals {first.id}\b.*placed anywhere"):
        write_problem(model, scene, tmp_path / "goal.pddl", pddl=True)
    # the XML export writes the problem of the first binding as before
    write_problem(model, scene, tmp_path / "goal.xml")


def test_roles_named_like_instances_and_types_get_names_of_their_own() -> None:
    """The model's untyped "cup" is a role the scene's "cup" and "cup-2" (type
    cup) may fill: role, instances and type share a name, which PDDL keeps in
    one namespace. Fast Downward still finds the 2 binds and 2 moves, and the
    names map back."""
    need_fast_downward()
    problem = Problem.create(
        objects=["cup", "cup-2"],
        locations=["l1", "l2", "slot"],
        grasps=["g1", "g2"],
        allowed=[("cup", "g1"), ("cup-2", "g2")],
        initial=[("cup", "l1"), ("cup-2", "l2")],
        goal=[("cup", "slot")],
        subgoals=[Subgoal("A", "cup", "slot")],
    )
    roles = Roles({"cup": "cup", "cup-2": "cup"}, {"cup": "cup"})
    domain, text = problem_to_pddl(problem, roles=roles)
    declared = re.search(r"\(:objects\n(.*?)\n  \)", text, re.S)
    assert declared is not None
    words = [w for w in declared.group(1).split() if w != "-"]
    assert len(words) == len(set(words))
    status, names, _ = fast_downward_plan(domain, text)
    assert status == "SOLVED_OPTIMALLY" and names is not None and len(names) == 4
    actions, binding = plan_from_pddl(problem, names, roles)
    assert binding["cup"] in {"cup", "cup-2"} and len(actions) == 2
    validate(roles.rebind(problem, binding), actions)
