"""The table seen by a camera, calibrated from markers lying on it
(docs/perception.md "Calibration"; docs/formats.md "Markers file", "Camera file").

A *markers file* says which ArUco / AprilTag dictionary the markers come from,
their side (m) and where each id lies on the table (its centre, and a yaw);
:func:`calibrate` finds them in an image with OpenCV's ``aruco`` module and
fits the homography image → table to their corners (RANSAC, then least
squares on the inliers): the :class:`TableCalibration` a *camera file*
(``demoplan/camera-1``) holds. With it a view that is not straight down is
rectified to a top view of the table (:func:`rectify`), where the detector of
:mod:`demoplan.perception.blocks` finds the blocks.

A homography maps the table's plane only: a cube's top face lies ``side``
above it, so it is seen farther from the camera's foot (the point of the table
under the camera's centre) than it is, by the factor ``H / (H − side)``, H the
camera's height. :func:`camera_centre` recovers the centre from the camera's
intrinsics (given), or from the homography alone with the focal length
estimated from it (square pixels, principal point at the image centre: two
constraints, r1·r2 = 0 and ‖r1‖ = ‖r2‖, on one unknown; Zhang 2000, §3.1),
which needs a tilted view; straight down the focal length cannot be told from
the markers and the height correction needs the intrinsics.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from demoplan.documents.poses import Number
from demoplan.errors import InputError
from demoplan.fileio import check_format, describe_validation_error, read_document
from demoplan.perception.calibration_inputs import (
    MAX_MARKER_SIDE,
    MAX_REACH,
    Intrinsics,
    MarkerLayout,
    _dictionaries,
    _intrinsics,
    _IntrinsicsSchema,
    _Row,
    is_marker_id,
    load_intrinsics,
    load_markers,
    markers_from_document,
)
from demoplan.perception.camera import Camera

__all__ = [
    "CameraCentre",
    "Intrinsics",
    "MarkerLayout",
    "TableCalibration",
    "calibrate",
    "calibration_document",
    "calibration_from_document",
    "calibration_overlay",
    "camera_centre",
    "detect_markers",
    "edge_colour",
    "is_marker_id",
    "load_calibration",
    "load_intrinsics",
    "load_markers",
    "markers_from_document",
    "rectify",
    "top_face_on_table",
]

MIN_CORNERS = 4
"""A homography has 8 degrees of freedom: at least four point pairs (one marker's corners)."""
RANSAC_PX = 3.0
"""A marker corner farther than this (px) from where the homography puts it is an outlier."""
_Point = Annotated[list[Number], Field(min_length=2, max_length=2)]


@dataclass(frozen=True, slots=True)
class CameraCentre:
    """Where the camera's centre is, in table coordinates (m; z up from the
    table), and how it was found: ``intrinsics`` (given) or ``estimated``
    (the focal length estimated from the homography)."""

    position: tuple[float, float, float]
    source: str
    focal_px: float
    height_column: np.ndarray = field(default_factory=lambda: np.zeros(3))
    """What a metre of height adds to the table → image homography's last
    column: the plane ``z = h`` maps to the image by ``inv(homography)`` with
    ``h · height_column`` added to its last column (K r3, in its scale)."""


@dataclass(frozen=True, slots=True)
class TableCalibration:
    """Image → table: ``homography`` (3 × 3) maps OpenCV pixel coordinates
    (x right, y down, (0, 0) the centre of the top-left pixel) of the
    undistorted image to table (x, y) in metres."""

    homography: np.ndarray
    image_size: tuple[int, int]
    error_px: float
    error_mm: float
    markers: tuple[int, ...] = ()
    dictionary: str = ""
    marker_side: float = 0.0
    intrinsics: Intrinsics | None = None
    centre: CameraCentre | None = None
    marker_corners: Mapping[int, np.ndarray] = field(default_factory=dict)

    def to_table(self, points: np.ndarray) -> np.ndarray:
        """Pixel points (N × 2, undistorted image) → table points (N × 2, m)."""
        return _apply(self.homography, points)

    def to_image(self, points: np.ndarray) -> np.ndarray:
        """Table points (N × 2, m) → pixel points (N × 2, undistorted image)."""
        return _apply(np.linalg.inv(self.homography), points)


def _apply(homography: np.ndarray, points: np.ndarray) -> np.ndarray:
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    mapped = np.c_[pts, np.ones(len(pts))] @ homography.T
    result: np.ndarray = mapped[:, :2] / mapped[:, 2:3]
    return result


def detect_markers(image: np.ndarray, dictionary: str) -> dict[int, np.ndarray]:
    """The markers of ``dictionary`` in an RGB image: id → its 4 corners (px,
    OpenCV's order), refined to sub-pixel accuracy."""
    from demoplan.perception.opencv import cv2

    grey = cv2.cvtColor(np.ascontiguousarray(image, dtype=np.uint8), cv2.COLOR_RGB2GRAY)
    parameters = cv2.aruco.DetectorParameters()
    parameters.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
    detector = cv2.aruco.ArucoDetector(
        cv2.aruco.getPredefinedDictionary(_dictionaries()[dictionary]), parameters
    )
    corners, ids, _ = detector.detectMarkers(grey)
    found: dict[int, np.ndarray] = {}
    if ids is None:
        return found
    for marker_id, quad in zip(ids.ravel(), corners, strict=True):
        found.setdefault(int(marker_id), np.asarray(quad, dtype=float).reshape(4, 2))
    return found


def _undistort(points: np.ndarray, intrinsics: Intrinsics | None) -> np.ndarray:
    if intrinsics is None or not np.any(intrinsics.distortion):
        return points
    from demoplan.perception.opencv import cv2

    undistorted = cv2.undistortPoints(
        points.reshape(-1, 1, 2), intrinsics.matrix, intrinsics.distortion, P=intrinsics.matrix
    )
    result: np.ndarray = undistorted.reshape(-1, 2)
    return result


def calibrate(
    image: np.ndarray,
    layout: MarkerLayout,
    *,
    source: str = "image",
    intrinsics: Intrinsics | None = None,
) -> TableCalibration:
    """The homography image → table from the markers of ``layout`` found in
    ``image`` (RGB), with its reprojection error; an InputError naming
    ``source`` when fewer than four corners of markers in the layout are found."""
    from demoplan.perception.opencv import cv2

    found = detect_markers(image, layout.dictionary)
    known = {i: c for i, c in found.items() if i in layout.positions}
    expected = (
        f"markers of {layout.dictionary} with ids "
        f"{', '.join(map(str, sorted(layout.positions)))} expected"
    )
    if not found:
        raise InputError(f"no markers found; {expected}", source=source)
    if not known:
        raise InputError(
            f"markers {', '.join(map(str, sorted(found)))} found, none of them in the markers "
            f"file; {expected}",
            source=source,
        )
    ids = tuple(sorted(known))
    pixels = _undistort(np.concatenate([known[i] for i in ids]), intrinsics)
    table = np.concatenate([layout.corners(i) for i in ids])
    if len(pixels) < MIN_CORNERS:  # pragma: no cover - one marker has four corners
        raise InputError(f"fewer than {MIN_CORNERS} marker corners; {expected}", source=source)
    homography, inliers = cv2.findHomography(pixels, table, cv2.RANSAC, RANSAC_PX / 1000.0)
    if homography is None:
        raise InputError(f"the markers' corners fit no homography; {expected}", source=source)
    keep = inliers.ravel().astype(bool)
    if keep.sum() >= MIN_CORNERS:  # least squares on the inliers
        refined, _ = cv2.findHomography(pixels[keep], table[keep], 0)
        if refined is not None:
            homography = refined
    homography = homography / homography[2, 2]
    height, width = image.shape[:2]
    calibration = TableCalibration(
        homography,
        (width, height),
        0.0,
        0.0,
        ids,
        layout.dictionary,
        layout.side,
        intrinsics,
        None,
        {i: known[i] for i in ids},
    )
    error_px = float(np.sqrt(np.mean(np.sum((calibration.to_image(table) - pixels) ** 2, axis=1))))
    error_mm = 1000 * float(
        np.sqrt(np.mean(np.sum((calibration.to_table(pixels) - table) ** 2, axis=1)))
    )
    calibration = TableCalibration(
        homography,
        (width, height),
        error_px,
        error_mm,
        ids,
        layout.dictionary,
        layout.side,
        intrinsics,
        None,
        calibration.marker_corners,
    )
    return _with_centre(calibration)


def _with_centre(calibration: TableCalibration) -> TableCalibration:
    from dataclasses import replace

    return replace(calibration, centre=camera_centre(calibration))


def _estimated_focal(table_to_image: np.ndarray, size: tuple[int, int]) -> float | None:
    """The focal length (px) that makes the homography a rotation and a
    translation (principal point at the image centre, square pixels), or
    ``None`` when the view is too close to straight down to tell."""
    cx, cy = (size[0] - 1) / 2, (size[1] - 1) / 2
    shift = np.array([[1.0, 0.0, -cx], [0.0, 1.0, -cy], [0.0, 0.0, 1.0]])
    h = shift @ table_to_image
    h = h / np.linalg.norm(h[:, :2])
    (h11, h12, _), (h21, h22, _), (h31, h32, _) = h
    # a w + b = 0 with w = 1 / f²: r1·r2 = 0 and ‖r1‖² = ‖r2‖²
    a = np.array([h11 * h12 + h21 * h22, h11**2 + h21**2 - h12**2 - h22**2])
    b = np.array([h31 * h32, h31**2 - h32**2])
    # straight down, b vanishes and so does the information about f
    tilt = float(np.hypot(h31, h32) / np.hypot(np.hypot(h11, h12), np.hypot(h21, h22)))
    if tilt * max(size) < 0.05:  # the perspective changes the scale across the image < 5 %
        return None
    w = -float(a @ b) / float(a @ a) if float(a @ a) > 0 else -1.0
    if not (w > 0):
        return None
    return 1.0 / math.sqrt(w)


def camera_centre(calibration: TableCalibration) -> CameraCentre | None:
    """The camera's centre in table coordinates (z up), from its intrinsics or,
    without them, with the focal length estimated from the homography; ``None``
    when neither can say (a view straight down without intrinsics)."""
    table_to_image = np.linalg.inv(calibration.homography)
    if calibration.intrinsics is not None:
        matrix = calibration.intrinsics.matrix
        source = "intrinsics"
    else:
        focal = _estimated_focal(table_to_image, calibration.image_size)
        if focal is None:
            return None
        width, height = calibration.image_size
        matrix = np.array([[focal, 0, (width - 1) / 2], [0, focal, (height - 1) / 2], [0, 0, 1]])
        source = "estimated"
    b = np.linalg.inv(matrix) @ table_to_image
    scale = 2.0 / (np.linalg.norm(b[:, 0]) + np.linalg.norm(b[:, 1]))
    if b[2, 2] * scale < 0:  # the table in front of the camera
        scale = -scale
    r1, r2, t = b[:, 0] * scale, b[:, 1] * scale, b[:, 2] * scale
    u, _, vt = np.linalg.svd(np.c_[r1, r2, np.cross(r1, r2)])
    rotation = u @ vt
    centre = -rotation.T @ t
    up = rotation[:, 2]
    if centre[2] < 0:  # the table's axes seen mirrored: z points away from the camera
        centre[2], up = -centre[2], -up
    x, y, z = (float(v) for v in centre)
    return CameraCentre((x, y, z), source, float(matrix[0, 0]), matrix @ up / scale)


def rectify(
    image: np.ndarray,
    calibration: TableCalibration,
    px_per_m: float = 1000.0,
    max_pixels: int = 6_000_000,
    above: float = 0.0,
) -> tuple[np.ndarray, Camera]:
    """A top view of the table (image right = +x, up = +y) at ``px_per_m``
    (less when the visible table would need more than ``max_pixels``), and the
    :class:`Camera` the detector reads it with. Markers are painted over with
    the table's colour around them, table outside the photograph in the
    median colour of its edge. The view covers the table the photograph shows
    around the markers: their extent, widened by a quarter of it and two
    marker sides on every side (without markers, up to ``MAX_REACH``).
    ``above``: the view of the plane that far above the table instead (it
    needs the camera centre), over the same (x, y) pixel grid."""
    from demoplan.perception.opencv import cv2

    picture: np.ndarray = np.ascontiguousarray(image, dtype=np.uint8)
    if calibration.intrinsics is not None and np.any(calibration.intrinsics.distortion):
        picture = cv2.undistort(
            picture, calibration.intrinsics.matrix, calibration.intrinsics.distortion
        )
    picture = _hide_markers(picture, calibration)
    width, height = calibration.image_size
    border = np.array(
        [(x, 0.0) for x in np.linspace(0, width - 1, 33)]
        + [(width - 1.0, y) for y in np.linspace(0, height - 1, 33)]
        + [(x, height - 1.0) for x in np.linspace(width - 1, 0, 33)]
        + [(0.0, y) for y in np.linspace(height - 1, 0, 33)]
    )
    # points beyond the horizon map behind the camera: keep those in front
    mapped = np.c_[border, np.ones(len(border))] @ calibration.homography.T
    ahead = mapped[:, 2] * np.sign(np.median(mapped[:, 2])) > 1e-9
    footprint = mapped[ahead, :2] / mapped[ahead, 2:3]
    if calibration.marker_corners:  # the table around the markers
        corners = np.concatenate(
            [calibration.to_table(c) for c in calibration.marker_corners.values()]
        )
        margin = 0.1 * float(np.ptp(corners, axis=0).max()) + calibration.marker_side
        low = np.maximum(footprint.min(axis=0), corners.min(axis=0) - margin)
        high = np.minimum(footprint.max(axis=0), corners.max(axis=0) + margin)
    else:
        centre = calibration.to_table(np.array([[(width - 1) / 2, (height - 1) / 2]]))[0]
        low = np.maximum(footprint.min(axis=0), centre - MAX_REACH)
        high = np.minimum(footprint.max(axis=0), centre + MAX_REACH)
    extent = high - low
    if not np.all(extent > 0):
        raise InputError(
            "the calibration maps no part of the image onto the table around the markers"
        )
    scale = min(px_per_m, math.sqrt(max_pixels / max(float(extent[0] * extent[1]), 1e-12)))
    out_w, out_h = (max(1, math.ceil(float(e) * scale)) for e in extent)
    # the centre of rectified pixel (c, r): x = low_x + (c + 0.5) / S,
    # y = low_y + (out_h − r − 0.5) / S
    table_to_rectified = np.array(
        [
            [scale, 0.0, -low[0] * scale - 0.5],
            [0.0, -scale, out_h + low[1] * scale - 0.5],
            [0, 0, 1],
        ]
    )
    image_to_plane = calibration.homography
    if above:
        if calibration.centre is None:
            raise ValueError("a plane above the table needs the camera centre")
        plane_to_image = np.linalg.inv(calibration.homography)
        plane_to_image[:, 2] += above * calibration.centre.height_column
        image_to_plane = np.linalg.inv(plane_to_image)
    warp = table_to_rectified @ image_to_plane
    rectified = cv2.warpPerspective(
        picture,
        warp,
        (out_w, out_h),
        flags=cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_CONSTANT,
        borderValue=edge_colour(picture),
    )
    return rectified, Camera(scale, (float(low[0]), float(low[1])))


def edge_colour(picture: np.ndarray) -> tuple[int, int, int]:
    """The median colour of the photograph's outermost pixels: the table, mostly."""
    edge = np.concatenate([picture[0], picture[-1], picture[:, 0], picture[:, -1]])
    r, g, b = (int(v) for v in np.median(edge, axis=0))
    return r, g, b


def _hide_markers(picture: np.ndarray, calibration: TableCalibration) -> np.ndarray:
    """The photograph with each marker (and a quarter of its side around it, its
    white margin) painted in the median colour of a ring of table around it:
    black and white squares are no blocks."""
    from demoplan.perception.opencv import cv2

    if not calibration.marker_corners:
        return picture
    painted = picture.copy()
    for quad in calibration.marker_corners.values():
        centre = quad.mean(axis=0)
        inner = centre + (quad - centre) * 1.6
        outer = centre + (quad - centre) * 2.0
        mask = np.zeros(picture.shape[:2], dtype=np.uint8)
        cv2.fillPoly(mask, [np.rint(outer).astype(np.int32)], 1)
        cv2.fillPoly(mask, [np.rint(inner).astype(np.int32)], 0)
        ring = picture[mask.astype(bool)]
        colour = np.median(ring, axis=0) if len(ring) else np.array([128, 128, 128])
        cv2.fillPoly(painted, [np.rint(inner).astype(np.int32)], [int(c) for c in colour])
    return painted


def _matrix(value: np.ndarray, digits: int = 10) -> list[list[float]]:
    return [[round(float(v), digits) for v in row] for row in value]


def calibration_document(calibration: TableCalibration) -> dict[str, Any]:
    """The ``demoplan/camera-1`` document of a calibration (docs/formats.md)."""
    document: dict[str, Any] = {
        "format": "demoplan/camera-1",
        "image_size": list(calibration.image_size),
        "homography": [
            [float(f"{v:.12g}") for v in row]
            for row in calibration.homography / calibration.homography[2, 2]
        ],
        "reprojection_error": {
            "px": round(calibration.error_px, 4),
            "mm": round(calibration.error_mm, 4),
        },
    }
    if calibration.markers:
        document["markers"] = {
            "dictionary": calibration.dictionary,
            "side": calibration.marker_side,
            "ids": list(calibration.markers),
            "corners": {
                str(i): [[round(float(v), 3) for v in point] for point in quad]
                for i, quad in calibration.marker_corners.items()
            },
        }
    if calibration.intrinsics is not None:
        document["intrinsics"] = {
            "camera_matrix": _matrix(calibration.intrinsics.matrix),
            "distortion": [float(v) for v in calibration.intrinsics.distortion],
        }
    if calibration.centre is not None:
        document["camera_centre"] = {
            "position": [round(v, 6) for v in calibration.centre.position],
            "from": calibration.centre.source,
            "focal_px": round(calibration.centre.focal_px, 3),
        }
    return document


class _ErrorSchema(BaseModel):
    model_config = ConfigDict(extra="forbid")
    px: float = Field(
        ge=0,
        description="RMS distance (px) of the markers' corners from where the homography "
        "puts them.",
    )
    mm: float = Field(ge=0, description="The same on the table (mm).")


class _UsedMarkersSchema(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    dictionary: str = Field(description="The markers' dictionary.")
    side: Number = Field(gt=0, le=MAX_MARKER_SIDE, description="Their side (m).")
    ids: list[Annotated[int, Field(ge=0, le=999_999)]] = Field(
        description="The ids found and used."
    )
    corners: dict[str, list[_Point]] = Field(
        default={},
        description="Each id's four corners in the image (px, OpenCV's order): the "
        "markers are painted over, and the rectified view covers the table around them.",
    )


class _CentreSchema(BaseModel):
    model_config = ConfigDict(extra="forbid")
    position: list[float] = Field(
        min_length=3,
        max_length=3,
        description="The camera's centre (m) in table coordinates, z up.",
    )
    source: str = Field(
        alias="from",
        pattern="^(intrinsics|estimated)$",
        description="`intrinsics` (given) or `estimated` (focal length from the homography).",
    )
    focal_px: float = Field(gt=0, description="The focal length (px) it was found with.")


class _CameraSchema(BaseModel):
    model_config = ConfigDict(extra="forbid", populate_by_name=True, allow_inf_nan=False)
    format: str = Field(description="`demoplan/camera-1`.")
    image_size: list[int] = Field(
        min_length=2, max_length=2, description="[width, height] (px) of the calibrated images."
    )
    homography: list[_Row] = Field(
        min_length=3,
        max_length=3,
        description="3 × 3: OpenCV pixel coordinates (x right, y down, (0, 0) the top-left "
        "pixel's centre) of the undistorted image → table (x, y) in metres.",
    )
    reprojection_error: _ErrorSchema | None = Field(
        None, description="How well it fits the markers."
    )
    markers: _UsedMarkersSchema | None = Field(None, description="The markers it was made from.")
    intrinsics: _IntrinsicsSchema | None = Field(
        None,
        description="`camera_matrix` (3 × 3, px) and `distortion` (OpenCV's coefficients), "
        "when known: images are undistorted first, and the camera centre comes from them.",
    )
    camera_centre: _CentreSchema | None = Field(
        None, description="Where the camera is (written by `calibrate`; recomputed when read)."
    )


def calibration_from_document(data: dict[str, Any], source: str) -> TableCalibration:
    """Parse a ``demoplan/camera-1`` document."""
    check_format(data, {"camera"}, source)
    try:
        parsed = _CameraSchema.model_validate(data)
    except ValidationError as exc:
        raise describe_validation_error(exc, source) from None
    homography = np.array(parsed.homography, dtype=float)
    scale = float(np.abs(homography).max())
    if not (
        0 < scale < 1e150
        and abs(homography[2, 2]) > 1e-12 * scale
        and abs(np.linalg.det(homography / scale)) > 1e-300
    ):
        raise InputError(
            "an invertible 3 × 3 matrix (pixels → table metres) with its last entry not 0 expected",
            source=source,
            field="homography",
        )
    width, height = parsed.image_size
    if not (0 < width <= 20_000 and 0 < height <= 20_000):
        raise InputError(
            "[width, height] in pixels, each 1 to 20,000, expected",
            source=source,
            field="image_size",
        )
    intrinsics = (
        _intrinsics(data["intrinsics"], source, "intrinsics")
        if parsed.intrinsics is not None
        else None
    )
    error = parsed.reprojection_error
    used = parsed.markers
    corners: dict[int, np.ndarray] = {}
    for key, quad in (used.corners if used else {}).items():
        points = np.array(quad, dtype=float)
        if not is_marker_id(key) or points.shape != (4, 2):
            raise InputError(
                "a marker id: four [x, y] corners (px) expected",
                source=source,
                field=f"markers.corners.{key if len(key) <= 12 else key[:12] + '…'}",
            )
        corners[int(key)] = points
    calibration = TableCalibration(
        homography / homography[2, 2],
        (width, height),
        error.px if error else math.nan,
        error.mm if error else math.nan,
        tuple(used.ids) if used else (),
        used.dictionary if used else "",
        used.side if used else 0.0,
        intrinsics,
        None,
        corners,
    )
    return _with_centre(calibration)


def load_calibration(path: Path) -> TableCalibration:
    """Read a camera file (docs/formats.md "Camera file")."""
    return calibration_from_document(read_document(Path(path)), str(path))


def check_image_size(calibration: TableCalibration, image: np.ndarray, source: str) -> None:
    """An image of another size than the calibrated one is another camera (or crop)."""
    height, width = image.shape[:2]
    if (width, height) != tuple(calibration.image_size):
        raise InputError(
            f"{width} × {height} pixels; the camera file was calibrated on "
            f"{calibration.image_size[0]} × {calibration.image_size[1]} images",
            source=source,
        )


def grid_lines(calibration: TableCalibration, spacing: float = 0.05) -> Sequence[np.ndarray]:
    """Lines of a table grid every ``spacing`` m across the markers' area, in
    pixels: what the overlay draws to check the calibration by eye."""
    corners = [calibration.to_table(c) for c in calibration.marker_corners.values()]
    if not corners:
        return []
    points = np.concatenate(corners)
    low = np.floor(points.min(axis=0) / spacing - 2) * spacing
    high = np.ceil(points.max(axis=0) / spacing + 2) * spacing
    lines = []
    for x in np.arange(low[0], high[0] + spacing / 2, spacing):
        ys = np.linspace(low[1], high[1], 50)
        lines.append(calibration.to_image(np.c_[np.full_like(ys, x), ys]))
    for y in np.arange(low[1], high[1] + spacing / 2, spacing):
        xs = np.linspace(low[0], high[0], 50)
        lines.append(calibration.to_image(np.c_[xs, np.full_like(xs, y)]))
    return lines


def table_to_photo(
    calibration: TableCalibration, points: np.ndarray, height: float = 0.0
) -> np.ndarray:
    """Points (N × 2, m) on the plane ``height`` above the table → pixels of the
    photograph (x right, y down; distorted again where the intrinsics say the
    lens distorts). Without the camera centre every plane maps as the table."""
    from demoplan.perception.opencv import cv2

    plane_to_image = np.linalg.inv(calibration.homography)
    if height and calibration.centre is not None:
        plane_to_image[:, 2] += height * calibration.centre.height_column
    pixels = _apply(plane_to_image, points)
    lens = calibration.intrinsics
    if lens is None or not np.any(lens.distortion) or not len(pixels):
        return pixels
    normal = _apply(np.linalg.inv(lens.matrix), pixels)
    rays = np.c_[normal, np.ones(len(normal))]
    distorted, _ = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), lens.matrix, lens.distortion)
    result: np.ndarray = distorted.reshape(-1, 2)
    return result


def calibration_overlay(image: np.ndarray, calibration: TableCalibration) -> np.ndarray:
    """The photograph with a grid of the table every 5 cm (cyan; the 10 cm
    lines drawn alike), the detected markers' outlines (green) and their ids
    (yellow): a person sees at a glance whether the grid lies flat on the table."""
    from demoplan.perception.opencv import cv2

    picture = np.ascontiguousarray(image, dtype=np.uint8).copy()
    height, width = picture.shape[:2]
    thickness = max(1, round(max(width, height) / 640))
    for line in grid_lines(calibration):
        inside = np.all(np.isfinite(line), axis=1) & (np.abs(line) < 4 * max(width, height)).all(
            axis=1
        )
        if inside.sum() >= 2:
            cv2.polylines(
                picture, [np.rint(line[inside]).astype(np.int32)], False, (0, 200, 220), thickness
            )
    for marker_id, quad in calibration.marker_corners.items():
        cv2.polylines(picture, [np.rint(quad).astype(np.int32)], True, (40, 220, 40), 2 * thickness)
        corner = (int(quad[0][0]), int(quad[0][1]) - 4 * thickness)  # above its first corner
        for colour, weight in (((0, 0, 0), 3 * thickness + 1), ((255, 230, 40), thickness)):
            cv2.putText(
                picture,
                str(marker_id),
                corner,
                cv2.FONT_HERSHEY_SIMPLEX,
                0.6 * thickness,
                colour,
                weight,
            )
    return picture


def top_face_on_table(
    x: float, y: float, apparent_side: float, centre: CameraCentre | None, side: float | None
) -> tuple[float, float, float, bool]:
    """Where a cube standing on the table is, from where its top face shows in the
    table's rectified view: the top face, ``side`` above the table, is seen
    scaled by ``H / (H − side)`` about the camera's foot (H the camera's
    height), so it is scaled back. Without ``side`` the cube's side comes from
    the apparent one, s' = s·H / (H − s). Without a camera centre nothing is
    corrected (the last value says whether it was)."""
    if centre is None:
        return x, y, apparent_side, False
    cx, cy, height = centre.position
    cube = side if side is not None else apparent_side * height / (height + apparent_side)
    if cube >= height:
        return x, y, apparent_side, False
    shrink = (height - cube) / height
    return cx + (x - cx) * shrink, cy + (y - cy) * shrink, apparent_side * shrink, True
