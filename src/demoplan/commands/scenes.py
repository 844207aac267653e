"""What the studio shows while a user moves objects (docs/studio-api.md): a
learned task's targets in the scene on the table (``targets``), and what stands
on an object that is picked up and moves with it (``carried_by``, for a drop).

Both resolve the scene as ``plan`` does — the same preparation, the same
support rule (docs/scenes.md) — so that the page shows what planning would do.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from demoplan.model import ObjectGeometry, Pose, TaskModel, Vector3
from demoplan.scenes.geometry import GeometrySettings, Location, supports
from demoplan.scenes.prepared import prepare
from demoplan.scenes.scene import Scene

__all__ = ["Standing", "Target", "carried_by", "targets"]


@dataclass(frozen=True, slots=True)
class Target:
    """Where planning would put ``object``: the pose of state ``state`` (``label``)."""

    state: str
    label: str
    object: str
    pose: Pose


@dataclass(frozen=True, slots=True)
class Standing:
    """An object where it stands: its bottom centre, its yaw (deg), its shape."""

    position: Vector3
    yaw: float
    geometry: ObjectGeometry


def targets(model: TaskModel, scene: Scene) -> tuple[Target, ...]:
    """The states of the first candidate goal resolved in ``scene`` (clutter
    allowed, as ``plan`` allows it); none when the scene has no candidate."""
    prepared = prepare(model, scene, clutter=True)
    if not prepared.candidates:
        return ()
    return tuple(
        Target(subtask.state, subtask.label, subtask.object, subtask.pose)
        for subtask in prepared.candidates[0].subtasks
    )


def carried_by(
    name: str, standing: Mapping[str, Standing], settings: GeometrySettings
) -> frozenset[str]:
    """The objects standing on ``name``, directly or on each other: they move
    with it (the support rule of :func:`demoplan.scenes.geometry.supports`)."""
    locations = [
        Location(n, thing.position, thing.yaw, "current", (n,), (thing.geometry,))
        for n, thing in standing.items()
    ]
    pairs, _ = supports(locations, settings)
    carried: set[str] = set()
    frontier = {name}
    while frontier:
        below = frontier
        frontier = {upper for upper, lower in pairs if lower in below} - carried - {name}
        carried |= frontier
    return frozenset(carried)
