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
from typing import Any

from demoplan.errors import UsageError
from demoplan.execution.executor import ExecutionSettings, RunEvent, RunReport, execute
from demoplan.execution.faults import Faults
from demoplan.execution.robosuite_scene import (
    CONTROL_FREQUENCY,
    check_installed,
    environment_name,
)
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
    on_event: Callable[[RunEvent], object] | None = None,
) -> JudgedRunReport:
    """Carry ``model``'s task out in robosuite's ``sim`` (``robosuite:ENV``)
    reset with ``seed``: observe, plan, act, replan (as :func:`execute`),
    then ask robosuite whether the task is done."""
    name = environment_name(sim)
    if faults != Faults():
        raise UsageError(f"--faults: --sim {sim} injects none (robosuite's world is its own)")
    check_installed(sim)
    from demoplan.execution.robosuite_world import RobosuiteWorld

    world = RobosuiteWorld(name, seed)
    try:
        prepared = prepare(model, world.scene(f"{sim} (seed {seed})"), clutter=clutter)
        report = execute(model, prepared, world, settings or ExecutionSettings(), on_event)
        judged = world.env_success()
        steps = world.hand.steps
    finally:
        world.close()
    values = {f.name: getattr(report, f.name) for f in fields(report)}
    values |= {
        "success": report.success and judged,
        "world": sim,
        "motions_refused": tuple(world.motion_failures),
        "simulated_seconds": steps / CONTROL_FREQUENCY,
    }
    if report.success and not judged:
        values["reason"] = f"robosuite's success check fails after demoplan's {report.reason}"
    return JudgedRunReport(
        **values, env_success=judged, demoplan_success=report.success, control_steps=steps
    )
