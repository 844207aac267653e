"""Seeded random start layouts for a task model (``demoplan evaluate --random-scenes``).

A layout scatters the model's objects on the table around the demonstrated
workspace (the box around every initial pose, release pose and landmark the
demonstrations recorded, grown by :attr:`LayoutSettings.margin`), stands some
of them on others (``stack_probability``: an object on a free flat top no
smaller than its own outline), and with ``clutter`` puts that many small
objects the model never saw on the goal's table-level targets. A landmark
that stood at different places in the demonstrations (a lunch box, a tray) is
moved and turned at random — any yaw, its whole outline in the workspace,
clear of the other landmarks — and keeps its shape and size, so that the runs
test the task following it; one that stood still stays where the first
demonstration recorded it. Objects standing on the table keep a gripper's
reach clear of each other and of the landmarks' outlines, so each can be
grasped and none stands inside a landmark.

A layout is a function of the model and its seed only: :func:`random_scene`
returns the scene document (``demoplan/scene-1``) that ``demoplan run``
reads, so any evaluated run can be repeated from the file written for it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely
from shapely.geometry.base import BaseGeometry

from demoplan.errors import InputError
from demoplan.model import (
    LEVEL_TOLERANCE,
    ObjectGeometry,
    TaskModel,
    demonstrated_shapes,
    footprint,
)
from demoplan.scenes.landmarks import moved_landmarks
from demoplan.scenes.scene import Scene, scene_from_document
from demoplan.scenes.table import demonstrated_workspace

__all__ = ["LayoutSettings", "random_scene", "random_scene_document", "workspace_box"]

CLUTTER_SIZE = 0.03
"""m: the side of a clutter cube."""
_SALT = 0x5CE7E
"""Mixed into each layout's seed: a layout's draws differ from the faults' of the same seed."""


@dataclass(frozen=True, slots=True)
class LayoutSettings:
    """How random layouts are drawn (docs/execution.md "Evaluation")."""

    stack_probability: float = 0.25
    clutter: int = 0
    margin: float = 0.05
    """m the demonstrated workspace is grown by on each side."""
    yaw_range: float = 30.0
    """deg: an object's yaw is drawn from ±this."""
    finger_radius: float = 0.005
    """m: the gripper's (written into the scene; objects keep twice this plus 1 cm apart)."""
    attempts: int = 400
    """Draws per object before the layout is refused as too crowded."""


def workspace_box(
    model: TaskModel, margin: float
) -> tuple[tuple[float, float], tuple[float, float]]:
    """The box (x, y) around the demonstrated workspace, grown by ``margin``."""
    outlines = [
        shapely.Point(pose.position[0], pose.position[1])
        if shape is None
        else footprint(shape, pose.position, pose.yaw)
        for pose, shape in demonstrated_workspace(model)
    ]
    x0, y0, x1, y1 = shapely.union_all(outlines).bounds
    return (x0 - margin, y0 - margin), (x1 + margin, y1 + margin)


@dataclass(slots=True)
class _Placed:
    name: str
    shape: ObjectGeometry
    x: float
    y: float
    z: float
    yaw: float
    outline: BaseGeometry
    covered: bool = False


def _outline(
    shape: ObjectGeometry | None, place: tuple[float, float, float, float]
) -> BaseGeometry:
    """A landmark's outline at ``(x, y, z, yaw)``: its footprint, or its point where
    its size is unknown."""
    x, y, z, yaw = place
    return shapely.Point(x, y) if shape is None else footprint(shape, (x, y, z), yaw)


def _goal_targets(model: TaskModel) -> list[tuple[float, float]]:
    """The table-level release positions of the first demonstration (an object's last)."""
    last: dict[str, tuple[float, float, float]] = {}
    for step in model.demonstrations[0].steps:
        last[step.object] = step.pose.position
    return [(x, y) for x, y, z in last.values() if z < LEVEL_TOLERANCE]


class _Layout:
    """The objects placed so far, and the draws that place more."""

    def __init__(self, model: TaskModel, seed: int, settings: LayoutSettings) -> None:
        self.rng = np.random.default_rng([_SALT, seed])
        self.settings = settings
        self.box = workspace_box(model, settings.margin)
        self.clearance = 2 * settings.finger_radius + 0.01
        shapes = demonstrated_shapes(model.demonstrations)
        moved = moved_landmarks(model)
        self.landmark_places: dict[str, tuple[float, float, float, float]] = {}
        self.landmark_shapes: dict[str, ObjectGeometry] = {}
        self.landmarks: list[BaseGeometry] = []
        for name, pose in model.demonstrations[0].landmarks:
            shape = shapes.get(name)
            x, y, z = pose.position
            place = (x, y, z, pose.yaw)
            if name in moved:
                place = self._landmark_place(shape, z) or place
            self.landmark_places[name] = place
            if shape is not None:
                self.landmark_shapes[name] = shape
            self.landmarks.append(_outline(shape, place).buffer(self.clearance))
        self.placed: list[_Placed] = []

    def _landmark_place(
        self, shape: ObjectGeometry | None, z: float
    ) -> tuple[float, float, float, float] | None:
        """A random place and yaw (any turn) for a landmark: its outline within
        the workspace box, a gripper's reach clear of the landmarks placed so
        far. None where no draw fits (it then stays where it stood)."""
        (x0, y0), (x1, y1) = self.box
        table = shapely.box(x0, y0, x1, y1)
        for _ in range(self.settings.attempts):
            x, y = float(self.rng.uniform(x0, x1)), float(self.rng.uniform(y0, y1))
            place = (x, y, z, float(self.rng.uniform(-180.0, 180.0)))
            outline = _outline(shape, place)
            if table.contains(outline) and not any(
                outline.buffer(self.clearance).intersects(o) for o in self.landmarks
            ):
                return place
        return None

    def _free(self, outline: BaseGeometry) -> bool:
        grown = outline.buffer(self.clearance)
        on_table = (p.outline for p in self.placed if p.z < LEVEL_TOLERANCE)
        return not any(grown.intersects(o) for o in (*self.landmarks, *on_table))

    def on_table(self, name: str, shape: ObjectGeometry, at: tuple[float, float] | None) -> None:
        """Place ``name`` on the table: at ``at`` where that is free, else at a free random spot."""
        (x0, y0), (x1, y1) = self.box
        for attempt in range(self.settings.attempts):
            if at is not None and attempt == 0:
                x, y = at
            else:
                x, y = self.rng.uniform(x0, x1), self.rng.uniform(y0, y1)
            yaw = float(self.rng.uniform(-1, 1) * self.settings.yaw_range)
            outline = footprint(shape, (x, y, 0.0), yaw)
            if self._free(outline):
                self.placed.append(_Placed(name, shape, float(x), float(y), 0.0, yaw, outline))
                return
        raise InputError(
            f"no free place for {name!r} after {self.settings.attempts} random draws; "
            "a larger margin or fewer clutter objects expected",
            source="random layout",
        )

    def stacked(self, name: str, shape: ObjectGeometry) -> bool:
        """Stand ``name`` on a random free flat top no smaller than it; False: none."""
        own = footprint(shape, (0.0, 0.0, 0.0), 0.0).area
        tops = [
            p
            for p in self.placed
            if not p.covered
            and p.shape.shape in {"box", "cylinder"}
            and p.outline.area >= own
            and not p.name.startswith("clutter")
        ]
        if not tops:
            return False
        below = tops[int(self.rng.integers(len(tops)))]
        below.covered = True
        z = below.z + below.shape.size[2]
        outline = footprint(shape, (below.x, below.y, z), below.yaw)
        self.placed.append(_Placed(name, shape, below.x, below.y, z, below.yaw, outline))
        return True


def random_scene_document(
    model: TaskModel, seed: int, settings: LayoutSettings = LayoutSettings()
) -> dict[str, Any]:
    """Layout ``seed`` of the model's objects as a scene document (``demoplan/scene-1``)."""
    if not model.demonstrations:
        raise InputError("has no demonstrations; a workspace to scatter objects in expected")
    layout = _Layout(model, seed, settings)
    targets = _goal_targets(model)
    for k in range(settings.clutter):
        at = targets[int(layout.rng.integers(len(targets)))] if targets else None
        cube = ObjectGeometry("box", (CLUTTER_SIZE, CLUTTER_SIZE, CLUTTER_SIZE))
        layout.on_table(f"clutter-{k + 1}", cube, at)
    shapes = demonstrated_shapes(model.demonstrations)
    types = model.object_types()
    names = sorted(types)
    for i in layout.rng.permutation(len(names)):
        name = names[int(i)]
        shape = shapes.get(name) or shapes.get(types[name])
        if shape is None:
            raise InputError(
                f"{name}: no shape or size in the model's demonstrations; random layouts "
                "need every object's (or give SCENE files instead of --random-scenes)",
                field="demonstrations",
            )
        if layout.rng.random() < settings.stack_probability and layout.stacked(name, shape):
            continue
        layout.on_table(name, shape, None)
    objects: dict[str, Any] = {}
    for p in sorted(layout.placed, key=lambda p: p.name):
        entry: dict[str, Any] = {
            "position": [round(p.x, 6), round(p.y, 6), round(p.z, 6)],
            "yaw": round(p.yaw, 4),
            "shape": p.shape.shape,
            "size": list(p.shape.size),
        }
        if types.get(p.name, p.name) != p.name:
            entry["type"] = types[p.name]
        objects[p.name] = entry
    document: dict[str, Any] = {
        "format": "demoplan/scene-1",
        "description": f"random start layout {seed} (demoplan evaluate)",
        "objects": objects,
        "gripper": {"finger_radius": settings.finger_radius},
    }
    if layout.landmark_places:
        document["landmarks"] = {}
        for name, (x, y, z, yaw) in layout.landmark_places.items():
            mark: dict[str, Any] = {
                "position": [round(x, 6), round(y, 6), round(z, 6)],
                "yaw": round(yaw, 4),
            }
            if name in layout.landmark_shapes:
                shape = layout.landmark_shapes[name]
                mark.update(shape=shape.shape, size=list(shape.size))
            document["landmarks"][name] = mark
    return document


def random_scene(model: TaskModel, seed: int, settings: LayoutSettings = LayoutSettings()) -> Scene:
    """Layout ``seed`` as a :class:`Scene` (see :func:`random_scene_document`)."""
    return scene_from_document(random_scene_document(model, seed, settings), f"random-{seed}")
