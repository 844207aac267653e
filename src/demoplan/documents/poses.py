"""Poses, units and object geometry as demoplan's files spell them (docs/formats.md).

The pydantic schemas that demonstration files (:mod:`demoplan.documents.demonstrations`)
and scene files (:mod:`demoplan.scenes.scene`) share: a pose is a ``position``
(two or three coordinates) and at most one orientation (``yaw``, ``rpy`` or
``quat``), in the file's ``units``; :func:`pose_from_dict` turns one into a
:class:`~demoplan.model.Pose` in metres and a unit quaternion.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, field_validator, model_validator

from demoplan.documents.colours import GivenColour
from demoplan.errors import InputError
from demoplan.model import Compartment, ObjectGeometry, Pose
from demoplan.rotations import canonical_quat, quat_from_rpy, quat_from_yaw, unit_length_expected

__all__ = [
    "LENGTH_SCALE",
    "MAX_COORDINATE",
    "MAX_DISTANCE_M",
    "MAX_SIZE_M",
    "MIN_SIZE_M",
    "Coordinate",
    "LandmarkSchema",
    "Number",
    "ObjectSchema",
    "PoseSchema",
    "UnitsSchema",
    "check_physical",
    "pose_from_dict",
    "pose_to_dict",
    "positive_extents",
]

LENGTH_SCALE = {"m": 1.0, "cm": 0.01, "mm": 0.001}
"""Metres per unit of length."""

# A number is a JSON number: not a string ("1.5") nor a boolean (true), which
# pydantic's lax mode would otherwise turn into 1.5 and 1.0.
Number = Annotated[float, Field(strict=True)]
MAX_COORDINATE = 1.0e4  # m (in the file's units): a table, a room, a building — not 1e300
Coordinate = Annotated[float, Field(strict=True, ge=-MAX_COORDINATE, le=MAX_COORDINATE)]
MAX_ANGLE = 360.0  # deg or rad (in the file's units): a turn or a few, not 1e308
Angle = Annotated[float, Field(strict=True, ge=-MAX_ANGLE, le=MAX_ANGLE)]


class _Schema(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)


class UnitsSchema(_Schema):
    length: Literal["m", "cm", "mm"] = "m"
    angle: Literal["deg", "rad"] = "deg"


class PoseSchema(_Schema):
    position: list[Coordinate] = Field(min_length=2, max_length=3)
    yaw: Angle | None = None
    rpy: list[Angle] | None = Field(default=None, min_length=3, max_length=3)
    quat: list[Number] | None = Field(default=None, min_length=4, max_length=4)

    @model_validator(mode="after")
    def _one_orientation(self) -> PoseSchema:
        given = [k for k in ("yaw", "rpy", "quat") if getattr(self, k) is not None]
        if len(given) > 1:
            raise ValueError(f"give one orientation (yaw, rpy or quat), got {' and '.join(given)}")
        if self.quat is not None and (problem := unit_length_expected(math.hypot(*self.quat))):
            raise ValueError(f"quat [x, y, z, w]: {problem}")
        return self


def positive_extents(size: list[float]) -> list[float]:
    """``size`` if its three extents are positive; else the ValueError a schema reports."""
    if any(v <= 0 for v in size):
        raise ValueError(f"size must be three positive extents [x, y, z], got {size}")
    return size


def _type_name(text: str) -> str:
    if not text or len(text) > 100 or "#" in text or any(c.isspace() for c in text):
        raise ValueError(
            f"{text!r} is not a type name; a name of 1 to 100 characters without spaces or "
            "'#' expected (roles are named plate#1, plate#2)"
        )
    return text


TypeName = Annotated[str, AfterValidator(_type_name)]
"""A type names a kind of object (``plate``): no spaces, no ``#`` (roles are ``plate#1``)."""


class ObjectSchema(_Schema):
    shape: Literal["box", "cylinder", "sphere", "mesh"] = "box"
    size: list[Number] = Field(min_length=3, max_length=3)
    type: TypeName | None = None
    mass: Number | None = Field(default=None, gt=0)  # kg (demoplan.documents.masses)
    density: Number | None = Field(default=None, gt=0)  # kg/m³
    colour: GivenColour = None  # every figure draws it (demoplan.documents.colours)

    @field_validator("size")
    @classmethod
    def _positive(cls, size: list[float]) -> list[float]:
        return positive_extents(size)


class LandmarkSchema(PoseSchema):
    """A landmark: a pose, and optionally the thing's ``shape`` and ``size``
    (its extents [x, y, z]; z is its height) — a tray things stand on, drawn
    in every figure."""

    shape: Literal["box", "cylinder", "sphere", "mesh"] = "box"
    size: list[Number] | None = Field(default=None, min_length=3, max_length=3)
    compartments: list[Annotated[list[Coordinate], Field(min_length=6, max_length=6)]] = []
    """Its open interiors (a bin's compartments): ``[x_low, y_low, z_low, x_high,
    y_high, z_high]`` in its frame from its position; learning makes a placement
    inside one a region goal (docs/learning.md, "Region goals")."""
    colour: GivenColour = None

    @field_validator("size")
    @classmethod
    def _positive(cls, size: list[float] | None) -> list[float] | None:
        return None if size is None else positive_extents(size)

    @field_validator("compartments")
    @classmethod
    def _low_below_high(cls, boxes: list[list[float]]) -> list[list[float]]:
        for box in boxes:
            if any(box[k] >= box[k + 3] for k in range(3)):
                raise ValueError(f"expected [x, y, z] low below [x, y, z] high, got {box}")
        return boxes

    def pose(self, units: UnitsSchema) -> Pose:
        fields = self.model_dump(include=set(PoseSchema.model_fields))  # not a subclass's
        return pose_from_dict(PoseSchema(**fields), units)

    def compartment_boxes(self, units: UnitsSchema) -> tuple[Compartment, ...]:
        """Its compartments in metres."""
        scale = LENGTH_SCALE[units.length]
        out = []
        for box in self.compartments:
            x0, y0, z0, x1, y1, z1 = (v * scale for v in box)
            out.append((x0, y0, z0, x1, y1, z1))
        return tuple(out)

    def geometry(self, units: UnitsSchema) -> ObjectGeometry | None:
        if self.size is None:
            return None
        scale = LENGTH_SCALE[units.length]
        x, y, z = (v * scale for v in self.size)
        return ObjectGeometry(self.shape, (x, y, z))


MAX_DISTANCE_M = 1000.0
"""The farthest a position may lie from the origin on any axis: 1 km."""
MIN_SIZE_M = 1e-4
"""The smallest extent of an object: 0.1 mm."""
MAX_SIZE_M = 10.0
"""The largest extent of an object: 10 m."""


def check_physical(document: Any, length: str, source: str, prefix: str = "") -> None:
    """Refuse numbers no tabletop holds, after the file's length unit: a
    ``position`` (or a ``freespace`` spot) farther than :data:`MAX_DISTANCE_M`
    on an axis, a ``size`` extent outside [:data:`MIN_SIZE_M`,
    :data:`MAX_SIZE_M`]. One InputError naming the field (docs/limits.md)."""
    scale = LENGTH_SCALE.get(length, 1.0)

    def numbers(value: Any) -> list[float]:
        if isinstance(value, list) and all(
            isinstance(v, int | float) and not isinstance(v, bool) for v in value
        ):
            return [float(v) for v in value]
        return []

    def walk(value: Any, where: str) -> None:
        if isinstance(value, dict):
            for key, item in value.items():
                field = f"{where}.{key}" if where else str(key)
                if key == "position":
                    _check_position(numbers(item), scale, length, source, field)
                elif key == "size":
                    for extent in numbers(item):
                        if not MIN_SIZE_M <= extent * scale <= MAX_SIZE_M:
                            raise InputError(
                                f"extent {extent:g} {length} is outside 0.1 mm – 10 m (a "
                                "documented limit: docs/limits.md)",
                                source=source,
                                field=field,
                            )
                elif key == "freespace" and isinstance(item, list):
                    for index, spot in enumerate(item):
                        _check_position(numbers(spot), scale, length, source, f"{field}[{index}]")
                else:
                    walk(item, field)
        elif isinstance(value, list):
            for index, item in enumerate(value):
                walk(item, f"{where}[{index}]")

    walk(document, prefix)


def _check_position(
    values: list[float], scale: float, length: str, source: str, field: str
) -> None:
    for value in values:
        if abs(value * scale) > MAX_DISTANCE_M:
            raise InputError(
                f"{value:g} {length} lies more than 1 km from the origin; a position on a "
                "table expected (a documented limit: docs/limits.md)",
                source=source,
                field=field,
            )


def pose_from_dict(data: PoseSchema, units: UnitsSchema) -> Pose:
    """A validated pose → :class:`Pose` in metres and a unit quaternion."""
    scale = LENGTH_SCALE[units.length]
    x, y, *rest = (v * scale for v in data.position)
    z = rest[0] if rest else 0.0
    to_deg = math.degrees if units.angle == "rad" else float
    orientation = None
    if data.yaw is not None:
        orientation = quat_from_yaw(to_deg(data.yaw))
    elif data.rpy is not None:
        orientation = quat_from_rpy([to_deg(v) for v in data.rpy])
    elif data.quat is not None:
        orientation = canonical_quat(data.quat)
    return Pose(position=(x, y, z), orientation=orientation)


def pose_to_dict(pose: Pose) -> dict[str, Any]:
    """A pose as written by demoplan: metres, and ``quat`` (exact) when oriented."""
    out: dict[str, Any] = {"position": list(pose.position)}
    if pose.orientation is not None:
        out["quat"] = list(pose.orientation)
    return out
