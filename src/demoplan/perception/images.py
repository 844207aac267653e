"""Perceiving blocks from image files, as ``demoplan perceive`` does it: one
picture, or the pictures before and after the last move for stacking (paper
§V.B), within a time budget, to the blocks of a scene (:func:`perceive_files`).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from demoplan.budget import PERCEPTION_TIMEOUT, time_budget
from demoplan.errors import InputError, UsageError
from demoplan.perception.blocks import DetectedBlock, PerceptionSettings, Rejection, detect_blocks
from demoplan.perception.camera import Camera, load_image
from demoplan.perception.colours import load_palette
from demoplan.perception.image_measures import ImageMeasures
from demoplan.perception.overlay import (
    Drawn,
    NoBlocksError,
    draw_overlay,
    speck_side,
    square_corners,
    top_view_to_image,
)
from demoplan.perception.sizes import (
    SIDE_TOLERANCE,
    block_sizes,
    held_to_sizes,
    in_scale,
    rejection_in_scale,
)
from demoplan.perception.stacking import BlockTracker, TrackedBlock
from demoplan.perception.working_resolution import factor_for_scale, factor_for_size, reduced

__all__ = [
    "SIDE_TOLERANCE",
    "Perception",
    "Sides",
    "blocks_in_top_view",
    "given_sides",
    "one_side",
    "perceive_files",
    "perceive_top_view",
    "seen_now",
]


@dataclass(frozen=True, slots=True)
class Perception:
    """What one picture showed: the blocks (by name, as the scene has them), the
    coloured regions found to be no block (each with why), and — when asked
    for — the picture with both drawn on it (``demoplan perceive --plot``)."""

    blocks: dict[str, TrackedBlock]
    rejected: tuple[Rejection, ...]
    overlay: np.ndarray | None = None
    scale: str = ""
    """How pixels became metres (``--px-per-m``, the cube size, …): one phrase."""


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


Sides = float | Sequence[float] | None
"""``--side``: the blocks' side in metres, several sides (blocks of several sizes),
or none given."""


def given_sides(side: Sides) -> tuple[float, ...]:
    """``side`` as a tuple of sides: empty when none is given."""
    if side is None:
        return ()
    return (float(side),) if isinstance(side, int | float) else tuple(map(float, side))


def check_side(side: Sides) -> None:
    """``--side``, when given: each a block's side in metres, within the size limit."""
    # not from the pose documents: their models (pydantic) are a tenth of a second
    # of demoplan perceive's start-up, which needs them for nothing else
    from demoplan.documents.extents import MAX_SIZE_M

    for one in given_sides(side):
        if not (math.isfinite(one) and 0 < one <= MAX_SIZE_M):
            raise UsageError(
                f"--side {one:g}: a block's side in metres, at most {MAX_SIZE_M:g} m expected "
                "(an object's largest extent, docs/limits.md)"
            )


def one_side(side: Sides, where: str) -> float | None:
    """The one side given, or ``None``; a usage error naming the values when
    several are given where one is needed (``where``: for what)."""
    sides = given_sides(side)
    if len(sides) > 1:
        values = " ".join(f"--side {one:g}" for one in sides)
        raise UsageError(f"{values}: one block size expected {where}")
    return sides[0] if sides else None


def check_top_view(px_per_m: float, origin: tuple[float, float]) -> None:
    """``--px-per-m`` and ``--origin``: finite, the origin within ±10 km."""
    if not math.isfinite(px_per_m):
        raise UsageError(f"--px-per-m {px_per_m:g}: pixels per metre, a finite number expected")
    if not all(map(math.isfinite, origin)) or max(map(abs, origin)) > 1e4:
        raise UsageError(
            f"--origin {origin[0]:g} {origin[1]:g}: the image's bottom-left corner in metres, "
            "each a finite number within ±10,000 (10 km) expected"
        )


def perceive_files(
    image: Path,
    px_per_m: float,
    origin: tuple[float, float],
    *,
    before: Path | None = None,
    side: Sides = None,
    timeout: float = PERCEPTION_TIMEOUT,
    colours: Path | None = None,
) -> dict[str, TrackedBlock]:
    """The blocks in ``image``, by name: :func:`perceive_top_view`'s."""
    return perceive_top_view(
        image, px_per_m, origin, before=before, side=side, timeout=timeout, colours=colours
    ).blocks


def perceive_top_view(
    image: Path,
    px_per_m: float | None,
    origin: tuple[float, float],
    *,
    before: Path | None = None,
    side: Sides = None,
    timeout: float = PERCEPTION_TIMEOUT,
    colours: Path | None = None,
    overlay: bool = False,
    rejections: bool = True,
) -> Perception:
    """The blocks in ``image`` (a top-down orthographic picture, ``px_per_m``
    pixels per metre, its bottom-left corner at world ``origin``), by name;
    with ``before`` (the picture before the last move) a block the moved one
    now covers stands under it; ``colours`` a palette file of colours to add
    (:func:`~demoplan.perception.colours.load_palette`); the regions rejected;
    with ``overlay``, both drawn on the picture. An input error when there is no
    block: a scene needs one. With ``rejections`` false and no ``overlay`` (and
    ``px_per_m``) the regions rejected are not recorded — ``demoplan perceive``
    without ``--plot`` shows none: their outlines, hundreds of specks on a
    photograph, cost 5–60 ms of its CPU — and ``rejected`` is empty; the blocks
    are the same.

    ``side``: the blocks' side, or several (blocks of several sizes): squares are
    looked for within 15 % of one of them
    (:attr:`~demoplan.perception.blocks.PerceptionSettings.sides`).
    Without ``px_per_m`` the blocks' one ``side`` gives the scale (a camera looking
    straight down: the most common size of the squares found, in pixels, is
    ``side``; :func:`~demoplan.perception.sizes.block_sizes`). Without
    ``side`` (and ``before``) the blocks are held to the sizes most squares found
    share (:func:`~demoplan.perception.sizes.block_sizes`): others are rejected.

    A large photograph is looked at reduced by a whole factor
    (:mod:`~demoplan.perception.working_resolution`; the overlay is drawn on the
    reduction, and the scale's line says so)."""
    sides = given_sides(side)
    if px_per_m is None:
        if not sides:
            raise UsageError("the scale is needed: --px-per-m, or the blocks' --side")
        check_top_view(1.0, origin)
    else:
        check_top_view(px_per_m, origin)
    check_side(sides)
    settings = PerceptionSettings(colours=load_palette(colours) if colours is not None else {})
    if px_per_m is None:
        cube = one_side(sides, "for the scale of a view straight down (or --px-per-m)")
        assert cube is not None
        return _perceive_at_cube_scale(image, cube, origin, settings, before, timeout, overlay)
    if sides:
        settings = replace(
            settings,
            min_side=(1 - SIDE_TOLERANCE) * min(sides),
            max_side=(1 + SIDE_TOLERANCE) * max(sides),
            sides=sides,
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
        photograph = load_image(image)
        factor = factor_for_scale(settings.min_side * px_per_m, photograph.shape)
        camera = Camera(px_per_m / factor, origin)
        if before is not None:
            earlier = detect_blocks(reduced(load_image(before), factor).picture, camera, settings)
            tracker = BlockTracker(
                TrackedBlock(b.name, b.x, b.y, 0.0, b.yaw, b.side, b.colour) for b in earlier
            )
        working = reduced(photograph, factor)
        picture = working.picture
        measures = ImageMeasures(picture)  # converted once for every stage
        rejected: list[Rejection] = []
        recorded = rejections or overlay
        # the blocks' size from the photograph (with a picture before, the strips
        # left in view of covered blocks are the tracker's to place)
        held = not sides and before is None
        detected = blocks_in_top_view(
            picture, camera, settings, held, rejected if recorded else None, measures
        )
        blocks = tracker.update(detected)
    scale = f"--px-per-m {px_per_m:g}, origin {origin[0]:g} {origin[1]:g}"
    scale += working.note(photograph.shape)
    seen = _perception(image, camera, picture, blocks, detected, rejected, overlay, scale)
    return seen if recorded else replace(seen, rejected=())


def blocks_in_top_view(
    picture: np.ndarray,
    camera: Camera,
    settings: PerceptionSettings,
    held: bool,
    rejected: list[Rejection] | None = None,
    measures: ImageMeasures | None = None,
) -> list[DetectedBlock]:
    """The blocks :func:`~demoplan.perception.blocks.detect_blocks` finds in
    ``picture``, ``held`` to the block sizes most of them share
    (:func:`~demoplan.perception.sizes.held_to_sizes`, when no size was given):
    what ``demoplan perceive`` of a top view reports, for a picture in memory (the
    generated families are scored on it). The squares of no block size are added
    to ``rejected`` when it is given."""
    measures = ImageMeasures(picture) if measures is None else measures
    detected = detect_blocks(picture, camera, settings, rejected, measures)
    if not held:
        return detected
    kept, odd = held_to_sizes(
        detected,
        block_sizes([d.side for d in detected]),
        seen=(measures, camera),
        colours=settings.colours,
    )
    if rejected is not None:
        rejected += odd
    return kept


def _perception(
    image: Path,
    camera: Camera,
    picture: np.ndarray,
    blocks: dict[str, TrackedBlock],
    detected: list[DetectedBlock],
    rejected: list[Rejection],
    overlay: bool,
    scale: str,
) -> Perception:
    """What a picture showed, with the overlay drawn when asked for; an input error
    when there is no block."""
    to_image = top_view_to_image(camera, picture.shape[0])
    if not blocks:
        raise NoBlocksError(
            "no blocks found; a scene needs at least one (is --px-per-m right? --side too strict?)",
            source=str(image),
            overlay=draw_overlay(picture, [], [(r, 0.0) for r in rejected], to_image)
            if overlay
            else None,
        )
    seen, left = seen_now(blocks, detected)
    rejected += left
    drawn = None
    if overlay:
        found = [Drawn(b.name, b.x, b.y, b.yaw, b.side) for b in seen]
        side = speck_side([b.side for b in blocks.values()])
        drawn = draw_overlay(picture, found, [(r, 0.0) for r in rejected], to_image, side)
    return Perception(blocks, tuple(rejected), drawn, scale)


MIN_SIDE_PX = 16.0
"""The smallest block side (px) looked for when the scale is not known: a smaller
square top does not give a scale to a few per cent."""
MAX_SIDE_SHARE = 0.25
"""The largest block side looked for when the scale is not known, as a share of
the image's shorter side."""


def _perceive_at_cube_scale(
    image: Path,
    side: float,
    origin: tuple[float, float],
    settings: PerceptionSettings,
    before: Path | None,
    timeout: float,
    overlay: bool,
) -> Perception:
    """``perceive_top_view`` when only the blocks' ``side`` is known: the blocks
    found in pixels (sides from :data:`MIN_SIDE_PX` to :data:`MAX_SIDE_SHARE` of
    the image), the most common size taken to be ``side`` — the scale of a camera
    looking straight down — and the squares of other sizes rejected; the image's
    bottom-left corner at ``origin``."""
    if before is not None:
        raise UsageError(
            "--before needs the scale (--px-per-m, --camera or --markers): two pictures "
            "are compared in metres"
        )
    with (
        time_budget(
            timeout,
            f"perception stopped at its time budget (--timeout {timeout:g} s){{where}}: many "
            "small regions or a large image, the scale not known; give it more time, or "
            "--px-per-m",
        ),
        _memory_refused(image),
    ):
        photograph = load_image(image)
        working = reduced(photograph, factor_for_size(photograph.shape))
        picture = working.picture
        shorter = min(picture.shape[:2])
        in_pixels = replace(
            settings, min_side=MIN_SIDE_PX, max_side=max(MIN_SIDE_PX, MAX_SIDE_SHARE * shorter)
        )
        rejected: list[Rejection] = []
        measures = ImageMeasures(picture)  # converted once for every stage
        found = detect_blocks(picture, Camera(1.0), in_pixels, rejected, measures)
    sizes = block_sizes([d.side for d in found])
    if not sizes:
        in_pixels_to_image = top_view_to_image(Camera(1.0), picture.shape[0])
        raise NoBlocksError(
            "no blocks found, so no scale from --side; a scene needs at least one "
            "(or give --px-per-m)",
            source=str(image),
            overlay=draw_overlay(
                picture, [], [(r, 0.0) for r in rejected], in_pixels_to_image, MIN_SIDE_PX
            )
            if overlay
            else None,
        )
    px_per_m = sizes[0][0] / side
    kept, odd = held_to_sizes(
        found, sizes, unit="px", seen=(measures, Camera(1.0)), colours=settings.colours
    )
    detected = [in_scale(d, px_per_m, origin) for d in kept]
    rejected = [rejection_in_scale(r, px_per_m, origin) for r in [*rejected, *odd]]
    blocks = BlockTracker().update(detected)
    factor = working.factor
    scale = (
        f"the cube size: --side {side:g} m is {factor * sizes[0][0]:.1f} px, "
        f"{factor * px_per_m:.1f} px/m (a camera looking straight down), origin "
        f"{origin[0]:g} {origin[1]:g} at the image's bottom-left corner"
        + working.note(photograph.shape)
    )
    camera = Camera(px_per_m, origin)
    return _perception(image, camera, picture, blocks, detected, rejected, overlay, scale)


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
