"""Poses, units and object geometry as demoplan's files spell them (SPEC §2).

The pydantic schemas that demonstration files (:mod:`demoplan.learning.demonstrations`)
and scene files (:mod:`demoplan.scenes.scene`) share: a pose is a ``position``
(two or three coordinates) and at most one orientation (``yaw``, ``rpy`` or
``quat``), in the file's ``units``; :func:`pose_from_dict` turns one into a
:class:`~demoplan.model.Pose` in metres and a unit quaternion.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from demoplan.model import Pose
from demoplan.rotations import canonical_quat, quat_from_rpy, quat_from_yaw

__all__ = [
    "LENGTH_SCALE",
    "MAX_COORDINATE",
    "Coordinate",
    "Number",
    "ObjectSchema",
    "PoseSchema",
    "UnitsSchema",
    "pose_from_dict",
    "pose_to_dict",
]

LENGTH_SCALE = {"m": 1.0, "cm": 0.01, "mm": 0.001}
"""Metres per unit of length."""

# A number is a JSON number: not a string ("1.5") nor a boolean (true), which
# pydantic's lax mode would otherwise turn into 1.5 and 1.0.
Number = Annotated[float, Field(strict=True)]
MAX_COORDINATE = 1.0e4  # m (in the file's units): a table, a room, a building — not 1e300
Coordinate = Annotated[float, Field(strict=True, ge=-MAX_COORDINATE, le=MAX_COORDINATE)]


class _Schema(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)


class UnitsSchema(_Schema):
    length: Literal["m", "cm", "mm"] = "m"
    angle: Literal["deg", "rad"] = "deg"


class PoseSchema(_Schema):
    position: list[Coordinate] = Field(min_length=2, max_length=3)
    yaw: Number | None = None
    rpy: list[Number] | None = Field(default=None, min_length=3, max_length=3)
    quat: list[Number] | None = Field(default=None, min_length=4, max_length=4)

    @model_validator(mode="after")
    def _one_orientation(self) -> PoseSchema:
        given = [k for k in ("yaw", "rpy", "quat") if getattr(self, k) is not None]
        if len(given) > 1:
            raise ValueError(f"give one orientation (yaw, rpy or quat), got {' and '.join(given)}")
        if self.quat is not None and math.hypot(*self.quat) < 1e-9:
            raise ValueError("quat must be a non-zero quaternion [x, y, z, w]")
        return self


class ObjectSchema(_Schema):
    shape: Literal["box", "cylinder", "sphere", "mesh"] = "box"
    size: list[Number] = Field(min_length=3, max_length=3)

    @field_validator("size")
    @classmethod
    def _positive(cls, size: list[float]) -> list[float]:
        if any(v <= 0 for v in size):
            raise ValueError(f"size must be three positive extents [x, y, z], got {size}")
        return size


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
