"""``plan`` and ``problem``: a learned task in a scene (paper §IV.C)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from demoplan.budget import Budget, Clock, default_budget
from demoplan.commands.inputs import model_named, task_and_scene
from demoplan.errors import LimitReachedError, UsageError
from demoplan.fileio import refuse_overwriting_inputs
from demoplan.model import TaskModel
from demoplan.planning.pddl import Roles, pddl_domain_path, save_pddl_problem
from demoplan.planning.problem import optimality_line
from demoplan.planning.xml import save_problem
from demoplan.scenes.geometry import GeometrySettings
from demoplan.scenes.plan import ScenePlan, building_within, goal_problem, plan_in_scene
from demoplan.scenes.prepared import PreparedScene, prepare
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
    every candidate's outcome and the prepared scene. The scene is prepared
    once, on the command's clock (a flood of objects stops at the budget)."""
    clock = Clock(_budget(timeout, budget))
    task, raw_scene = task_and_scene(model, scene)
    with model_named(model):
        with building_within(clock):
            prepared = prepare(task, raw_scene, clutter=clutter, settings=settings)
        result = plan_in_scene(task, prepared, clock=clock, settings=settings)
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
    roles: Roles | None = None
    """With identical objects, the roles the PDDL export lets a planner bind
    (:func:`~demoplan.planning.pddl.plan_from_pddl` reads its plans)."""


def write_problem(
    model: TaskModel | Path,
    scene: Scene | Path,
    output: Path,
    *,
    goal: int = 1,
    settings: GeometrySettings = GeometrySettings(),
    pddl: bool = False,
    grounded: bool = False,
) -> WrittenProblem:
    """Write the planning problem of the goal of demonstration ``goal`` (from 1)
    in ``scene`` to ``output``: the paper's XML, or with ``pddl`` the PDDL
    problem and its domain beside it (``grounded``: plain STRIPS).

    With identical objects the problem names the instances as the first
    binding of roles to instances puts them; the PDDL export lets the planner
    choose the binding (:class:`~demoplan.planning.pddl.Roles`)."""
    if grounded and not pddl:
        raise UsageError("--grounded chooses the PDDL form: it needs --pddl")
    inputs = [path for path in (model, scene) if isinstance(path, Path)]
    refuse_overwriting_inputs(output, inputs)
    if pddl:
        refuse_overwriting_inputs(pddl_domain_path(output), inputs)
    task, raw_scene = task_and_scene(model, scene)
    with model_named(model):
        prepared = prepare(task, raw_scene)
        chosen = goal_problem(task, prepared, goal, settings)
    if pddl:
        roles = _interchangeable(prepared, chosen, goal)
        domain = save_pddl_problem(chosen.problem, output, grounded=grounded, roles=roles)
        return WrittenProblem(chosen, (output, domain), roles)
    save_problem(chosen.problem, output)
    return WrittenProblem(chosen, (output,))


def _interchangeable(prepared: PreparedScene, chosen: SceneProblem, goal: int) -> Roles | None:
    """The identical objects of ``chosen``, whose problem names the instances
    as the first binding puts them: each instance's type and role (None where
    the roles have one binding only). A UsageError where the goal's targets
    depend on the binding (a state placed anywhere, where its instance
    stands; a state relative to a role this goal does not move): one PDDL
    problem cannot say that."""
    if len(prepared.bindings) == 1:
        return None
    index = next(i for i, c in enumerate(prepared.candidates) if c.goal == chosen.candidate.goal)
    choices: dict[str, set[str]] = {}
    for task in prepared.bindings:
        for role, instance in task.binding.pairs:
            choices.setdefault(role, set()).add(instance)
    varying = {role for role, instances in choices.items() if len(instances) > 1}
    kind = {obj.name: obj.kind for obj in prepared.scene.objects}
    kinds_with_roles = {kind[instance] for role in varying for instance in choices[role]}

    def targets(binding: int) -> list[tuple[object, ...]]:
        task = prepared.bindings[binding]
        role_of = {instance: role for role, instance in task.binding.pairs}
        return [
            (s.label, role_of.get(s.object, s.object), s.pose, s.turnable)
            for s in task.candidates[index].subtasks
        ]

    first = targets(0)
    differing = sorted(
        {
            mine[0]
            for other in range(1, len(prepared.bindings))
            for mine, theirs in zip(first, targets(other), strict=True)
            if mine != theirs
        },
        key=str,
    )
    if differing:
        raise UsageError(
            f"--pddl: the targets of goal {goal} depend on which instance fills which role "
            f"(subgoals {', '.join(map(str, differing))}: placed anywhere, or relative to an "
            "object this goal does not move), which one PDDL problem cannot say; "
            "'demoplan plan' weighs every binding"
        )
    return Roles(
        kinds={name: k for name, k in kind.items() if k in kinds_with_roles},
        filled={
            instance: role
            for role, instance in prepared.bindings[0].binding.pairs
            if role in varying
        },
    )
