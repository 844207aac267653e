"""Scene files (docs/formats.md ``demoplan/scene-1``): the world at run time.

```json
{"format": "demoplan/scene-1",
 "objects": {"red": {"position": [0.31, 0.04, 0.04], "yaw": 0, "size": [0.04, 0.04, 0.04]}},
 "freespace": [[0.10, 0.30], [0.15, 0.30]],
 "gripper": {"finger_radius": 0.02}}
```

Beyond the basic fields a scene may give, per object, ``"shape"`` (``box``
default, ``cylinder``, ``sphere``) and ``"grasps"`` (finger axes in degrees in
the object's frame; default ``[0, 90]``: two orthogonal side grasps, as the
paper's blocks have); ``"landmarks"`` (static poses used as references); and
``"table": {"min": [x, y], "max": [x, y]}`` (where free space may be generated).
An object's size may be left out when the task model knows it from the
demonstrations (:func:`complete_geometry`). An object or a landmark may name its
``"colour"`` (``"#d62728"`` or ``[r, g, b]`` in 0–1): every renderer draws it in
that colour (:func:`demoplan.plotting.colours.assign_colours`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from demoplan.documents.colours import GivenColour
from demoplan.documents.masses import with_mass
from demoplan.documents.names import ObjectName
from demoplan.documents.poses import (
    LENGTH_SCALE,
    Coordinate,
    LandmarkSchema,
    Number,
    PoseSchema,
    TypeName,
    UnitsSchema,
    pose_from_dict,
    pose_to_dict,
    positive_extents,
)
from demoplan.documents.units import check_document
from demoplan.errors import InputError
from demoplan.fileio import check_format, describe_validation_error, read_document
from demoplan.model import (
    Demonstration,
    ObjectGeometry,
    Pose,
    TaskModel,
    Vector3,
    demonstrated_shapes,
)

__all__ = [
    "DEFAULT_GRASPS",
    "Gripper",
    "Scene",
    "SceneObject",
    "complete_geometry",
    "final_layout",
    "load_scene",
    "scene_from_document",
    "scene_of_objects_file",
    "scene_to_dict",
]

MAX_GRIPPER = 0.5  # m: finger radius or clearance beyond this is a unit mistake
DEFAULT_GRASPS = (0.0, 90.0)
"""Finger axes (degrees, object frame) of an object whose scene entry names none."""


@dataclass(frozen=True, slots=True)
class SceneObject:
    """A movable object: pose, geometry (None until known) and grasps (finger axes, deg)."""

    name: str
    pose: Pose
    geometry: ObjectGeometry | None
    grasps: tuple[float, ...] = DEFAULT_GRASPS
    type: str | None = None
    """Declared type: one of several interchangeable instances (two plates);
    ``None``: the object is of its own type, its name."""

    @property
    def kind(self) -> str:
        """The object's type: as declared, else its name."""
        return self.type or self.name


@dataclass(frozen=True, slots=True)
class Gripper:
    """A parallel-jaw gripper: each finger a disc of ``finger_radius`` (paper §V.B's g_r).

    With grasp axis u, the fingers stand at ``a ± ĝ`` with ``|ĝ|`` = half the
    object's extent along u + ``finger_radius`` + ``clearance``.
    """

    finger_radius: float = 0.02
    clearance: float = 0.0


@dataclass(frozen=True, slots=True)
class Scene:
    """The world at run time (docs/formats.md "Scene")."""

    objects: tuple[SceneObject, ...]
    landmarks: tuple[tuple[str, Pose], ...] = ()
    freespace: tuple[Vector3, ...] | None = None
    gripper: Gripper = Gripper()
    table: tuple[tuple[float, float], tuple[float, float]] | None = None
    source: str = "scene"
    robot: tuple[float, float, float] | None = None
    """Where the arm of ``--sim arm`` stands: (x, y, yaw°); None: placed to reach the task."""
    landmark_geometry: tuple[tuple[str, ObjectGeometry], ...] = ()
    """The shape and size of landmarks that have one (a tray): things stand on
    their top, and figures draw them."""
    colours: tuple[tuple[str, str], ...] = ()
    """(name, ``#rrggbb``) of each object and landmark whose file gives its
    colour; the others take the figures' palette."""
    reach: float | None = None
    """m: how far from ``robot``'s base (horizontally) the hand puts things down,
    where a world knows it (robosuite's Panda); a region goal's target is chosen
    within it (:mod:`demoplan.scenes.regions`). None: anywhere. Not in scene files."""

    def object(self, name: str) -> SceneObject:
        for obj in self.objects:
            if obj.name == name:
                return obj
        raise KeyError(name)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(obj.name for obj in self.objects)

    @property
    def landmark_names(self) -> tuple[str, ...]:
        return tuple(name for name, _ in self.landmarks)

    @property
    def given_colours(self) -> dict[str, str]:
        """Name → ``#rrggbb`` of the objects and landmarks the file gives a colour."""
        return dict(self.colours)


def final_layout(demonstration: Demonstration) -> Scene:
    """``demonstration``'s layout after its last step, as a scene (the studio
    shows a learned task's targets there when no scene is given)."""
    poses = demonstration.initial_poses()
    for step in demonstration.steps:
        poses[step.object] = step.pose
    geometry = demonstration.geometry()
    landmarks = demonstration.landmark_poses()
    return Scene(
        objects=tuple(
            SceneObject(name, pose, geometry.get(name))
            for name, pose in poses.items()
            if name not in landmarks
        ),
        landmarks=tuple(landmarks.items()),
        landmark_geometry=tuple((n, g) for n, g in geometry.items() if n in landmarks),
        source="the first demonstration's final layout",
    )


class _Schema(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)


class _ObjectSchema(PoseSchema):
    size: list[Number] | None = Field(default=None, min_length=3, max_length=3)
    shape: Literal["box", "cylinder", "sphere"] = "box"
    grasps: list[Number] | None = Field(default=None, min_length=1, max_length=16)
    mass: Number | None = Field(default=None, gt=0)  # kg (demoplan.documents.masses)
    density: Number | None = Field(default=None, gt=0)  # kg/m³
    type: TypeName | None = None
    colour: GivenColour = None

    @field_validator("size")
    @classmethod
    def _positive(cls, size: list[float] | None) -> list[float] | None:
        return None if size is None else positive_extents(size)


class _GripperSchema(_Schema):
    finger_radius: Number = Field(default=0.02, gt=0)
    clearance: Number = Field(default=0.0, ge=0)


class _TableSchema(_Schema):
    min: list[Coordinate] = Field(min_length=2, max_length=2)
    max: list[Coordinate] = Field(min_length=2, max_length=2)

    @model_validator(mode="after")
    def _ordered(self) -> _TableSchema:
        if not (self.min[0] < self.max[0] and self.min[1] < self.max[1]):
            raise ValueError(f"table min {self.min} must lie below and left of max {self.max}")
        return self


class _RobotSchema(_Schema):
    base: list[Coordinate] = Field(min_length=2, max_length=2)
    yaw: Number = Field(default=0.0, ge=-360, le=360)


class _SceneSchema(_Schema):
    format: str
    name: str | None = None
    description: str | None = None
    units: UnitsSchema = UnitsSchema()
    objects: dict[ObjectName, _ObjectSchema]
    landmarks: dict[ObjectName, LandmarkSchema] = {}
    freespace: list[list[Coordinate]] | None = None
    gripper: _GripperSchema = _GripperSchema()
    table: _TableSchema | None = None
    robot: _RobotSchema | None = None

    @field_validator("objects")
    @classmethod
    def _some(cls, objects: dict[ObjectName, _ObjectSchema]) -> dict[ObjectName, _ObjectSchema]:
        if not objects:
            raise ValueError("no objects; at least one expected")
        return objects

    @field_validator("freespace")
    @classmethod
    def _spots(cls, spots: list[list[float]] | None) -> list[list[float]] | None:
        for spot in spots or []:
            if len(spot) not in (2, 3):
                raise ValueError(f"a free-space spot is [x, y] or [x, y, z], got {spot}")
        return spots


def scene_from_document(data: dict[str, Any], source: str) -> Scene:
    """Parse a ``demoplan/scene-1`` document (lengths to metres)."""
    check_format(data, {"scene"}, source)
    try:
        parsed = _SceneSchema.model_validate(data)
    except ValidationError as exc:
        raise describe_validation_error(exc, source) from None
    check_document(data, parsed.units, source)
    scale = LENGTH_SCALE[parsed.units.length]
    objects = [_scene_object(name, entry, parsed, source) for name, entry in parsed.objects.items()]
    freespace = _freespace(parsed, scale, source)
    gripper = Gripper(parsed.gripper.finger_radius * scale, parsed.gripper.clearance * scale)
    for name in ("finger_radius", "clearance"):
        if getattr(gripper, name) > MAX_GRIPPER:
            raise InputError(
                f"{getattr(gripper, name):g} m is too large; at most {MAX_GRIPPER} m expected",
                source=source,
                field=f"gripper.{name}",
            )
    table = None
    if parsed.table is not None:
        lo, hi = parsed.table.min, parsed.table.max
        table = ((lo[0] * scale, lo[1] * scale), (hi[0] * scale, hi[1] * scale))
    robot = None
    if parsed.robot is not None:
        robot = (parsed.robot.base[0] * scale, parsed.robot.base[1] * scale, parsed.robot.yaw)
    return Scene(
        objects=tuple(objects),
        landmarks=tuple((n, entry.pose(parsed.units)) for n, entry in parsed.landmarks.items()),
        landmark_geometry=tuple(
            (n, geometry)
            for n, entry in parsed.landmarks.items()
            if (geometry := entry.geometry(parsed.units)) is not None
        ),
        freespace=freespace,
        gripper=gripper,
        table=table,
        source=source,
        robot=robot,
        colours=tuple(
            (name, str(entry.colour))
            for entries in (parsed.objects, parsed.landmarks)
            for name, entry in entries.items()
            if entry.colour is not None
        ),
    )


def _scene_object(
    name: str, entry: _ObjectSchema, parsed: _SceneSchema, source: str
) -> SceneObject:
    """One object of a scene document, checked (lengths to metres)."""
    scale = LENGTH_SCALE[parsed.units.length]
    to_deg = math.degrees if parsed.units.angle == "rad" else float
    if "#" in name and entry.type is None:
        raise InputError(
            "'#' names a role of a type (plate#1); an object name without '#' expected "
            "(as in demonstration files)",
            source=source,
            field=f"objects.{name}",
        )
    if name in parsed.landmarks:
        raise InputError(
            "is both an object and a landmark; one kind expected",
            source=source,
            field=f"objects.{name}",
        )
    pose = pose_from_dict(
        PoseSchema(**entry.model_dump(include=set(PoseSchema.model_fields))),
        parsed.units,
    )
    if pose.position[2] < -0.005:
        raise InputError(
            f"z = {pose.position[2]:g} m lies under the table top; z ≥ 0 expected",
            source=source,
            field=f"objects.{name}.position",
        )
    geometry = None
    if entry.size is not None:
        size = (entry.size[0] * scale, entry.size[1] * scale, entry.size[2] * scale)
        geometry = with_mass(
            ObjectGeometry(entry.shape, size),
            entry.mass,
            entry.density,
            source,
            f"objects.{name}",
        )
    elif entry.mass is not None or entry.density is not None:
        raise InputError(
            'has no "size" to go with it; a mass or density is given with the size',
            source=source,
            field=f"objects.{name}.{'mass' if entry.mass is not None else 'density'}",
        )
    grasps = DEFAULT_GRASPS if entry.grasps is None else tuple(to_deg(g) for g in entry.grasps)
    kind = None if entry.type in (None, name) else entry.type
    return SceneObject(name, pose, geometry, grasps, kind)


def _freespace(parsed: _SceneSchema, scale: float, source: str) -> tuple[Vector3, ...] | None:
    """A scene document's free-space spots (lengths to metres), on the table."""
    if parsed.freespace is None:
        return None
    freespace = tuple(
        (s[0] * scale, s[1] * scale, (s[2] if len(s) > 2 else 0.0) * scale)
        for s in parsed.freespace
    )
    for index, spot in enumerate(freespace):
        if abs(spot[2]) > 0.005:
            raise InputError(
                f"z = {spot[2]:g} m; free-space spots lie on the table (z = 0)",
                source=source,
                field=f"freespace[{index}]",
            )
    return freespace


def scene_of_objects_file(document: dict[str, Any], source: str) -> dict[str, Any]:
    """The scene an objects file (``demoplan/objects-1``, docs/formats.md
    "Objects file") starts from: the document as a ``demoplan/scene-1``, its
    colours, sizes and masses read as a scene's."""
    check_format(document, {"objects"}, source)
    return {**document, "format": "demoplan/scene-1"}


def load_scene(path: str | Path) -> Scene:
    """Read a scene file (JSON or YAML); an objects file (``demoplan/objects-1``,
    what the studio's *Save objects* writes) is read as the scene it starts from."""
    source = str(path)
    document = read_document(Path(path))
    kind, _ = check_format(document, {"scene", "objects"}, source)
    if kind == "objects":
        document = scene_of_objects_file(document, source)
    return scene_from_document(document, source)


def complete_geometry(scene: Scene, model: TaskModel) -> Scene:
    """Give every object without a size in the scene the geometry the
    demonstrations recorded for it; an object known nowhere is an error."""
    known = demonstrated_shapes(model.demonstrations)  # one geometry per object (checked)
    types = model.object_types()
    for name, kind in types.items():  # one geometry per type (checked)
        if name in known:
            known.setdefault(kind, known[name])
    objects = []
    for obj in scene.objects:
        if obj.geometry is None:
            shape = known.get(obj.name, known.get(obj.kind))
            if shape is None:
                raise InputError(
                    "has no size and the task model's demonstrations do not give one; "
                    'expected "size": [x, y, z]',
                    source=scene.source,
                    field=f"objects.{obj.name}",
                )
            obj = replace(obj, geometry=shape)
        objects.append(obj)
    return replace(scene, objects=tuple(objects))


def scene_to_dict(scene: Scene) -> dict[str, Any]:
    """A scene in the file form of docs/formats.md (metres, quaternions)."""
    objects: dict[str, Any] = {}
    for obj in scene.objects:
        entry = pose_to_dict(obj.pose)
        if obj.geometry is not None:
            entry["shape"] = obj.geometry.shape
            entry["size"] = list(obj.geometry.size)
            if obj.geometry.mass is not None:
                entry["mass"] = obj.geometry.mass
        if obj.grasps != DEFAULT_GRASPS:
            entry["grasps"] = list(obj.grasps)
        if obj.type is not None:
            entry["type"] = obj.type
        objects[obj.name] = entry
    colours = scene.given_colours
    out: dict[str, Any] = {"format": "demoplan/scene-1", "objects": objects}
    if scene.landmarks:
        shapes = dict(scene.landmark_geometry)
        out["landmarks"] = {}
        for name, pose in scene.landmarks:
            entry = pose_to_dict(pose)
            if name in shapes:
                entry["shape"] = shapes[name].shape
                entry["size"] = list(shapes[name].size)
            out["landmarks"][name] = entry
    for name, colour in colours.items():
        group = out["landmarks"] if name in scene.landmark_names else objects
        group[name]["colour"] = colour
    if scene.freespace is not None:
        out["freespace"] = [list(s) for s in scene.freespace]
    out["gripper"] = {
        "finger_radius": scene.gripper.finger_radius,
        "clearance": scene.gripper.clearance,
    }
    if scene.table is not None:
        out["table"] = {"min": list(scene.table[0]), "max": list(scene.table[1])}
    if scene.robot is not None:
        out["robot"] = {"base": list(scene.robot[:2]), "yaw": scene.robot[2]}
    return out
