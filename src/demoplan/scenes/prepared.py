"""A scene made ready for a task model, once per run.

:func:`prepare` checks the scene against the model (every object it needs,
none it never saw unless ``clutter``), completes it (sizes from the
demonstrations, every landmark's pose and shape: :func:`complete_scene`) and
resolves its candidate goals (paper §IV.C: each demonstrated goal, with
target poses in this scene). ``plan``, ``run``, the figures and the library
take the :class:`PreparedScene`; the executor's replans resolve the goals
again in the observed world, which is complete already.
"""

from __future__ import annotations

from dataclasses import dataclass

from demoplan.model import TaskModel
from demoplan.scenes.landmarks import complete_scene
from demoplan.scenes.scene import Scene
from demoplan.scenes.targets import Candidate, check_scene_objects, resolve_goals

__all__ = ["PreparedScene", "prepare"]


@dataclass(frozen=True, slots=True)
class PreparedScene:
    """A scene checked against a model and completed, with its candidate goals."""

    scene: Scene
    clutter: bool
    candidates: tuple[Candidate, ...]


def prepare(
    model: TaskModel, scene: Scene | PreparedScene, *, clutter: bool = False
) -> PreparedScene:
    """``scene`` made ready for ``model`` (see the module docstring); a scene
    prepared already is returned as it is."""
    if isinstance(scene, PreparedScene):
        return scene
    check_scene_objects(model, scene, clutter=clutter)
    completed = complete_scene(scene, model)
    return PreparedScene(completed, clutter, tuple(resolve_goals(model, completed)))
