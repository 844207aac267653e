"""Photograph-like renders of cubes on a lab table, for tests and benchmarks.

No photograph of coloured cubes that may be redistributed can be fetched here,
so these renders stand in for real ones (docs/perception.md says so). They
carry what made real photographs hard: a grey board with a black grid, four
black-and-white square markers (ArUco-like bit patterns drawn as pixels), a
dark grey machine base, cubes whose side faces show because the camera is not
straight above them, shadows, a specular highlight on some tops, sensor
noise, blur and JPEG compression.

The camera is a pinhole at height ``height`` (m) above the table, its optical
axis vertical, above the world point ``nadir`` (which need not be the image's
centre: the camera is "not exactly above" the scene). Every horizontal plane
then maps to the image by a similarity, so the plane of the cubes' tops
(z = side) is an exact top-down camera of docs/formats.md: :func:`top_camera`
gives it, and a cube's top face seen there is centred on the cube's (x, y).
The truth is the blocks as given (:class:`~demoplan.perception.synthetic.SyntheticBlock`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from demoplan.perception.camera import Camera
from demoplan.perception.opencv import cv2
from demoplan.perception.synthetic import COLOURS, SyntheticBlock

__all__ = ["PhotoRig", "random_photo_blocks", "render_photo", "top_camera"]

BOARD = (150, 152, 150)
GRID = (25, 25, 25)


@dataclass(frozen=True, slots=True)
class PhotoRig:
    """The camera and the table of a photograph-like render.

    ``focal`` in pixels, ``height`` the camera's height above the table (m),
    ``nadir`` the world (x, y) straight under it and ``nadir_px`` where that
    point is in the image (u right, v up from the bottom-left corner);
    ``grid`` the spacing of the board's black lines (m).
    """

    width: int = 1280
    height_px: int = 720
    focal: float = 2000.0
    height: float = 1.0
    nadir: tuple[float, float] = (0.32, 0.18)
    nadir_px: tuple[float, float] = (640.0, 360.0)
    grid: float = 0.05
    marker: float = 0.06

    def to_pixels(self, x: float, y: float, z: float = 0.0) -> tuple[float, float]:
        """World point → (u, v) pixels from the image's bottom-left corner, v up."""
        scale = self.focal / (self.height - z)
        return (
            self.nadir_px[0] + scale * (x - self.nadir[0]),
            self.nadir_px[1] + scale * (y - self.nadir[1]),
        )

    def table_extent(self) -> tuple[float, float, float, float]:
        """World (x0, y0, x1, y1) of the table seen in the image."""
        scale = self.focal / self.height
        x0 = self.nadir[0] - self.nadir_px[0] / scale
        y0 = self.nadir[1] - self.nadir_px[1] / scale
        return x0, y0, x0 + self.width / scale, y0 + self.height_px / scale


def top_camera(rig: PhotoRig, side: float) -> Camera:
    """The top-down camera of the plane of the cubes' tops (z = ``side``)."""
    scale = rig.focal / (rig.height - side)
    return Camera(
        scale, (rig.nadir[0] - rig.nadir_px[0] / scale, rig.nadir[1] - rig.nadir_px[1] / scale)
    )


def _corners(block: SyntheticBlock) -> np.ndarray:
    c, s = math.cos(math.radians(block.yaw)), math.sin(math.radians(block.yaw))
    h = block.side / 2
    local = np.array([(-h, -h), (h, -h), (h, h), (-h, h)])
    corners: np.ndarray = local @ np.array([[c, s], [-s, c]]) + np.array([block.x, block.y])
    return corners


def random_photo_blocks(
    count: int,
    rig: PhotoRig,
    rng: np.random.Generator,
    *,
    side: float = 0.04,
    colours: Sequence[str] = tuple(COLOURS),
) -> list[SyntheticBlock]:
    """``count`` cubes of side ``side`` at random poses on the board, apart (their
    images, side faces included, do not overlap) and off the markers."""
    x0, y0, x1, y1 = rig.table_extent()
    margin = rig.marker + 0.03
    placed: list[SyntheticBlock] = []
    for _ in range(count):
        for _ in range(2000):
            x = float(rng.uniform(x0 + 0.04, x1 - 0.04))
            y = float(rng.uniform(y0 + 0.04, y1 - 0.04))
            near_marker = (x < x0 + margin or x > x1 - margin) and (
                y < y0 + margin or y > y1 - margin
            )
            if near_marker or any(math.dist((x, y), (b.x, b.y)) < 2.2 * side for b in placed):
                continue
            colour = str(colours[int(rng.integers(len(colours)))])
            placed.append(SyntheticBlock(colour, x, y, float(rng.uniform(-45, 45)), side))
            break
    return placed


def _marker_bits(rng: np.random.Generator) -> np.ndarray:
    """A 6 × 6 marker: a black border around 4 × 4 random bits."""
    bits = np.zeros((6, 6), dtype=bool)
    bits[1:5, 1:5] = rng.random((4, 4)) < 0.5
    return bits


def render_photo(
    blocks: Sequence[SyntheticBlock],
    rig: PhotoRig = PhotoRig(),
    *,
    rng: np.random.Generator | int | None = 0,
    noise: float = 3.0,
    blur: float = 0.8,
    jpeg_quality: int = 85,
    highlight: float = 0.5,
    machine: bool = True,
    supersample: int = 3,
) -> np.ndarray:
    """An RGB ``uint8`` photograph-like image of ``blocks`` on a gridded board."""
    generator = np.random.default_rng(rng)
    n = supersample
    rows, cols = rig.height_px * n, rig.width * n
    canvas = np.empty((rows, cols, 3), dtype=np.uint8)
    canvas[:] = BOARD
    shift = 4

    def points(world: np.ndarray, z: float) -> np.ndarray:
        pixels = []
        for x, y in world:
            u, v = rig.to_pixels(float(x), float(y), z)
            pixels.append(((u * n - 0.5) * 16, ((rig.height_px - v) * n - 0.5) * 16))
        rounded: np.ndarray = np.rint(np.array(pixels)).astype(np.int32)
        return rounded

    def fill(world: np.ndarray, z: float, colour: tuple[int, ...]) -> None:
        cv2.fillPoly(canvas, [points(world, z)], colour, lineType=cv2.LINE_8, shift=shift)

    x0, y0, x1, y1 = rig.table_extent()
    line = 0.002
    for gx in np.arange(math.ceil(x0 / rig.grid) * rig.grid, x1, rig.grid):
        fill(
            np.array([(gx - line, y0), (gx + line, y0), (gx + line, y1), (gx - line, y1)]), 0, GRID
        )
    for gy in np.arange(math.ceil(y0 / rig.grid) * rig.grid, y1, rig.grid):
        fill(
            np.array([(x0, gy - line), (x1, gy - line), (x1, gy + line), (x0, gy + line)]), 0, GRID
        )
    # four markers near the corners: white quiet zone, black border, bits
    cell = rig.marker / 6
    for mx, my in (
        (x0 + 0.015, y0 + 0.015),
        (x1 - 0.015 - rig.marker, y0 + 0.015),
        (x0 + 0.015, y1 - 0.015 - rig.marker),
        (x1 - 0.015 - rig.marker, y1 - 0.015 - rig.marker),
    ):
        quiet = cell
        fill(
            np.array(
                [
                    (mx - quiet, my - quiet),
                    (mx + rig.marker + quiet, my - quiet),
                    (mx + rig.marker + quiet, my + rig.marker + quiet),
                    (mx - quiet, my + rig.marker + quiet),
                ]
            ),
            0,
            (240, 240, 238),
        )
        for (i, j), white in np.ndenumerate(_marker_bits(generator)):
            cx, cy = mx + j * cell, my + (5 - i) * cell
            square = np.array([(cx, cy), (cx + cell, cy), (cx + cell, cy + cell), (cx, cy + cell)])
            fill(square, 0, (240, 240, 238) if white else (20, 20, 20))
    if machine:  # the dark base of an arm at the middle of the top edge
        centre = ((x0 + x1) / 2, y1)
        angles = np.linspace(0, 2 * math.pi, 48, endpoint=False)
        disc = np.stack([centre[0] + 0.07 * np.cos(angles), centre[1] + 0.07 * np.sin(angles)], 1)
        fill(disc, 0.05, (60, 62, 66))
    # shadows: each cube's footprint swept away from the light
    light = np.array([0.012, -0.018])
    shadow = np.zeros((rows, cols), dtype=np.uint8)
    for block in blocks:
        base = _corners(block)
        hull = cv2.convexHull(np.concatenate([base, base + light]).astype(np.float32))
        cv2.fillPoly(shadow, [points(hull.reshape(-1, 2), 0)], 1, shift=shift)
    canvas[shadow > 0] = (canvas[shadow > 0] * 0.62).astype(np.uint8)
    # side faces (lit less than the top), then tops over everything
    for block in blocks:
        tint = np.asarray(COLOURS[block.colour], float) * generator.uniform(0.92, 1.08)
        base = _corners(block)
        for k in range(4):
            a, b = base[k], base[(k + 1) % 4]
            normal = np.array([b[1] - a[1], a[0] - b[0]])
            middle = (a + b) / 2
            if normal @ (middle - np.asarray(rig.nadir)) <= 0:
                continue  # faces away from the camera
            face = normal / np.linalg.norm(normal)
            shade = 0.42 + 0.18 * float(face @ np.array([-0.6, 0.8]))
            quad_bottom = points(np.array([a, b]), 0)
            quad_top = points(np.array([b, a]), block.side)
            colour = tuple(int(c) for c in np.clip(tint * shade, 0, 255))
            cv2.fillPoly(canvas, [np.concatenate([quad_bottom, quad_top])], colour, shift=shift)
    for block in blocks:
        tint = np.asarray(COLOURS[block.colour], float) * generator.uniform(0.95, 1.05)
        colour = tuple(int(c) for c in np.clip(tint, 0, 255))
        fill(_corners(block), block.side, colour)
    image: np.ndarray = np.asarray(
        cv2.resize(
            canvas.astype(np.float32), (rig.width, rig.height_px), interpolation=cv2.INTER_AREA
        ),
        dtype=np.float32,
    )
    if highlight:  # a soft white glint on some tops
        _add_glints(image, blocks, rig, highlight, generator)
    return _lens_and_sensor(image, rig, blur, noise, jpeg_quality, generator)


def _lens_and_sensor(
    image: np.ndarray,
    rig: PhotoRig,
    blur: float,
    noise: float,
    jpeg_quality: int,
    generator: np.random.Generator,
) -> np.ndarray:
    """The rendered scene as a camera records it: light falling off across the
    table, blur, sensor noise, 8 bits, JPEG."""
    # lighting falls off across the table, then the lens and the sensor
    ramp = (
        1.0
        - 0.12 * np.linspace(0, 1, rig.width)[None, :]
        - 0.06 * np.linspace(0, 1, rig.height_px)[:, None]
    )
    image = image * ramp[..., None]
    if blur:
        image = np.asarray(cv2.GaussianBlur(image, (0, 0), blur), dtype=np.float32)
    if noise:
        image = image + generator.normal(0.0, noise, image.shape)
    photo: np.ndarray = np.clip(np.rint(image), 0, 255).astype(np.uint8)
    if jpeg_quality:
        ok, encoded = cv2.imencode(
            ".jpg", cv2.cvtColor(photo, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, jpeg_quality]
        )
        assert ok
        decoded = cv2.imdecode(encoded, cv2.IMREAD_COLOR)
        assert decoded is not None
        photo = np.asarray(cv2.cvtColor(decoded, cv2.COLOR_BGR2RGB), dtype=np.uint8)
    return photo


def _add_glints(
    image: np.ndarray,
    blocks: Sequence[SyntheticBlock],
    rig: PhotoRig,
    highlight: float,
    generator: np.random.Generator,
) -> None:
    """A soft white glint on the top of each block, with chance ``highlight``."""
    vv, uu = np.mgrid[0 : rig.height_px, 0 : rig.width]
    for block in blocks:
        if generator.random() > highlight:
            continue
        spot = np.array([block.x, block.y]) + generator.uniform(-0.25, 0.25, 2) * block.side
        u, v = rig.to_pixels(float(spot[0]), float(spot[1]), block.side)
        radius = 0.08 * block.side * rig.focal / (rig.height - block.side)
        near = (
            slice(
                max(0, int(rig.height_px - v - 4 * radius)),
                max(0, int(rig.height_px - v + 4 * radius)),
            ),
            slice(max(0, int(u - 4 * radius)), max(0, int(u + 4 * radius))),
        )
        r2 = (uu[near] + 0.5 - u) ** 2 + (rig.height_px - vv[near] - 0.5 - v) ** 2
        glint = 0.8 * np.exp(-r2 / (2 * radius**2))[..., None]
        image[near] = image[near] * (1 - glint) + 250 * glint
