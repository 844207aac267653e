"""A scene made ready for a task model, once per run.

:func:`prepare` checks the scene against the model (every object it needs,
none it never saw unless ``clutter``), completes it (sizes from the
demonstrations, every landmark's pose and shape: :func:`complete_scene`),
binds the model's roles to the scene's instances (every way there is:
:mod:`demoplan.scenes.binding`) and resolves each binding's candidate goals
(paper §IV.C: each demonstrated goal, with target poses in this scene).
``plan``, ``run``, the figures and the library take the
:class:`PreparedScene`; the executor's replans resolve the goals again in
the observed world, which is complete already.
"""

from __future__ import annotations

from dataclasses import dataclass

from demoplan.model import TaskModel
from demoplan.scenes.binding import Binding, bind_model, lower_bound, role_bindings
from demoplan.scenes.geometry import GeometrySettings
from demoplan.scenes.landmarks import complete_scene
from demoplan.scenes.scene import Scene
from demoplan.scenes.targets import Candidate, check_scene_objects, resolve_goals

__all__ = ["BoundTask", "PreparedScene", "prepare"]


@dataclass(frozen=True, slots=True)
class BoundTask:
    """The model with one binding of its roles to the scene's instances: the
    model naming those instances, its candidate goals, and per candidate a
    lower bound on its plans' length (:func:`~demoplan.scenes.binding.lower_bound`)."""

    binding: Binding
    model: TaskModel
    candidates: tuple[Candidate, ...]
    bounds: tuple[int, ...]


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


def prepare(
    model: TaskModel,
    scene: Scene | PreparedScene,
    *,
    clutter: bool = False,
    settings: GeometrySettings = GeometrySettings(),
) -> PreparedScene:
    """``scene`` made ready for ``model`` (see the module docstring); a scene
    prepared already is returned as it is."""
    if isinstance(scene, PreparedScene):
        return scene
    check_scene_objects(model, scene, clutter=clutter)
    completed = complete_scene(scene, model)
    tolerance = 2 * settings.merge_distance
    bound = []
    for binding in role_bindings(model, completed):
        task = bind_model(model, binding)
        candidates = tuple(resolve_goals(task, completed))
        bounds = tuple(lower_bound(c, completed, tolerance) for c in candidates)
        bound.append(BoundTask(binding, task, candidates, bounds))
    bound.sort(key=lambda task: task.bounds[:1])
    return PreparedScene(completed, clutter, tuple(bound))
