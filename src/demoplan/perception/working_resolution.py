"""The resolution blocks are looked for at: a phone's photograph reduced by a whole factor.

A 12-megapixel phone photograph of a table shows a 40 mm cube some 200 px
across; finding its top to a pixel needs a few dozen. Every stage of the
detector costs per pixel (about 4 s of CPU and 1 GB for 12 megapixels, where a
1280 × 720 photograph takes half a second), and without a scale the range of
sides looked for grows with the image (from :data:`~.images.MIN_SIDE_PX` to a
quarter of its shorter side) until a cube's print, its glints and its grain are
squares too. So a large image is reduced by a whole factor ``k`` — each pixel
the mean of a ``k × k`` square of the photograph (OpenCV's area interpolation),
the rows and columns that do not fill a square dropped at the top and right, so
that the bottom-left corner, the world's origin, stays where it was — and the
blocks are found on the reduction at ``k`` times fewer pixels per metre:

``k`` brings the image's shorter side to at most :data:`UNSCALED_SHORTER_SIDE`
pixels (a phone photograph of a table's cubes is then about as large as a
robot's camera image) and, with the scale known (``--px-per-m``), keeps at
least :data:`WORKING_SIDE_PX` pixels across the smallest top looked for
(``--side`` less 15 %, else 20 mm). An image whose shorter side is under twice
:data:`UNSCALED_SHORTER_SIDE` (a 1280 × 720 camera's, a 1920 × 1080 one's) is
left as it is, pixel for pixel: halving loses what is a millimetre or two wide
(the gaps of cubes touching in a row, a black top's edge on a grid line;
docs/perception.md, "Tried and left out")."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from demoplan.perception.opencv import cv2

__all__ = [
    "UNSCALED_SHORTER_SIDE",
    "WORKING_SIDE_PX",
    "Reduced",
    "factor_for_scale",
    "factor_for_size",
    "reduced",
]

WORKING_SIDE_PX = 40.0
"""Pixels across the smallest top looked for that a reduction keeps (the
``small`` family's 25 mm cubes are found at 26 px; 40 leaves room)."""

UNSCALED_SHORTER_SIDE = 1200
"""Without a scale, an image whose shorter side exceeds a whole multiple of this
is reduced by that multiple (a 3024 × 4032 phone photograph by 2)."""


@dataclass(frozen=True, slots=True)
class Reduced:
    """A picture reduced by a whole ``factor`` (1: the photograph itself)."""

    picture: np.ndarray
    factor: int

    def note(self, original: tuple[int, ...]) -> str:
        """How it was reduced, for the scale's line; empty when it was not."""
        if self.factor == 1:
            return ""
        height, width = self.picture.shape[:2]
        return (
            f"; blocks looked for at 1/{self.factor} of its resolution "
            f"({width} × {height} of {original[1]} × {original[0]} px)"
        )


def factor_for_scale(smallest_side_px: float, shape: tuple[int, ...]) -> int:
    """The whole factor for an image of ``shape`` whose smallest top looked for is
    ``smallest_side_px`` across: :func:`factor_for_size`'s, at most the one that
    keeps that top :data:`WORKING_SIDE_PX` across."""
    if not math.isfinite(smallest_side_px):
        return 1
    return max(1, min(int(smallest_side_px // WORKING_SIDE_PX), factor_for_size(shape)))


def factor_for_size(shape: tuple[int, ...]) -> int:
    """The whole factor that brings the shorter side of an image of ``shape``
    to at most :data:`UNSCALED_SHORTER_SIDE` — 1 for any image up to twice it."""
    return max(1, min(shape[:2]) // UNSCALED_SHORTER_SIDE)


def reduced(picture: np.ndarray, factor: int) -> Reduced:
    """``picture`` (H × W × 3, uint8) reduced by ``factor``: each pixel the mean of
    a ``factor × factor`` square; the rows at the top and the columns at the right
    that do not fill one are dropped (the bottom-left corner stays the origin)."""
    if factor <= 1:
        return Reduced(picture, 1)
    height, width = picture.shape[:2]
    rows, cols = height // factor, width // factor
    if rows < 1 or cols < 1:
        return Reduced(picture, 1)
    kept = picture[height - rows * factor :, : cols * factor]
    small = cv2.resize(kept, (cols, rows), interpolation=cv2.INTER_AREA)
    return Reduced(np.ascontiguousarray(small), factor)
