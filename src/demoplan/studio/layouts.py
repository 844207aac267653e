"""Layouts the studio's page draws: the templates (the shipped examples' first
demonstrations), the layout of a demonstration or scene file, objects
scattered at random (seeded, not overlapping, on the table), and where an
object comes to rest when it is released (on the table, or on the top of
what it lands on — the support rule of docs/scenes.md).

A layout is the JSON of docs/studio-api.md: ``objects`` (shape, size,
colour), ``landmarks`` (shape, size where known, pose, colour), ``poses``
(each object's ``position`` [x, y, z], z its bottom, and ``yaw`` in
degrees) and ``table`` (the rectangle drawn: ``origin`` and ``size``).
"""

from __future__ import annotations

import random
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import shapely
from shapely.geometry.base import BaseGeometry

from demoplan.commands.objects import ObjectsFile
from demoplan.commands.scenes import Standing, drop, place_landmark
from demoplan.errors import InputError
from demoplan.model import Demonstration, ObjectGeometry, Pose, footprint
from demoplan.plotting.colours import assign_colours
from demoplan.scenes.scene import Scene
from demoplan.studio.requests import Layout
from demoplan.studio.workfolder import FileMissingError
from demoplan.wording import plural

__all__ = [
    "TABLE_MARGIN",
    "TEMPLATES",
    "Template",
    "dropped_pose",
    "layout_of_demonstration",
    "layout_of_objects",
    "layout_of_scene",
    "objects_document",
    "placed_landmark",
    "scattered",
    "template_layout",
]

TABLE_MARGIN = 0.1
"""m: the table drawn reaches this far beyond everything on it."""
SCATTER_GAP = 0.01
"""m: the least gap between two scattered objects (or an object and a landmark)."""
SCATTER_TRIES = 2000
"""Random places tried per object before the scatter gives up."""


@dataclass(frozen=True, slots=True)
class Template:
    """A task to teach: its id, its title, and the shipped example it starts from."""

    id: str
    title: str
    example: str
    """The example's file or folder, relative to ``examples/``."""


TEMPLATES = (
    Template("set_table", "Set the table (the paper's Experiment 1)", "set_table"),
    Template("blocks", "Stack the blocks (the paper's Experiment 2)", "blocks/demonstrations.json"),
    Template("kit", "Fill the kit tray", "kitting/demonstrations.json"),
    Template("empty", "An empty table for your own objects", ""),
)
EMPTY_TABLE = {"origin": [0.0, 0.0], "size": [0.8, 0.6]}
"""m: the table of the empty template."""


def template_layout(template_id: str, seed: int | None = None) -> dict[str, Any]:
    """The template's initial layout: the first demonstration's ``initial``, or
    with ``seed`` its objects scattered (:func:`scattered`)."""
    from demoplan.commands.inputs import load_examples

    template = next((t for t in TEMPLATES if t.id == template_id), None)
    if template is None:
        raise FileMissingError(
            f"template: no template {template_id!r}; one of {', '.join(t.id for t in TEMPLATES)}"
        )
    if not template.example:
        return {
            "template": template.id,
            "objects": {},
            "landmarks": {},
            "poses": {},
            "table": EMPTY_TABLE,
        }
    demonstrations = load_examples([template.example])
    layout = layout_of_demonstration(demonstrations[0], demonstrations, template.id)
    if seed is None:
        return layout
    return scattered(Layout.model_validate(layout), seed)


def layout_of_demonstration(
    demonstration: Demonstration,
    context: Iterable[Demonstration] = (),
    template: str | None = None,
) -> dict[str, Any]:
    """The layout of ``demonstration`` before its first step; the table holds
    every pose of it and of ``context`` (the other demonstrations of the task)."""
    geometry = demonstration.geometry()
    landmark_names = {name for name, _ in demonstration.landmarks}
    objects = {n: g for n, g in geometry.items() if n not in landmark_names}
    colours = assign_colours([*objects, *landmark_names], demonstration.given_colours)
    poses = demonstration.initial_poses()
    outlines: list[BaseGeometry] = []
    for demo in [demonstration, *context]:
        shapes = demo.geometry()
        placed = [*demo.initial, *((s.object, s.pose) for s in demo.steps), *demo.landmarks]
        outlines += [_outline(shapes.get(name), pose) for name, pose in placed]
    return {
        "template": template,
        "objects": {name: _shape(g, colours[name]) for name, g in objects.items()},
        "landmarks": {
            name: _landmark(geometry.get(name), pose, colours[name])
            for name, pose in demonstration.landmarks
        },
        "poses": {name: _pose(poses[name]) for name in objects if name in poses},
        "table": _table(outlines),
    }


def layout_of_scene(scene: Scene) -> dict[str, Any]:
    """The layout of a scene: its objects where they stand (size null where the
    scene leaves it to the model) in the colours it gives (else the figures'),
    its landmarks, its table or one around all."""
    landmark_shapes = dict(scene.landmark_geometry)
    colours = assign_colours([*scene.names, *scene.landmark_names], scene.given_colours)
    outlines = [_outline(o.geometry, o.pose) for o in scene.objects]
    outlines += [_outline(landmark_shapes.get(n), pose) for n, pose in scene.landmarks]
    if scene.table is not None:
        (x0, y0), (x1, y1) = scene.table
        table = {"origin": [x0, y0], "size": [x1 - x0, y1 - y0]}
    else:
        table = _table(outlines)
    return {
        "template": None,
        "objects": {
            o.name: (
                _shape(o.geometry, colours[o.name], o.type)
                if o.geometry is not None
                else {"shape": "box", "size": None, "colour": colours[o.name]}
            )
            for o in scene.objects
        },
        "landmarks": {
            name: _landmark(landmark_shapes.get(name), pose, colours[name])
            for name, pose in scene.landmarks
        },
        "poses": {o.name: _pose(o.pose) for o in scene.objects},
        "table": table,
    }


def layout_of_objects(objects: ObjectsFile, name: str) -> dict[str, Any]:
    """The layout of an objects file (``name``): its start as a scene, in the
    colours, masses and types it gives."""
    layout = layout_of_scene(objects.scene)
    layout["template"] = None
    for thing, key, value in objects.masses:
        if thing in layout["objects"]:
            layout["objects"][thing][key] = value
    return layout


def objects_document(layout: Layout) -> dict[str, Any]:
    """``layout`` as an objects file (``demoplan/objects-1``): every object with
    its shape, size, colour, mass or density, type and start pose; every
    landmark with its shape, size, pose and colour."""
    objects: dict[str, Any] = {}
    for name, shape in layout.objects.items():
        pose = layout.poses[name]
        entry: dict[str, Any] = {"shape": shape.shape, "size": _tidy(shape.size)}
        entry |= {"position": _tidy(pose.xyz), "yaw": round(pose.yaw, 6)}
        extras = {"colour": shape.colour, "mass": shape.mass, "density": shape.density}
        entry |= {k: v for k, v in (extras | {"type": shape.type}).items() if v is not None}
        objects[name] = entry
    landmarks: dict[str, Any] = {}
    for name, mark in layout.landmarks.items():
        landmarks[name] = {
            "shape": mark.shape,
            "position": _tidy(mark.xyz),
            "yaw": round(mark.yaw, 6),
        }
        if mark.size is not None:
            landmarks[name]["size"] = _tidy(mark.size)
        if mark.colour is not None:
            landmarks[name]["colour"] = mark.colour
    document: dict[str, Any] = {"format": "demoplan/objects-1", "objects": objects}
    return document | ({"landmarks": landmarks} if landmarks else {})


def _tidy(values: Iterable[float] | None) -> list[float] | None:
    """Lengths as a file shows them: to the micrometre, without the last bits of
    the page's arithmetic (0.10500000000000001 m is 0.105 m; the page snaps to
    0.1 mm)."""
    return None if values is None else [round(float(v), 6) for v in values]


def scattered(layout: Layout, seed: int) -> dict[str, Any]:
    """``layout`` with its objects scattered on the table at random (seeded: the
    same seed, the same layout): standing on the table, apart from each other
    and from the landmarks by :data:`SCATTER_GAP`, at any yaw."""
    table = layout.table or _table_body(layout)
    (x0, y0), (width, depth) = table.origin, table.size
    rng = random.Random(seed)
    taken: list[BaseGeometry] = [
        footprint(_geometry(mark.shape, mark.size), mark.xyz, mark.yaw)
        for mark in layout.landmarks.values()
        if mark.size is not None
    ]
    poses: dict[str, Any] = {}
    for name in sorted(layout.objects):
        shape = layout.objects[name]
        if shape.size is None:
            raise InputError(
                "has no size; a layout to scatter gives every object's size",
                field=f"layout.objects.{name}.size",
            )
        geometry = _geometry(shape.shape, shape.size)
        reach = max(geometry.size[0], geometry.size[1]) / 2 * 2**0.5
        for _ in range(SCATTER_TRIES):
            x = x0 + reach + rng.random() * max(width - 2 * reach, 0.0)
            y = y0 + reach + rng.random() * max(depth - 2 * reach, 0.0)
            yaw = float(rng.randrange(360))
            outline = footprint(geometry, (x, y), yaw)
            if not any(outline.distance(other) < SCATTER_GAP for other in taken):
                break
        else:
            raise InputError(
                f"no room on the table ({width:g} × {depth:g} m) for {name!r} among "
                f"{plural(len(taken), 'other')}; a larger table or fewer objects expected",
                field="layout.table",
            )
        taken.append(outline)
        poses[name] = {"position": [round(x, 4), round(y, 4), 0.0], "yaw": yaw}
    out = layout.model_dump()
    out["poses"] = {name: poses[name] for name in layout.objects}
    out["table"] = table.model_dump()
    return out


def dropped_pose(
    layout: Layout, name: str, position: tuple[float, float], yaw: float
) -> dict[str, Any]:
    """Where ``name`` comes to rest released over ``position`` at ``yaw``
    (:func:`demoplan.commands.scenes.drop`): its pose and what it stands on.
    Every object's size is needed (an InputError naming the first without)."""
    rest = drop(name, position, yaw, *_standing(layout))
    return {"pose": {"position": list(rest.position), "yaw": rest.yaw}, "on": rest.on}


def placed_landmark(
    layout: Layout, name: str, position: tuple[float, float], yaw: float
) -> dict[str, Any]:
    """``name``'s landmark moved to ``position`` at ``yaw``: it stands on the
    table, and may not be put down on or through an object or another landmark
    (:func:`demoplan.commands.scenes.place_landmark`)."""
    mark = layout.landmarks.get(name)
    if mark is None:
        raise InputError(
            f"unknown landmark {name!r}; expected one of {sorted(layout.landmarks)}",
            field="landmark",
        )
    pose = {"position": [position[0], position[1], 0.0], "yaw": yaw}
    if mark.size is None:
        return {"pose": pose}
    moved = Standing((position[0], position[1], 0.0), yaw, _geometry(mark.shape, mark.size))
    place_landmark(name, moved, *_standing(layout))
    return {"pose": pose}


def _standing(layout: Layout) -> tuple[dict[str, Standing], dict[str, Standing]]:
    """The layout's objects (each must have a size) and its sized landmarks, where they stand."""
    objects = {
        n: Standing(layout.poses[n].xyz, layout.poses[n].yaw, _known(layout, n))
        for n in layout.objects
    }
    landmarks = {
        n: Standing(mark.xyz, mark.yaw, _geometry(mark.shape, mark.size))
        for n, mark in layout.landmarks.items()
        if mark.size is not None
    }
    return objects, landmarks


def _known(layout: Layout, name: str) -> ObjectGeometry:
    shape = layout.objects[name]
    if shape.size is None:
        raise InputError(
            "has no size; every object's size expected", field=f"layout.objects.{name}.size"
        )
    return _geometry(shape.shape, shape.size)


def _geometry(shape: str, size: list[float]) -> ObjectGeometry:
    return ObjectGeometry(shape, (size[0], size[1], size[2]))


def _outline(shape: ObjectGeometry | None, pose: Pose) -> BaseGeometry:
    if shape is None:
        return shapely.Point(pose.position[0], pose.position[1])
    return footprint(shape, pose.position, pose.yaw)


def _table(outlines: list[BaseGeometry]) -> dict[str, Any]:
    if not outlines:
        return {"origin": [-0.5, -0.5], "size": [1.0, 1.0]}
    x0, y0, x1, y1 = shapely.union_all(outlines).bounds
    return {
        "origin": [round(x0 - TABLE_MARGIN, 4), round(y0 - TABLE_MARGIN, 4)],
        "size": [round(x1 - x0 + 2 * TABLE_MARGIN, 4), round(y1 - y0 + 2 * TABLE_MARGIN, 4)],
    }


def _table_body(layout: Layout) -> Any:
    from demoplan.studio.requests import TableBody

    outlines: list[BaseGeometry] = []
    for name, pose in layout.poses.items():
        size = layout.objects[name].size
        point = shapely.Point(pose.xyz[0], pose.xyz[1])
        outlines.append(point if size is None else point.buffer(max(size[:2]) / 2))
    outlines += [shapely.Point(m.xyz[0], m.xyz[1]) for m in layout.landmarks.values()]
    return TableBody.model_validate(_table(outlines))


def _shape(geometry: ObjectGeometry, colour: str, kind: str | None = None) -> dict[str, Any]:
    shape = {"shape": geometry.shape, "size": list(geometry.size), "colour": colour}
    return shape if kind is None else {**shape, "type": kind}


def _landmark(geometry: ObjectGeometry | None, pose: Pose, colour: str) -> dict[str, Any]:
    return {
        "shape": geometry.shape if geometry is not None else "box",
        "size": list(geometry.size) if geometry is not None else None,
        "position": list(pose.position),
        "yaw": round(pose.yaw, 6),
        "colour": colour,
    }


def _pose(pose: Pose) -> dict[str, Any]:
    return {"position": list(pose.position), "yaw": round(pose.yaw, 6)}
