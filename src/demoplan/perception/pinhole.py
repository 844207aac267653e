"""Renders of a table seen through a pinhole camera, for tests, benchmarks and
docs: ArUco markers lying on the table and coloured cubes as 3-D boxes (the
top face and the side faces the camera sees, darker than the top), drawn as
projected polygons in painter's order, supersampled (anti-aliased edges) and
with Gaussian sensor noise. The truth is exact: the camera and the boxes as given.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from demoplan.perception.synthetic import COLOURS, TABLE, SyntheticBlock

__all__ = ["PinholeCamera", "render_table"]


@dataclass(frozen=True, slots=True)
class PinholeCamera:
    """K (px), and the table → camera rotation and translation (OpenCV's
    camera frame: x right, y down, z forward); table z up."""

    matrix: np.ndarray
    rotation: np.ndarray
    translation: np.ndarray
    width: int
    height: int

    @staticmethod
    def looking_at(
        target: tuple[float, float],
        *,
        tilt: float,
        heading: float,
        distance: float,
        focal: float,
        width: int = 640,
        height: int = 480,
        roll: float = 0.0,
    ) -> PinholeCamera:
        """A camera ``distance`` (m) from the table point ``target``, its axis
        ``tilt`` degrees from vertical, seen from the compass direction
        ``heading`` (deg from +x), turned ``roll`` degrees about its axis."""
        t, a = math.radians(tilt), math.radians(heading)
        centre = np.array(
            [
                target[0] + distance * math.sin(t) * math.cos(a),
                target[1] + distance * math.sin(t) * math.sin(a),
                distance * math.cos(t),
            ]
        )
        forward = np.array([target[0], target[1], 0.0]) - centre
        forward /= np.linalg.norm(forward)
        # image "up" points away from the camera's foot along the table when tilted
        up_hint = (
            np.array([-math.cos(a), -math.sin(a), 0.0]) if tilt > 1e-6 else np.array([0, 1.0, 0])
        )
        right = np.cross(forward, up_hint)
        if np.linalg.norm(right) < 1e-9:
            right = np.array([1.0, 0.0, 0.0])
        right /= np.linalg.norm(right)
        down = np.cross(forward, right)
        r = math.radians(roll)
        right, down = (
            math.cos(r) * right + math.sin(r) * down,
            -math.sin(r) * right + math.cos(r) * down,
        )
        rotation = np.array([right, down, forward])
        matrix = np.array([[focal, 0, (width - 1) / 2], [0, focal, (height - 1) / 2], [0, 0, 1]])
        return PinholeCamera(matrix, rotation, -rotation @ centre, width, height)

    @property
    def centre(self) -> np.ndarray:
        """The camera's centre in table coordinates."""
        result: np.ndarray = -self.rotation.T @ self.translation
        return result

    def project(self, points: np.ndarray) -> np.ndarray:
        """Table points (N × 3, m) → pixels (N × 2, OpenCV: (0, 0) the top-left pixel's centre)."""
        camera = np.asarray(points, dtype=float) @ self.rotation.T + self.translation
        pixels = camera @ self.matrix.T
        result: np.ndarray = pixels[:, :2] / pixels[:, 2:3]
        return result


def _box_faces(block: SyntheticBlock) -> list[tuple[np.ndarray, np.ndarray]]:
    """A cube's faces: (corners 4 × 3, outward normal), top first."""
    h = block.side / 2
    c, s = math.cos(math.radians(block.yaw)), math.sin(math.radians(block.yaw))

    def corner(a: float, b: float, z: float) -> tuple[float, float, float]:
        return (block.x + c * a - s * b, block.y + s * a + c * b, z)

    square = ((-h, -h), (h, -h), (h, h), (-h, h))
    top = np.array([corner(a, b, block.side) for a, b in square])
    bottom = np.array([corner(a, b, 0.0) for a, b in square])
    faces = [(top, np.array([0.0, 0.0, 1.0]))]
    for i in range(4):
        j = (i + 1) % 4
        quad = np.array([bottom[i], bottom[j], top[j], top[i]])
        middle = (bottom[i] + bottom[j]) / 2 - np.array([block.x, block.y, 0.0])
        normal = np.array([middle[0], middle[1], 0.0]) / h
        faces.append((quad, normal))
    return faces


def render_table(
    camera: PinholeCamera,
    blocks: Sequence[SyntheticBlock],
    markers: Mapping[int, tuple[float, float] | tuple[float, float, float]],
    *,
    marker_side: float = 0.05,
    dictionary: str = "DICT_4X4_50",
    noise: float = 2.0,
    supersample: int = 3,
    side_shading: tuple[float, float] = (0.55, 0.75),
    side_faces: bool = True,
    rng: np.random.Generator | int | None = 0,
) -> np.ndarray:
    """An RGB ``uint8`` photograph-like render (camera.height × camera.width × 3)
    of markers (id → centre (x, y) on the table, or (x, y, yaw°): the top of
    the pattern faces +y at yaw 0, as in a markers file) and ``blocks``;
    ``side_faces=False`` draws each cube's top face alone (a square tile ``side``
    above the table), which isolates the calibration and the height correction
    from telling a top face from the side faces."""
    from demoplan.perception.opencv import cv2

    generator = np.random.default_rng(rng)
    n = supersample
    scaled = camera.matrix.copy()
    scaled[:2] *= n
    scaled[0, 2] = (camera.matrix[0, 2] + 0.5) * n - 0.5
    scaled[1, 2] = (camera.matrix[1, 2] + 0.5) * n - 0.5
    big = PinholeCamera(
        scaled, camera.rotation, camera.translation, camera.width * n, camera.height * n
    )
    canvas = np.empty((big.height, big.width, 3), dtype=np.uint8)
    canvas[:] = TABLE
    # markers: the marker image (with a white margin) warped onto the table
    aruco = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, dictionary))
    cells = 200
    for marker_id, place in markers.items():
        x, y = place[0], place[1]
        yaw = math.radians(place[2]) if len(place) > 2 else 0.0
        pattern = cv2.aruco.generateImageMarker(aruco, marker_id, cells)
        margin = cells // 4
        padded = cv2.copyMakeBorder(
            pattern, margin, margin, margin, margin, cv2.BORDER_CONSTANT, value=255
        )
        size = padded.shape[0]
        reach = marker_side / 2 * size / cells
        c, s = math.cos(yaw), math.sin(yaw)
        corners = np.array(
            [
                (x + c * a - s * b, y + s * a + c * b, 0.0)
                for a, b in ((-reach, reach), (reach, reach), (reach, -reach), (-reach, -reach))
            ]
        )
        source = np.array(
            [(-0.5, -0.5), (size - 0.5, -0.5), (size - 0.5, size - 0.5), (-0.5, size - 0.5)],
            dtype=np.float32,
        )
        warp = cv2.getPerspectiveTransform(source, big.project(corners).astype(np.float32))
        rgb = cv2.cvtColor(padded, cv2.COLOR_GRAY2RGB)
        warped = cv2.warpPerspective(rgb, warp, (big.width, big.height), flags=cv2.INTER_AREA)
        mask = cv2.warpPerspective(
            np.full(padded.shape, 255, np.uint8), warp, (big.width, big.height)
        )
        canvas[mask > 127] = warped[mask > 127]
    # cubes, farthest first; each one's visible faces, top last
    centre = camera.centre
    ordered = sorted(blocks, key=lambda b: -math.dist(centre, (b.x, b.y, b.side / 2)))
    for block in ordered:
        tint = np.asarray(COLOURS[block.colour], dtype=float)
        faces = _box_faces(block)
        for index, (quad, normal) in sorted(enumerate(faces), key=lambda f: f[0] == 0):
            if index > 0 and not side_faces:
                continue  # the top face alone: a tile ``side`` above the table
            if float(normal @ (centre - quad.mean(axis=0))) <= 0:
                continue  # facing away
            light = 1.0 if index == 0 else side_shading[index % 2]
            polygon = np.rint(big.project(quad) * 16).astype(np.int32)
            colour = [int(v) for v in np.clip(tint * light, 0, 255)]
            cv2.fillPoly(canvas, [polygon], colour, lineType=cv2.LINE_8, shift=4)
    small = cv2.resize(canvas, (camera.width, camera.height), interpolation=cv2.INTER_AREA).astype(
        float
    )
    if noise:
        small += generator.normal(0.0, noise, small.shape)
    result: np.ndarray = np.clip(np.rint(small), 0, 255).astype(np.uint8)
    return result
