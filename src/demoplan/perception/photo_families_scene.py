"""Scenes for the generated photograph families: cubes (stacked, touching, black,
white, patterned), coloured shapes that are no cubes, hands, under a camera that
may be tilted — rendered as a camera records them, with the truth in the terms
of the real photographs' labels (``demoplan.perception.labelled``).

Every solid is a prism: a footprint polygon on the table (or on the cube below),
raised by its height. It is drawn, farthest from the camera first, as the side
faces the camera sees (those whose outward normal points towards the camera's
centre, darker than the top, by their angle to the light) and then its top; a
hand is a flat skin-coloured outline above everything. Each cube's top face is
also written into a map of which face each canvas sample shows, so its truth
says how much of it is in view (a stacked cube, a hand or the image's border
covers the rest).

The truth of a cube is where a person labelling the photograph puts it: the
centre of its top face in the image (``u`` right, ``v`` down, the top-left
pixel's centre at (0, 0)) and the side of that face in pixels (the camera's
scale at that face times the cube's side). A straight-down camera maps each
horizontal plane to the image by a similarity; a tilted one does not, and the
label's ``px_per_m`` is then the scale at the image's centre on the plane of the
tops of cubes standing on the table, as the real labels give it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from demoplan.perception.opencv import cv2
from demoplan.perception.photo_families_tipped import TippedRow, pixels_of, tipped_faces
from demoplan.perception.photos import BOARD, PhotoRig, canvas_points, draw_board, lens_and_sensor

__all__ = [
    "BACKGROUNDS",
    "GLYPHS",
    "HAND_HEIGHT",
    "Cube",
    "CubeTruth",
    "Hand",
    "PhotoScene",
    "Shape",
    "render_scene",
]

BACKGROUNDS: dict[str, tuple[int, int, int]] = {
    "board": BOARD,  # the grey board with its black grid and markers
    "paper": (214, 212, 204),  # a sheet of white paper under room light
    "blue": (70, 110, 170),  # a blue table top
}
HAND_HEIGHT = 0.07
"""Height (m) of a hand reaching over the table: above the cubes' tops."""
LIGHT = np.array([0.3, -0.45])
"""A shadow's reach on the table per metre of height (the light is up and to the left)."""

_Bar = tuple[float, float, float, float]  # x0, y0, x1, y1 in face units, the face is [-0.5, 0.5]²
GLYPHS: dict[str, tuple[_Bar, ...]] = {
    "L": ((-0.25, -0.3, -0.1, 0.3), (-0.25, -0.3, 0.25, -0.15)),
    "T": ((-0.07, -0.3, 0.07, 0.2), (-0.3, 0.15, 0.3, 0.3)),
    "H": ((-0.28, -0.3, -0.14, 0.3), (0.14, -0.3, 0.28, 0.3), (-0.14, -0.06, 0.14, 0.06)),
    "E": (
        (-0.25, -0.3, -0.11, 0.3),
        (-0.11, -0.3, 0.25, -0.17),
        (-0.11, -0.06, 0.17, 0.06),
        (-0.11, 0.17, 0.25, 0.3),
    ),
    "frame": (  # a printed border, as alphabet blocks have
        (-0.42, -0.42, 0.42, -0.34),
        (-0.42, 0.34, 0.42, 0.42),
        (-0.42, -0.34, -0.34, 0.34),
        (0.34, -0.34, 0.42, 0.34),
    ),
    "dots": tuple(
        (cx - 0.06, cy - 0.06, cx + 0.06, cy + 0.06)
        for cx, cy in ((0, 0), (-0.25, -0.25), (0.25, 0.25), (-0.25, 0.25), (0.25, -0.25))
    ),
}
"""Patterns printed on a top face: bars in the face's own units (its centre at 0,
its side 1), turning with the cube."""


def _turned(local: np.ndarray, yaw: float, x: float, y: float) -> np.ndarray:
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    placed: np.ndarray = local @ np.array([[c, s], [-s, c]]) + np.array([x, y])
    return placed


@dataclass(frozen=True, slots=True)
class Cube:
    """A cube: its colour's name and RGB, the centre of its footprint (m), yaw
    (deg), side (m), the height its bottom stands at (``z``: 0 on the table, a
    cube's side on that cube) and a pattern printed on its top (a :data:`GLYPHS`
    name, or none)."""

    colour: str
    rgb: tuple[int, int, int]
    x: float
    y: float
    yaw: float
    side: float
    z: float = 0.0
    pattern: str = ""

    @property
    def top(self) -> float:
        """The height of its top face (m)."""
        return self.z + self.side

    def footprint(self) -> np.ndarray:
        """Corners (m), counter-clockwise."""
        h = self.side / 2
        return _turned(np.array([(-h, -h), (h, -h), (h, h), (-h, h)]), self.yaw, self.x, self.y)


@dataclass(frozen=True, slots=True)
class Shape:
    """A coloured solid that is no cube: ``kind`` one of ``cylinder`` (standing),
    ``cuboid`` (a lying box 0.6 ``size`` wide and ``stretch`` times as long: its
    top no square, nor two cubes' tops side by side), ``star`` and ``pentagon``
    (flat-topped pieces); ``size`` its width across (m)."""

    kind: str
    colour: str
    rgb: tuple[int, int, int]
    x: float
    y: float
    yaw: float
    size: float
    height: float
    stretch: float = 2.0

    def footprint(self) -> np.ndarray:
        """Its outline on the table (m), counter-clockwise."""
        r = self.size / 2
        if self.kind == "cylinder":
            angles = np.linspace(0, 2 * math.pi, 36, endpoint=False)
            local = np.stack([r * np.cos(angles), r * np.sin(angles)], 1)
        elif self.kind == "cuboid":
            wide = 0.6 * r
            long = wide * self.stretch
            local = np.array([(-long, -wide), (long, -wide), (long, wide), (-long, wide)])
        elif self.kind == "star":
            angles = np.pi / 2 + np.arange(10) * np.pi / 5
            radii = np.where(np.arange(10) % 2 == 0, r, 0.42 * r)
            local = np.stack([radii * np.cos(angles), radii * np.sin(angles)], 1)
        elif self.kind == "pentagon":
            angles = np.pi / 2 + np.arange(5) * 2 * np.pi / 5
            local = np.stack([r * np.cos(angles), r * np.sin(angles)], 1)
        else:
            raise ValueError(f"unknown shape kind {self.kind!r}")
        return _turned(local, self.yaw, self.x, self.y)


@dataclass(frozen=True, slots=True)
class Hand:
    """A hand reaching over the table: the palm's centre (m), ``towards`` the
    direction (deg) its fingers point, ``width`` the palm's width (m), its skin's
    RGB; the arm runs from the wrist away from the fingers, ``arm`` metres long
    (to past the image's border)."""

    x: float
    y: float
    towards: float
    width: float
    rgb: tuple[int, int, int]
    arm: float = 0.6

    def outlines(self) -> list[np.ndarray]:
        """Palm, four fingers, a thumb and the forearm, each an outline (m)."""
        w = self.width
        angles = np.linspace(0, 2 * math.pi, 24, endpoint=False)
        palm = np.stack([0.55 * w * np.cos(angles), 0.5 * w * np.sin(angles)], 1)

        def finger(base: tuple[float, float], angle: float, length: float) -> np.ndarray:
            a = math.radians(angle)
            along, across = (
                np.array([math.cos(a), math.sin(a)]),
                np.array([-math.sin(a), math.cos(a)]),
            )
            half = 0.1 * w
            tip = [
                along * length + half * (math.cos(t) * along + math.sin(t) * across)
                for t in np.linspace(-math.pi / 2, math.pi / 2, 7)
            ]
            return np.array(
                [base - half * across, *(np.array(base) + p for p in tip), base + half * across]
            )

        parts = [palm]
        for k, length in enumerate((0.75, 0.85, 0.8, 0.65)):
            across = (k - 1.5) * 0.24 * w
            parts.append(finger((0.4 * w, across), (k - 1.5) * 6.0, length * w))
        parts.append(finger((0.0, 0.45 * w), 55.0, 0.7 * w))  # the thumb
        parts.append(
            np.array(
                [
                    (-0.3 * w, -0.38 * w),
                    (-self.arm, -0.5 * w),
                    (-self.arm, 0.5 * w),
                    (-0.3 * w, 0.38 * w),
                ]
            )
        )
        return [_turned(part, self.towards, self.x, self.y) for part in parts]


@dataclass(frozen=True, slots=True)
class PhotoScene:
    """What a generated photograph shows: the camera and table (``rig``), the
    cubes, the shapes that are no cubes, hands, rows of cubes lying tipped over
    (no cubes' tops either), the table's surface (a
    :data:`BACKGROUNDS` name), the exposure (a gain: over 1 colours clip) and the
    chance of a glint on each top."""

    rig: PhotoRig
    cubes: tuple[Cube, ...]
    shapes: tuple[Shape, ...] = ()
    hands: tuple[Hand, ...] = ()
    tipped: tuple[TippedRow, ...] = ()
    background: str = "board"
    exposure: float = 1.0
    glints: float = 0.5


@dataclass(frozen=True, slots=True)
class CubeTruth:
    """A cube's top face as the image shows it: centre (``u`` right, ``v`` down,
    pixels, the top-left pixel's centre at (0, 0)), side in pixels, and the share
    of the face in view (1: all of it)."""

    cube: Cube
    u: float
    v: float
    side_px: float
    in_view: float


@dataclass(frozen=True, slots=True)
class _Prism:
    footprint: np.ndarray
    bottom: float
    height: float
    rgb: tuple[int, int, int]
    face: int  # 1 + the cube's index for a cube's top, 0 for anything else
    pattern: str = ""


class _Canvas:
    """A supersampled colour canvas with a map of which cube's top each sample shows."""

    def __init__(self, rig: PhotoRig, supersample: int, colour: tuple[int, int, int]) -> None:
        self.rig = rig
        self.n = supersample
        self.rgb = np.empty((rig.height_px * supersample, rig.width * supersample, 3), np.uint8)
        self.rgb[:] = colour
        self.faces = np.zeros(self.rgb.shape[:2], np.uint16)

    def points(self, world: np.ndarray, z: float) -> np.ndarray:
        return canvas_points(self.rig, world, z, self.n)

    def fill(self, polygon: np.ndarray, colour: tuple[int, ...], face: int = 0) -> None:
        cv2.fillPoly(self.rgb, [polygon], colour, lineType=cv2.LINE_8, shift=4)
        cv2.fillPoly(self.faces, [polygon], face, lineType=cv2.LINE_8, shift=4)

    def area(self, polygon: np.ndarray) -> float:
        """A polygon's area in canvas samples (off the canvas too)."""
        p = polygon.astype(float) / 16
        return 0.5 * abs(
            float(np.dot(p[:, 0], np.roll(p[:, 1], 1)) - np.dot(p[:, 1], np.roll(p[:, 0], 1)))
        )


def _prisms(scene: PhotoScene) -> list[_Prism]:
    solids = [
        _Prism(cube.footprint(), cube.z, cube.side, cube.rgb, index + 1, cube.pattern)
        for index, cube in enumerate(scene.cubes)
    ]
    solids += [_Prism(s.footprint(), 0.0, s.height, s.rgb, 0) for s in scene.shapes]
    eye = np.array(scene.rig.camera_centre())
    return sorted(solids, key=lambda p: _distance(p, eye), reverse=True)  # the farthest first


def _distance(prism: _Prism, eye: np.ndarray) -> float:
    """From the camera's centre ``eye`` (x, y, z) to the middle of ``prism``'s top."""
    centre = prism.footprint.mean(axis=0)
    return float(np.linalg.norm(eye - np.array([*centre, prism.bottom + prism.height])))


def _draw_prism(canvas: _Canvas, prism: _Prism, tint: float, eye: np.ndarray) -> None:
    """The sides of ``prism`` the camera at ``eye`` (x, y) sees, then its top, a
    cube's rounded edges around it (a darker rim 3 % of the side wide: two cubes
    face to face show a seam) and the pattern printed on it."""
    base, top = prism.bottom, prism.bottom + prism.height
    colour = np.asarray(prism.rgb, float) * tint
    corners = prism.footprint
    for k in range(len(corners)):
        a, b = corners[k], corners[(k + 1) % len(corners)]
        normal = np.array([b[1] - a[1], a[0] - b[0]])  # outward (counter-clockwise outline)
        if normal @ (eye - (a + b) / 2) <= 0:
            continue  # turned away from the camera
        face = normal / np.linalg.norm(normal)
        shade = 0.42 + 0.18 * float(face @ np.array([-0.6, 0.8]))
        quad = np.concatenate(
            [canvas.points(np.array([a, b]), base), canvas.points(np.array([b, a]), top)]
        )
        canvas.fill(quad, tuple(int(c) for c in np.clip(colour * shade, 0, 255)))
    outline = canvas.points(corners, top)
    canvas.fill(outline, tuple(int(c) for c in np.clip(colour, 0, 255)), prism.face)
    if prism.face:
        rim = max(1, round(0.03 * float(np.linalg.norm(outline[1] - outline[0])) / 16))
        darker = tuple(int(c) for c in np.clip(colour * 0.75, 0, 255))
        cv2.polylines(canvas.rgb, [outline], True, darker, rim, cv2.LINE_8, shift=4)
    if prism.pattern:
        _print_pattern(canvas, prism, top, colour)


def _print_pattern(canvas: _Canvas, prism: _Prism, top: float, colour: np.ndarray) -> None:
    """The glyph on a cube's top: white on a dark face, near-black on a pale one."""
    ink = (240, 240, 236) if float(colour.mean()) < 110 else (30, 30, 34)
    corners = prism.footprint
    origin, along, across = corners[0], corners[1] - corners[0], corners[3] - corners[0]
    for x0, y0, x1, y1 in GLYPHS[prism.pattern]:
        local = np.array([(x0, y0), (x1, y0), (x1, y1), (x0, y1)]) + 0.5
        world = origin + local[:, :1] * along + local[:, 1:] * across
        canvas.fill(canvas.points(world, top), ink, prism.face)


def _shadows(canvas: _Canvas, scene: PhotoScene) -> None:
    """Each solid's and hand's outline swept away from the light, darkening the table."""
    shadow = np.zeros(canvas.faces.shape, np.uint8)
    outlines = [(c.footprint(), c.top) for c in scene.cubes if c.z == 0]
    outlines += [(s.footprint(), s.height) for s in scene.shapes]
    outlines += [(row.footprint(), row.top()) for row in scene.tipped]
    for footprint, height in outlines:
        hull = cv2.convexHull(
            np.concatenate([footprint, footprint + LIGHT * height]).astype(np.float32)
        )
        cv2.fillPoly(shadow, [canvas.points(hull.reshape(-1, 2), 0)], 1, shift=4)
    for hand in scene.hands:
        for outline in hand.outlines():
            cv2.fillPoly(shadow, [canvas.points(outline + LIGHT * HAND_HEIGHT, 0)], 1, shift=4)
    canvas.rgb[shadow > 0] = (canvas.rgb[shadow > 0] * 0.62).astype(np.uint8)


def render_scene(
    scene: PhotoScene,
    rng: np.random.Generator,
    *,
    supersample: int = 3,
    noise: float = 3.0,
    blur: float = 0.8,
    jpeg_quality: int = 85,
) -> tuple[np.ndarray, list[CubeTruth]]:
    """The RGB ``uint8`` photograph of ``scene`` and the truth of each of its cubes."""
    rig = scene.rig
    canvas = _Canvas(rig, supersample, BACKGROUNDS[scene.background])
    if scene.background == "board":
        draw_board(canvas.rgb, rig, rng, supersample=supersample)
    _shadows(canvas, scene)
    eye = np.array(rig.camera_centre()[:2])
    # the tipped rows' faces drawn among the prisms, farthest first (they draw no
    # random numbers: scenes without them render as before)
    eye_3d = np.array(rig.camera_centre())
    faces = sorted(
        (face for row in scene.tipped for face in tipped_faces(row, eye_3d)),
        key=lambda face: -face[0],
    )
    for prism in _prisms(scene):
        while faces and faces[0][0] >= _distance(prism, eye_3d):
            _, corners, colour = faces.pop(0)
            canvas.fill(pixels_of(rig, corners, supersample), colour)
        _draw_prism(canvas, prism, float(rng.uniform(0.93, 1.07)), eye)
    for _, corners, colour in faces:
        canvas.fill(pixels_of(rig, corners, supersample), colour)
    for hand in scene.hands:
        shade = float(rng.uniform(0.95, 1.05))
        skin = tuple(int(c) for c in np.clip(np.asarray(hand.rgb) * shade, 0, 255))
        for outline in hand.outlines():
            canvas.fill(canvas.points(outline, HAND_HEIGHT), skin)
    image = np.asarray(
        cv2.resize(
            canvas.rgb.astype(np.float32), (rig.width, rig.height_px), interpolation=cv2.INTER_AREA
        ),
        dtype=np.float32,
    )
    truths = _truths(scene, canvas)
    _add_glints(image, truths, scene.glints, rng)
    photo = lens_and_sensor(image, rig, blur, noise, jpeg_quality, rng, exposure=scene.exposure)
    return photo, truths


def _truths(scene: PhotoScene, canvas: _Canvas) -> list[CubeTruth]:
    rig = scene.rig
    truths = []
    for index, cube in enumerate(scene.cubes):
        u, v = rig.to_pixels(cube.x, cube.y, cube.top)
        shown = int(np.count_nonzero(canvas.faces == index + 1))
        whole = canvas.area(canvas.points(cube.footprint(), cube.top))
        truths.append(
            CubeTruth(
                cube,
                u - 0.5,
                rig.height_px - v - 0.5,
                cube.side * rig.scale_at(cube.x, cube.y, cube.top),
                min(1.0, shown / whole),
            )
        )
    return truths


def _add_glints(
    image: np.ndarray, truths: Sequence[CubeTruth], chance: float, rng: np.random.Generator
) -> None:
    """A soft white glint on a top face in full view, with chance ``chance``."""
    height, width = image.shape[:2]
    for truth in truths:
        if truth.in_view < 0.99 or rng.random() > chance:
            continue
        u, v = np.array([truth.u, truth.v]) + rng.uniform(-0.25, 0.25, 2) * truth.side_px
        radius = 0.08 * truth.side_px
        r0, r1 = max(0, int(v - 4 * radius)), min(height, int(v + 4 * radius) + 1)
        c0, c1 = max(0, int(u - 4 * radius)), min(width, int(u + 4 * radius) + 1)
        vv, uu = np.mgrid[r0:r1, c0:c1]
        glint = 0.8 * np.exp(-((uu - u) ** 2 + (vv - v) ** 2) / (2 * radius**2))[..., None]
        image[r0:r1, c0:c1] = image[r0:r1, c0:c1] * (1 - glint) + 250 * glint
