"""``run``: a learned task carried out in simulation (paper §IV.C, execution
with replanning). The perception commands (``perceive``, ``calibrate``) are in
:mod:`demoplan.commands.perception`."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

from demoplan.budget import Clock
from demoplan.commands.inputs import model_named, task_and_scene
from demoplan.errors import UsageError
from demoplan.execution.executor import ExecutionSettings, RunEvent, RunReport, execute
from demoplan.execution.faults import Faults
from demoplan.execution.runner import run_task
from demoplan.execution.video_output import check_video_path
from demoplan.execution.world import World
from demoplan.fileio import refuse_overwriting_inputs, staged_folder
from demoplan.model import TaskModel
from demoplan.scenes.plan import building_within
from demoplan.scenes.prepared import prepare
from demoplan.scenes.scene import Scene

__all__ = [
    "remove_unfinished_video",
    "run",
]


def run(
    model: TaskModel | str | Path,
    scene: Scene | str | Path | None,
    *,
    world: World | None = None,
    sim: str = "kinematic",
    faults: Faults = Faults(),
    seed: int = 0,
    perception: str = "state",
    settings: ExecutionSettings | None = None,
    clutter: bool = False,
    frames: Path | None = None,
    video: Path | None = None,
    on_event: Callable[[RunEvent], object] | None = None,
) -> RunReport:
    """Carry the task out: plan, act, observe, replan where the world differs.

    Without ``world``, in a simulated one (``sim``: ``kinematic``, ``mujoco``
    or ``arm``, with injected ``faults`` drawn from ``seed``; or
    ``robosuite:ENV``, robosuite's environment reset with ``seed``, whose
    objects are the scene: ``scene`` None, and robosuite judges the run too,
    :mod:`demoplan.execution.robosuite_run`); with ``world``,
    in that one — it must start as ``scene`` describes (that is where a real
    robot plugs in). ``frames``: a folder for a frame per action and a
    storyboard, written whole or not at all; ``video``: an MP4 of the run;
    ``settings``: tolerances, the replans allowed and each (re)planning's
    budget (default: :class:`~demoplan.execution.executor.ExecutionSettings`'s);
    ``clutter``: objects the model never saw are allowed (no goal; moved only
    when in the way);
    ``on_event`` hears the run's progress."""
    if sim.startswith("robosuite:"):
        renders = [("--video", video), ("--perception", perception != "state")]
        if unsupported := [name for name, given in renders if given]:
            raise UsageError(
                f"{', '.join(unsupported)}: not with --sim {sim} (it renders --frames only)"
            )
        return _run_in_robosuite(
            model, scene, sim, seed, settings, faults, clutter, frames, on_event
        )
    if scene is None:
        raise UsageError("a SCENE is needed (only --sim robosuite:ENV observes its own)")
    if video is not None:
        check_video_path(video)
        if frames is not None and video.resolve().is_relative_to(frames.resolve()):
            raise UsageError(
                f"--video {video} lies in the --frames folder {frames}, which is written whole "
                "or not at all; a video path outside it expected"
            )
        refuse_overwriting_inputs(
            video, [Path(p) for p in (model, scene) if isinstance(p, str | Path)]
        )
    settings = settings or ExecutionSettings()
    task, start = task_and_scene(model, scene)
    with model_named(model):
        with building_within(Clock(settings.budget)):  # checked and completed once
            prepared = prepare(task, start, clutter=clutter, settings=settings.geometry)
        if world is not None:
            return execute(task, prepared, world, settings, on_event=on_event)
        options: dict[str, Any] = {
            "sim": sim,
            "faults": faults,
            "seed": seed,
            "perception": perception,
            "settings": settings,
            "on_event": on_event,
            "video": video,
        }
        if frames is None:
            return run_task(task, prepared, **options)
        # The frames folder whole or not at all: built beside it, swapped in at the end.
        with staged_folder(frames, "demoplan run --frames") as building:
            report = run_task(task, prepared, frames=building, **options)
        moved = tuple(str(frames / Path(f).name) for f in report.frames)  # where they now are
        return replace(report, frames=moved)


def _run_in_robosuite(
    model: TaskModel | str | Path,
    scene: Scene | str | Path | None,
    sim: str,
    seed: int,
    settings: ExecutionSettings | None,
    faults: Faults,
    clutter: bool,
    frames: Path | None,
    on_event: Callable[[RunEvent], object] | None,
) -> RunReport:
    """``run`` in robosuite: the scene is the environment's; ``frames`` rendered
    by MuJoCo (the folder written whole or not at all)."""
    from demoplan.execution.robosuite_run import run_in_robosuite
    from demoplan.learning.modelfile import load_model

    if scene is not None:
        raise UsageError(f"--sim {sim} observes its scene after reset(seed); no SCENE expected")
    task = model if isinstance(model, TaskModel) else load_model(model)
    options: dict[str, Any] = {"seed": seed, "settings": settings, "faults": faults}
    options |= {"clutter": clutter, "on_event": on_event}
    with model_named(model):
        if frames is None:
            return run_in_robosuite(task, sim, **options)
        with staged_folder(frames, "demoplan run --frames") as building:
            report = run_in_robosuite(task, sim, frames=building, **options)
        moved = tuple(str(frames / Path(f).name) for f in report.frames)
        return replace(report, frames=moved)


def remove_unfinished_video(video: Path) -> None:
    """Remove what a run killed while recording ``video`` (SIGKILL: no cleanup
    of its own) left beside it — its private part folders, nothing else."""
    import shutil

    from demoplan.execution.video_output import partial_folders

    for folder in partial_folders(video):
        shutil.rmtree(folder, ignore_errors=True)
