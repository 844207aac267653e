"""``export bt`` (issue 31): the exported tree loads in BehaviorTree.CPP v4 itself
(behaviortreepy), its leaves bound to the kinematic world, and ticks to SUCCESS —
or, with faults injected, recovers or fails naming the executor's failure kind,
never SUCCESS with an object off its target. The oracle of "at its target" is
the chosen plan's goal (its locations' poses), not anything read from the XML."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from defusedxml.ElementTree import fromstring
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from demoplan.budget import Budget
from demoplan.cli import app
from demoplan.commands.export import behaviour_tree
from demoplan.documents.demonstrations import load_demonstrations
from demoplan.errors import InputError
from demoplan.execution.behaviour_tree import ATTEMPTS, NODES, TreeRun, run_behaviour_tree
from demoplan.execution.faults import Faults
from demoplan.execution.kinematic import KinematicWorld
from demoplan.execution.report import FailureKind
from demoplan.learning import learn
from demoplan.learning.modelfile import save_model
from demoplan.model import TaskModel
from demoplan.scenes.plan import ScenePlan
from demoplan.scenes.problems import pose_of
from demoplan.scenes.scene import Scene
from tests.support.helpers import EXAMPLES, paper_model
from tests.support.identical_families import table_for_two, table_scene

pytest.importorskip("behaviortreepy")

TOLERANCE = 0.01  # m: the executor's position tolerance, which the tree's checks carry


def _examples() -> dict[str, tuple[TaskModel, Path]]:
    return {
        "set_table": (paper_model("set_table"), EXAMPLES / "scenes" / "set-table-cluttered.json"),
        "blocks": (paper_model("blocks"), EXAMPLES / "scenes" / "pyramid-fig4.json"),
        "kitting": (
            learn(load_demonstrations([EXAMPLES / "kitting" / "demonstrations.json"])),
            EXAMPLES / "kitting" / "scene-manual-on-motor.json",
        ),
    }


@pytest.fixture(scope="module")
def exported() -> dict[str, tuple[str, ScenePlan]]:
    return {name: behaviour_tree(model, scene) for name, (model, scene) in _examples().items()}


def off_target(result: ScenePlan, world: KinematicWorld) -> list[str]:
    """Goal objects farther than the tolerance from the chosen plan's goal (or held)."""
    problem = result.chosen.problem
    off = []
    for obj, location in problem.problem.goal:
        pose = world.poses.get(obj)
        target = pose_of(problem.location(location))
        if pose is None or math.dist(pose.position, target.position) > TOLERANCE:
            off.append(obj)
    return off


def tick(xml: str, result: ScenePlan, **world: Any) -> tuple[TreeRun, KinematicWorld]:
    kinematic = KinematicWorld(result.scene, **world)
    return run_behaviour_tree(xml, kinematic), kinematic


@pytest.mark.parametrize("example", ["set_table", "blocks", "kitting"])
def test_the_exported_tree_ticks_to_success_in_the_engine(
    exported: dict[str, tuple[str, ScenePlan]], example: str
) -> None:
    """Both paper experiments and the kit: the tree, in BehaviorTree.CPP, does the
    plan's actions exactly (no more: nothing went wrong) and reaches the goal."""
    xml, result = exported[example]
    run, world = tick(xml, result)
    assert run.success, run
    assert off_target(result, world) == []
    assert world.held is None
    assert run.actions == len(result.chosen.plan)


@pytest.mark.parametrize("example", ["set_table", "blocks", "kitting"])
def test_the_tree_follows_the_plan_and_honours_the_learned_order(
    exported: dict[str, tuple[str, ScenePlan]], example: str
) -> None:
    """The subgoal Fallbacks come in an order where every learned precedence
    holds; their moves, read in document order, are the plan's actions."""
    xml, result = exported[example]
    root = fromstring(xml)
    task = next(t for t in root.iter("BehaviorTree") if t.get("ID") == "Task")
    subgoals = [
        f.get("name", "").split(":")[0].removeprefix("subgoal ")
        for f in task.iter("Fallback")
        if f.get("name", "").startswith("subgoal ")
    ]
    chosen = result.chosen
    for before, after in chosen.problem.candidate.precedences:
        if before in subgoals and after in subgoals:
            assert subgoals.index(before) < subgoals.index(after), (before, after)
    body = next(c for c in task if c.tag == "Sequence")
    moves = []
    for child in body:
        if child.get("name") == "the goal holds":
            continue
        for node in child.iter("SubTree"):
            kind = node.get("ID")
            if kind == "MoveToFree":
                moves += [("GRASP", node.get("object")), ("PUT_DOWN", node.get("object"))]
            elif kind in ("Grasp", "PutDown"):
                moves.append(("GRASP" if kind == "Grasp" else "PUT_DOWN", node.get("object")))
    assert moves == [(a.kind, a.object) for a in chosen.plan.actions]


def test_every_port_given_is_declared_in_the_tree_nodes_model(
    exported: dict[str, tuple[str, ScenePlan]],
) -> None:
    """The engine does not check a SubTree's attributes against its model (it
    remaps any): this does, for every tree, and that each leaf is declared."""
    declared_leaves = {n.leaf for n in NODES}
    for xml, _ in exported.values():
        root = fromstring(xml)
        model = root.find("TreeNodesModel")
        assert model is not None
        ports = {m.get("ID"): {p.get("name") for p in m} for m in model if m.tag == "SubTree"}
        leaves = {m.get("ID") for m in model if m.tag in ("Action", "Condition")}
        assert leaves == declared_leaves
        assert set(ports) == {n.id for n in NODES}
        for node in root.iter("SubTree"):
            given_ports = set(node.attrib) - {"ID", "name"}
            assert given_ports <= ports[node.get("ID")], (node.get("ID"), given_ports)


def test_a_leaf_the_engine_does_not_know_is_an_error_at_load(
    exported: dict[str, tuple[str, ScenePlan]],
) -> None:
    """A load is a test: a tree naming a leaf nothing registered is refused
    before the engine sees it."""
    xml, result = exported["blocks"]
    with pytest.raises(InputError, match="<GraspActon> in tree 'Grasp': an unknown node type"):
        tick(xml.replace("<GraspAction", "<GraspActon"), result)


def test_plan_only_is_the_flat_sequence_of_the_plan() -> None:
    model, scene = _examples()["blocks"]
    xml, result = behaviour_tree(model, scene, plan_only=True)
    root = fromstring(xml)
    task = next(t for t in root.iter("BehaviorTree") if t.get("ID") == "Task")
    assert [n.tag for n in task.iter()].count("Fallback") == 0
    steps = [(n.get("ID"), n.get("object")) for n in task.iter("SubTree")]
    assert steps == [
        ("Grasp" if a.kind == "GRASP" else "PutDown", a.object) for a in result.chosen.plan.actions
    ]
    run, world = tick(xml, result)
    assert run.success and off_target(result, world) == []


@pytest.mark.parametrize("fault", ["drop", "misplace", "grasp", "displace"])
@pytest.mark.parametrize("example", ["set_table", "blocks", "kitting"])
def test_the_fallbacks_recover_from_one_fault(
    exported: dict[str, tuple[str, ScenePlan]], example: str, fault: str
) -> None:
    """One fault, at the second action (a put-down: drop and misplace; the first
    for a grasp), or after the third (displace): the tree still reaches the goal,
    with more actions than the plan where it had to redo one."""
    xml, result = exported[example]
    action = {"drop": 2, "misplace": 2, "grasp": 1, "displace": 3}[fault]
    run, world = tick(xml, result, schedule={action: fault})
    assert [f.kind for f in run.injected] in ([fault], [])
    assert run.success, run
    assert off_target(result, world) == []
    if fault in ("drop", "grasp") and run.injected:
        assert run.actions > len(result.chosen.plan)


def test_a_grasp_that_keeps_missing_fails_the_tree_with_the_reason(
    exported: dict[str, tuple[str, ScenePlan]],
) -> None:
    xml, result = exported["set_table"]
    misses = {k: "grasp" for k in range(1, ATTEMPTS + 1)}
    run, _ = tick(xml, result, schedule=misses)
    assert not run.success
    assert run.failure == FailureKind.GRASP
    first = next(
        f for f in fromstring(xml).iter("Fallback") if f.get("name", "").startswith("subgoal")
    )
    assert run.failed_subgoal == first.get("name", "").split(":")[0].removeprefix("subgoal ")
    assert len(run.injected) == ATTEMPTS


def test_attempts_bound_the_retries() -> None:
    """One missed grasp: a tree with one attempt per subgoal fails with it, one
    with two recovers."""
    model, scene = _examples()["blocks"]
    for attempts, recovers in ((1, False), (2, True)):
        xml, result = behaviour_tree(
            model, scene, attempts=attempts, budget=Budget(timeout=math.inf)
        )
        assert f'num_attempts="{attempts}"' in xml
        run, world = tick(xml, result, schedule={1: "grasp"})
        assert run.success is recovers
        if recovers:
            assert off_target(result, world) == []
        else:
            assert run.failure == FailureKind.GRASP


def test_an_object_on_a_target_fails_the_tree_as_a_new_object(
    exported: dict[str, tuple[str, ScenePlan]],
) -> None:
    xml, result = exported["blocks"]
    run, world = tick(xml, result, schedule={2: "block"})
    assert [f.kind for f in run.injected] == ["block"]
    assert not run.success
    assert run.failure == FailureKind.NEW_OBJECT
    assert world.injected_objects[0] in run.failure_detail


@settings(
    max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True
)
@given(example=st.sampled_from(["set_table", "blocks", "kitting"]), seed=st.integers(0, 10_000))
def test_with_random_faults_never_success_off_target(
    exported: dict[str, tuple[str, ScenePlan]], example: str, seed: int
) -> None:
    """Every fault kind at once: the tree either reaches the goal (checked) or
    fails naming one of the executor's failure kinds and the subgoal."""
    xml, result = exported[example]
    faults = Faults(drop=0.2, displace=0.1, misplace=0.1, grasp=0.1, block=0.05)
    run, world = tick(xml, result, faults=faults, seed=seed)
    if run.success:
        assert off_target(result, world) == []
    else:
        assert run.failure in {k.value for k in FailureKind}
        assert run.failed_subgoal


@settings(
    max_examples=4, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True
)
@given(seed=st.integers(0, 1000))
def test_generated_tables_for_two_tick_to_success(seed: int) -> None:
    """A table laid for two (roles of identical plates, forks…), in a generated
    scene: the tree names the scene's instances and reaches the goal; with
    faults, it reaches it or fails with a failure kind, never SUCCESS off target."""
    rng = np.random.default_rng(seed)
    orders = [
        {k: rng.permutation(2).tolist() for k in ("plate", "fork", "knife", "glass")}
        for _ in range(3)
    ]
    taught = table_for_two(rng, orders)
    model = learn(taught.demonstrations)
    scene: Scene = table_scene(rng, {k: rng.permutation(2).tolist() for k in orders[0]})
    xml, result = behaviour_tree(model, scene, budget=Budget(timeout=math.inf))
    task = next(t for t in fromstring(xml).iter("BehaviorTree") if t.get("ID") == "Task")
    named = {n.get("object") for n in task.iter("SubTree")}
    assert named <= {obj.name for obj in scene.objects}
    run, world = tick(xml, result)
    assert run.success, run
    assert off_target(result, world) == []
    faults = Faults(drop=0.2, displace=0.1, grasp=0.1, block=0.05)
    run, world = tick(xml, result, faults=faults, seed=seed)
    if run.success:
        assert off_target(result, world) == []
    else:
        assert run.failure in {k.value for k in FailureKind}


def test_the_command_writes_the_tree_and_refuses_without_a_plan(tmp_path: Path) -> None:
    """exit 0 and a tree that loads; a scene with no plan: exit 3, the reason, no file."""
    model_path = tmp_path / "blocks.json"
    save_model(paper_model("blocks"), model_path)
    out = tmp_path / "task.xml"
    runner = CliRunner()
    scene = EXAMPLES / "scenes" / "pyramid-fig4.json"
    result = runner.invoke(app, ["export", "bt", str(model_path), str(scene), "-o", str(out)])
    assert result.exit_code == 0, result.stderr
    assert out.read_text().startswith("<?xml")
    assert "goal of demonstration 2" in result.stderr
    _, result_in_library = behaviour_tree(paper_model("blocks"), scene)
    run, world = tick(out.read_text(), result_in_library)
    assert run.success and off_target(result_in_library, world) == []
    ran = runner.invoke(app, ["run", "--bt", str(out), str(model_path), str(scene)])
    assert ran.exit_code == 0, ran.stderr
    assert "SUCCESS after 8 actions" in ran.stderr
    missing_hand = ["--faults", "grasp=1"]
    ran = runner.invoke(app, ["run", "--bt", str(out), str(model_path), str(scene), *missing_hand])
    assert ran.exit_code == 3
    assert ran.stderr.splitlines()[-1].startswith("demoplan: error: the tree failed (subgoal ")
    assert ": grasp: " in ran.stderr
    data = json.loads(scene.read_text())
    data["freespace"] = []
    no_room = tmp_path / "no-room.json"
    no_room.write_text(json.dumps(data))
    missing = tmp_path / "none.xml"
    result = runner.invoke(app, ["export", "bt", str(model_path), str(no_room), "-o", str(missing)])
    assert result.exit_code == 3, result.stderr
    assert "no plan" in result.stderr.lower() or "cannot" in result.stderr.lower()
    assert not missing.exists()


def test_the_drawing_has_a_row_per_node_of_the_main_tree(
    exported: dict[str, tuple[str, ScenePlan]], tmp_path: Path
) -> None:
    pytest.importorskip("matplotlib")
    from demoplan.plotting.behaviour_tree import save_behaviour_tree, tree_rows

    xml, _ = exported["kitting"]
    task = next(t for t in fromstring(xml).iter("BehaviorTree") if t.get("ID") == "Task")
    nodes = list(task.iter())[1:]
    rows = tree_rows(xml)
    assert len(rows) == len(nodes)
    parents = {child: parent for parent in task.iter() for child in parent}
    for row, node in zip(rows, nodes, strict=True):
        expected = parents[node]
        assert (row.parent == -1) == (expected is task)
        if row.parent >= 0:
            assert nodes[row.parent] is expected
    picture = tmp_path / "tree.png"
    save_behaviour_tree(xml, picture)
    assert picture.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_tree_ticks_with_the_floating_hand_in_mujoco(
    exported: dict[str, tuple[str, ScenePlan]],
) -> None:
    """Experiment 2 in physics (``run --bt --sim mujoco``): the same leaves bound to
    the floating hand reach the goal, each object within the tolerance."""
    pytest.importorskip("mujoco")
    from demoplan.execution.physics import MujocoWorld

    xml, result = exported["blocks"]
    world = MujocoWorld(result.scene, Faults(), 0)
    try:
        run = run_behaviour_tree(xml, world)
        final = world.observe()
    finally:
        world.close()
    assert run.success, run
    problem = result.chosen.problem
    for obj, location in problem.problem.goal:
        target = pose_of(problem.location(location))
        assert math.dist(final.poses[obj].position, target.position) <= TOLERANCE, obj


def test_a_tree_grasping_what_the_world_cannot_take_is_refused_before_moving(
    exported: dict[str, tuple[str, ScenePlan]],
) -> None:
    """An object the scene does not have (a hand-edited tree), and, in MuJoCo,
    objects too thin for the floating hand's pads: one InputError, nothing moved."""
    xml, result = exported["blocks"]
    world = KinematicWorld(result.scene)
    with pytest.raises(InputError, match="'redd', which the scene does not have"):
        run_behaviour_tree(xml.replace('object="red"', 'object="redd"'), world)
    assert world.actions == 0
    first_x = re.search(r'x="[^"]*"', xml)
    assert first_x is not None
    bad_number = xml[: first_x.start()] + 'x="abc"' + xml[first_x.end() :]
    with pytest.raises(InputError, match="x='abc': a number of metres within 1000 m expected"):
        run_behaviour_tree(bad_number, world)
    assert world.actions == 0
    pytest.importorskip("mujoco")
    from demoplan.execution.physics import MujocoWorld

    xml, result = exported["set_table"]
    hand = MujocoWorld(result.scene, Faults(), 0)
    try:
        with pytest.raises(InputError, match="cannot be carried out by this robot: napkin"):
            run_behaviour_tree(xml, hand)
    finally:
        hand.close()


def test_the_tree_ticks_with_the_arm(
    exported: dict[str, tuple[str, ScenePlan]], tmp_path: Path
) -> None:
    """Experiment 2 on the 6-DOF arm (``run --bt --sim arm``), standing where it
    reaches the tree's targets: the goal reached, each object within 1 cm."""
    for module in ("mujoco", "dm_control", "mink"):
        pytest.importorskip(module)
    from demoplan.commands.export import run_tree

    xml, result = exported["blocks"]
    tree = tmp_path / "pyramid.xml"
    tree.write_text(xml)
    run = run_tree(
        tree, paper_model("blocks"), EXAMPLES / "scenes" / "pyramid-fig4.json", sim="arm"
    )
    assert run.success, run
    problem = result.chosen.problem
    for obj, location in problem.problem.goal:
        target = pose_of(problem.location(location))
        assert math.dist(run.final.poses[obj].position, target.position) <= TOLERANCE, obj
