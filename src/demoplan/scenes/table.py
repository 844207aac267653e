"""The table free space is generated on, where the scene gives no ``table``
(docs/scenes.md "Free space").

Free space is sought first on the demonstrations' workspace grown by
``GeometrySettings.workspace_margin`` (:func:`workspace_table`: the table the
studio draws for them), and only where some object has no room there on the
table :func:`infer_table` infers.

That table is inferred from everything known about where things stand: the
scene's objects and the goal's targets (their footprints), the landmarks
(their outlines where their size is known, else their positions) and the
demonstrations' workspace (every initial pose, every release pose and every
landmark the demonstrations recorded, with the object's outline where its size
is known). The box around all of it is grown on each side by
``GeometrySettings.table_margin``, or, where that is less, by enough to hold a
parking spot for the largest object beside everything
(``2 × spot_reach + grid_step``): an inferred table always has room to park
each object, so a plan is never lost for want of a table the scene did not
describe.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import shapely
from shapely.geometry.base import BaseGeometry

from demoplan.model import ObjectGeometry, Pose, TaskModel, demonstrated_shapes
from demoplan.scenes.geometry import (
    GeometrySettings,
    Location,
    bounding_radius,
    footprint,
    location_footprint,
    spot_reach,
)
from demoplan.scenes.scene import Gripper, Scene

__all__ = [
    "Surroundings",
    "Table",
    "demonstrated_workspace",
    "infer_table",
    "landmarks_of",
    "surroundings_of",
    "workspace_table",
]

Table = tuple[tuple[float, float], tuple[float, float]]
"""``((x_min, y_min), (x_max, y_max))`` in metres."""


@dataclass(frozen=True, slots=True)
class Surroundings:
    """What is known of the table beyond the scene's objects and the targets:
    the landmarks and the demonstrations' poses, each with its shape where known."""

    landmarks: tuple[tuple[str, Pose, ObjectGeometry | None], ...] = ()
    workspace: tuple[tuple[Pose, ObjectGeometry | None], ...] = ()

    def landmark_outlines(self) -> list[BaseGeometry]:
        """The outlines of the landmarks whose size is known (free space keeps off them)."""
        return [
            footprint(shape, pose.position, pose.yaw)
            for _, pose, shape in self.landmarks
            if shape
        ]


def surroundings_of(model: TaskModel, scene: Scene) -> Surroundings:
    """The landmarks of ``scene`` (completed: :func:`~demoplan.scenes.landmarks.complete_scene`)
    with their shapes, and the demonstrations' workspace of ``model``."""
    return Surroundings(landmarks_of(scene), demonstrated_workspace(model))


def landmarks_of(scene: Scene) -> tuple[tuple[str, Pose, ObjectGeometry | None], ...]:
    """Each landmark of ``scene`` with its shape where the scene knows it."""
    shapes = dict(scene.landmark_geometry)
    return tuple((name, pose, shapes.get(name)) for name, pose in scene.landmarks)


def demonstrated_workspace(model: TaskModel) -> tuple[tuple[Pose, ObjectGeometry | None], ...]:
    """Every initial pose, release pose and landmark the demonstrations recorded,
    with the object's (or landmark's) shape where known."""
    shapes = demonstrated_shapes(model.demonstrations)
    workspace: list[tuple[Pose, ObjectGeometry | None]] = []
    for demo in model.demonstrations:
        workspace += [(pose, shapes.get(name)) for name, pose in demo.initial]
        workspace += [(step.pose, shapes.get(step.object)) for step in demo.steps]
        workspace += [(pose, shapes.get(name)) for name, pose in demo.landmarks]
    return tuple(workspace)


def workspace_table(
    surroundings: Surroundings, settings: GeometrySettings = GeometrySettings()
) -> Table | None:
    """The demonstrations' workspace — every initial pose, release pose and
    landmark they recorded, with its outline where the size is known — grown by
    ``settings.workspace_margin`` on each side: the table the studio draws for
    the demonstrations, where free space is sought first. None where the
    demonstrations recorded no pose."""
    if not surroundings.workspace:
        return None
    outlines = [
        shapely.Point(pose.position[0], pose.position[1])
        if shape is None
        else footprint(shape, pose.position, pose.yaw)
        for pose, shape in surroundings.workspace
    ]
    x0, y0, x1, y1 = shapely.union_all(outlines).bounds
    margin = settings.workspace_margin
    return ((x0 - margin, y0 - margin), (x1 + margin, y1 + margin))


def infer_table(
    locations: Sequence[Location],
    shapes: Sequence[ObjectGeometry],
    gripper: Gripper,
    surroundings: Surroundings = Surroundings(),
    settings: GeometrySettings = GeometrySettings(),
) -> Table:
    """The table around ``locations`` and ``surroundings`` (see the module docstring)."""
    outlines = [location_footprint(location) for location in locations]
    for pose, shape in [(p, s) for _, p, s in surroundings.landmarks] + list(
        surroundings.workspace
    ):
        if shape is None:
            outlines.append(shapely.Point(pose.position[0], pose.position[1]))
        else:
            outlines.append(footprint(shape, pose.position, pose.yaw))
    x0, y0, x1, y1 = shapely.union_all(outlines).bounds
    widest = max((bounding_radius(s) for s in shapes), default=0.0)
    margin = max(settings.table_margin, 2 * spot_reach(widest, gripper) + settings.grid_step)
    return ((x0 - margin, y0 - margin), (x1 + margin, y1 + margin))
