"""Generated families of photograph-like renders, each carrying one thing that
makes real photographs of cubes hard (issue 41), with labels in the real
photographs' terms (``demoplan.perception.labelled``), so that the same scoring
applies: a top face is found by a detection within 0.6 of its side of its centre.

The families (:data:`FAMILIES`, each a function of a random generator):

- ``touching_rows``: rows of two to five cubes face to face (gaps under 1.5 mm,
  neighbours often of one colour), beside lone cubes;
- ``stacks``: a cube on a cube (two or three high, a few millimetres off and a
  little turned), the lower cubes' side strips showing below the top one;
- ``achromatic``: black, white and grey cubes on the grey board or white paper;
- ``patterned``: a letter, a frame or dots printed on each top;
- ``hands``: a hand and forearm (skin-coloured, with fingers) reaching for a cube;
- ``side_faces``: a low camera far off the cubes' axis: side faces nearly as
  large as the tops;
- ``overexposed``: a gain of 1.4–1.8 (mostly yellow cubes: they clip pale);
- ``small``: 25 mm cubes at about 26 px, many, some in touching pairs;
- ``tilted``: the camera 10–30° from straight down (the label's scale holds at
  the image's centre only);
- ``distractors``: cylinders, cuboids, stars and pentagons of the cubes'
  colours beside the cubes — none is a block; about one photograph in seven
  has shapes only;
- ``tipped_rows``: rows of two to four cubes of different colours lying tipped
  over (rolled 30–45° about the row), each cube showing a lit face and a darker
  strip, beside standing cubes — no face of a row is a top;
- ``towers``: towers of three to five cubes of different colours off the nadir,
  under a camera of a phone's focal length: their lower cubes' side faces,
  squarish near the image's edge, are no tops (mrhan_stacks, bottom right).

A top face less than :data:`PARTIAL_BELOW` in view (a cube on it, a hand over
it, the image's border through it) is ``partial`` (it need not be found); one
less than :data:`HIDDEN_BELOW` in view is not labelled.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from demoplan.budget import time_budget
from demoplan.errors import DemoplanError
from demoplan.fileio import write_atomic
from demoplan.perception.blocks import PerceptionSettings
from demoplan.perception.camera import Camera, save_image
from demoplan.perception.images import SIDE_TOLERANCE, blocks_in_top_view
from demoplan.perception.labelled import LabelledBlock, LabelledPhoto, PhotoRun, score_detections
from demoplan.perception.photo_families_scene import (
    GLYPHS,
    Cube,
    CubeTruth,
    Hand,
    PhotoScene,
    Shape,
    render_scene,
)
from demoplan.perception.photo_families_tipped import TippedRow
from demoplan.perception.photos import PhotoRig
from demoplan.perception.synthetic import COLOURS

__all__ = [
    "ACHROMATIC",
    "CHROMATIC",
    "FAMILIES",
    "HIDDEN_BELOW",
    "PARTIAL_BELOW",
    "FamilyCase",
    "family_case",
    "family_cases",
    "perceive_case",
    "save_case",
]

PARTIAL_BELOW = 0.85
"""A top face with less than this share in view is labelled partial."""
HIDDEN_BELOW = 0.3
"""A top face with less than this share in view is not labelled at all."""
SIDE = 0.04
SMALL_SIDE = 0.025

CHROMATIC: dict[str, tuple[int, int, int]] = {
    **{name: COLOURS[name] for name in ("red", "green", "blue", "yellow")},
    "orange": (225, 110, 35),
    "purple": (95, 60, 165),
}
ACHROMATIC: dict[str, tuple[int, int, int]] = {
    "black": (30, 30, 33),
    "grey": (105, 105, 108),
    "white": (238, 238, 234),
}
SKIN = ((224, 172, 140), (198, 134, 102), (141, 85, 54), (236, 188, 158))


class _Layout:
    """Places things apart on the part of the table the image shows (off the
    markers and the machine base of a board)."""

    def __init__(self, rig: PhotoRig, rng: np.random.Generator, background: str) -> None:
        self.rig, self.rng = rig, rng
        self.taken: list[tuple[float, float, float]] = []
        # colours no cube has here: a blue cube on the blue table is as lost as
        # a grey one on the grey board
        self.unseen = {"blue"} if background == "blue" else set()
        if background == "board":
            x0, y0, x1, y1 = rig.table_extent()
            r = 0.75 * rig.marker + 0.015
            self.taken += [
                (x, y, r)
                for x in (x0 + 0.015 + rig.marker / 2, x1 - 0.015 - rig.marker / 2)
                for y in (y0 + 0.015 + rig.marker / 2, y1 - 0.015 - rig.marker / 2)
            ]
            self.taken.append(((x0 + x1) / 2, y1, 0.09))

    def colour(self, names: Mapping[str, tuple[int, int, int]]) -> str:
        """One of ``names`` at random, none the table hides."""
        shown = [name for name in names if name not in self.unseen]
        return shown[int(self.rng.integers(len(shown)))]

    def spot(self, radius: float, margin_px: float = 50.0) -> tuple[float, float] | None:
        """A free centre for a thing of ``radius`` (m) wholly in the image, or none."""
        rig = self.rig
        for _ in range(400):
            u = float(self.rng.uniform(margin_px, rig.width - margin_px))
            v = float(self.rng.uniform(margin_px, rig.height_px - margin_px))
            x, y = rig.to_table(u, v, SIDE)
            reach = radius * rig.scale_at(x, y, SIDE)
            if not (margin_px <= u - reach and u + reach <= rig.width - margin_px):
                continue
            if not (margin_px <= v - reach and v + reach <= rig.height_px - margin_px):
                continue
            if all(math.dist((x, y), (tx, ty)) >= radius + tr + 0.01 for tx, ty, tr in self.taken):
                self.taken.append((x, y, radius))
                return x, y
        return None


def _lone_cubes(
    layout: _Layout,
    count: int,
    names: Mapping[str, tuple[int, int, int]],
    *,
    side: float = SIDE,
    patterns: Sequence[str] = ("",),
) -> list[Cube]:
    rng = layout.rng
    cubes = []
    for _ in range(count):
        spot = layout.spot(side * 0.75)
        if spot is None:
            break
        name = layout.colour(names)
        pattern = patterns[int(rng.integers(len(patterns)))]
        yaw = float(rng.uniform(-45, 45))
        cubes.append(Cube(name, names[name], *spot, yaw, side, pattern=pattern))
    return cubes


def _row(
    layout: _Layout, count: int, names: Mapping[str, tuple[int, int, int]], side: float
) -> list[Cube]:
    """``count`` cubes face to face along a line (gaps under 1.5 mm)."""
    rng = layout.rng
    gap = float(rng.uniform(0.0, 0.0015))
    pitch = side + gap
    spot = layout.spot(count * pitch / 2 + 0.2 * side)
    if spot is None:
        return []
    yaw = float(rng.uniform(-45, 45))
    along = np.array([math.cos(math.radians(yaw)), math.sin(math.radians(yaw))])
    cubes = []
    for k in range(count):
        x, y = np.array(spot) + (k - (count - 1) / 2) * pitch * along
        name = layout.colour(names)
        turn = float(rng.uniform(-2.0, 2.0))
        cubes.append(Cube(name, names[name], float(x), float(y), yaw + turn, side))
    return cubes


def _rig(rng: np.random.Generator, heights: tuple[float, float] = (1.0, 1.6)) -> PhotoRig:
    """A straight-down camera at a height in ``heights`` (m), its axis anywhere over the image."""
    return PhotoRig(
        height=float(rng.uniform(*heights)),
        nadir_px=(float(rng.uniform(150, 1130)), float(rng.uniform(100, 620))),
    )


def _background(
    rng: np.random.Generator, choices: Sequence[str] = ("board", "paper", "blue")
) -> str:
    return choices[int(rng.integers(len(choices)))]


def touching_rows(rng: np.random.Generator) -> PhotoScene:
    """Two or three rows of two to five cubes face to face, of three colours, and lone cubes."""
    rig, background = _rig(rng), _background(rng)
    layout = _Layout(rig, rng, background)
    shown = sorted(set(CHROMATIC) - layout.unseen)
    palette = {n: CHROMATIC[n] for n in rng.choice(shown, 3, replace=False)}
    cubes = [
        c
        for _ in range(int(rng.integers(2, 4)))
        for c in _row(layout, int(rng.integers(2, 6)), palette, SIDE)
    ]
    cubes += _lone_cubes(layout, int(rng.integers(0, 4)), CHROMATIC)
    return PhotoScene(rig, tuple(cubes), background=background)


def stacks(rng: np.random.Generator) -> PhotoScene:
    """Two to four stacks two or three cubes high (each a few mm off and up to 12°
    turned on the one below), and lone cubes; the camera 0.8–1.3 m up."""
    rig, background = _rig(rng, (0.8, 1.3)), _background(rng)
    layout = _Layout(rig, rng, background)
    cubes: list[Cube] = []
    for _ in range(int(rng.integers(2, 5))):
        spot = layout.spot(0.8 * SIDE)
        if spot is None:
            break
        shown = sorted(set(CHROMATIC) - layout.unseen)
        names = list(rng.choice(shown, int(rng.integers(2, 4)), replace=False))
        yaw = float(rng.uniform(-45, 45))
        for level, name in enumerate(names):
            dx, dy = rng.uniform(-0.003, 0.003, 2) if level else (0.0, 0.0)
            turn = float(rng.uniform(-12, 12)) if level else 0.0
            cubes.append(
                Cube(
                    str(name),
                    CHROMATIC[str(name)],
                    spot[0] + dx,
                    spot[1] + dy,
                    yaw + turn,
                    SIDE,
                    level * SIDE,
                )
            )
    cubes += _lone_cubes(layout, int(rng.integers(1, 5)), CHROMATIC)
    return PhotoScene(rig, tuple(cubes), background=background)


def achromatic(rng: np.random.Generator) -> PhotoScene:
    """Black and white cubes (and grey ones on paper) on the board or paper, with up to
    two coloured ones."""
    rig, background = _rig(rng), _background(rng, ("board", "paper"))
    layout = _Layout(rig, rng, background)
    names = dict(ACHROMATIC)
    if background == "board":
        del names["grey"]  # a grey cube on the grey board: nothing to see
    cubes = _lone_cubes(layout, int(rng.integers(4, 10)), names)
    cubes += _lone_cubes(layout, int(rng.integers(0, 3)), CHROMATIC)
    return PhotoScene(rig, tuple(cubes), background=background)


def patterned(rng: np.random.Generator) -> PhotoScene:
    """Four to nine cubes, each with a :data:`GLYPHS` pattern printed on its top."""
    rig, background = _rig(rng), _background(rng)
    layout = _Layout(rig, rng, background)
    names = {**CHROMATIC, "white": ACHROMATIC["white"]}
    cubes = _lone_cubes(layout, int(rng.integers(4, 10)), names, patterns=sorted(GLYPHS))
    return PhotoScene(rig, tuple(cubes), background=background)


def hands(rng: np.random.Generator) -> PhotoScene:
    """Four to eight cubes and one or two hands reaching for a cube, palm beside it,
    fingers towards it."""
    rig, background = _rig(rng), _background(rng)
    layout = _Layout(rig, rng, background)
    cubes = _lone_cubes(layout, int(rng.integers(4, 9)), CHROMATIC)
    reaching = []
    for target in rng.choice(len(cubes), min(len(cubes), int(rng.integers(1, 3))), replace=False):
        cube = cubes[int(target)]
        width = float(rng.uniform(0.075, 0.09))
        towards = float(rng.uniform(0, 360))
        reach = 0.55 * SIDE + 0.55 * width + float(rng.uniform(0.0, 0.5)) * width
        a = math.radians(towards)
        palm = (cube.x - reach * math.cos(a), cube.y - reach * math.sin(a))
        reaching.append(Hand(*palm, towards, width, SKIN[int(rng.integers(len(SKIN)))]))
    return PhotoScene(rig, tuple(cubes), hands=tuple(reaching), background=background)


def side_faces(rng: np.random.Generator) -> PhotoScene:
    """A camera 0.45–0.6 m up, its axis anywhere up to 300 px beyond the image: large side faces."""
    height = float(rng.uniform(0.45, 0.6))
    rig = PhotoRig(
        height=height,
        focal=float(rng.uniform(700, 900)) * height / 0.5,
        nadir_px=(float(rng.uniform(-300, 1580)), float(rng.uniform(-200, 920))),
    )
    background = _background(rng)
    layout = _Layout(rig, rng, background)
    cubes = _lone_cubes(layout, int(rng.integers(4, 9)), CHROMATIC)
    return PhotoScene(rig, tuple(cubes), background=background)


def overexposed(rng: np.random.Generator) -> PhotoScene:
    """Mostly yellow cubes under an exposure of 1.4–1.8 and strong glints."""
    rig, background = _rig(rng), _background(rng, ("board", "blue"))
    layout = _Layout(rig, rng, background)
    cubes = _lone_cubes(layout, int(rng.integers(2, 6)), {"yellow": CHROMATIC["yellow"]})
    cubes += _lone_cubes(layout, int(rng.integers(1, 5)), CHROMATIC)
    exposure = float(rng.uniform(1.4, 1.8))
    return PhotoScene(rig, tuple(cubes), background=background, exposure=exposure, glints=0.8)


def small(rng: np.random.Generator) -> PhotoScene:
    """10 to 30 cubes of 25 mm, some in touching pairs, the camera 1.85–2.1 m up (about
    26 px a side)."""
    rig, background = _rig(rng, (1.85, 2.1)), _background(rng)
    layout = _Layout(rig, rng, background)
    cubes = [
        c for _ in range(int(rng.integers(1, 5))) for c in _row(layout, 2, CHROMATIC, SMALL_SIDE)
    ]
    cubes += _lone_cubes(layout, int(rng.integers(8, 25)), CHROMATIC, side=SMALL_SIDE)
    return PhotoScene(rig, tuple(cubes), background=background)


def tilted(rng: np.random.Generator) -> PhotoScene:
    """Five to ten cubes under a camera tilted 10–30° towards +y (± 30°), 0.8–1.2 m up."""
    tilt = float(rng.uniform(10, 30))
    height = float(rng.uniform(0.8, 1.2))
    rig = PhotoRig(
        height=height,
        focal=2000.0 * height / 1.2 * math.cos(math.radians(tilt)),
        tilt=tilt,
        tilt_towards=float(rng.uniform(60, 120)),
    )
    background = _background(rng)
    layout = _Layout(rig, rng, background)
    cubes = _lone_cubes(layout, int(rng.integers(5, 11)), CHROMATIC)
    return PhotoScene(rig, tuple(cubes), background=background)


def distractors(rng: np.random.Generator) -> PhotoScene:
    """Cylinders, cuboids, stars and pentagons beside up to seven cubes (none in about
    one photograph in seven)."""
    rig, background = _rig(rng), _background(rng)
    layout = _Layout(rig, rng, background)
    cubes = _lone_cubes(layout, int(rng.integers(3, 8)) if rng.random() > 0.15 else 0, CHROMATIC)
    shapes = []
    for _ in range(int(rng.integers(3, 7))):
        kind = str(rng.choice(["cylinder", "cuboid", "star", "pentagon"]))
        size = SIDE * float(rng.uniform(0.9, 1.3))
        stretch = float(rng.uniform(1.7, 2.5))
        spot = layout.spot(size / 2 * (0.6 * stretch if kind == "cuboid" else 1.0) * 1.1)
        if spot is None:
            break
        height = {
            "cylinder": rng.uniform(0.03, 0.06),
            "cuboid": size,
            "star": rng.uniform(0.012, 0.03),
            "pentagon": rng.uniform(0.012, 0.03),
        }[kind]
        name = layout.colour(CHROMATIC)
        shapes.append(
            Shape(
                kind,
                name,
                CHROMATIC[name],
                *spot,
                float(rng.uniform(0, 360)),
                size,
                float(height),
                stretch,
            )
        )
    return PhotoScene(rig, tuple(cubes), shapes=tuple(shapes), background=background)


def tipped_rows(rng: np.random.Generator) -> PhotoScene:
    """One to three rows of two to four cubes lying tipped over, neighbours of other
    colours, rolled 30–45° about the row, and two to five standing cubes."""
    rig, background = _rig(rng), _background(rng)
    layout = _Layout(rig, rng, background)
    rows = []
    for _ in range(int(rng.integers(1, 4))):
        count = int(rng.integers(2, 5))
        spot = layout.spot(count * SIDE / 2 + 0.2 * SIDE)
        if spot is None:
            break
        names: list[str] = []
        while len(names) < count:
            name = layout.colour(CHROMATIC)
            if not names or name != names[-1]:
                names.append(name)
        rows.append(
            TippedRow(
                *spot,
                float(rng.uniform(0, 180)),
                float(rng.uniform(30, 45)) * (1 if rng.random() < 0.5 else -1),
                SIDE,
                tuple(names),
                tuple(CHROMATIC[name] for name in names),
            )
        )
    cubes = _lone_cubes(layout, int(rng.integers(2, 6)), CHROMATIC)
    return PhotoScene(rig, tuple(cubes), tipped=tuple(rows), background=background)


def towers(rng: np.random.Generator) -> PhotoScene:
    """One or two towers three to five cubes high, each cube of another colour than
    the one below it, standing a third of the focal length or more from the
    camera's nadir, their tops wholly in the image, and two to five lone cubes; the
    camera 0.9–1.15 m up with a phone's or a depth camera's focal length (900–1100
    px at 1280 px across: a lower cube's side face is r / f as deep as wide, r px
    from the nadir, squarish at the image's edge — mrhan_stacks' 100 and 185 mm
    stacks near the board's edge; at the other families' 2000 px a thin band)."""
    rig = PhotoRig(
        height=float(rng.uniform(0.9, 1.15)),
        focal=float(rng.uniform(900, 1100)),
        nadir_px=(float(rng.uniform(300, 980)), float(rng.uniform(150, 570))),
    )
    background = _background(rng)
    layout = _Layout(rig, rng, background)
    cubes: list[Cube] = []
    for _ in range(int(rng.integers(1, 3))):
        count = int(rng.integers(3, 6))
        for _ in range(100):
            spot = layout.spot(0.8 * SIDE)
            if spot is None:
                break
            foot = np.array(rig.to_pixels(*spot, 0.0))
            top = np.array(rig.to_pixels(*spot, count * SIDE))
            reach = 0.8 * SIDE * rig.scale_at(*spot, count * SIDE)
            if math.dist(foot, rig.nadir_px) >= rig.focal / 3 and _within(rig, top, reach + 50.0):
                break
            layout.taken.pop()  # too near the nadir, or its top out of view
            spot = None
        if spot is None:
            continue
        names: list[str] = []
        while len(names) < count:
            name = layout.colour(CHROMATIC)
            if not names or name != names[-1]:
                names.append(name)
        yaw = float(rng.uniform(-45, 45))
        for level, name in enumerate(names):
            turn = float(rng.uniform(-3, 3)) if level else 0.0
            cubes.append(Cube(name, CHROMATIC[name], *spot, yaw + turn, SIDE, level * SIDE))
    cubes += _lone_cubes(layout, int(rng.integers(2, 6)), CHROMATIC)
    return PhotoScene(rig, tuple(cubes), background=background)


def _within(rig: PhotoRig, point: np.ndarray, margin: float) -> bool:
    """Whether the image point ``point`` (px) lies ``margin`` px or more inside the image."""
    return bool(
        margin <= point[0] <= rig.width - margin and margin <= point[1] <= rig.height_px - margin
    )


FAMILIES: dict[str, Callable[[np.random.Generator], PhotoScene]] = {
    "touching_rows": touching_rows,
    "stacks": stacks,
    "achromatic": achromatic,
    "patterned": patterned,
    "hands": hands,
    "side_faces": side_faces,
    "overexposed": overexposed,
    "small": small,
    "tilted": tilted,
    "distractors": distractors,
    "tipped_rows": tipped_rows,
    "towers": towers,  # last: the others' seeds stay theirs
}
"""Each family's scene from a random generator (module docstring)."""


@dataclass(frozen=True, slots=True)
class FamilyCase:
    """One generated photograph: its family and seed, the scene, the image (RGB
    ``uint8``), the truth of every cube, its label (as a real photograph's is
    read) and the label file's content."""

    family: str
    seed: int
    scene: PhotoScene
    image: np.ndarray
    truths: tuple[CubeTruth, ...]
    label: LabelledPhoto
    document: Mapping[str, Any]

    @property
    def name(self) -> str:
        """``family-seed``: the name of its image and label files."""
        return f"{self.family}-{self.seed}"


def family_case(family: str, seed: int) -> FamilyCase:
    """The photograph ``seed`` of ``family`` (a :data:`FAMILIES` name), with its truth."""
    rng = np.random.default_rng([seed, list(FAMILIES).index(family)])
    scene = FAMILIES[family](rng)
    image, truths = render_scene(scene, rng)
    side = scene.cubes[0].side if scene.cubes else SIDE
    rig = scene.rig
    px_per_m = rig.scale_at(*rig.to_table(rig.width / 2, rig.height_px / 2, side), side)
    name = f"{family}-{seed}"
    labelled = [t for t in truths if t.in_view >= HIDDEN_BELOW]
    blocks = tuple(LabelledBlock(t.u, t.v, t.side_px, t.in_view < PARTIAL_BELOW) for t in labelled)
    label = LabelledPhoto(
        name, Path(f"{name}.png"), rig.width, rig.height_px, px_per_m, (side,), blocks
    )
    document = _document(family, seed, scene, labelled, px_per_m, side)
    return FamilyCase(family, seed, scene, image, tuple(truths), label, document)


def _document(
    family: str,
    seed: int,
    scene: PhotoScene,
    labelled: Sequence[CubeTruth],
    px_per_m: float,
    side: float,
) -> dict[str, Any]:
    """The label file of a generated photograph, in the real photographs' format."""
    rig = scene.rig

    def fold(yaw: float) -> float:
        return round(-((-yaw + 45.0) % 90.0 - 45.0), 2)

    blocks = []
    for truth in labelled:
        cube = truth.cube
        entry: dict[str, Any] = {
            "colour": cube.colour,
            "kind": "cube" + (f", {cube.pattern} printed on the top" if cube.pattern else ""),
            "u": round(truth.u, 2),
            "v": round(truth.v, 2),
            "side_px": round(truth.side_px, 2),
            "yaw_world_deg": fold(cube.yaw),
        }
        if truth.in_view < PARTIAL_BELOW:
            entry["partial"] = True
        if cube.z > 0:
            entry["stack_height"] = round(cube.top / cube.side)
        blocks.append(entry)
    non_cubes = []
    for shape in scene.shapes:
        u, v = rig.to_pixels(shape.x, shape.y, shape.height)
        non_cubes.append(
            {
                "colour": shape.colour,
                "kind": shape.kind,
                "u": round(u - 0.5, 2),
                "v": round(rig.height_px - v - 0.5, 2),
            }
        )
    for row in scene.tipped:
        u, v = rig.to_pixels(row.x, row.y, row.top())
        non_cubes.append(
            {
                "colour": "/".join(row.colours),
                "kind": f"a row of {len(row.colours)} cubes lying tipped over ({row.roll:.0f} deg)",
                "u": round(u - 0.5, 2),
                "v": round(rig.height_px - v - 0.5, 2),
            }
        )
    for hand in scene.hands:
        u, v = rig.to_pixels(hand.x, hand.y)
        non_cubes.append(
            {
                "colour": "skin",
                "kind": "hand and forearm",
                "u": round(u - 0.5, 2),
                "v": round(rig.height_px - v - 0.5, 2),
            }
        )
    return {
        "image": f"{family}-{seed}.png",
        "generated": {
            "family": family,
            "seed": seed,
            "module": "demoplan.perception.photo_families",
        },
        "px_per_m": round(px_per_m, 3),
        "px_per_m_note": (
            f"the scale on the plane of the tops ({side * 1000:g} mm up) at the image's centre"
            + (
                f"; the camera is tilted {rig.tilt:.1f} deg, so the scale varies across the image"
                if rig.tilt
                else ""
            )
        ),
        "side_m": side,
        "blocks": blocks,
        "non_cubes": non_cubes,
        "background": scene.background,
        "hard": [family],
        "note": f"camera {rig.height:.2f} m above the table, exposure x{scene.exposure:.2f}",
    }


def family_cases(per_family: int = 3, first_seed: int = 0) -> list[FamilyCase]:
    """``per_family`` photographs of every family (seeds from ``first_seed``), for
    the perception benchmark: each case's ``image`` and ``label`` are what
    :func:`perceive_case` scores."""
    return [
        family_case(family, seed)
        for family in FAMILIES
        for seed in range(first_seed, first_seed + per_family)
    ]


def perceive_case(
    case: FamilyCase, *, side_given: bool = False, timeout: float = math.inf
) -> PhotoRun:
    """``case`` perceived in process as ``demoplan perceive IMAGE --px-per-m S
    --origin 0 0`` (with ``--side`` the cubes' side when ``side_given``, and
    ``--timeout``) perceives its saved image — the same detection and, without
    ``--side``, the same size check (:func:`~.images.blocks_in_top_view`) —
    scored against its label."""
    camera = Camera(case.label.px_per_m, (0.0, 0.0))
    settings = PerceptionSettings()
    if side_given:
        side = case.label.side_m[0]
        settings = replace(
            settings, min_side=(1 - SIDE_TOLERANCE) * side, max_side=(1 + SIDE_TOLERANCE) * side
        )
    start = time.perf_counter()
    try:
        with time_budget(timeout, "perception stopped at its time budget{where}"):
            found = blocks_in_top_view(case.image, camera, settings, held=not side_given)
    except DemoplanError as error:
        seconds = time.perf_counter() - start
        return PhotoRun(
            case.name, score_detections(case.label, []), seconds, error.exit_code, str(error)
        )
    seconds = time.perf_counter() - start
    centres = [(block.x, block.y) for block in found]
    return PhotoRun(case.name, score_detections(case.label, centres), seconds, 0, "")


def save_case(case: FamilyCase, directory: str | Path) -> Path:
    """``case``'s image (PNG) and label file (JSON, as the real photographs' are)
    written into ``directory``; the label file's path."""
    folder = Path(directory)
    save_image(case.image, folder / f"{case.name}.png")
    label = folder / f"{case.name}.json"
    write_atomic(label, json.dumps(case.document, indent=1) + "\n")
    return label
