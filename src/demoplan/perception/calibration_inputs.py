"""What a table calibration is made from: the *markers file* (which ArUco /
AprilTag dictionary, the markers' side and where each id lies on the table;
docs/formats.md "Markers file") and, when known, the camera's *intrinsics*
(its matrix K and distortion; docs/formats.md "Camera file"), read and checked
into a :class:`MarkerLayout` and an :class:`Intrinsics`. The calibration
itself is :mod:`demoplan.perception.calibration`'s."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from demoplan.documents.poses import Number
from demoplan.errors import InputError
from demoplan.fileio import check_format, describe_validation_error, read_document

__all__ = [
    "Intrinsics",
    "MarkerLayout",
    "is_marker_id",
    "load_intrinsics",
    "load_markers",
    "markers_from_document",
]

MAX_MARKER_SIDE = 5.0
"""Metres: a marker larger than this is a mistake in the file."""
MAX_REACH = 3.0
"""Metres from the image centre's point on the table: the table a rectified view
without markers covers at most (a view towards the horizon sees far more table
than a calibration is good for)."""


def _dictionaries() -> dict[str, int]:
    from demoplan.perception.opencv import cv2

    return {
        name: int(getattr(cv2.aruco, name))
        for name in dir(cv2.aruco)
        if name.startswith("DICT_") and isinstance(getattr(cv2.aruco, name), int)
    }


MARKER_ID_EXPECTED = "a marker id expected: a whole number of 1 to 6 digits 0-9"
_Row = Annotated[list[Number], Field(min_length=3, max_length=3)]
MAX_PIXELS_FIELD = 1e6
"""The largest entry of a camera matrix (px)."""


def is_marker_id(key: str) -> bool:
    """``"3"`` is marker 3; ``"²"``, ``"٣"`` (Arabic-Indic 3) or 5,000 digits are not
    (``str.isdigit`` alone takes them, and ``int`` then fails or reads 3)."""
    return 1 <= len(key) <= 6 and all("0" <= c <= "9" for c in key)


class _MarkersSchema(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)

    format: str | None = Field(None, description="`demoplan/markers-1` (may be left out).")
    dictionary: str = Field(
        description="The OpenCV dictionary the markers come from: `DICT_4X4_50`, "
        "`DICT_6X6_250`, `DICT_APRILTAG_36h11`…"
    )
    side: Number = Field(
        gt=0, le=MAX_MARKER_SIDE, description="The side of a marker's black square (m)."
    )
    markers: dict[str, list[Number]] = Field(
        description="Each id's position on the table: `[x, y]` (m) of its centre, or "
        "`[x, y, yaw]` with yaw in degrees (0: the marker's top edge faces +y)."
    )

    @field_validator("markers")
    @classmethod
    def _positions(cls, value: dict[str, list[float]]) -> dict[str, list[float]]:
        if not value:
            raise ValueError("at least one marker expected")
        for key, position in value.items():
            if not is_marker_id(key):
                raise ValueError(f"marker id {key[:20]!r}: {MARKER_ID_EXPECTED}")
            if len(position) not in (2, 3):
                raise ValueError(f"marker {key}: [x, y] or [x, y, yaw] expected")
        return value


@dataclass(frozen=True, slots=True)
class MarkerLayout:
    """Markers lying on the table: the dictionary, their side (m) and each id's
    centre (x, y) (m) and yaw (deg; 0: the marker's top edge faces +y)."""

    dictionary: str
    side: float
    positions: Mapping[int, tuple[float, float, float]]

    def corners(self, marker_id: int) -> np.ndarray:
        """The table (x, y) of the marker's four corners, in OpenCV's order
        (top-left, top-right, bottom-right, bottom-left of the marker image)."""
        x, y, yaw = self.positions[marker_id]
        h = self.side / 2
        c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
        local = ((-h, h), (h, h), (h, -h), (-h, -h))
        return np.array([(x + c * a - s * b, y + s * a + c * b) for a, b in local])


def load_markers(path: Path) -> MarkerLayout:
    """Read a markers file (JSON or YAML; docs/formats.md "Markers file")."""
    source = str(path)
    data = read_document(Path(path))
    return markers_from_document(data, source)


def markers_from_document(data: dict[str, Any], source: str) -> MarkerLayout:
    """A :class:`MarkerLayout` from a parsed markers document."""
    if "format" in data:
        check_format(data, {"markers"}, source)
    try:
        parsed = _MarkersSchema.model_validate(data)
    except ValidationError as exc:
        raise describe_validation_error(exc, source) from None
    known = _dictionaries()
    if parsed.dictionary not in known:
        raise InputError(
            f"unknown dictionary {parsed.dictionary[:40]!r}; one of OpenCV's expected "
            "(DICT_4X4_50, DICT_5X5_100, DICT_6X6_250, DICT_ARUCO_ORIGINAL, DICT_APRILTAG_36h11…)",
            source=source,
            field="dictionary",
        )
    positions: dict[int, tuple[float, float, float]] = {}
    for key, value in parsed.markers.items():
        if max(abs(v) for v in value[:2]) > MAX_REACH * 100:
            raise InputError(
                "a position on the table within ±300 m expected",
                source=source,
                field=f"markers.{key}",
            )
        positions[int(key)] = (value[0], value[1], value[2] if len(value) == 3 else 0.0)
    return MarkerLayout(parsed.dictionary, parsed.side, positions)


@dataclass(frozen=True, slots=True)
class Intrinsics:
    """A pinhole camera's matrix K (px) and OpenCV distortion coefficients."""

    matrix: np.ndarray
    distortion: np.ndarray = field(default_factory=lambda: np.zeros(5))


class _IntrinsicsSchema(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)

    camera_matrix: list[_Row] = Field(
        min_length=3,
        max_length=3,
        description="K, 3 × 3: `[[fx, 0, cx], [0, fy, cy], [0, 0, 1]]` (px; OpenCV's pixel "
        "coordinates, (0, 0) the centre of the top-left pixel).",
    )
    distortion: list[Number] = Field(
        default=[],
        description="OpenCV distortion coefficients (k1, k2, p1, p2[, k3…]); none: no distortion.",
    )


def _intrinsics(data: Any, source: str, prefix: str) -> Intrinsics:
    try:
        parsed = _IntrinsicsSchema.model_validate(data)
    except ValidationError as exc:
        raise describe_validation_error(exc, source, prefix) from None
    matrix = np.array(parsed.camera_matrix, dtype=float)
    where = f"{prefix}.camera_matrix" if prefix else "camera_matrix"
    if matrix.shape != (3, 3) or not (matrix[0, 0] > 0 and matrix[1, 1] > 0):
        raise InputError(
            "a 3 × 3 camera matrix [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] with fx, fy > 0 expected",
            source=source,
            field=where,
        )
    if not np.allclose(matrix[2], [0, 0, 1]) or matrix[1, 0] != 0:
        raise InputError("its last row [0, 0, 1] expected", source=source, field=where)
    if np.abs(matrix).max() > MAX_PIXELS_FIELD:
        raise InputError(
            f"entries within {MAX_PIXELS_FIELD:,.0f} px expected (a focal length and an "
            "image centre in pixels)",
            source=source,
            field=where,
        )
    if len(parsed.distortion) not in (0, 4, 5, 8, 12, 14):
        raise InputError(
            "4, 5, 8, 12 or 14 OpenCV distortion coefficients expected",
            source=source,
            field=f"{prefix}.distortion" if prefix else "distortion",
        )
    distortion = np.array(parsed.distortion or [0.0] * 5, dtype=float)
    return Intrinsics(matrix, distortion)


def load_intrinsics(path: Path) -> Intrinsics:
    """Read an intrinsics file (``camera_matrix``, ``distortion``; docs/formats.md)."""
    return _intrinsics(read_document(Path(path)), str(path), "")
