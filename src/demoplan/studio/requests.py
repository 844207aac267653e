"""The request bodies of the studio's HTTP API, with their limits
(docs/studio-api.md, docs/limits.md): names are short printable strings,
numbers finite and within the project's limits (a position within 1 km of the
origin, an extent 0.1 mm – 10 m), lists and maps bounded. A document (a
demonstration, a scene) is checked here only for its size and depth; its
fields are checked by the project's own parsers, as ``learn`` and ``plan``
read them.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, StrictBool, StringConstraints, field_validator

from demoplan.documents.colours import HEX_COLOUR

__all__ = [
    "MAX_BODY_BYTES",
    "MAX_FILES",
    "MAX_OBJECTS",
    "DemonstrationRequest",
    "DropRequest",
    "LandmarkRequest",
    "Layout",
    "LearnRequest",
    "ObjectsRequest",
    "PlanRequest",
    "RunRequest",
    "SceneRequest",
    "ScrambleRequest",
    "SourceBody",
]

MAX_DISTANCE_M = 1000.0
"""m: a position's limit on any axis, as in every file (``demoplan.documents.poses``;
repeated here so that the server starts without the numeric stack, and checked
equal by tests/studio/test_studio_api.py)."""
MIN_SIZE_M = 1e-4
MAX_SIZE_M = 10.0
"""m: an object's extents, as in every file (``demoplan.documents.poses``)."""
MAX_BODY_BYTES = 1024 * 1024
"""A request body's limit (HTTP 413 beyond)."""
MAX_OBJECTS = 200
"""Objects (and landmarks) in a layout."""
MAX_FILES = 200
"""Files named in one request."""
MAX_DEPTH = 32
"""Nesting of a document's JSON (a demonstration is four levels deep)."""
MAX_SEED = 2**32 - 1
MAX_YAW = 3600.0
"""deg: ten turns either way; a larger angle is a unit mistake."""

Name = Annotated[
    str, StringConstraints(min_length=1, max_length=100, pattern=r"^[^\x00-\x1f\x7f]+$")
]
"""An object's or landmark's name: 1–100 printable characters."""
FileName = Annotated[str, StringConstraints(min_length=1, max_length=100)]
"""A work-folder file name (checked in full by :class:`~demoplan.studio.workfolder.WorkFolder`)."""
Coordinate = Annotated[float, Field(strict=True, ge=-MAX_DISTANCE_M, le=MAX_DISTANCE_M)]
Extent = Annotated[float, Field(strict=True, ge=MIN_SIZE_M, le=MAX_SIZE_M)]
Yaw = Annotated[float, Field(strict=True, ge=-MAX_YAW, le=MAX_YAW)]
Seed = Annotated[int, Field(strict=True, ge=0, le=MAX_SEED)]
TypeName = Annotated[
    str, StringConstraints(min_length=1, max_length=100, pattern=r"^[^\s#\x00-\x1f\x7f]+$")
]
"""A type of identical objects (``plate``): no spaces, no ``#`` (roles are ``plate#1``)."""
MAX_MASS_KG = 1000.0
"""kg: an object a hand moves; more is a unit mistake."""
MAX_DENSITY = 22600.0
"""kg/m³: osmium, the densest element."""


class _Body(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)


class PoseBody(_Body):
    """``{"position": [x, y, z], "yaw": deg}``: z the bottom face's centre (0 when left out)."""

    position: list[Coordinate] = Field(min_length=2, max_length=3)
    yaw: Yaw = 0.0

    @property
    def xyz(self) -> tuple[float, float, float]:
        x, y, *rest = self.position
        return (x, y, rest[0] if rest else 0.0)


class ShapeBody(_Body):
    """An object: its shape and size; its colour, its mass (kg) or density
    (kg/m³) and its type (identical objects share one) where given."""

    shape: Literal["box", "cylinder", "sphere", "mesh"] = "box"
    size: list[Extent] | None = Field(min_length=3, max_length=3)
    colour: str | None = Field(default=None, pattern=HEX_COLOUR.pattern)
    mass: Annotated[float, Field(strict=True, gt=0, le=MAX_MASS_KG)] | None = None
    density: Annotated[float, Field(strict=True, gt=0, le=MAX_DENSITY)] | None = None
    type: TypeName | None = None


class LandmarkBody(PoseBody):
    """A landmark: its shape (the size may be unknown) where it stands."""

    shape: Literal["box", "cylinder", "sphere", "mesh"] = "box"
    size: list[Extent] | None = Field(default=None, min_length=3, max_length=3)
    colour: str | None = Field(default=None, pattern=HEX_COLOUR.pattern)


class TableBody(_Body):
    origin: list[Coordinate] = Field(min_length=2, max_length=2)
    size: list[Annotated[float, Field(strict=True, gt=0, le=2 * MAX_DISTANCE_M)]] = Field(
        min_length=2, max_length=2
    )


class Layout(_Body):
    """Objects (shape, size), landmarks, each object's pose, and the table drawn."""

    template: Name | None = None
    objects: dict[Name, ShapeBody] = Field(max_length=MAX_OBJECTS)
    landmarks: dict[Name, LandmarkBody] = Field(default={}, max_length=MAX_OBJECTS)
    poses: dict[Name, PoseBody] = Field(max_length=MAX_OBJECTS)
    table: TableBody | None = None

    @field_validator("poses")
    @classmethod
    def _poses_known(cls, poses: dict[str, PoseBody], info: Any) -> dict[str, PoseBody]:
        objects = info.data.get("objects")
        if objects is None:
            return poses
        for name in poses:
            if name not in objects:
                raise ValueError(f"unknown object {name!r}; expected one of {sorted(objects)}")
        missing = sorted(set(objects) - set(poses))
        if missing:
            raise ValueError(f"no pose for {', '.join(map(repr, missing))}; one per object")
        return poses


def _bounded_document(document: dict[str, Any]) -> dict[str, Any]:
    """A document no deeper than :data:`MAX_DEPTH`, with finite numbers only."""
    stack: list[tuple[Any, int]] = [(document, 1)]
    while stack:
        value, depth = stack.pop()
        if depth > MAX_DEPTH:
            raise ValueError(f"nested deeper than {MAX_DEPTH} levels")
        if isinstance(value, float) and not math.isfinite(value):
            raise ValueError(f"{value} is not a finite number")
        if isinstance(value, dict):
            stack += [(v, depth + 1) for v in value.values()]
        elif isinstance(value, list):
            stack += [(v, depth + 1) for v in value]
    return document


class DemonstrationRequest(_Body):
    document: dict[str, Any]
    name: FileName | None = None

    @field_validator("document")
    @classmethod
    def _document_bounded(cls, document: dict[str, Any]) -> dict[str, Any]:
        return _bounded_document(document)


class SceneRequest(DemonstrationRequest):
    pass


class LandmarkRequest(_Body):
    """A landmark moved or turned: where it is put down."""

    layout: Layout
    landmark: Name
    position: list[Coordinate] = Field(min_length=2, max_length=2)
    yaw: Yaw = 0.0


class ObjectsRequest(_Body):
    """An objects file to write: the layout's objects, landmarks and start."""

    layout: Layout
    replace: StrictBool = False


class SourceBody(_Body):
    """What the Teach view starts from: a template, or an objects, scene or
    demonstration file of the work folder."""

    kind: Literal["template", "file"]
    id: Annotated[str, StringConstraints(min_length=1, max_length=100)]


class DropRequest(_Body):
    layout: Layout
    object: Name
    position: list[Coordinate] = Field(min_length=2, max_length=2)
    yaw: Yaw = 0.0


class LearnRequest(_Body):
    files: list[FileName] | None = Field(default=None, min_length=1, max_length=MAX_FILES)
    output: FileName = "model.json"
    scene: dict[str, Any] | None = None

    @field_validator("scene")
    @classmethod
    def _scene_bounded(cls, scene: dict[str, Any] | None) -> dict[str, Any] | None:
        return None if scene is None else _bounded_document(scene)


class ScrambleRequest(_Body):
    layout: Layout
    seed: Seed = 0


class PlanRequest(_Body):
    model: FileName
    scene: dict[str, Any]
    clutter: StrictBool = False

    @field_validator("scene")
    @classmethod
    def _scene_bounded(cls, scene: dict[str, Any]) -> dict[str, Any]:
        return _bounded_document(scene)


class RunRequest(PlanRequest):
    faults: str = Field(default="", max_length=200)
    seed: Seed = 0
    sim: Literal["kinematic", "arm"] = "kinematic"
