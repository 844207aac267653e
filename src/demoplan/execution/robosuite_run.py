"""``demoplan run MODEL --sim robosuite:ENV``: the task carried out in a robosuite
environment, the scene observed there after ``reset(seed)``, and the run
judged by robosuite as well as by demoplan.

A run is a success only when both agree: demoplan's executor reached a
demonstrated goal *and* robosuite's ``_check_success()`` holds after it. A
run robosuite judges failed is never reported as a success.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

from demoplan.errors import UsageError
from demoplan.execution.executor import ExecutionSettings, RunEvent, RunReport, execute
from demoplan.execution.faults import Faults
from demoplan.execution.frames import FrameWriter
from demoplan.execution.robosuite_frames import FramedRobosuiteWorld, SceneCamera
from demoplan.execution.robosuite_scene import (
    CONTROL_FREQUENCY,
    check_installed,
    environment_name,
)
from demoplan.execution.world import World
from demoplan.model import TaskModel
from demoplan.scenes.prepared import prepare

__all__ = ["JudgedRunReport", "is_robosuite", "run_in_robosuite"]


def is_robosuite(sim: str) -> bool:
    """Whether ``sim`` names a robosuite environment (``robosuite:ENV``)."""
    return sim.startswith("robosuite:")


@dataclass(frozen=True, slots=True, kw_only=True)
class JudgedRunReport(RunReport):
    """A run report with robosuite's verdict beside demoplan's: ``success`` is
    demoplan's reached goal and robosuite's ``_check_success()`` together."""

    env_success: bool
    """robosuite's ``_check_success()`` after the run."""
    demoplan_success: bool
    """Whether demoplan's executor reached a demonstrated goal."""
    control_steps: int = 0
    """The environment's control steps (20 per simulated second)."""

    def to_json(self) -> dict[str, Any]:
        return RunReport.to_json(self) | {
            "env_success": self.env_success,
            "demoplan_success": self.demoplan_success,
            "control_steps": self.control_steps,
        }


def run_in_robosuite(
    model: TaskModel,
    sim: str,
    *,
    seed: int = 0,
    settings: ExecutionSettings | None = None,
    faults: Faults = Faults(),
    clutter: bool = False,
    frames: Path | None = None,
    on_event: Callable[[RunEvent], object] | None = None,
) -> JudgedRunReport:
    """Carry ``model``'s task out in robosuite's ``sim`` (``robosuite:ENV``)
    reset with ``seed``: observe, plan, act, replan (as :func:`execute`),
    then ask robosuite whether the task is done. ``frames``: a folder for a
    frame at the start, after each action and at the end, rendered by MuJoCo
    (:mod:`demoplan.execution.robosuite_frames`), and their storyboard."""
    name = environment_name(sim)
    if faults != Faults():
        raise UsageError(f"--faults: --sim {sim} injects none (robosuite's world is its own)")
    check_installed(sim)
    writer = FrameWriter(frames) if frames is not None else None  # matplotlib first
    from demoplan.execution.robosuite_world import RobosuiteWorld

    world = RobosuiteWorld(name, seed)
    camera = SceneCamera(world.env)
    try:
        prepared = prepare(model, world.scene(f"{sim} (seed {seed})"), clutter=clutter)
        acting: World = world
        heard = on_event
        if writer is not None:
            writer.scene = prepared.scene
            acting = framed = FramedRobosuiteWorld(world, writer, camera)
            heard = framed.heard(on_event)
        report = execute(model, prepared, acting, settings or ExecutionSettings(), heard)
        if writer is not None:
            framed.capture_end(report.final)
        judged = world.env_success()
        steps = world.hand.steps
    finally:
        camera.close()
        world.close()
    values = {f.name: getattr(report, f.name) for f in fields(report)}
    values |= {
        "success": report.success and judged,
        "world": sim,
        "motions_refused": tuple(world.motion_failures),
        "simulated_seconds": steps / CONTROL_FREQUENCY,
        "frames": tuple(str(p) for p in writer.written) if writer is not None else (),
    }
    if report.success and not judged:
        values["reason"] = f"robosuite's success check fails after demoplan's {report.reason}"
    return JudgedRunReport(
        **values, env_success=judged, demoplan_success=report.success, control_steps=steps
    )
