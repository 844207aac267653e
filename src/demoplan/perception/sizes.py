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
ones). With ``--side`` and no other scale, the largest group's
median side in pixels is that side: the scale of a camera looking straight down
(:func:`demoplan.perception.images.perceive_top_view`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from demoplan.perception.blocks import DetectedBlock, Rejection, named_by_colour
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
    "rejection_in_scale",
    "standing_blocks",
]


def held_to_sizes(
    blocks: Sequence[DetectedBlock],
    sizes: Sequence[tuple[float, float, float]],
    unit: str = "mm",
    tolerance: float = SIDE_TOLERANCE,
    seen: tuple[np.ndarray | ImageMeasures, Camera] | None = None,
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
    camera). Sides in metres, shown in ``unit`` (``mm``, or ``px`` for an image
    whose scale is not known yet)."""
    if not sizes:
        return list(blocks), []
    low, high = within_sizes(sizes, tolerance)
    standing: frozenset[int] = frozenset()
    if seen is not None and any(not low <= block.side <= high for block in blocks):
        standing = standing_blocks(seen[0], blocks, seen[1])
    kept: list[DetectedBlock] = []
    rejected: list[Rejection] = []
    factor = 1000.0 if unit == "mm" else 1.0
    shown = " / ".join(f"{size[0] * factor:.0f}" for size in sizes)
    for index, block in enumerate(blocks):
        if low <= block.side <= high or index in standing:
            kept.append(block)
            continue
        outline = tuple(
            (float(x), float(y)) for x, y in square_corners(block.x, block.y, block.yaw, block.side)
        )
        detail = f"side {block.side * factor:.0f} {unit}, the blocks here {shown} {unit}"
        rejected.append(Rejection("not a block size", detail, block.colour, (outline,)))
    return named_by_colour(kept), rejected


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
