"""Shapes: is the thing a square was fitted in itself square?

The fit (:mod:`demoplan.perception.blocks`) matches a square to a region's mask
over the square's own pixels: a square inscribed in a larger shape of the same
colour — a pentagon, a hexagonal nut, a triangle's base — matches it there as
well as a cube's top does, and the shape's rim beyond the square is left over as
slivers too small to be anything. The thing's outline tells them apart: the
piece of the region around the square (its other squares taken out) has, when
the rest of it is such a rim, the corners of the thing, and a cube's top has
four.

Corners are those of the piece's convex hull — a fingertip's notch in a top
(:mod:`demoplan.perception.occlusion`) and the speckles and bevels of a
photographed edge do not add any — simplified by the Douglas–Peucker algorithm
(OpenCV's ``approxPolyDP``) to :data:`CORNER_TOLERANCE` of its perimeter.
"""

from __future__ import annotations

import math

import numpy as np

from demoplan.perception.colours import ColourRegion, RejectedPart
from demoplan.perception.opencv import cv2
from demoplan.perception.side_faces import corners_in_image

GROWN_PX = 3.0
"""Px a fitted square is grown by to hold its pixels (its ramp and the mask's blur)."""

__all__ = [
    "CORNER_TOLERANCE",
    "MAX_RIM_SHARE",
    "hull_corners",
    "not_square_outline",
    "outlines_not_square",
    "square_pixels",
    "square_shaped",
]

CORNER_TOLERANCE = 0.06
"""How far (a share of the convex hull's perimeter) an outline may stray from the
polygon that stands for it. A square's hull has 4 corners and a regular
pentagon's 5 at any tolerance under 0.11 (a pentagon's corner stands 0.12 of its
perimeter off the chord of its neighbours); a disc's is 4 at this one (its
sagitta to a quadrant's chord, 0.29 of its radius, is under 0.06 × 2π). A top's
own side face of its colour beside it, as wide as a quarter of its side, adds no
corner. On the development photographs and three draws of each generated family
every top found has 4 at this tolerance; at 0.02, 67 of 306 had 5 to 8."""
STRANDS = 0.2
"""Strands of a piece narrower than this share of its square's side are opened
away before its hull is taken (:func:`hull_corners`): a grid line or a cable joined
to a top, its bevel's glint. A pentagon's corners, rounded by it, stay corners."""
MAX_RIM_SHARE = 1.0
"""The rest of a piece beyond its square (the square grown by 3 px), as a share of
the square's area, up to which it is the rim of one thing with the square and
its outline is judged: less than a block's area, no other block of the colour
lies there (a regular pentagon's rim around its largest inscribed square is half
of the square; around the squares fitted in the generated pentagons, which are
allowed 15 % uncovered, 0.13–0.22 of it). More is room for another thing beside
the top — a neighbour of its colour not found — whose outline says nothing of the
top's."""


def hull_corners(piece: np.ndarray, strands: float = 0.0) -> int:
    """The corners of the convex hull of the mask ``piece`` (bool), simplified to
    :data:`CORNER_TOLERANCE` of its perimeter (0 for an empty mask), the mask first
    opened by a disc ``strands`` px across: strands as thin (a board's grid line
    joining a black top's mask) do not pull the hull out."""
    mask = piece.astype(np.uint8)
    width = round(strands)
    if width >= 2:
        disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (width, width))
        mask = np.asarray(cv2.morphologyEx(mask, cv2.MORPH_OPEN, disc), dtype=np.uint8)
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    if not contours:
        return 0
    hull = cv2.convexHull(max(contours, key=cv2.contourArea))
    perimeter = cv2.arcLength(hull, True)
    return len(cv2.approxPolyDP(hull, CORNER_TOLERANCE * perimeter, True))


def not_square_outline(
    mask: np.ndarray, square: np.ndarray, others: np.ndarray, area: float
) -> str | None:
    """Why the square (bool ``square``, grown a little over the one fitted: its
    pixels) is no block's top, judged by the thing it lies in, or ``None``: the
    connected piece of ``mask`` (bool, the region's) that holds the square, the
    region's other squares (bool ``others``) taken out, is a square and a rim
    (:data:`MAX_RIM_SHARE` of ``area``, the fitted square's) whose hull has other
    than 4 corners."""
    piece = mask & ~others
    count, labels = cv2.connectedComponents(piece.astype(np.uint8), connectivity=8)
    held = labels[square & piece]
    if count < 2 or held.size == 0:
        return None
    ids, counts = np.unique(held[held > 0], return_counts=True)
    if ids.size == 0:
        return None
    thing = labels == ids[np.argmax(counts)]
    if np.count_nonzero(thing & ~square) > MAX_RIM_SHARE * area:
        return None
    corners = hull_corners(thing, STRANDS * math.sqrt(area))
    return None if corners == 4 else f"{corners} corners"


def square_pixels(
    shape: tuple[int, ...], params: np.ndarray, grown: float = GROWN_PX
) -> np.ndarray:
    """The pixels of a crop of ``shape`` whose centres lie within the square
    ``params`` (u, v, θ, s; u right, v up from the crop's bottom) grown by
    ``grown`` px in side."""
    height, width = shape[:2]
    u, v, theta, side = (float(p) for p in params)
    c, s = np.cos(np.radians(theta)), np.sin(np.radians(theta))
    uu, vv = np.meshgrid(np.arange(width) + 0.5, height - np.arange(height) - 0.5)
    du, dv = uu - u, vv - v
    reach = np.maximum(np.abs(c * du + s * dv), np.abs(-s * du + c * dv))
    inside: np.ndarray = reach < (side + grown) / 2
    return inside


def outlines_not_square(mask: np.ndarray, squares: list[np.ndarray]) -> dict[int, str]:
    """The squares (indices into ``squares``, each u, v, θ, s on the crop of the
    region's ``mask``) whose thing is not square (:func:`not_square_outline`),
    each with its corners."""
    pixels = [square_pixels(mask.shape, params) for params in squares]
    refused = {}
    for index, params in enumerate(squares):
        others = np.zeros(mask.shape, dtype=bool)
        for other, held in enumerate(pixels):
            if other != index:
                others |= held
        why = not_square_outline(mask, pixels[index], others, float(params[3]) ** 2)
        if why is not None:
            refused[index] = why
    return refused


def in_image(region: ColourRegion, params: np.ndarray) -> tuple[float, float, float, float]:
    """A square on its region's crop (u right, v up from the crop's bottom) in the
    image: its centre x right, y down (px), θ, side."""
    row0, col0 = region.offset
    u, v, theta, side = (float(p) for p in params)
    return col0 + u, row0 + region.alpha.shape[0] - v, theta, side


def square_shaped(
    region: ColourRegion,
    squares: list[tuple[np.ndarray, float, float]],
    parts: list[RejectedPart] | None,
) -> list[tuple[np.ndarray, float, float]]:
    """The squares (u, v, θ, s on ``region``'s crop, coverage, misfit) found in
    ``region`` whose thing is square (:func:`outlines_not_square`); the others go
    to ``parts`` (when given) as rejected: ``not square``, its corners."""
    refused = outlines_not_square(region.alpha > 0.5, [params for params, _, _ in squares])
    if parts is not None:
        parts += [
            RejectedPart(
                "not square",
                corners,
                region.colour,
                (corners_in_image(in_image(region, squares[i][0])),),
            )
            for i, corners in refused.items()
        ]
    return [square for i, square in enumerate(squares) if i not in refused]
