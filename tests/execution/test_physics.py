"""Experiment 2 in MuJoCo (`demoplan run --sim mujoco`): real grasps, a stack that holds."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import pytest
from typer.testing import CliRunner

from demoplan.cli import app
from demoplan.execution.executor import execute
from demoplan.execution.faults import parse_faults
from demoplan.learning.modelfile import save_model
from demoplan.model import TaskModel
from demoplan.scenes.prepared import prepare
from demoplan.scenes.scene import Scene, complete_geometry, load_scene
from tests.support.helpers import EXAMPLES, paper_model

os.environ.setdefault("MUJOCO_GL", "egl")  # before MuJoCo is imported: headless rendering
pytest.importorskip("mujoco", reason="MuJoCo is not installed (pip install -e '.[sim]')")

from demoplan.execution.physics import MujocoWorld

SCENE = EXAMPLES / "scenes" / "pyramid-fig4.json"


@pytest.fixture(scope="module")
def blocks() -> tuple[TaskModel, Scene]:
    model = paper_model("blocks/demonstrations.json")
    return model, complete_geometry(load_scene(SCENE), model)


@pytest.fixture(scope="module")
def model_file(blocks: tuple[TaskModel, Scene], tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("model") / "blocks.json"
    save_model(blocks[0], path)
    return path


def test_the_scene_is_simulated_as_given(blocks: tuple[TaskModel, Scene]) -> None:
    """After settling, every block rests where the scene says (red on green and wood)."""
    _, scene = blocks
    observed = MujocoWorld(scene).observe()
    for obj in scene.objects:
        assert math.dist(observed.poses[obj.name].position, obj.pose.position) < 0.002, obj.name


def test_experiment_2_builds_the_pyramid(blocks: tuple[TaskModel, Scene]) -> None:
    """§V.B in physics: from the scrambled start the pyramid stands, red on top,
    every block within 1 cm of its target, and the stack still stands 2 s later."""
    model, scene = blocks
    world = MujocoWorld(scene)
    report = execute(model, prepare(model, scene, clutter=True), world)
    assert report.success, (report.reason, report.failures)
    assert report.goal == 1  # demonstration 2's goal: 4 moves
    assert max(report.pose_errors.values()) < 0.01
    red, wood, green = (report.final.poses[n].position for n in ("red", "wood", "green"))
    assert red[2] == pytest.approx(0.04, abs=0.003)  # on top of the other two
    assert wood[2] == pytest.approx(0.0, abs=0.002) and green[2] == pytest.approx(0.0, abs=0.002)
    world._settle(2.0)
    later = world.observe()
    assert math.dist(later.poses["red"].position, red) < 0.002  # the stack holds


def test_the_grasp_is_physical(blocks: tuple[TaskModel, Scene]) -> None:
    """Closing the fingers beside a block lifts nothing; on it, the block rises with the hand."""
    _, scene = blocks
    world = MujocoWorld(scene, parse_faults("grasp=1"))
    world.grasp("red", 0.0)
    assert world.observe().held is None
    assert world.observe().poses["red"].position[2] == pytest.approx(0.04, abs=0.003)
    world = MujocoWorld(scene)
    world.grasp("red", 90.0)
    observed = world.observe()
    assert observed.held == "red" and "red" not in observed.poses
    assert world.data.xpos[world._body("red")][2] > 0.08


@pytest.mark.parametrize("kind", ["drop", "displace", "misplace", "grasp"])
def test_faults_in_physics_are_recovered(blocks: tuple[TaskModel, Scene], kind: str) -> None:
    model, scene = blocks
    at = {"drop": 4, "displace": 4, "misplace": 4, "grasp": 3}[kind]
    world = MujocoWorld(scene, schedule={at: kind})
    report = execute(model, prepare(model, scene, clutter=True), world)
    assert [f.kind for f in world.injected] == [kind]
    assert report.success and max(report.pose_errors.values()) < 0.01
    assert report.replans >= 1 or kind == "drop"  # a drop that lands on target needs none


def test_run_mujoco_cli(blocks: tuple[TaskModel, Scene], tmp_path: Path) -> None:
    model_path = tmp_path / "blocks.json"
    save_model(blocks[0], model_path)
    result = CliRunner().invoke(
        app,
        [
            "run",
            str(model_path),
            str(SCENE),
            "--sim",
            "mujoco",
            "--json",
            "--frames",
            str(tmp_path / "f"),
        ],
    )
    assert result.exit_code == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["success"] and data["world"] == "mujoco"
    assert (tmp_path / "f" / "storyboard.png").exists()


@pytest.mark.parametrize("height_mm", [10, 12, 14, 16])
def test_the_graspable_check_agrees_with_the_physics(height_mm: int) -> None:
    """The pre-run check says what the simulated hand does: a box it calls too
    thin is not lifted off a clear table; one it accepts is lifted and placed."""
    from demoplan.model import Pose
    from demoplan.scenes.scene import scene_from_document

    document = {
        "format": "demoplan/scene-1",
        "objects": {
            "box": {"position": [0.3, 0.1, 0], "yaw": 0, "size": [0.05, 0.08, height_mm / 1000]},
            "other": {"position": [0.6, 0.4, 0], "yaw": 0, "size": [0.04, 0.04, 0.04]},
        },
    }
    world = MujocoWorld(scene_from_document(document, "generated"))
    try:
        refused = world.why_not_graspable("box")
        world.grasp("box", 0.0)
        lifted = world.observe().held == "box"
        world.put_down("box", Pose((0.4, 0.2, 0.0)))
        end = world.observe().poses["box"]
        placed = math.dist(end.position[:2], (0.4, 0.2)) < 0.01
    finally:
        world.close()
    assert (refused is None) == lifted == placed, (refused, lifted, placed)


def test_a_task_the_gripper_cannot_take_stops_before_any_motion(tmp_path: Path) -> None:
    """The kit's 1 cm pcb and 5 mm manual: one line naming both, exit 1, no
    grasp tried (before: 26 failed grasps and exit 4)."""
    model = tmp_path / "kit.json"
    runner = CliRunner()
    demos = EXAMPLES / "kitting" / "demonstrations.json"
    learned = runner.invoke(app, ["learn", str(demos), "-o", str(model)])
    assert learned.exit_code == 0, learned.stderr
    scene = EXAMPLES / "kitting" / "scene-manual-on-motor.json"
    result = runner.invoke(app, ["run", str(model), str(scene), "--sim", "mujoco", "--json"])
    assert result.exit_code == 1
    assert result.stderr.count("\n") == 1 and result.stdout == ""
    assert "pcb is 10 mm tall" in result.stderr and "manual is 5 mm tall" in result.stderr


def test_run_records_a_video_from_a_fixed_camera(model_file: Path, tmp_path: Path) -> None:
    """--video: an MP4 (imageio-ffmpeg's own ffmpeg) of the whole run at 20
    frames per simulated second, from one camera that does not move: the first
    and last frames differ only where the blocks moved (the pyramid is built)."""
    imageio_ffmpeg = pytest.importorskip("imageio_ffmpeg")
    import numpy as np

    video = tmp_path / "run.mp4"
    result = CliRunner().invoke(
        app, ["run", str(model_file), str(SCENE), "--sim", "mujoco", "--video", str(video)]
    )
    assert result.exit_code == 0, result.stderr
    frames = imageio_ffmpeg.read_frames(str(video))
    meta = next(frames)
    width, height = meta["size"]
    images = [np.frombuffer(f, np.uint8).reshape(height, width, 3) for f in frames]
    assert meta["fps"] == 20 and len(images) >= 100  # seconds of simulated motion
    first, last = images[0].astype(int), images[-1].astype(int)
    changed = np.abs(first - last).sum(axis=2) > 60
    assert 0.001 < changed.mean() < 0.2  # the blocks moved; the view did not
    assert [p.name for p in tmp_path.iterdir()] == ["run.mp4"]  # no partial file left


def test_video_needs_physics_and_an_mp4(model_file: Path, tmp_path: Path) -> None:
    runner = CliRunner()
    kinematic = runner.invoke(app, ["run", str(model_file), str(SCENE), "--video", "a.mp4"])
    assert kinematic.exit_code == 2 and "--sim mujoco" in kinematic.stderr
    avi = runner.invoke(
        app, ["run", str(model_file), str(SCENE), "--sim", "mujoco", "--video", "a.avi"]
    )
    assert avi.exit_code == 2 and ".mp4" in avi.stderr
    assert not (tmp_path / "a.mp4").exists()


def test_renders_mark_the_targets(blocks: tuple[TaskModel, Scene]) -> None:
    """show_targets: a translucent box of the object's size and colour where it
    should go — drawn only (the simulation does not change), so the start of
    a storyboard differs from its end."""
    import numpy as np

    from demoplan.model import Pose

    _, scene = blocks
    world = MujocoWorld(scene)
    try:
        before = world.render()
        if before is None:
            pytest.skip("MuJoCo cannot render here")
        state = world.observe().poses
        world.show_targets({"red": Pose((0.45, 0.12, 0.0))})
        after = world.render()
        assert after is not None
        changed = np.abs(after.astype(int) - before.astype(int)).sum(axis=2) > 30
        assert 0.001 < changed.mean() < 0.05  # a small box appears, nothing else moves
        assert world.observe().poses == state
    finally:
        world.close()
