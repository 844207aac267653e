"""The blocks' size from the photograph: the common sizes of the square tops found.

A table of cubes holds few sizes. The squares the detector accepts are grouped
by side — a group is the sides within :data:`SIDE_TOLERANCE` (15 %, as for a
given ``--side``) of its median — and a group of two or more squares, or the
largest group, is a block size; a square of no such size (a coloured patch, a
box lid, the top of something else) is not a block and is rejected with why
(``not a block size``) when it lies more than 15 % outside the span of the
block sizes' groups and does not stand as the photograph's cubes do (its own
side strip towards their nadir, :mod:`demoplan.perception.stack_sides`: a cube
of its own size, on the table farther from the camera than a group of raised
ones) and, looked at again around it at the block sizes, shows no square of
one (:func:`looked_again`: a print on a top or a top with its side faces is a
cube measured wrong). With ``--side`` and no other scale, the largest group's
median side in pixels is that side: the scale of a camera looking straight down
(:func:`demoplan.perception.images.perceive_top_view`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace

import numpy as np

from demoplan.perception.blocks import (
    DetectedBlock,
    PerceptionSettings,
    Rejection,
    detect_blocks,
    named_by_colour,
)
from demoplan.perception.camera import Camera
from demoplan.perception.image_measures import ImageMeasures, measures_of
from demoplan.perception.overlay import square_corners
from demoplan.perception.side_groups import SIDE_TOLERANCE, block_sizes, within_sizes
from demoplan.perception.stack_sides import standing_tops

__all__ = [
    "SIDE_TOLERANCE",
    "block_sizes",
    "held_to_sizes",
    "in_scale",
    "looked_again",
    "rejection_in_scale",
    "standing_blocks",
]

RELOOK_HALF_WIDTH = 1.5
"""The re-look at a square of no block size searches the photograph this many
block sides (the larger of the square's side and the largest block size's)
either side of the square's centre."""
RELOOK_NEAR = 0.6
"""A square the re-look finds stands for the odd one when its centre lies within
this share of its side of the odd square's centre (the labels' tolerance)."""


def held_to_sizes(
    blocks: Sequence[DetectedBlock],
    sizes: Sequence[tuple[float, float, float]],
    unit: str = "mm",
    tolerance: float = SIDE_TOLERANCE,
    seen: tuple[np.ndarray | ImageMeasures, Camera] | None = None,
    colours: Mapping[str, tuple[float, float, float]] | None = None,
) -> tuple[list[DetectedBlock], list[Rejection]]:
    """The blocks whose side lies within the span of the block sizes (from the
    smallest side of a block size's group to the largest) or within
    ``tolerance`` of it — the sides between two sizes included: a cube nearer
    the camera (on a stack, or under a tilted one) looks larger — renamed as the
    detector names them (``red``, ``red2``, … in order); the others rejected as
    ``not a block size`` — unless, with the photograph and its camera
    (``seen``), it stands as the photograph's cubes do
    (:func:`~demoplan.perception.stack_sides.standing_tops`: its own side strip
    towards the nadir, so it has a height): a cube of its own size, not a flat
    patch (mrhan_stacks' lone small cube on the table, 21 px, 0.81 of the
    smallest group's least side: small cubes on 65 mm columns, nearer the
    camera). Otherwise, with the photograph, the square is most often a cube
    mis-measured (a print on its top fitted, or its side faces with it): the
    photograph is looked at again around it at the block sizes
    (:func:`looked_again`, with the palette's ``colours``), and a square found
    there within :data:`RELOOK_NEAR` of its side of the odd one's centre, not on
    a block already kept, stands for it. Sides in metres, shown in ``unit``
    (``mm``, or ``px`` for an image whose scale is not known yet)."""
    if not sizes:
        return list(blocks), []
    low, high = within_sizes(sizes, tolerance)
    standing: frozenset[int] = frozenset()
    if seen is not None and any(not low <= block.side <= high for block in blocks):
        standing = standing_blocks(seen[0], blocks, seen[1])
    of_a_size = {
        index for index, block in enumerate(blocks) if low <= block.side <= high
    } | standing
    held = [block for index, block in enumerate(blocks) if index in of_a_size]
    kept: list[DetectedBlock] = []
    rejected: list[Rejection] = []
    factor = 1000.0 if unit == "mm" else 1.0
    shown = " / ".join(f"{size[0] * factor:.0f}" for size in sizes)
    for index, block in enumerate(blocks):
        if index in of_a_size:
            kept.append(block)
            continue
        if seen is not None:
            again = looked_again(seen[0], seen[1], block, (low, high), colours or {})
            if again is not None and not any(_near(again, other) for other in held):
                kept.append(again)
                held.append(again)
                continue
        outline = tuple(
            (float(x), float(y)) for x, y in square_corners(block.x, block.y, block.yaw, block.side)
        )
        detail = f"side {block.side * factor:.0f} {unit}, the blocks here {shown} {unit}"
        rejected.append(Rejection("not a block size", detail, block.colour, (outline,)))
    return named_by_colour(kept), rejected


def _near(block: DetectedBlock, other: DetectedBlock) -> bool:
    """Whether ``block``'s centre lies within :data:`RELOOK_NEAR` of its side of
    ``other``'s."""
    return bool(np.hypot(block.x - other.x, block.y - other.y) <= RELOOK_NEAR * block.side)


def looked_again(
    image: np.ndarray | ImageMeasures,
    camera: Camera,
    block: DetectedBlock,
    span: tuple[float, float],
    colours: Mapping[str, tuple[float, float, float]],
) -> DetectedBlock | None:
    """The square of a side within ``span`` (the block sizes',
    :func:`~demoplan.perception.side_groups.within_sizes`) nearest ``block``'s
    centre, within :data:`RELOOK_NEAR` of its side, found by the detector on the
    part of ``image`` (seen through ``camera``) :data:`RELOOK_HALF_WIDTH` block
    sides either side of the centre — ``None`` when there is none. The detector
    searches ``span`` but its fit may grow past it (a 65 mm lid searched at
    34–46 mm fits at 52 mm): such a square is not of the size. Positions stay
    in ``camera``'s frame (the part's bottom-left corner is its origin)."""
    picture = measures_of(image).image
    height, width = picture.shape[:2]
    u, v = camera.to_pixels(block.x, block.y)
    half = RELOOK_HALF_WIDTH * max(block.side, span[1]) * camera.px_per_m
    left, right = max(0, int(u - half)), min(width, int(np.ceil(u + half)))
    top, bottom = max(0, int(height - v - half)), min(height, int(np.ceil(height - v + half)))
    if right - left < span[0] * camera.px_per_m or bottom - top < span[0] * camera.px_per_m:
        return None
    part = np.ascontiguousarray(picture[top:bottom, left:right])
    part_camera = Camera(camera.px_per_m, camera.to_world(left, height - bottom))
    settings = PerceptionSettings(min_side=span[0], max_side=span[1], colours=colours)
    found = [
        other
        for other in detect_blocks(part, part_camera, settings, None, ImageMeasures(part))
        if span[0] <= other.side <= span[1] and _near(other, block)
    ]
    if not found:
        return None
    return min(found, key=lambda other: np.hypot(other.x - block.x, other.y - block.y))


def standing_blocks(
    image: np.ndarray | ImageMeasures, blocks: Sequence[DetectedBlock], camera: Camera
) -> frozenset[int]:
    """The indices of ``blocks`` (found in ``image`` through ``camera``) whose tops
    stand as the photograph's cubes do (:func:`~demoplan.perception.stack_sides.standing_tops`;
    ``image`` the photograph or its measures, :mod:`demoplan.perception.image_measures`)."""
    height = measures_of(image).image.shape[0]
    squares = []
    for block in blocks:
        u, v = camera.to_pixels(block.x, block.y)
        squares.append((u, height - v, block.yaw, block.side * camera.px_per_m))
    return standing_tops(image, squares)


def in_scale(block: DetectedBlock, px_per_m: float, origin: tuple[float, float]) -> DetectedBlock:
    """A block found in pixels (x, y from the image's bottom-left corner, side in
    px) on the table: ``px_per_m`` pixels per metre, the corner at ``origin``."""
    return replace(
        block,
        x=origin[0] + block.x / px_per_m,
        y=origin[1] + block.y / px_per_m,
        side=block.side / px_per_m,
    )


def rejection_in_scale(
    rejection: Rejection, px_per_m: float, origin: tuple[float, float]
) -> Rejection:
    """A rejection's outlines from pixels to the table (as :func:`in_scale`)."""
    outlines = tuple(
        tuple((origin[0] + x / px_per_m, origin[1] + y / px_per_m) for x, y in outline)
        for outline in rejection.outlines
    )
    return replace(rejection, outlines=outlines)
