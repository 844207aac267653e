"""``export bt``: a planned task as a BehaviorTree.CPP v4 tree (docs/execution.md
"Behaviour trees")."""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

from demoplan.budget import Budget
from demoplan.commands.inputs import model_named, task_and_scene
from demoplan.commands.planning import plan
from demoplan.errors import InputError, NoPlanError, UsageError
from demoplan.execution.behaviour_tree import (
    ATTEMPTS,
    TreeRun,
    run_behaviour_tree,
    task_tree,
    tree_targets,
)
from demoplan.execution.executor import ExecutionSettings
from demoplan.execution.faults import Faults
from demoplan.execution.runner import make_world
from demoplan.execution.tree_checks import MAX_ATTEMPTS, check_tree
from demoplan.fileio import display_path, read_input_text, refuse_overwriting_inputs
from demoplan.model import TaskModel
from demoplan.scenes.geometry import GeometrySettings
from demoplan.scenes.plan import ChosenPlan, ScenePlan
from demoplan.scenes.prepared import prepare
from demoplan.scenes.scene import Scene
from demoplan.wording import plural

__all__ = ["ExportedTree", "behaviour_tree", "export_behaviour_tree", "run_tree"]


@dataclass(frozen=True, slots=True)
class ExportedTree:
    """The tree written, and the plan it was made from."""

    path: Path
    xml: str
    plan: ScenePlan

    @property
    def summary(self) -> str:
        """``8 actions, goal of demonstration 2 (pyramid-2)``."""
        chosen = self.plan.chosen
        return f"{plural(len(chosen.plan), 'action')}, goal of {_goal_label(self.plan)}"


def behaviour_tree(
    model: TaskModel | Path,
    scene: Scene | Path,
    *,
    goal: int | None = None,
    plan_only: bool = False,
    attempts: int = ATTEMPTS,
    budget: Budget | None = None,
    settings: GeometrySettings = GeometrySettings(),
    execution: ExecutionSettings = ExecutionSettings(),
) -> tuple[str, ScenePlan]:
    """The BehaviorTree.CPP v4 XML of the plan chosen in ``scene`` (``goal``: of
    the goal of that demonstration, numbered from 1), and the plan; each
    subgoal tried ``attempts`` times.

    Raises NoPlanError (exit 3) where the scene or the goal has no plan."""
    if not 1 <= attempts <= MAX_ATTEMPTS:
        raise UsageError(f"--attempts {attempts}: 1 to {MAX_ATTEMPTS} expected")
    result = plan(model, scene, budget=budget, settings=settings)
    if goal is not None:
        result = _with_goal(result, goal)
    read_as_entries = [
        name for name in result.chosen.problem.problem.objects if "{" in name or "}" in name
    ]
    if read_as_entries:
        raise InputError(
            f"object {read_as_entries[0]!r} cannot be named in a behaviour tree: the engine "
            "reads {…} as a blackboard entry; rename it in the scene and the model",
            source=display_path(scene) if isinstance(scene, Path) else "scene",
        )
    tree = task_tree(result, settings=execution, plan_only=plan_only, attempts=attempts)
    # what the run would refuse is never written (a name the engine reads as {entry})
    check_tree(tree, source="the exported tree")
    return tree, result


def _with_goal(result: ScenePlan, goal: int) -> ScenePlan:
    demonstrations = {d for c in result.candidates for d in c.problem.candidate.demonstrations}
    if goal - 1 not in demonstrations:
        raise UsageError(
            f"--goal {goal}: the model has demonstrations 1..{max(demonstrations) + 1}"
        )
    candidate = next(c for c in result.candidates if goal - 1 in c.problem.candidate.demonstrations)
    if candidate.plan is None:
        raise NoPlanError(f"goal of demonstration {goal}: {candidate.reason or 'no plan'}")
    chosen = ChosenPlan.of(candidate, candidate.plan, result.scene, result.model)
    return replace(result, chosen=chosen)


def run_tree(
    tree: Path,
    model: TaskModel | Path,
    scene: Scene | Path,
    *,
    sim: str = "kinematic",
    faults: Faults = Faults(),
    seed: int = 0,
) -> TreeRun:
    """Tick the tree in ``tree`` (as ``export bt`` writes it) in the simulated
    world ``sim`` (``kinematic``, ``mujoco`` or ``arm``) set up as ``scene``
    (completed with ``model``'s shapes), ``faults`` drawn from ``seed``; the
    tree's leaves bound to the world's operations. The arm stands where it
    reaches the tree's targets."""
    xml = read_input_text(tree, "a behaviour tree (BehaviorTree.CPP v4 XML)")
    source = display_path(tree)
    task, start = task_and_scene(model, scene)
    with model_named(model):
        prepared = prepare(task, start)
    # the arm stands where it reaches the tree's targets (as a run's first plan's)
    workspace = [pose.position[:2] for _, pose in tree_targets(xml, source)]
    world = make_world(sim, prepared.scene, faults, seed, workspace=workspace)
    try:
        return run_behaviour_tree(xml, world, source=source)
    finally:
        close = getattr(world, "close", None)
        if close is not None:
            close()


def _goal_label(result: ScenePlan) -> str:
    return result.model.demonstration_label(result.chosen.goal)


def export_behaviour_tree(
    model: TaskModel | Path,
    scene: Scene | Path,
    output: Path,
    *,
    goal: int | None = None,
    plan_only: bool = False,
    attempts: int = ATTEMPTS,
    budget: Budget | None = None,
    settings: GeometrySettings = GeometrySettings(),
    plot: Path | None = None,
) -> ExportedTree:
    """Write :func:`behaviour_tree` to ``output`` (atomically; never over an
    input) and, with ``plot``, its drawing there — both or neither
    (:class:`~demoplan.fileio.StagedOutputs`); nothing is written where
    there is no plan."""
    from demoplan.fileio import StagedOutputs
    from demoplan.plotting.behaviour_tree import behaviour_tree_figure
    from demoplan.plotting.output import check_figure_path, figure_errors

    inputs = [p for p in (model, scene) if isinstance(p, Path)]
    refuse_overwriting_inputs(output, inputs)
    if plot is not None:
        check_figure_path(plot, "--plot")
        refuse_overwriting_inputs(plot, [*inputs, output])
    xml, result = behaviour_tree(
        model,
        scene,
        goal=goal,
        plan_only=plan_only,
        attempts=attempts,
        budget=budget,
        settings=settings,
    )
    with StagedOutputs() as outputs:  # the tree and its drawing, both or neither
        outputs.add(output, xml.encode("utf-8", "backslashreplace"))  # as write_atomic
        if plot is not None:
            with figure_errors(plot):
                outputs.add(plot, behaviour_tree_figure(xml, plot))
    return ExportedTree(output, xml, result)
