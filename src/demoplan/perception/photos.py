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

A :class:`PhotoRig` may also lean its camera (``tilt``): planes then map to
the image by a homography, not a similarity, and :func:`top_camera` no longer
holds; the generated families (:mod:`demoplan.perception.photo_families`) use
it, with their truth in pixels as the real photographs' labels give it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from demoplan.perception.camera import Camera
from demoplan.perception.opencv import cv2
from demoplan.perception.synthetic import COLOURS, SyntheticBlock

__all__ = [
    "BOARD",
    "PhotoRig",
    "canvas_points",
    "draw_board",
    "lens_and_sensor",
    "light_falloff",
    "random_photo_blocks",
    "render_photo",
    "top_camera",
]

BOARD = (150, 152, 150)
GRID = (25, 25, 25)


@dataclass(frozen=True, slots=True)
class PhotoRig:
    """The camera and the table of a photograph-like render.

    ``focal`` in pixels, ``height`` the camera's height above the table (m),
    ``nadir`` the world (x, y) straight under it and ``nadir_px`` where the
    optical axis meets the image (u right, v up from the bottom-left corner);
    ``grid`` the spacing of the board's black lines (m). ``tilt`` (degrees) leans
    the optical axis from the vertical towards the world direction
    ``tilt_towards`` (degrees from world x; 90: the camera looks towards +y, as a
    person at the table's near edge holds a phone); with a tilt, ``nadir_px`` is
    where the axis meets the image and the point straight under the camera lies
    elsewhere (often outside the image).
    """

    width: int = 1280
    height_px: int = 720
    focal: float = 2000.0
    height: float = 1.0
    nadir: tuple[float, float] = (0.32, 0.18)
    nadir_px: tuple[float, float] = (640.0, 360.0)
    grid: float = 0.05
    marker: float = 0.06
    tilt: float = 0.0
    tilt_towards: float = 90.0

    def _basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The camera's image-right, image-up and viewing directions in the world:
        the straight-down camera's (x, y, −z) turned by ``tilt`` about the
        horizontal axis across ``tilt_towards`` (Rodrigues' formula)."""
        towards = math.radians(self.tilt_towards)
        axis = np.array([math.sin(towards), -math.cos(towards), 0.0])
        t = math.radians(self.tilt)
        cross = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
        turn = np.eye(3) + math.sin(t) * cross + (1 - math.cos(t)) * cross @ cross
        return (
            turn @ np.array([1.0, 0, 0]),
            turn @ np.array([0, 1.0, 0]),
            turn @ np.array([0, 0, -1.0]),
        )

    def camera_centre(self) -> tuple[float, float, float]:
        """The camera's optical centre in the world (m)."""
        return self.nadir[0], self.nadir[1], self.height

    def to_pixels(self, x: float, y: float, z: float = 0.0) -> tuple[float, float]:
        """World point → (u, v) pixels from the image's bottom-left corner, v up."""
        if not self.tilt:
            scale = self.focal / (self.height - z)
            return (
                self.nadir_px[0] + scale * (x - self.nadir[0]),
                self.nadir_px[1] + scale * (y - self.nadir[1]),
            )
        right, up, view = self._basis()
        ray = np.array([x - self.nadir[0], y - self.nadir[1], z - self.height])
        depth = float(view @ ray)
        return (
            self.nadir_px[0] + self.focal * float(right @ ray) / depth,
            self.nadir_px[1] + self.focal * float(up @ ray) / depth,
        )

    def to_table(self, u: float, v: float, z: float = 0.0) -> tuple[float, float]:
        """The world (x, y) on the plane at height ``z`` that pixel (u, v) (v up)
        sees: :meth:`to_pixels` undone."""
        right, up, view = self._basis()
        ray = (
            right * (u - self.nadir_px[0]) / self.focal
            + up * (v - self.nadir_px[1]) / self.focal
            + view
        )
        reach = (z - self.height) / ray[2]
        return self.nadir[0] + reach * float(ray[0]), self.nadir[1] + reach * float(ray[1])

    def scale_at(self, x: float, y: float, z: float = 0.0) -> float:
        """Pixels per metre on the plane at height ``z`` around (x, y): the square
        root of the area ratio of the image there (a straight-down camera: the same
        everywhere on the plane; a tilted one: larger nearer the camera)."""
        step = 1e-4
        u0, v0 = self.to_pixels(x, y, z)
        ux, vx = self.to_pixels(x + step, y, z)
        uy, vy = self.to_pixels(x, y + step, z)
        return math.sqrt(abs((ux - u0) * (vy - v0) - (uy - u0) * (vx - v0))) / step

    def table_extent(self) -> tuple[float, float, float, float]:
        """World (x0, y0, x1, y1) of the table seen in the image (with a tilt: the
        box around the table the image's corners see)."""
        if not self.tilt:
            scale = self.focal / self.height
            x0 = self.nadir[0] - self.nadir_px[0] / scale
            y0 = self.nadir[1] - self.nadir_px[1] / scale
            return x0, y0, x0 + self.width / scale, y0 + self.height_px / scale
        seen = [self.to_table(u, v) for u in (0, self.width) for v in (0, self.height_px)]
        xs, ys = [p[0] for p in seen], [p[1] for p in seen]
        return min(xs), min(ys), max(xs), max(ys)


def top_camera(rig: PhotoRig, side: float) -> Camera:
    """The top-down camera of the plane of the cubes' tops (z = ``side``) of a
    straight-down ``rig`` (no tilt)."""
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


def canvas_points(rig: PhotoRig, world: np.ndarray, z: float, supersample: int) -> np.ndarray:
    """World points at height ``z`` → fixed-point (4 fractional bits) pixel
    coordinates of a canvas ``supersample`` times the image's size, for OpenCV's
    polygon fills (``shift=4``)."""
    n = supersample
    pixels = []
    for x, y in world:
        u, v = rig.to_pixels(float(x), float(y), z)
        pixels.append(((u * n - 0.5) * 16, ((rig.height_px - v) * n - 0.5) * 16))
    rounded: np.ndarray = np.rint(np.array(pixels)).astype(np.int32)
    return rounded


def draw_board(
    canvas: np.ndarray,
    rig: PhotoRig,
    generator: np.random.Generator,
    *,
    supersample: int,
    machine: bool = True,
) -> None:
    """The gridded board on ``canvas`` (``supersample`` times the image's size,
    filled with the board's colour): black grid lines, four markers near the
    corners of the table seen, and with ``machine`` a dark arm base at the middle
    of the top edge."""

    def fill(world: np.ndarray, z: float, colour: tuple[int, ...]) -> None:
        polygon = canvas_points(rig, world, z, supersample)
        cv2.fillPoly(canvas, [polygon], colour, lineType=cv2.LINE_8, shift=4)

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
    """An RGB ``uint8`` photograph-like image of ``blocks`` on a gridded board.

    The side faces drawn are those turned away from the camera, which the top
    then covers but for slivers (the faces a camera sees are drawn by
    :mod:`demoplan.perception.photo_families`); kept so that a seed gives the
    image it always gave."""
    generator = np.random.default_rng(rng)
    n = supersample
    rows, cols = rig.height_px * n, rig.width * n
    canvas = np.empty((rows, cols, 3), dtype=np.uint8)
    canvas[:] = BOARD
    shift = 4

    def points(world: np.ndarray, z: float) -> np.ndarray:
        return canvas_points(rig, world, z, n)

    def fill(world: np.ndarray, z: float, colour: tuple[int, ...]) -> None:
        cv2.fillPoly(canvas, [points(world, z)], colour, lineType=cv2.LINE_8, shift=shift)

    draw_board(canvas, rig, generator, supersample=n, machine=machine)
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
    return lens_and_sensor(image, rig, blur, noise, jpeg_quality, generator)


def light_falloff(rig: PhotoRig) -> np.ndarray:
    """The share of the light each pixel gets (rows × columns): 1 at the top-left
    corner, falling off to 0.82 at the bottom-right."""
    ramp: np.ndarray = (
        1.0
        - 0.12 * np.linspace(0, 1, rig.width)[None, :]
        - 0.06 * np.linspace(0, 1, rig.height_px)[:, None]
    )
    return ramp


def lens_and_sensor(
    image: np.ndarray,
    rig: PhotoRig,
    blur: float,
    noise: float,
    jpeg_quality: int,
    generator: np.random.Generator,
    *,
    exposure: float = 1.0,
) -> np.ndarray:
    """The rendered scene (float RGB, image size) as a camera records it: light
    falling off across the table, the exposure (a gain; over 1 the channels
    bleed into each other, a colour's distance from its grey shrinking by the
    gain, and bright colours clip at 255 — an over-exposed yellow turns pale),
    blur, sensor noise, 8 bits, JPEG."""
    # lighting falls off across the table, then the lens and the sensor
    image = image * light_falloff(rig)[..., None]
    if exposure != 1.0:
        grey = image.mean(axis=2, keepdims=True)
        image = np.minimum((grey + (image - grey) / exposure) * exposure, 255.0)
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
