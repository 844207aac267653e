"""Perceiving blocks from image files, as ``demoplan perceive`` does it: one
picture, or the pictures before and after the last move for stacking (paper
§V.B), within a time budget, to the blocks of a scene (:func:`perceive_files`).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path

from demoplan.budget import PERCEPTION_TIMEOUT, time_budget
from demoplan.documents.poses import MAX_SIZE_M
from demoplan.errors import InputError, UsageError
from demoplan.perception.blocks import PerceptionSettings, detect_blocks
from demoplan.perception.camera import Camera, load_image
from demoplan.perception.colours import load_palette
from demoplan.perception.stacking import BlockTracker, TrackedBlock

__all__ = ["SIDE_TOLERANCE", "perceive_files"]

SIDE_TOLERANCE = 0.15
"""With the blocks' side known, sizes this far off it (relative) are not blocks."""


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
    """The blocks in ``image`` (a top-down orthographic picture, ``px_per_m``
    pixels per metre, its bottom-left corner at world ``origin``), by name;
    with ``before`` (the picture before the last move) a block the moved one
    now covers stands under it; ``colours`` a palette file of colours to add
    (:func:`~demoplan.perception.colours.load_palette`). An input error when
    there is none: a scene needs one."""
    if not all(map(math.isfinite, (px_per_m, *origin))) or max(map(abs, origin)) > 1e4:
        raise UsageError("--px-per-m and --origin must be finite, the origin within ±10 km")
    if side is not None and not (math.isfinite(side) and 0 < side <= MAX_SIZE_M):
        raise UsageError(
            f"--side {side:g}: a block's side in metres, at most {MAX_SIZE_M:g} m expected "
            "(an object's largest extent, docs/limits.md)"
        )
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
        blocks = tracker.update(detect_blocks(load_image(image), camera, settings))
    if not blocks:
        raise InputError(
            "no blocks found; a scene needs at least one (is --px-per-m right? --side too strict?)",
            source=str(image),
        )
    return blocks


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
