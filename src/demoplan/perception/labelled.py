"""Scoring block perception on labelled photographs (the development set of real
photographs in tests/data/photos, NOTICE.md there).

A label file names the photograph, its scale (``px_per_m``, pixels per metre on
the table top) and the cubes whose top face a person sees: each with the pixel
centre (``u``, ``v``; x right, y down, the top-left pixel's centre at (0, 0)),
the side in pixels and, optionally, ``partial`` (occluded or cut by the border:
it need not be found). A detection is a *found* block when its centre lies
within 0.6 of the side of a labelled top face — one detection per face, the
closest pairs first — and every other detection is a *false* block. The image
is read as a top view with ``px_per_m`` and origin 0 0, so pixel (u, v) is the
table point x = (u + 0.5) / px_per_m, y = (H − v − 0.5) / px_per_m.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from demoplan.errors import DemoplanError, InputError

__all__ = [
    "FOUND_WITHIN",
    "LabelledBlock",
    "LabelledPhoto",
    "PhotoRun",
    "PhotoScore",
    "load_labelled",
    "perceive_labelled",
    "score_detections",
]

FOUND_WITHIN = 0.6
"""A detection within this share of a labelled top face's side from its centre finds it."""


@dataclass(frozen=True, slots=True)
class LabelledBlock:
    """A cube's top face as labelled: pixel centre (x right, y down), side (px)."""

    u: float
    v: float
    side_px: float
    partial: bool


@dataclass(frozen=True, slots=True)
class LabelledPhoto:
    """A labelled photograph: the image file, its size, its scale and its cubes."""

    name: str
    image: Path
    width: int
    height: int
    px_per_m: float
    side_m: tuple[float, ...]
    blocks: tuple[LabelledBlock, ...]
    corrected_after_running: str = ""
    """What of the label was changed after a detector had run on the photograph,
    and why (empty: labelled before any run, as it stands)."""

    @property
    def needed(self) -> int:
        """Labelled top faces that must be found (those not marked partial)."""
        return sum(not block.partial for block in self.blocks)

    def to_pixel(self, x: float, y: float) -> tuple[float, float]:
        """The pixel (u right, v down) a table point (m, origin 0 0) lies on."""
        return x * self.px_per_m - 0.5, self.height - y * self.px_per_m - 0.5


@dataclass(frozen=True, slots=True)
class PhotoScore:
    """Found (of the needed faces), needed, and false detections."""

    found: int
    needed: int
    false: int


@dataclass(frozen=True, slots=True)
class PhotoRun:
    """One photograph perceived: its score, the seconds perception took, and the exit
    code ``demoplan perceive`` would give (0, or the error's) with the error's text."""

    photo: str
    score: PhotoScore
    seconds: float
    exit_code: int
    error: str


def _number(document: dict[str, object], key: str, source: str) -> float:
    value = document.get(key)
    if not isinstance(value, int | float) or isinstance(value, bool) or not value > 0:
        raise InputError("a positive number expected", source=source, field=key)
    return float(value)


def load_labelled(path: str | Path) -> LabelledPhoto:
    """The labelled photograph a label file (JSON) describes; its ``image`` is read
    relative to the label file (only its size, here)."""
    from PIL import Image

    label = Path(path)
    source = str(label)
    try:
        document = json.loads(label.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise InputError(f"a label file (JSON) expected: {error}", source=source) from None
    if not isinstance(document, dict) or not isinstance(document.get("image"), str):
        raise InputError("a mapping with an image file name expected", source=source, field="image")
    px_per_m = _number(document, "px_per_m", source)
    sides = document.get("side_m", 0.04)
    side_m = tuple(float(s) for s in (sides if isinstance(sides, list) else [sides]))
    blocks = []
    for index, entry in enumerate(document.get("blocks", [])):
        field = f"blocks[{index}]"
        if not isinstance(entry, dict):
            raise InputError("a block (u, v, side_px) expected", source=source, field=field)
        u, v = entry.get("u"), entry.get("v")
        if not isinstance(u, int | float) or not isinstance(v, int | float):
            raise InputError("pixel centre u, v expected", source=source, field=field)
        side_px = entry.get("side_px") or side_m[0] * px_per_m
        blocks.append(LabelledBlock(float(u), float(v), float(side_px), bool(entry.get("partial"))))
    corrected = document.get("corrected_after_running", "")
    if not isinstance(corrected, str):
        raise InputError(
            "what was corrected after running, and why, as text expected",
            source=source,
            field="corrected_after_running",
        )
    image = label.parent / document["image"]
    with Image.open(image) as opened:
        width, height = opened.size
    return LabelledPhoto(
        label.stem, image, width, height, px_per_m, side_m, tuple(blocks), corrected
    )


def score_detections(photo: LabelledPhoto, centres: Sequence[tuple[float, float]]) -> PhotoScore:
    """How detections at table points ``centres`` (m, origin 0 0) score on ``photo``:
    matched to labelled faces closest pairs first, each within :data:`FOUND_WITHIN`
    of its face's side."""
    pixels = [photo.to_pixel(x, y) for x, y in centres]
    pairs = sorted(
        (math.hypot(u - block.u, v - block.v), j, i)
        for j, (u, v) in enumerate(pixels)
        for i, block in enumerate(photo.blocks)
    )
    used_detections: set[int] = set()
    used_labels: set[int] = set()
    for distance, j, i in pairs:
        if j in used_detections or i in used_labels:
            continue
        if distance <= FOUND_WITHIN * photo.blocks[i].side_px:
            used_detections.add(j)
            used_labels.add(i)
    found = sum(1 for i in used_labels if not photo.blocks[i].partial)
    return PhotoScore(found, photo.needed, len(pixels) - len(used_detections))


def perceive_labelled(
    photo: LabelledPhoto,
    *,
    timeout: float = math.inf,
    side: float | Sequence[float] | None = None,
) -> PhotoRun:
    """``photo`` perceived in process as ``demoplan perceive IMAGE --px-per-m S
    --origin 0 0`` perceives it (with ``--timeout`` and ``--side``, one side or
    several; no ``--plot``: the regions rejected not recorded), scored."""
    from demoplan.perception.images import perceive_top_view

    start = time.perf_counter()
    try:
        found = perceive_top_view(
            photo.image, photo.px_per_m, (0.0, 0.0), side=side, timeout=timeout, rejections=False
        )
    except DemoplanError as error:
        seconds = time.perf_counter() - start
        return PhotoRun(
            photo.name, score_detections(photo, []), seconds, error.exit_code, str(error)
        )
    seconds = time.perf_counter() - start
    centres = [(block.x, block.y) for block in found.blocks.values()]
    return PhotoRun(photo.name, score_detections(photo, centres), seconds, 0, "")
