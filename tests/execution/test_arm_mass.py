"""What the arm carries: its choice of tool and its check before a run (trial
carries in the same MuJoCo simulation) against the physics of the run, over
objects of every size, shape and mass; household weights carried by the
fingers, or refused before the arm moves."""

from __future__ import annotations

import json
import math
import os
from dataclasses import replace
from pathlib import Path

import pytest
from hypothesis import HealthCheck, event, example, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from demoplan.cli import app
from demoplan.documents.masses import MAX_DENSITY
from demoplan.model import WOOD_DENSITY, ObjectGeometry, Pose, TaskModel
from demoplan.scenes.scene import Scene, SceneObject, complete_geometry, load_scene
from tests.support.helpers import EXAMPLES, paper_model

os.environ.setdefault("MUJOCO_GL", "egl")
pytest.importorskip("mujoco", reason="MuJoCo is not installed (pip install -e '.[sim]')")
pytest.importorskip("mink", reason="mink is not installed (pip install -e '.[sim]')")

from demoplan.execution.arm import ArmWorld, Tool, carries, choose_tool

TOOLS: tuple[Tool, ...] = ("suction", "fingers")

BLOCKS = EXAMPLES / "scenes" / "pyramid-fig4.json"


@pytest.fixture(scope="module")
def blocks() -> TaskModel:
    return paper_model("blocks/demonstrations.json")


def test_the_physics_gives_each_object_its_mass(blocks: TaskModel) -> None:
    scene = complete_geometry(load_scene(BLOCKS), blocks)
    heavy = replace(scene.objects[0], geometry=replace(scene.objects[0].geometry, mass=0.123))
    world = ArmWorld(replace(scene, objects=(heavy, *scene.objects[1:])))
    masses = {name: float(world.model.body_mass[world._body(name)]) for name in world.names}
    assert masses[heavy.name] == pytest.approx(0.123)
    for name in world.names[1:]:
        assert masses[name] == pytest.approx(WOOD_DENSITY * 0.04**3)


HOUSEHOLD = {  # plausible sizes (m) and weights (kg): stoneware
    "bowl": ObjectGeometry("cylinder", (0.14, 0.14, 0.06), 0.4),
    "mug": ObjectGeometry("cylinder", (0.08, 0.08, 0.095), 0.4),
    "plate": ObjectGeometry("cylinder", (0.24, 0.24, 0.02), 0.5),
}
HOUSEHOLD_TOOLS = {"bowl": None, "mug": "fingers", "plate": None}
"""All three too heavy for the 10 mm suction cup with its margin (it carries
0.44 kg at most, 0.35 kg through every motion of a run); the mug fits
between the fingers (8 of their 8.5 cm), the bowl and the plate do not."""


@pytest.mark.parametrize("name", sorted(HOUSEHOLD))
def test_household_weights_go_by_the_tool_that_carries_them(name: str) -> None:
    """A 0.4 kg mug goes by the fingers; a 0.4 kg bowl and a 0.5 kg plate are
    refused, saying their weight and their width against the fingers'
    stroke — and the physics agrees, where the check's trial did not go: the
    mug is carried by the fingers; the bowl and the plate by neither tool
    through the motions of a run (the cup's hardest, the half turn behind the
    base before a top camera's picture, included)."""
    geometry = HOUSEHOLD[name]
    choice = choose_tool(geometry)
    assert choice.tool == HOUSEHOLD_TOOLS[name], choice
    pick, place = Pose((0.35, 0.12, 0.0)), Pose((0.45, -0.1, 0.0))
    if choice.tool is not None:
        assert carries(geometry, pick, place, choice.tool, choice.axis) == (True, True)
        return
    assert choice.why is not None and f"weighs {geometry.kg:g} kg" in choice.why
    assert f"{100 * geometry.size[0]:.1f} cm across" in choice.why
    for tool in TOOLS:
        assert not _carried_past_a_park(geometry, pick, place, tool), tool


def _carried_past_a_park(shape: ObjectGeometry, pick: Pose, place: Pose, tool: Tool) -> bool:
    """The arm takes ``shape`` at ``pick`` with ``tool``, turns round behind its
    base (:meth:`ArmWorld.park`) and back, and puts it down at ``place`` within 1 cm."""
    world = ArmWorld(Scene(objects=(SceneObject("load", pick, shape),), robot=(0.0, 0.0, 0.0)))
    try:
        world.tools["load"] = tool
        world.grasp("load", 0.0)
        if world.observe().held != "load":
            return False
        world.park()
        world.put_down("load", place)
        seen = world.observe()
        pose = seen.poses.get("load")
        return (
            seen.held is None
            and pose is not None
            and math.dist(pose.position, place.position) < 0.01
        )
    finally:
        world.close()


def test_the_arm_changes_tools_between_objects() -> None:
    """The mug by the fingers, then a wooden block by the cup (the jaws drawn
    up again): each lifted by the tool chosen for it and put down within 1 cm
    of its place, the arm touching nothing but its load."""
    shapes = {"mug": HOUSEHOLD["mug"], "block": WOODEN_BLOCK}
    starts = {"mug": Pose((0.35, -0.15, 0.0)), "block": Pose((0.45, -0.1, 0.0))}
    targets = {"mug": Pose((0.35, 0.15, 0.0)), "block": Pose((0.45, 0.1, 0.0))}
    scene = Scene(
        objects=tuple(SceneObject(name, starts[name], shapes[name]) for name in shapes),
        robot=(0.0, 0.0, 0.0),
    )
    world = ArmWorld(scene)
    try:
        for name, tool in (("mug", "fingers"), ("block", "suction")):
            world.grasp(name, 0.0)
            assert world.observe().held == name and world.tool == tool
            world.put_down(name, targets[name])
            seen = world.observe()
            assert seen.held is None
            assert math.dist(seen.poses[name].position, targets[name].position) < 0.01
        assert world.collisions == [] and world.motion_failures == []
    finally:
        world.close()


@pytest.fixture(scope="module")
def household(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A model that puts the bowl, the mug and the plate each at its place
    (three demonstrations, in two orders), written where the runs read it."""
    folder = tmp_path_factory.mktemp("household")
    targets = {"plate": (0.30, 0.20), "bowl": (0.30, -0.15), "mug": (0.50, 0.0)}
    objects = {
        name: {"shape": shape.shape, "size": list(shape.size)} for name, shape in HOUSEHOLD.items()
    }
    demonstrations = [
        {
            "name": f"d{k + 1}",
            "objects": objects,
            "steps": [
                {"object": name, "position": [targets[name][0] + dx, targets[name][1] + dy]}
                for name in (["plate", "bowl", "mug"] if k % 2 == 0 else ["mug", "bowl", "plate"])
            ],
        }
        for k, (dx, dy) in enumerate([(0.0, 0.0), (0.004, -0.003), (-0.003, 0.004)])
    ]
    (folder / "demos.json").write_text(
        json.dumps({"format": "demoplan/demonstrations-1", "demonstrations": demonstrations})
    )
    result = CliRunner().invoke(
        app, ["learn", str(folder / "demos.json"), "-o", str(folder / "model.json")]
    )
    assert result.exit_code == 0, result.output
    (folder / "targets.json").write_text(json.dumps(targets))
    return folder


@pytest.mark.parametrize("name", sorted(HOUSEHOLD))
def test_household_objects_are_carried_or_refused_in_a_run(household: Path, name: str) -> None:
    """``run --sim arm`` with ``name`` away from its place (the others at
    theirs, so only it is moved): the mug is taken by the fingers and carried
    to its place (success, within 1 cm); the bowl and the plate are refused
    before the arm moves, in one line naming the object, its weight and its width."""
    targets = json.loads((household / "targets.json").read_text())
    start = {"plate": (0.56, 0.22), "bowl": (0.56, -0.18), "mug": (0.36, 0.02)}
    objects = {
        other: {
            "position": [*(start[other] if other == name else targets[other]), 0.0],
            "shape": shape.shape,
            "size": list(shape.size),
            "mass": shape.kg,
        }
        for other, shape in HOUSEHOLD.items()
    }
    scene = household / f"{name}-away.json"
    scene.write_text(json.dumps({"format": "demoplan/scene-1", "objects": objects}))
    result = CliRunner().invoke(
        app, ["run", str(household / "model.json"), str(scene), "--sim", "arm", "--json"]
    )
    if HOUSEHOLD_TOOLS[name] is None:
        assert result.exit_code == 1, result.output
        lines = result.output.strip().splitlines()
        assert len(lines) == 1 and f"{name} weighs {HOUSEHOLD[name].kg:g} kg" in lines[0], lines
        assert "cm across" in lines[0] and "suction cup" in lines[0]
        return
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout)
    assert report["success"], report
    assert [action[:2] for action in report["actions"]] == [
        ["GRASP", name],
        ["PUT_DOWN", name],
    ]
    assert report["collisions"] == []


def _pose(distance: float, angle: float, yaw: float) -> Pose:
    a, half = math.radians(angle), math.radians(yaw) / 2
    return Pose(
        (distance * math.cos(a), distance * math.sin(a), 0.0),
        (0.0, 0.0, math.sin(half), math.cos(half)),
    )


def _placements() -> st.SearchStrategy[tuple[Pose, Pose]]:
    """A place to take an object from and one to put it, 30–50 cm from the
    arm's base (at the origin facing +x), on either side of its front, the
    one to the right or to the left (at least 18 cm apart)."""
    right = st.builds(_pose, st.floats(0.3, 0.5), st.floats(-45.0, -18.0), st.floats(-90, 90))
    left = st.builds(_pose, st.floats(0.3, 0.5), st.floats(18.0, 45.0), st.floats(-90, 90))
    return st.one_of(st.tuples(right, left), st.tuples(left, right))


_objects = st.builds(
    lambda shape, x, y, z, mass: ObjectGeometry(shape, (x, y, z), mass),
    st.sampled_from(["box", "cylinder"]),
    st.floats(0.02, 0.12),
    st.floats(0.02, 0.12),
    st.floats(0.01, 0.12),
    st.floats(math.log(0.005), math.log(2.0)).map(math.exp),  # kg, log-uniform
).filter(lambda shape: shape.kg / shape.volume <= MAX_DENSITY)  # no solid is denser
REFUSED_BEYOND = 2.0
"""How much heavier a refused object is tried at the test's own places (see
:func:`_check_agrees_with_the_physics`)."""
WOODEN_BLOCK = ObjectGeometry("box", (0.04, 0.04, 0.04))
BOWL = ObjectGeometry("cylinder", (0.15, 0.15, 0.07), 0.4)
MUG = ObjectGeometry("cylinder", (0.08, 0.08, 0.1), 0.4)
ACROSS = (_pose(0.35, -30.0, 0.0), _pose(0.45, 25.0, 60.0))


def _check_agrees_with_the_physics(shape: ObjectGeometry, where: tuple[Pose, Pose]) -> None:
    """Accepted: lifted and carried by the tool chosen to a place the
    check's trials never went. Refused: the same object twice as heavy is
    carried there by neither the suction cup nor the fingers. Not at 1.25
    times, the mass the check tries: its margin covers the half turn behind
    the base (park), which these carries do not make, so between two places
    a refused object may still go (the cup carries 0.44 kg there, 0.35 kg
    through a park; docs/execution.md) — but never at twice: the check is
    never more cautious than that."""
    pick, place = where
    choice = choose_tool(shape)
    event(f"by the {choice.tool}" if choice.tool else "refused")
    if choice.tool is not None:
        carried = carries(shape, pick, place, choice.tool, choice.axis)
        assert carried == (True, True), (shape, choice, pick, place)
    else:
        heavier = replace(shape, mass=REFUSED_BEYOND * shape.kg)
        for tool in ("suction", "fingers"):
            carried = carries(heavier, pick, place, tool, choice.axis)
            assert carried != (True, True), (shape, tool, pick, place)


@settings(
    max_examples=2, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow]
)
@given(shape=_objects, where=_placements())
@example(shape=WOODEN_BLOCK, where=ACROSS)  # both sides, every run
@example(shape=BOWL, where=ACROSS)
@example(shape=MUG, where=ACROSS)
def test_the_check_agrees_with_the_physics(shape: ObjectGeometry, where: tuple[Pose, Pose]) -> None:
    _check_agrees_with_the_physics(shape, where)


@pytest.mark.slow
@settings(
    max_examples=10, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow]
)  # Four objects by the cup, four by the fingers (across either axis), two refused (0.6 and
# 1 kg). Draws 11-15 of 16 were the tenth mutated (the same 1 kg box by the fingers, its
# places moved by centimetres) and the 16th a third refused cylinder: 18 s of CPU, no new case.
@given(shape=_objects, where=_placements())
def test_the_check_agrees_with_the_physics_at_length(
    shape: ObjectGeometry, where: tuple[Pose, Pose]
) -> None:
    _check_agrees_with_the_physics(shape, where)
