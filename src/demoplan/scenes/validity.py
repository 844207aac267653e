"""A scene checked against physics before planning (docs/scenes.md "Landmarks"):
no object stands inside a landmark's body.

A landmark with a shape and size is a solid body (a lunch box, a board):
objects stand beside it or on its top, never inside its volume — a sandwich
at z = 0 within a 2 cm box's outline is the teacher's slip or a wrong height,
and planning on would put things on or beside a sandwich that is not there.
A landmark that held something inside its volume in the demonstrations (a
bin whose recorded size is its walls' bounding box, with the objects on its
floor) is hollow: objects inside it are allowed. Two objects that pass
through each other are refused by :mod:`demoplan.scenes.problems`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import shapely

from demoplan.errors import InputError
from demoplan.model import ObjectGeometry, Pose, TaskModel, demonstrated_shapes, footprint
from demoplan.scenes.geometry import GeometrySettings
from demoplan.scenes.scene import Scene

__all__ = ["check_landmark_overlaps", "hollow_landmarks"]


def _meets(
    shape: ObjectGeometry,
    pose: Pose,
    body: ObjectGeometry,
    at: Pose,
    settings: GeometrySettings,
) -> bool:
    """Whether ``shape`` at ``pose`` reaches into the volume of ``body`` at ``at``:
    their outlines overlap by more than the touch tolerance at heights that
    overlap by more than the level tolerance."""
    low = max(pose.position[2], at.position[2])
    high = min(pose.position[2] + shape.size[2], at.position[2] + body.size[2])
    if high - low <= settings.level_tolerance:
        return False
    inner = footprint(shape, pose.position, pose.yaw).buffer(-settings.touch_tolerance)
    outer = footprint(body, at.position, at.yaw).buffer(-settings.touch_tolerance)
    return bool(inner.intersects(outer))


def hollow_landmarks(model: TaskModel, settings: GeometrySettings = GeometrySettings()) -> set[str]:
    """The landmarks that held an object inside their volume in some
    demonstration (where it stood at the start or was released): containers
    such as a bin, not solid bodies."""
    shapes = demonstrated_shapes(model.demonstrations)
    hollow: set[str] = set()
    for demo in model.demonstrations:
        placed = [*demo.initial, *((step.object, step.pose) for step in demo.steps)]
        for name, at in demo.landmarks:
            body = shapes.get(name)
            if body is None or name in hollow:
                continue
            if any(
                obj in shapes and obj != name and _meets(shapes[obj], pose, body, at, settings)
                for obj, pose in placed
            ):
                hollow.add(name)
    return hollow


def check_landmark_overlaps(
    scene: Scene,
    hollow: Sequence[str] | set[str] = (),
    settings: GeometrySettings = GeometrySettings(),
) -> None:
    """An :class:`InputError` (exit 1) naming the object and the landmark where
    an object of ``scene`` (completed: sizes known) stands inside the body of
    a landmark with a size that is not ``hollow``; the field is the object's
    position, and the message says where the landmark's top is."""
    bodies = [
        (name, pose, shape)
        for name, pose in scene.landmarks
        if name not in hollow and (shape := dict(scene.landmark_geometry).get(name)) is not None
    ]
    objects = [obj for obj in scene.objects if obj.geometry is not None]
    if not bodies or not objects:
        return
    outlines = np.array(
        [
            footprint(obj.geometry, obj.pose.position, obj.pose.yaw).buffer(
                -settings.touch_tolerance
            )
            for obj in objects
            if obj.geometry is not None
        ],
        dtype=object,
    )
    bottoms = np.array([obj.pose.position[2] for obj in objects])
    tops = np.array(
        [obj.pose.position[2] + obj.geometry.size[2] for obj in objects if obj.geometry]
    )
    for name, at, body in bodies:
        low, high = at.position[2], at.position[2] + body.size[2]
        level = (np.minimum(tops, high) - np.maximum(bottoms, low)) > settings.level_tolerance
        outline = footprint(body, at.position, at.yaw).buffer(-settings.touch_tolerance)
        clash = np.flatnonzero(level & shapely.intersects(outline, outlines))
        if len(clash):
            obj = objects[int(clash[0])]
            z = obj.pose.position[2]
            raise InputError(
                f"{obj.name} stands inside landmark {name!r} (at z = {z:.3f} m its outline "
                f"meets the {name}'s, whose body spans z = {low:.3f}–{high:.3f} m); an object "
                f"beside the landmark or on its top (z = {high:.3f} m) expected",
                source=scene.source,
                field=f"objects.{obj.name}.position",
            )
