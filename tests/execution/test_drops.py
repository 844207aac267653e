"""What falls lands on what is below it: a drop over a landmark with a size (a
lunch box, a tray) lands on its top, in the kinematic world and in the MuJoCo
worlds — not at z = 0 inside the box; and never across its edge."""

from __future__ import annotations

import importlib.util
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.execution.kinematic import KinematicWorld
from demoplan.model import Pose, footprint
from demoplan.scenes.scene import Scene, scene_from_document

BLOCK = [0.04, 0.04, 0.04]


def _scene(box: list[float], box_yaw: float = 0.0) -> Scene:
    """A 4 cm block to be carried from (0.30, −0.20) to (0.50, 0.20), across a
    landmark box of ``box`` (size) standing at (0.40, 0) between the two."""
    return scene_from_document(
        {
            "format": "demoplan/scene-1",
            "objects": {"red": {"position": [0.30, -0.20, 0], "size": BLOCK}},
            "landmarks": {
                "lunchbox": {
                    "position": [0.40, 0.0, 0],
                    "yaw": box_yaw,
                    "shape": "box",
                    "size": box,
                }
            },
        },
        "scene.json",
    )


TARGET = Pose((0.50, 0.20, 0.0))


def _dropped(world: Any) -> Pose:
    """Where red lands when the world drops it on the way to :data:`TARGET`."""
    world.grasp("red", 0.0, world.observe().poses["red"])
    world.put_down("red", TARGET)
    seen = world.observe()
    assert [f.kind for f in world.injected] == ["drop"] and seen.held is None
    return seen.poses["red"]


def test_a_block_dropped_over_the_lunch_box_lands_on_its_top() -> None:
    """The box (30 × 30 × 3 cm) covers the whole way the drop may happen on (20–80 %)."""
    pose = _dropped(KinematicWorld(_scene([0.30, 0.30, 0.03]), schedule={2: "drop"}))
    assert pose.position[2] == pytest.approx(0.03)
    assert 0.26 < pose.position[0] < 0.54 and -0.14 < pose.position[1] < 0.14


@settings(max_examples=60, deadline=None)
@given(
    width=st.floats(0.05, 0.4),
    depth=st.floats(0.05, 0.4),
    height=st.floats(0.005, 0.1),
    yaw=st.floats(-90.0, 90.0),
    seed=st.integers(0, 1000),
)
def test_a_dropped_block_rests_on_the_box_or_on_the_table_never_across_its_edge(
    width: float, depth: float, height: float, yaw: float, seed: int
) -> None:
    """Over boxes of every size and turn: where the block lands, its outline is
    inside the box's and it stands on the box's top, or outside it and on the
    table."""
    scene = _scene([width, depth, height], yaw)
    world = KinematicWorld(scene, seed=seed, schedule={2: "drop"})
    pose = _dropped(world)
    (_, box_pose) = scene.landmarks[0]
    box = footprint(dict(scene.landmark_geometry)["lunchbox"], box_pose.position, yaw)
    block = footprint(scene.objects[0].geometry, pose.position, pose.yaw)  # type: ignore[arg-type]
    covered = block.intersection(box).area / block.area
    if pose.position[2] > 0:
        assert pose.position[2] == pytest.approx(height) and covered == pytest.approx(1.0)
    else:
        assert covered == pytest.approx(0.0, abs=1e-9)


@pytest.mark.skipif(importlib.util.find_spec("mujoco") is None, reason="MuJoCo not installed")
@pytest.mark.parametrize("sim", ["mujoco", "arm"])
def test_in_the_physics_a_dropped_block_lands_on_the_box(sim: str) -> None:
    """The physics lets the block go low over the spot the kinematic rules
    chose — over the box's top, not inside it — and it comes to rest there,
    upright."""
    if sim == "arm" and importlib.util.find_spec("mink") is None:
        pytest.skip("mink is not installed")
    from demoplan.execution.arm import ArmWorld
    from demoplan.execution.physics import MujocoWorld

    scene = _scene([0.30, 0.30, 0.03])
    world: Any
    if sim == "arm":
        world = ArmWorld(scene, schedule={2: "drop"}, workspace=[TARGET.position[:2]])
    else:
        world = MujocoWorld(scene, schedule={2: "drop"})
    try:
        pose = _dropped(world)
        assert world.injected[0].position[2] == pytest.approx(0.03)  # where it was to land
        assert pose.position[2] == pytest.approx(0.03, abs=0.003), pose
        assert abs(pose.orientation[0]) < 0.02 and abs(pose.orientation[1]) < 0.02  # upright
    finally:
        world.close()
