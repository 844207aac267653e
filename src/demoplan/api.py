"""The whole loop in three calls: ``learn``, ``plan``, ``run``.

>>> import demoplan
>>> model = demoplan.learn(["examples/blocks"], settings=demoplan.PAPER_SETTINGS)
>>> result = demoplan.plan(model, "examples/scenes/pyramid-fig4.json")
>>> [len(c.plan) if c.plan else None for c in result.candidates]  # 5 and 4 moves
[10, 8]
>>> report = demoplan.run(model, "examples/scenes/pyramid-fig4.json")
>>> report.success
True

Each takes paths or the objects they name; ``run`` drives a simulated world,
or — with ``world=`` — any object with the :class:`~demoplan.execution.world.World`
protocol: that is where a real robot plugs in (observe, grasp, put down).
The shell twin: ``demoplan learn``, ``demoplan plan``, ``demoplan run``.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path

from demoplan.commands.inputs import load_inputs
from demoplan.execution.executor import ExecutionSettings, RunReport, execute
from demoplan.execution.faults import Faults
from demoplan.execution.runner import run_task
from demoplan.execution.world import World
from demoplan.learning.learner import learn as learn_demonstrations
from demoplan.learning.modelfile import load_model
from demoplan.learning.settings import LearningSettings
from demoplan.model import Demonstration, TaskModel
from demoplan.planning.budget import PLANNING_SECONDS, Budget
from demoplan.scenes.plan import ScenePlan, plan_in_scene
from demoplan.scenes.prepared import prepare
from demoplan.scenes.scene import Scene, load_scene

__all__ = ["learn", "plan", "run"]


def learn(
    sources: Iterable[Demonstration | str | Path],
    *,
    require: Sequence[str] = (),
    settings: LearningSettings | None = None,
) -> TaskModel:
    """A task model from demonstrations: objects, or files and folders
    (demonstration files, pose streams — CSV, ROS 2 bags — segmented on the
    way), in the order given. Default settings unless ``settings``;
    ``require``: teacher constraints such as ``"red<green"``."""
    demonstrations: list[Demonstration] = []
    for source in sources:
        if isinstance(source, Demonstration):
            demonstrations.append(source)
        else:
            demonstrations += load_inputs([source])
    return learn_demonstrations(demonstrations, require=require, settings=settings)


def plan(
    model: TaskModel | str | Path,
    scene: Scene | str | Path,
    *,
    timeout: float = PLANNING_SECONDS,
    clutter: bool = False,
) -> ScenePlan:
    """Every demonstrated goal planned in ``scene``, the shortest chosen (§IV.C),
    within ``timeout`` seconds in all; ``clutter``: objects the model never saw
    may stand in the scene. Raises NoPlanError / LimitReachedError."""
    return plan_in_scene(
        _model(model), _scene(scene), budget=Budget(timeout=timeout), clutter=clutter
    )


def run(
    model: TaskModel | str | Path,
    scene: Scene | str | Path,
    *,
    world: World | None = None,
    sim: str = "kinematic",
    faults: Faults = Faults(),
    seed: int = 0,
    max_replans: int = 25,
    planning_seconds: float = PLANNING_SECONDS,
    clutter: bool = False,
) -> RunReport:
    """Carry the task out: plan, act, observe, replan where the world differs.

    Without ``world``, in a simulated one (``sim``: ``kinematic`` or ``mujoco``,
    with injected ``faults``); with ``world``, in that one — it must start as
    ``scene`` describes. ``clutter``: as in :func:`plan`, objects the model
    never saw are allowed (no goal; moved only when in the way)."""
    task = _model(model)
    start = prepare(task, _scene(scene), clutter=clutter)  # checked and completed once
    if world is None:
        return run_task(
            task,
            start.scene,
            sim=sim,
            faults=faults,
            seed=seed,
            max_replans=max_replans,
            planning_seconds=planning_seconds,
            clutter=clutter,
        )
    settings = ExecutionSettings(max_replans=max_replans, budget=Budget(timeout=planning_seconds))
    return execute(task, start, world, settings)


def _model(model: TaskModel | str | Path) -> TaskModel:
    return model if isinstance(model, TaskModel) else load_model(model)


def _scene(scene: Scene | str | Path) -> Scene:
    return scene if isinstance(scene, Scene) else load_scene(scene)
