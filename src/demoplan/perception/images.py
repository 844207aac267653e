"""Perceiving blocks from image files, as ``demoplan perceive`` does it: one
picture, or the pictures before and after the last move for stacking (paper
§V.B), within a time budget, to the blocks of a scene (:func:`perceive_files`).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from demoplan.budget import PERCEPTION_TIMEOUT, time_budget
from demoplan.documents.poses import MAX_SIZE_M
from demoplan.errors import InputError, UsageError
from demoplan.perception.blocks import DetectedBlock, PerceptionSettings, Rejection, detect_blocks
from demoplan.perception.camera import Camera, load_image
from demoplan.perception.colours import load_palette
from demoplan.perception.overlay import Drawn, draw_overlay, square_corners, top_view_to_image
from demoplan.perception.stacking import BlockTracker, TrackedBlock

__all__ = ["SIDE_TOLERANCE", "Perception", "perceive_files", "perceive_top_view", "seen_now"]


@dataclass(frozen=True, slots=True)
class Perception:
    """What one picture showed: the blocks (by name, as the scene has them), the
    coloured regions found to be no block (each with why), and — when asked
    for — the picture with both drawn on it (``demoplan perceive --plot``)."""

    blocks: dict[str, TrackedBlock]
    rejected: tuple[Rejection, ...]
    overlay: np.ndarray | None = None


def seen_now(
    blocks: dict[str, TrackedBlock], detected: list[DetectedBlock]
) -> tuple[list[TrackedBlock], list[Rejection]]:
    """The scene's blocks this picture's detections are (a block kept from before,
    covered now, is not drawn), and the detections the tracker set aside —
    what is left in view of a covered block."""
    poses = {(b.x, b.y): b for b in blocks.values()}
    seen = [poses[(d.x, d.y)] for d in detected if (d.x, d.y) in poses]
    left = [
        Rejection(
            "covered",
            "what is left in view of a covered block",
            d.colour,
            (tuple((float(x), float(y)) for x, y in square_corners(d.x, d.y, d.yaw, d.side)),),
        )
        for d in detected
        if (d.x, d.y) not in poses
    ]
    return seen, left


SIDE_TOLERANCE = 0.15
"""With the blocks' side known, sizes this far off it (relative) are not blocks."""


def check_side(side: float | None) -> None:
    """``--side``, when given: a block's side in metres, within the size limit."""
    if side is not None and not (math.isfinite(side) and 0 < side <= MAX_SIZE_M):
        raise UsageError(
            f"--side {side:g}: a block's side in metres, at most {MAX_SIZE_M:g} m expected "
            "(an object's largest extent, docs/limits.md)"
        )


def check_top_view(px_per_m: float, origin: tuple[float, float]) -> None:
    """``--px-per-m`` and ``--origin``: finite, the origin within ±10 km."""
    if not all(map(math.isfinite, (px_per_m, *origin))) or max(map(abs, origin)) > 1e4:
        raise UsageError("--px-per-m and --origin must be finite, the origin within ±10 km")


def perceive_files(
    image: Path,
    px_per_m: float,
    origin: tuple[float, float],
    *,
    before: Path | None = None,
    side: float | None = None,
    timeout: float = PERCEPTION_TIMEOUT,
    colours: Path | None = None,
) -> dict[str, TrackedBlock]:
    """The blocks in ``image``, by name: :func:`perceive_top_view`'s."""
    return perceive_top_view(
        image, px_per_m, origin, before=before, side=side, timeout=timeout, colours=colours
    ).blocks


def perceive_top_view(
    image: Path,
    px_per_m: float,
    origin: tuple[float, float],
    *,
    before: Path | None = None,
    side: float | None = None,
    timeout: float = PERCEPTION_TIMEOUT,
    colours: Path | None = None,
    overlay: bool = False,
) -> Perception:
    """The blocks in ``image`` (a top-down orthographic picture, ``px_per_m``
    pixels per metre, its bottom-left corner at world ``origin``), by name;
    with ``before`` (the picture before the last move) a block the moved one
    now covers stands under it; ``colours`` a palette file of colours to add
    (:func:`~demoplan.perception.colours.load_palette`); the regions rejected;
    with ``overlay``, both drawn on the picture. An input error when there is no
    block: a scene needs one."""
    check_top_view(px_per_m, origin)
    check_side(side)
    camera = Camera(px_per_m, origin)
    settings = PerceptionSettings(colours=load_palette(colours) if colours is not None else {})
    if side is not None:
        settings = replace(
            settings, min_side=(1 - SIDE_TOLERANCE) * side, max_side=(1 + SIDE_TOLERANCE) * side
        )
    tracker = BlockTracker()
    with (
        time_budget(
            timeout,
            f"perception stopped at its time budget (--timeout {timeout:g} s){{where}}: many "
            "small regions or a large image; give it more time, or say the blocks' size (--side)",
        ),
        _memory_refused(image),
    ):
        if before is not None:
            earlier = detect_blocks(load_image(before), camera, settings)
            tracker = BlockTracker(
                TrackedBlock(b.name, b.x, b.y, 0.0, b.yaw, b.side, b.colour) for b in earlier
            )
        picture = load_image(image)
        rejected: list[Rejection] = []
        detected = detect_blocks(picture, camera, settings, rejected)
        blocks = tracker.update(detected)
    if not blocks:
        raise InputError(
            "no blocks found; a scene needs at least one (is --px-per-m right? --side too strict?)",
            source=str(image),
        )
    seen, left = seen_now(blocks, detected)
    rejected += left
    drawn = None
    if overlay:
        found = [Drawn(b.name, b.x, b.y, b.yaw, b.side) for b in seen]
        to_image = top_view_to_image(camera, picture.shape[0])
        drawn = draw_overlay(picture, found, [(r, 0.0) for r in rejected], to_image)
    return Perception(blocks, tuple(rejected), drawn)


@contextmanager
def _memory_refused(image: Path) -> Iterator[None]:
    """A MemoryError inside the block becomes one line: perception holds about
    30 bytes a pixel at its peak (a 4000 × 4000 image: 0.6 GB)."""
    try:
        yield
    except MemoryError:
        raise InputError(
            "the image does not fit in memory to perceive (about 30 bytes a pixel: "
            "16 megapixels took 0.6 GB); a smaller image expected",
            source=str(image),
        ) from None
