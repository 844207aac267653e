"""``demoplan run``: a world, the executor, a live display and frames, wired together."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from demoplan.errors import InputError, UsageError
from demoplan.execution.executor import (
    ExecutionSettings,
    RunEvent,
    RunReport,
    execute,
    first_plan,
    first_targets,
)
from demoplan.execution.faults import Faults
from demoplan.execution.kinematic import KinematicWorld
from demoplan.execution.video_output import VideoOutput
from demoplan.execution.world import World
from demoplan.fileio import output_target
from demoplan.model import TaskModel
from demoplan.scenes.plan import ChosenPlan
from demoplan.scenes.prepared import PreparedScene
from demoplan.scenes.scene import Scene

if TYPE_CHECKING:
    from demoplan.execution.frames import FrameWriter

__all__ = ["make_world", "run_task", "start_world"]


MAX_SIMULATED_OBJECTS = 1000
"""Most objects a physics world (``--sim mujoco``, ``arm``) is built with: each
is a free body that the world lets settle before the run (500 took 3.5 s,
2000 took 20 s on the shared machine; 20,000 would take minutes, outside any
planning budget). ``--sim kinematic`` has no such limit."""


def _check_simulated_size(sim: str, scene: Scene) -> None:
    if sim in ("mujoco", "arm") and len(scene.objects) > MAX_SIMULATED_OBJECTS:
        raise InputError(
            f"{len(scene.objects):,} objects; --sim {sim} simulates at most "
            f"{MAX_SIMULATED_OBJECTS:,} (each a free body settled before the run: 2000 took "
            "20 s); --sim kinematic has no such limit",
            source=scene.source,
            field="objects",
        )


def make_world(
    sim: str,
    scene: Scene,
    faults: Faults,
    seed: int,
    perception: str = "state",
    workspace: Sequence[tuple[float, float]] = (),
) -> World:
    """The simulated world ``sim`` (``kinematic``, ``mujoco`` or ``arm``) set up as
    ``scene``, observed through its state or (``perception="camera"``, MuJoCo)
    its top camera; ``workspace``: the (x, y) points the arm must reach besides
    the objects (the plan's targets), where it places its base."""
    if perception not in ("state", "camera"):
        raise UsageError(f"--perception {perception}: expected state or camera")
    _check_simulated_size(sim, scene)
    if sim == "kinematic":
        if perception == "camera":
            raise UsageError("--perception camera needs --sim mujoco (a world that renders)")
        return KinematicWorld(scene, faults, seed)
    if sim in ("mujoco", "arm"):
        from demoplan.execution.physics import MujocoWorld

        world: MujocoWorld
        if sim == "arm":
            from demoplan.execution.arm import ArmWorld

            world = ArmWorld(scene, faults, seed, workspace=workspace)
        else:
            world = MujocoWorld(scene, faults, seed)
        if perception == "camera":
            from demoplan.execution.camera_world import CameraWorld

            return CameraWorld(world, scene)
        return world
    raise UsageError(f"--sim {sim}: expected kinematic, mujoco or arm")


def start_world(
    model: TaskModel,
    prepared: PreparedScene,
    sim: str,
    faults: Faults,
    seed: int,
    settings: ExecutionSettings,
    perception: str = "state",
) -> tuple[World, ChosenPlan | None]:
    """The world of a run (:func:`make_world`), and for the arm the first plan
    too: the arm stands where it reaches that plan's targets, and the executor
    starts from it (``execute(first=…)``) instead of planning it again."""
    scene = prepared.scene
    _check_simulated_size(sim, scene)  # before the arm's first plan
    if sim != "arm":
        return make_world(sim, scene, faults, seed, perception), None
    first = first_plan(model, prepared, settings)
    workspace = [pose.position[:2] for _, pose in first_targets(first)]
    return make_world(sim, scene, faults, seed, perception, workspace), first


def run_task(
    model: TaskModel,
    prepared: PreparedScene,
    *,
    sim: str = "kinematic",
    faults: Faults = Faults(),
    seed: int = 0,
    frames: Path | None = None,
    perception: str = "state",
    settings: ExecutionSettings | None = None,
    on_event: Callable[[RunEvent], object] | None = None,
    video: Path | None = None,
) -> RunReport:
    """Run the task in a simulated world set up as the ``prepared`` scene
    (objects the model never saw allowed where it was prepared so: as in
    ``plan``, they get no goal and are moved only when in the way); ``on_event``
    hears the run's progress (plans, actions, failures, replans: a live display
    is the caller's);
    ``frames``: a folder for a frame per action and a storyboard;
    ``video``: an MP4 of the run from the fixed overview camera (``sim``
    ``mujoco``; written whole or not at all);
    ``settings``: tolerances, the replans allowed and the budget of each
    (re)planning (default: :class:`~demoplan.execution.executor.ExecutionSettings`'s)."""
    scene = prepared.scene
    if video is not None and sim not in ("mujoco", "arm"):
        raise UsageError("--video records the physics simulation: it needs --sim mujoco or arm")
    settings = settings or ExecutionSettings()
    world, first = start_world(model, prepared, sim, faults, seed, settings, perception)
    recording: VideoOutput | None = None
    finished = False
    try:  # from here on the world is closed and the video finished or removed however it ends
        if video is not None:
            recording = VideoOutput(output_target(video, stream_ok=False)[0])
            _start_video(world, recording)
        writer = None
        if frames is not None:
            from demoplan.execution.frames import FrameWriter

            writer = FrameWriter(frames, scene=scene)
        heard = _listener(world, writer, on_event)
        report = execute(model, prepared, _FramedWorld(world, writer), settings, heard, first)
        simulated: Any = getattr(world, "world", world)
        # the run as it ended, before the robot steps out of the picture
        ended = replace(
            report,
            world=world.name,
            collisions=tuple(getattr(simulated, "collisions", ())),
            motions_refused=tuple(getattr(simulated, "motion_failures", ())),
            simulated_seconds=getattr(simulated, "simulated", None),
        )
        if writer is not None or recording is not None:
            _step_aside(simulated)
        written: tuple[str, ...] = ()
        if writer is not None:
            writer.capture(report.final, "end", _picture(world))
            writer.storyboard()
            written = tuple(str(p) for p in writer.written)
        finished = True
    finally:
        _close_world(world, recording, finished)
    return replace(ended, frames=written)


def _step_aside(simulator: Any) -> None:
    """The robot out of the picture once the run is over, so that the end frame
    and the video's last seconds show what it did rather than the arm over the
    thing it put down last: a simulator that parks (the arm turned round
    behind its base, the floating hand beside the table) does. It is no part
    of the task: the report is the run's as it ended, and a park the arm's
    checks refuse leaves it where it stands."""
    park = getattr(simulator, "park", None)
    if park is not None:
        park()


def _start_video(world: World, output: VideoOutput) -> None:
    """Start recording ``world`` into ``output``'s private folder beside the video
    (:class:`~demoplan.execution.video_output.VideoOutput`; the file is put at its
    target once the run is finished: :func:`_close_world`). A recording that
    cannot start is an input error. However it ends — an error, or a Ctrl-C while
    ffmpeg starts — the caller closes the world first (ffmpeg stopped) and then
    removes the folder: removed while ffmpeg was still opening its file, the
    folder could be left behind with that file in it."""
    simulator: Any = getattr(world, "world", world)  # a camera world films through its own
    try:
        simulator.record_video(output.recording)
    except (OSError, RuntimeError) as exc:  # ffmpeg could not start or open the file
        raise output.error(_first_line(exc)) from None


def _listener(
    world: World,
    writer: FrameWriter | None,
    on_event: Callable[[RunEvent], object] | None,
) -> Callable[[RunEvent], None]:
    """What hears the executor's events: the world's renders are shown the
    targets, the frames get the start and the failures, then ``on_event``."""

    def heard(event: RunEvent) -> None:
        show = getattr(getattr(world, "world", world), "show_targets", None)
        if show is not None and event.kind in ("plan", "replan"):
            show(dict(event.targets))  # the renders mark where the objects should go
        if writer is not None:
            if event.kind == "plan" and not writer.frames:  # the start, with its targets
                writer.targets = dict(event.targets)
                writer.capture(world.observe(), "start", _picture(world))
            elif event.kind == "failure":
                writer.mark_failure(event.text)
        if on_event is not None:
            on_event(event)

    return heard


class _FramedWorld:
    """``world`` as the executor acts on it, capturing a frame after each action
    (the world observed as the executor sees it) where there is a ``writer``."""

    def __init__(self, world: World, writer: FrameWriter | None) -> None:
        self._world = world
        self._writer = writer
        self.name = world.name

    def observe(self) -> Any:
        return self._world.observe()

    def grasp(self, obj: str, axis: float, where: Any = None) -> None:
        self._world.grasp(obj, axis, where)
        self._frame(f"GRASP {obj}")

    def put_down(self, obj: str, pose: Any) -> None:
        self._world.put_down(obj, pose)
        self._frame(f"PUT_DOWN {obj}")

    def between_actions(self, upcoming: Any = ()) -> None:
        self._world.between_actions(upcoming)

    def why_not_graspable(self, obj: str) -> str | None:
        check = getattr(self._world, "why_not_graspable", None)
        return None if check is None else check(obj)

    def why_not_reachable(self, obj: str, pose: Any) -> str | None:
        check = getattr(self._world, "why_not_reachable", None)
        return None if check is None else check(obj, pose)

    def why_not_reachable_together(self, places: Any) -> str | None:
        check = getattr(self._world, "why_not_reachable_together", None)
        return None if check is None else check(places)

    @property
    def injected(self) -> Any:  # the simulated world's faults, for the report
        return getattr(self._world, "injected", ())

    @property
    def motion_failures(self) -> Any:  # what the robot noticed (executor.ROBOT_NOTES)
        return getattr(self._world, "motion_failures", ())

    @property
    def grasp_problems(self) -> Any:
        return getattr(self._world, "grasp_problems", ())

    def _frame(self, caption: str) -> None:
        writer = self._writer
        if writer is not None:
            writer.capture(
                self._world.observe(), f"{len(writer.frames)}: {caption}", _picture(self._world)
            )


def _close_world(world: World, recording: VideoOutput | None, finished: bool) -> None:
    """Close ``world`` (which also finishes its video) and put the recording
    at its target when the run ``finished`` and the video is complete, else
    remove it; a video that failed on the way (a full disk, ffmpeg gone) is
    an input error when the run finished."""
    close = getattr(world, "close", None)
    try:
        if close is not None:
            close()  # also finishes the video
    except (OSError, RuntimeError) as exc:  # ffmpeg failed on the way (a full disk)
        if recording is not None:
            error = recording.error(_first_line(exc))  # before the partial file goes
            recording.discard()
            if finished:
                raise error from None
        return
    if recording is not None:
        if finished:
            recording.finish()
        else:
            recording.discard()


def _first_line(exc: BaseException) -> str:
    return (str(exc).strip().splitlines() or [type(exc).__name__])[0]


def _picture(world: World) -> Any:
    """The world's own rendering, when it makes one (MuJoCo); else None."""
    render = getattr(world, "render", None)
    return None if render is None else render()
