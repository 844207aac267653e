"""What the studio shows while a user moves objects (docs/studio-api.md): a
learned task's targets in the scene on the table (``targets``), what stands on
an object that is picked up and moves with it (``carried_by``), where a released
object comes to rest (``drop``) and whether a landmark may be put down
(``place_landmark``).

All resolve the scene as ``plan`` does — the same preparation, the same
support rule (docs/scenes.md) — so that the page shows what planning would do.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from demoplan.model import Pose, TaskModel
from demoplan.scenes.drops import Landing, Standing, carried_by, landing, landmark_clear
from demoplan.scenes.geometry import GeometrySettings
from demoplan.scenes.prepared import prepare
from demoplan.scenes.scene import Scene, final_layout

__all__ = [
    "Landing",
    "Standing",
    "Target",
    "carried_by",
    "drop",
    "place_landmark",
    "targets",
]


@dataclass(frozen=True, slots=True)
class Target:
    """Where planning would put ``object``: the pose of state ``state`` (``label``)."""

    state: str
    label: str
    object: str
    pose: Pose


def targets(model: TaskModel, scene: Scene | None) -> tuple[Target, ...]:
    """The states of the first candidate goal resolved in ``scene`` (clutter
    allowed, as ``plan`` allows it; no scene: the first demonstration's final
    layout); none when the scene has no candidate."""
    if scene is None:
        scene = final_layout(model.demonstrations[0])
    prepared = prepare(model, scene, clutter=True)
    if not prepared.candidates:
        return ()
    return tuple(
        Target(subtask.state, subtask.label, subtask.object, subtask.pose)
        for subtask in prepared.candidates[0].subtasks
    )


def drop(
    name: str,
    position: tuple[float, float],
    yaw: float,
    objects: Mapping[str, Standing],
    landmarks: Mapping[str, Standing],
) -> Landing:
    """Where object ``name`` comes to rest released over ``position`` at ``yaw``
    among ``objects`` and ``landmarks`` standing on the table
    (:func:`demoplan.scenes.drops.landing`, the scene's default settings)."""
    return landing(name, position, yaw, objects, landmarks, GeometrySettings())


def place_landmark(
    name: str,
    moved: Standing,
    objects: Mapping[str, Standing],
    landmarks: Mapping[str, Standing],
) -> Standing:
    """Landmark ``name`` put down as ``moved``, when it stands clear of every
    object and other landmark (:func:`demoplan.scenes.drops.landmark_clear`)."""
    landmark_clear(name, moved, objects, landmarks, GeometrySettings())
    return moved
