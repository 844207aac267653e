"""What the arm carries: its check before a run (a trial carry in the same
MuJoCo simulation) against the physics of the run, over objects of every size,
shape and mass; household weights are refused before the arm moves."""

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
from demoplan.learning.modelfile import save_model
from demoplan.model import WOOD_DENSITY, ObjectGeometry, Pose, TaskModel
from demoplan.scenes.scene import complete_geometry, load_scene
from tests.helpers import EXAMPLES, paper_model

os.environ.setdefault("MUJOCO_GL", "egl")
pytest.importorskip("mujoco", reason="MuJoCo is not installed (pip install -e '.[sim]')")
pytest.importorskip("mink", reason="mink is not installed (pip install -e '.[sim]')")

from demoplan.execution.arm import ArmWorld, carries, why_not_carried

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


@pytest.mark.parametrize(
    ("name", "shape", "size", "mass"),
    [
        ("bowl", "cylinder", (0.15, 0.15, 0.07), 0.4),
        ("mug", "cylinder", (0.08, 0.08, 0.1), 0.3),
        ("plate", "cylinder", (0.25, 0.25, 0.02), 0.35),
    ],
)
def test_household_weights_are_refused_before_the_arm_moves(
    name: str, shape: str, size: tuple[float, float, float], mass: float
) -> None:
    """The suction cup does not carry a 0.4 kg bowl, a 0.3 kg mug or a 0.35 kg
    plate: the check says so, and the physics agrees (the arm drops it or
    never lifts it, at the object's own mass, where the trial did not go)."""
    geometry = ObjectGeometry(shape, size, mass)
    why = why_not_carried(geometry)
    assert why is not None and f"weighs {mass:g} kg" in why
    assert carries(geometry, Pose((0.35, 0.12, 0.0)), Pose((0.45, -0.1, 0.0))) != (True, True)


def test_a_heavy_object_in_a_run_is_refused_in_one_line(blocks: TaskModel, tmp_path: Path) -> None:
    """Experiment 2 with red weighing 0.3 kg (a mug's weight, steel of its size):
    exit 1, one line naming red and its weight, before any motion."""
    data = json.loads(BLOCKS.read_text())
    data["objects"]["red"]["mass"] = 0.3
    scene, model = tmp_path / "heavy.json", tmp_path / "blocks.json"
    scene.write_text(json.dumps(data))
    save_model(blocks, model)
    result = CliRunner().invoke(app, ["run", str(model), str(scene), "--sim", "arm"])
    assert result.exit_code == 1, result.output
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and "red weighs 0.3 kg; the suction cup" in lines[0], lines


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
    st.floats(math.log(0.005), math.log(0.5)).map(math.exp),  # kg, log-uniform
)
REFUSED_BEYOND = 2.0
"""How much heavier a refused object is tried at the test's own places (see
:func:`_check_agrees_with_the_physics`)."""
WOODEN_BLOCK = ObjectGeometry("box", (0.04, 0.04, 0.04))
BOWL = ObjectGeometry("cylinder", (0.15, 0.15, 0.07), 0.4)
ACROSS = (_pose(0.35, -30.0, 0.0), _pose(0.45, 25.0, 60.0))


def _check_agrees_with_the_physics(shape: ObjectGeometry, where: tuple[Pose, Pose]) -> None:
    """Accepted: lifted and carried to a place the check's trial never went.
    Refused: the same object twice as heavy is not carried there either. The
    check tries 1.25 times the mass at its own places; near the cup's limit a
    load's fate depends on the motion (docs/execution.md), so elsewhere a
    refused object may still go at 1.25 times — found here once: a 0.13 kg
    tray carried at 0.165 kg between two places, dropped at 0.197 kg — but
    never at twice: the check is never more cautious than that."""
    pick, place = where
    accepted = why_not_carried(shape) is None
    event("accepted" if accepted else "refused")
    if accepted:
        assert carries(shape, pick, place) == (True, True), (shape, pick, place)
    else:
        heavier = replace(shape, mass=REFUSED_BEYOND * shape.kg)
        assert carries(heavier, pick, place) != (True, True), (shape, pick, place)


@settings(
    max_examples=2, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow]
)
@given(shape=_objects, where=_placements())
@example(shape=WOODEN_BLOCK, where=ACROSS)  # both sides, every run
@example(shape=BOWL, where=ACROSS)
def test_the_check_agrees_with_the_physics(shape: ObjectGeometry, where: tuple[Pose, Pose]) -> None:
    _check_agrees_with_the_physics(shape, where)


@pytest.mark.slow
@settings(
    max_examples=40, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow]
)
@given(shape=_objects, where=_placements())
def test_the_check_agrees_with_the_physics_at_length(
    shape: ObjectGeometry, where: tuple[Pose, Pose]
) -> None:
    _check_agrees_with_the_physics(shape, where)
