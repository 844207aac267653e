"""``plan`` and ``problem``: a learned task in a scene (paper §IV.C)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from demoplan.budget import Budget, default_budget
from demoplan.commands.inputs import model_named, task_and_scene
from demoplan.errors import LimitReachedError, UsageError
from demoplan.fileio import refuse_overwriting_inputs
from demoplan.model import TaskModel
from demoplan.planning.pddl import pddl_domain_path, save_pddl_problem
from demoplan.planning.problem import optimality_line
from demoplan.planning.xml import save_problem
from demoplan.scenes.geometry import GeometrySettings
from demoplan.scenes.plan import ScenePlan, goal_problem, plan_in_scene
from demoplan.scenes.prepared import prepare
from demoplan.scenes.problems import SceneProblem
from demoplan.scenes.scene import Scene

__all__ = ["WrittenProblem", "plan", "write_problem"]


def plan(
    model: TaskModel | str | Path,
    scene: Scene | str | Path,
    *,
    timeout: float | None = None,
    budget: Budget | None = None,
    settings: GeometrySettings = GeometrySettings(),
    clutter: bool = False,
    optimal: bool = False,
) -> ScenePlan:
    """Every demonstrated goal planned in ``scene``, the shortest chosen (§IV.C),
    within ``timeout`` seconds in all, or the limits of ``budget`` (neither:
    :func:`~demoplan.budget.default_budget`);
    ``clutter``: objects the model never saw may stand in the scene;
    ``optimal``: only a plan proved shortest (else LimitReachedError).

    Raises :class:`~demoplan.scenes.plan.SceneNoPlanError` (exit 3) or
    :class:`~demoplan.scenes.plan.SceneLimitReachedError` (exit 4), which carry
    every candidate's outcome and the prepared scene."""
    task, raw_scene = task_and_scene(model, scene)
    with model_named(model):
        prepared = prepare(task, raw_scene, clutter=clutter, settings=settings)
        result = plan_in_scene(
            task, prepared, budget=_budget(timeout, budget), settings=settings, clutter=clutter
        )
    if optimal and not result.optimal:
        raise LimitReachedError(
            f"{optimality_line(result.as_plan())}; no plan proved shortest (--optimal)"
        )
    return result


def _budget(timeout: float | None, budget: Budget | None) -> Budget:
    if timeout is not None and budget is not None:
        raise UsageError("give a timeout or a budget, not both")
    if timeout is not None:
        return Budget(timeout=timeout)
    return budget or default_budget()


@dataclass(frozen=True, slots=True)
class WrittenProblem:
    """The problem :func:`write_problem` wrote, and the files (the PDDL domain second)."""

    problem: SceneProblem
    files: tuple[Path, ...]


def write_problem(
    model: Path,
    scene: Path,
    output: Path,
    *,
    goal: int = 1,
    settings: GeometrySettings = GeometrySettings(),
    pddl: bool = False,
    grounded: bool = False,
) -> WrittenProblem:
    """Write the planning problem of the goal of demonstration ``goal`` (from 1)
    in ``scene`` to ``output``: the paper's XML, or with ``pddl`` the PDDL
    problem and its domain beside it (``grounded``: plain STRIPS)."""
    if grounded and not pddl:
        raise UsageError("--grounded chooses the PDDL form: it needs --pddl")
    inputs = [model, scene]
    refuse_overwriting_inputs(output, inputs)
    if pddl:
        refuse_overwriting_inputs(pddl_domain_path(output), inputs)
    task, raw_scene = task_and_scene(model, scene)
    with model_named(model):
        chosen = goal_problem(task, raw_scene, goal, settings)
    if pddl:
        domain = save_pddl_problem(chosen.problem, output, grounded=grounded)
        return WrittenProblem(chosen, (output, domain))
    save_problem(chosen.problem, output)
    return WrittenProblem(chosen, (output,))
