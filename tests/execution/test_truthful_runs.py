"""A run that did not reach its goal is never reported as a success: not in
`run`'s summary, not in `--json`, not in the events a live display reads; and
its reason names what went wrong first, not the last thing the replanner tried."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from demoplan.cli import app
from demoplan.execution.executor import MAX_SAME_GRASP, ExecutionSettings, execute
from demoplan.execution.faults import Faults
from demoplan.execution.kinematic import KinematicWorld
from demoplan.execution.report import RunEvent
from demoplan.learning.modelfile import save_model
from demoplan.model import Pose, TaskModel
from demoplan.scenes.prepared import prepare
from demoplan.scenes.scene import Scene, complete_geometry, load_scene
from tests.support.helpers import EXAMPLES, paper_model

BLOCKS = EXAMPLES / "scenes" / "pyramid-fig4.json"


@pytest.fixture(scope="module")
def blocks() -> TaskModel:
    return paper_model("blocks/demonstrations.json")


@pytest.fixture(scope="module")
def scene(blocks: TaskModel) -> Scene:
    return complete_geometry(load_scene(BLOCKS), blocks)


def test_a_forced_failure_is_failed_in_the_terminal_and_in_json(
    blocks: TaskModel, tmp_path: Path
) -> None:
    """Every grasp misses (`--faults grasp=1`): the summary says FAILED, stderr
    gives the cause in one line, `--json` says failed with the exit code, 4
    (docs/limits.md: a limit reached — here the grasps to try)."""
    model = tmp_path / "blocks.model.json"
    save_model(blocks, model)
    args = ["run", str(model), str(BLOCKS), "--faults", "grasp=1"]
    shown = CliRunner().invoke(app, args)
    assert shown.exit_code == 4, shown.output
    verdict = shown.stdout.strip().splitlines()[-1]
    assert verdict.startswith("FAILED: ") and "success" not in verdict
    error = shown.stderr.strip().splitlines()
    assert len(error) == 1 and error[0].startswith("demoplan: error: ")
    assert " could not be grasped in 6 attempts (grasps tried: across 0° at " in error[0]
    printed = CliRunner().invoke(app, [*args, "--json"])
    assert printed.exit_code == 4
    report = json.loads(printed.stdout)
    assert (report["success"], report["status"], report["exit_code"]) == (False, "failed", 4)
    assert error[0] == f"demoplan: error: {report['reason']}"


class _ReachShrinks(KinematicWorld):
    """A world whose grasps miss at the first actions, and whose robot, from
    the ``shrinks_at``-th action on, reaches nothing: the replan after the
    misses is refused, as the arm refused the user's lunch box (a sandwich
    to be put down out of its reach) after the apple slipped three times."""

    def __init__(self, scene: Scene, misses: int, shrinks_at: int):
        super().__init__(scene, schedule={k: "grasp" for k in range(1, misses + 1)})
        self.shrinks_at = shrinks_at

    def why_not_reachable(self, obj: str, pose: Pose) -> str | None:
        if self.actions < self.shrinks_at:
            return None
        return f"at ({pose.position[0]:.3f}, {pose.position[1]:.3f}) is out of the arm's reach"


def test_the_reason_names_the_grasp_that_failed_not_the_refused_replan(
    blocks: TaskModel, scene: Scene
) -> None:
    """The first grasp misses three times; the replan that would take another
    grasp is refused by the robot's check. The reason leads with the grasp
    (the object, the attempts, the grasp tried with its place and count), then
    says the new plan was refused; exit 3 (no plan from the observed world)."""
    world = _ReachShrinks(scene, MAX_SAME_GRASP, MAX_SAME_GRASP)
    events: list[RunEvent] = []
    report = execute(blocks, prepare(blocks, scene, clutter=True), world, on_event=events.append)
    first = report.actions[0].action.object
    start = scene.object(first).pose.position
    assert not report.success and report.exit_code == 3
    assert report.reason.startswith(
        f"{first} could not be grasped in 3 attempts (grasp tried: across "
    )
    assert f"at ({start[0]:.3f}, {start[1]:.3f}) 3 times); then the new plan " in report.reason
    assert "cannot be carried out by this robot: " in report.reason
    assert report.reason.index("could not be grasped") < report.reason.index("out of the arm's")
    done = events[-1]
    assert (done.kind, done.status) == ("done", "failed")
    assert done.text == f"FAILED: {report.reason}"


def test_a_run_that_ends_on_a_refused_motion_names_it(blocks: TaskModel, scene: Scene) -> None:
    """A failure the robot noticed itself (a world's ``motion_failures``: the
    arm's refused motions) is part of the failure and of the reason."""

    class Refusing(KinematicWorld):
        motion_failures: list[str]

        def put_down(self, obj: str, pose: Pose) -> None:
            if pose == self.picked_from:  # back where it was taken: that motion is made
                super().put_down(obj, pose)
                return
            self.actions += 1  # holds on: the motion is refused, nothing moves
            self.motion_failures.append(f"the arm would swing near {pose.position[0]:.3f}")

    world = Refusing(scene)
    world.motion_failures = []
    report = execute(
        blocks, prepare(blocks, scene, clutter=True), world, ExecutionSettings(max_replans=2)
    )
    assert not report.success and report.exit_code == 4
    failure = report.failures[-1]
    assert failure.kind == "release" and failure.note.startswith("the arm would swing near ")
    assert report.reason.startswith(f"step {failure.step}: release: ")
    assert f"({failure.note}) (3 times); then gave up after 2 replans" in report.reason


def test_a_grasp_the_arm_refused_says_the_arm_never_went(blocks: TaskModel, scene: Scene) -> None:
    """A grasp whose motion the robot refused (a world's ``motion_failures``) is
    reported as a motion not made — ``X was not grasped: the arm refused the motion
    (why)`` — not only as an object missing from the hand; the run then goes on."""

    class RefusingOnce(KinematicWorld):
        motion_failures: list[str]

        def grasp(self, obj: str, axis: float, where: Pose | None = None) -> None:
            if not self.motion_failures:  # the first grasp: refused, nothing moves
                self.actions += 1
                self.motion_failures.append("the arm would swing through a new posture")
                return
            super().grasp(obj, axis, where)

    world = RefusingOnce(scene)
    world.motion_failures = []
    report = execute(blocks, prepare(blocks, scene, clutter=True), world)
    assert report.success
    (failure,) = report.failures
    obj = report.actions[failure.step - 1].action.object
    assert failure.kind == "grasp"
    assert failure.detail == (
        f"{obj} was not grasped: the arm refused the motion "
        "(the arm would swing through a new posture)"
    )
    assert failure.note == "the arm would swing through a new posture"


class _RefusingGrasps(KinematicWorld):
    """A world whose arm refuses every grasp of ``obj`` across the finger axes
    ``axes`` (modulo 180°) — its check is deterministic: the same motion is
    refused every time — and makes every other motion."""

    def __init__(self, scene: Scene, obj: str, axes: set[float] | None):
        super().__init__(scene)
        self.obj, self.axes = obj, axes
        self.motion_failures: list[str] = []
        self.attempts: list[tuple[str, float]] = []

    def grasp(self, obj: str, axis: float, where: Pose | None = None) -> None:
        self.attempts.append((obj, axis % 180.0))
        if obj == self.obj and (self.axes is None or axis % 180.0 in self.axes):
            self.actions += 1  # refused: nothing moves
            self.motion_failures.append(f"the arm would swing through a new posture ({axis:g}°)")
            return
        super().grasp(obj, axis, where)


def test_a_refused_grasp_is_not_tried_again_another_grasp_is(
    blocks: TaskModel, scene: Scene
) -> None:
    """A grasp whose motion the arm refused was retried unchanged up to
    MAX_SAME_GRASP times (the same motion, refused each time) before another
    grasp was planned: now the replan takes another grasp at once, and the
    report counts the refusal once."""
    first = execute(blocks, prepare(blocks, scene, clutter=True), KinematicWorld(scene))
    obj = first.actions[0].action.object
    world = _RefusingGrasps(scene, obj, {0.0})
    report = execute(blocks, prepare(blocks, scene, clutter=True), world)
    assert report.success, report.reason
    assert len(world.motion_failures) == 1, world.motion_failures
    (failure,) = report.failures
    assert failure.kind == "grasp" and failure.detail.startswith(f"{obj} was not grasped: ")
    tried = [axis for name, axis in world.attempts if name == obj]
    assert tried[0] == 0.0 and tried[1] != 0.0, tried


def test_an_object_whose_every_grasp_the_arm_refuses_is_given_up_on_at_once(
    blocks: TaskModel, scene: Scene
) -> None:
    """Each grasp of the object refused once, then the run stops naming it
    (exit 4), not after three refusals of each."""
    first = execute(blocks, prepare(blocks, scene, clutter=True), KinematicWorld(scene))
    obj = first.actions[0].action.object
    world = _RefusingGrasps(scene, obj, None)
    report = execute(blocks, prepare(blocks, scene, clutter=True), world)
    assert not report.success and report.exit_code == 4
    tried = [axis for name, axis in world.attempts if name == obj]
    assert len(tried) == len(set(tried)) == len(world.motion_failures), tried
    assert f"then gave up on {obj}: the arm refused each of its grasps at (" in report.reason
    assert report.reason.startswith(f"{obj} could not be grasped in {len(tried)} attempts")


def test_a_run_that_succeeds_says_so_in_its_last_event(blocks: TaskModel, scene: Scene) -> None:
    events: list[RunEvent] = []
    report = execute(
        blocks,
        prepare(blocks, scene, clutter=True),
        KinematicWorld(scene, Faults()),
        on_event=events.append,
    )
    assert report.success and report.status == "succeeded"
    assert (events[-1].kind, events[-1].status, events[-1].text) == (
        "done",
        "succeeded",
        report.reason,
    )
    assert report.to_json()["status"] == "succeeded" and report.to_json()["exit_code"] == 0


def test_places_out_of_reach_are_one_reason_whatever_their_number() -> None:
    """One place out of reach: its reason; two: the first's reason and the
    other counted (grammatical for one); without a world that tells why
    several are (too far apart), never a reason per place."""
    from types import SimpleNamespace

    from demoplan.execution.executor import _out_of_reach
    from demoplan.planning.problem import Action

    where = {"loc1": (0.1, 0.1), "loc2": (0.9, 0.1), "loc3": (0.9, 0.5), "loc4": (0.5, 0.3)}
    problem: Any = SimpleNamespace(
        location=lambda name: SimpleNamespace(position=(*where[name], 0.0), yaw=0.0)
    )
    far = {"loc2", "loc3"}

    def reachable(obj: str, pose: Pose) -> str | None:
        x, y = pose.position[:2]
        name = next(n for n, p in where.items() if p == (x, y))
        return f"at ({x:.3f}, {y:.3f}) is out of the arm's reach" if name in far else None

    actions = [
        Action("GRASP", "cup", "loc1", "grasp1"),
        Action("PUT_DOWN", "cup", "loc2", "grasp1"),
        Action("GRASP", "pen", "loc4", "grasp2"),
        Action("PUT_DOWN", "pen", "loc3", "grasp2"),
    ]
    world: Any = SimpleNamespace()  # tells nothing about places together
    (line,) = _out_of_reach(world, actions, problem, reachable)
    assert line == (
        "cup put down at (0.900, 0.100) is out of the arm's reach; "
        "so is 1 more of the plan's 4 places (pen)"
    )
    far = {"loc2"}
    assert _out_of_reach(world, actions, problem, reachable) == [
        "cup put down at (0.900, 0.100) is out of the arm's reach"
    ]
