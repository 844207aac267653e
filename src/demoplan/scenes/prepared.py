"""A scene made ready for a task model, once per run.

:func:`prepare` checks the scene against the model (every object it needs,
none it never saw unless ``clutter``), completes it (sizes from the
demonstrations, every landmark's pose and shape: :func:`complete_scene`),
refuses an object standing inside a landmark's body
(:mod:`demoplan.scenes.validity`), binds the model's roles to the scene's
instances (every way there is: :mod:`demoplan.scenes.binding`) and resolves
each binding's candidate goals (paper §IV.C: each demonstrated goal, with
target poses in this scene). ``plan``, ``run``, the figures and the library take the
:class:`PreparedScene` — the planner, the problem builder and the executor
never prepare a scene themselves. Each replan prepares the observed world
once (:func:`prepare_observed`: complete already and checked when the run
started, so only its roles are bound and its goals resolved).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from demoplan.model import TaskModel
from demoplan.scenes.binding import Binding, bind_model, lower_bound, role_bindings
from demoplan.scenes.geometry import GeometrySettings
from demoplan.scenes.landmarks import complete_scene
from demoplan.scenes.scene import Scene
from demoplan.scenes.targets import Candidate, check_scene_objects, resolve_goals
from demoplan.scenes.validity import check_landmark_overlaps, hollow_landmarks

__all__ = [
    "BoundTask",
    "PreparedScene",
    "bound_tasks",
    "goal_floors",
    "prepare",
    "prepare_observed",
]


class BoundTask:
    """The model with one binding of its roles to the scene's instances: the
    model naming those instances, its candidate goals, and per candidate a
    lower bound on its plans' length (:func:`~demoplan.scenes.binding.lower_bound`).
    Each is worked out when first asked for: a scene may have thousands of
    bindings, of which the search plans a few."""

    __slots__ = ("_bounds", "_candidates", "_model", "_roles", "_scene", "binding", "tolerance")

    def __init__(self, binding: Binding, roles: TaskModel, scene: Scene, tolerance: float):
        self.binding = binding
        self._roles, self._scene = roles, scene
        self.tolerance = tolerance
        """m: an object this near its target may already be there (the bounds)."""
        self._model: TaskModel | None = None
        self._candidates: tuple[Candidate, ...] | None = None
        self._bounds: tuple[int, ...] | None = None

    @property
    def model(self) -> TaskModel:
        if self._model is None:
            self._model = bind_model(self._roles, self.binding)
        return self._model

    @property
    def candidates(self) -> tuple[Candidate, ...]:
        if self._candidates is None:
            self._candidates = tuple(resolve_goals(self.model, self._scene))
        return self._candidates

    @property
    def bounds(self) -> tuple[int, ...]:
        if self._bounds is None:
            self._bounds = tuple(
                lower_bound(c, self._scene, self.tolerance) for c in self.candidates
            )
        return self._bounds


@dataclass(frozen=True, slots=True)
class PreparedScene:
    """A scene checked against a model and completed, with its candidate goals
    under every binding (the first: the one whose first goal has the lowest
    bound, ties to the earliest; a model without roles has one)."""

    scene: Scene
    clutter: bool
    bindings: tuple[BoundTask, ...]

    @property
    def candidates(self) -> tuple[Candidate, ...]:
        """The candidate goals under the first binding."""
        return self.bindings[0].candidates

    @property
    def model(self) -> TaskModel:
        """The model bound to the scene's instances by the first binding."""
        return self.bindings[0].model

    def floors(self, index: int) -> list[int]:
        """Per binding, a lower bound on the plans of candidate goal ``index``:
        :func:`goal_floors`."""
        return goal_floors(self.bindings, index, self.scene)


def bound_tasks(
    model: TaskModel, scene: Scene, bindings: Sequence[Binding], tolerance: float
) -> tuple[BoundTask, ...]:
    """One :class:`BoundTask` per binding (nothing resolved yet)."""
    return tuple(BoundTask(binding, model, scene, tolerance) for binding in bindings)


def goal_floors(tasks: Sequence[BoundTask], index: int, scene: Scene) -> list[int]:
    """Per binding, :func:`~demoplan.scenes.binding.lower_bound` of candidate
    goal ``index`` — without resolving the goal under every binding where its
    targets cannot depend on the binding: no state of the goal placed
    anywhere (where its instance stands) and none relative to a role the goal
    does not move (whose pose is its instance's). Then each role's target is
    the one the first binding resolves, and a binding's bound counts the roles
    whose instance stands elsewhere."""
    first = tasks[0]
    if len(tasks) == 1 or not _targets_fixed(tasks, index):
        return [task.bounds[index] for task in tasks]
    role_of = {instance: role for role, instance in first.binding.pairs}
    targets = {
        role_of.get(name, name): pose.position
        for name, pose in first.candidates[index].final_poses().items()
    }
    where = {obj.name: obj.pose.position for obj in scene.objects}
    floors = []
    for task in tasks:
        renaming = task.binding.renaming
        away = 0
        for role, target in targets.items():
            instance = renaming.get(role, role)
            if instance not in where or math.dist(where[instance], target) > task.tolerance:
                away += 1
        floors.append(2 * away)
    return floors


def _targets_fixed(tasks: Sequence[BoundTask], index: int) -> bool:
    """Whether goal ``index``'s targets are the same under every binding (see
    :func:`goal_floors`)."""
    varying: dict[str, set[str]] = {}
    for task in tasks:
        for role, instance in task.binding.pairs:
            varying.setdefault(role, set()).add(instance)
    roles = {role for role, instances in varying.items() if len(instances) > 1}
    first = tasks[0]
    role_of = {instance: role for role, instance in first.binding.pairs}
    candidate = first.candidates[index]
    states = {state.id: state for state in first.model.states}
    moved = {role_of.get(s.object, s.object) for s in candidate.subtasks}
    for subtask in candidate.subtasks:
        state = states[subtask.state]
        if state.position.anywhere:
            return False
        for reference in (state.position.reference, state.orientation.reference):
            name = None if reference is None else role_of.get(reference, reference)
            if name in roles and name not in moved:
                return False
    return True


def prepare(
    model: TaskModel,
    scene: Scene,
    *,
    clutter: bool = False,
    settings: GeometrySettings = GeometrySettings(),
) -> PreparedScene:
    """``scene`` made ready for ``model`` (see the module docstring): once per
    command."""
    check_scene_objects(model, scene, clutter=clutter)
    completed = complete_scene(scene, model)
    check_landmark_overlaps(completed, hollow_landmarks(model, settings), settings)
    tasks = bound_tasks(
        model, completed, role_bindings(model, completed), 2 * settings.merge_distance
    )
    floors = goal_floors(tasks, 0, completed) if tasks[0].candidates else []
    order = sorted(range(len(tasks)), key=lambda b: floors[b] if floors else 0)
    return PreparedScene(completed, clutter, tuple(tasks[b] for b in order))


def prepare_observed(
    model: TaskModel, scene: Scene, settings: GeometrySettings = GeometrySettings()
) -> PreparedScene:
    """The world observed during a run made ready for a replan: ``scene`` is
    complete (the prepared scene's geometry, the observed poses) and objects the
    model never saw are allowed (planned around as clutter); its roles are bound
    to its instances in :func:`~demoplan.scenes.binding.role_bindings`' order
    (the replan orders them itself), nothing resolved yet."""
    bindings = role_bindings(model, scene)
    return PreparedScene(
        scene, True, bound_tasks(model, scene, bindings, 2 * settings.merge_distance)
    )
