"""Seams: is a square found in a region one block, or the end of a longer thing?

A square fitted at the end of a region of one colour may be a block beside
another of its colour, or the end of a cuboid twice as long (a 2:1 brick lying
down, a column seen from above). Both look alike in the soft mask; in the
photograph, two blocks side by side are parted by a *seam* — a dark gap or
groove between them, or a step in brightness (the two faces lit unlike, or one
of them a side face). A side the square shares with the rest of its region
along its whole length, with no seam across it, is no block's side: the square
is part of a longer thing.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np

from demoplan.perception.image_measures import ImageMeasures
from demoplan.perception.opencv import cv2

__all__ = ["SEAM_CONTRAST", "image_lightness", "seam_lines", "seamless_side"]

SEAM_CONTRAST = 3.0
"""L* by which a seam must be darker than both faces beside it (a groove, a gap),
or the two faces differ (a step), for a shared side to part two blocks."""

_ALONG = np.linspace(-0.4, 0.4, 17)
"""Points along a side (as fractions of the square's side) that test whether the
region goes on beyond it over its whole length: to a tenth of a side from each
corner (a real block's corners are rounded by bevels and the JPEG's blur; a block
slid along its neighbour by more than that shows a free end)."""
SEAM_REACH = 0.1
"""How far (in sides) across the fitted side a seam is looked for, the darkest line
there: a square fitted to a row of one colour lies a few pixels off the seam
between two cubes (their rims blur into one mask), and a cuboid has no seam
anywhere near."""
SEAM_SEARCH = 0.2
"""How far (in sides) across a shared side :func:`seam_lines` looks for the
groove's line, the faces taken half as far again beyond: within a quarter side,
where :func:`seamless_side` takes the faces."""


def _across(side: float) -> np.ndarray:
    """Offsets (px) across a side of ``side`` px, every pixel to
    :data:`SEAM_REACH` of it on either side (at least 2 px)."""
    reach = max(2.0, round(SEAM_REACH * side))
    return np.arange(-reach, reach + 1.0)


def seamless_side(
    lightness: np.ndarray, alpha: np.ndarray, offset: tuple[int, int], params: np.ndarray
) -> str | None:
    """Why the square ``params`` (u, v, θ, s on the crop ``alpha`` whose top-left
    pixel is ``offset`` = (row, column) in the image; u right, v up from the crop's
    bottom) is the end of a longer thing, or ``None``: one of its sides has the
    region's mask beyond it along its whole length, as far as a quarter of a side
    out (the mask averaged over 5 × 5 px), and the image's lightness
    (``lightness``, L*, the whole image) shows no seam there
    (:data:`SEAM_CONTRAST`, within :data:`SEAM_REACH` of the side)."""
    side = float(params[3])
    height = alpha.shape[0]
    row0, col0 = offset
    for nu, nv, us, vs in _shared_sides(alpha, params):
        profiles = [
            _sample(lightness, col0 + us + nu * out - 0.5, row0 + height - (vs + nv * out) - 0.5)
            for out in (side / 4, 3 * side / 4, *(side / 2 + k for k in _across(side)))
        ]
        inner, outer, line = profiles[0], profiles[1], np.min(profiles[2:], axis=0)
        dip = float(np.median(np.minimum(inner, outer) - line))
        step = abs(float(np.median(inner) - np.median(outer)))
        if dip < SEAM_CONTRAST and step < SEAM_CONTRAST:
            return f"a side shared without a seam (L* {dip:.0f} darker, {step:.0f} apart)"
    return None


def seam_lines(
    lightness: np.ndarray, alpha: np.ndarray, offset: tuple[int, int], params: np.ndarray
) -> list[tuple[float, float, float]]:
    """The grooves along the sides of the square ``params`` (as
    :func:`seamless_side` takes it) that it shares with the rest of its region:
    per such side, its outward normal (nu, nv) on the crop and how far out of the
    side (px; negative: inside the square) the groove's darkest line lies — the
    darkest line of the median profile across the side within
    :data:`SEAM_SEARCH` of it, when that is darker by :data:`SEAM_CONTRAST` than
    the faces beyond :data:`SEAM_SEARCH` either way. A square fitted to a row of
    one colour may reach past the seam by more than :data:`SEAM_REACH`: the mask
    runs on across it, and holds the cubes' side faces across the row."""
    side = float(params[3])
    height = alpha.shape[0]
    row0, col0 = offset
    search = max(2.0, round(SEAM_SEARCH * side))
    across = np.arange(-search, search + 1.0)
    faces = (-1.5 * search, 1.5 * search)
    lines = []
    for nu, nv, us, vs in _shared_sides(alpha, params):
        profile = np.array(
            [
                np.median(
                    _sample(
                        lightness,
                        col0 + us + nu * (side / 2 + k) - 0.5,
                        row0 + height - (vs + nv * (side / 2 + k)) - 0.5,
                    )
                )
                for k in (*faces, *across)
            ]
        )
        darkest = int(np.argmin(profile[2:]))
        if min(profile[0], profile[1]) - profile[2 + darkest] >= SEAM_CONTRAST:
            lines.append((nu, nv, float(across[darkest])))
    return lines


def _shared_sides(
    alpha: np.ndarray, params: np.ndarray
) -> Iterator[tuple[float, float, np.ndarray, np.ndarray]]:
    """Per side of ``params`` the region's mask runs on beyond along its whole
    length (the mask averaged over 5 × 5 px held 3 px and a quarter side out): its
    outward normal (nu, nv) and the points (us, vs) on the crop along it."""
    u, v, theta, side = (float(p) for p in params)
    c, s = math.cos(math.radians(theta)), math.sin(math.radians(theta))
    along = _ALONG * side
    smooth = np.asarray(cv2.blur(alpha.astype(np.float32), (5, 5)))  # over the face's speckles
    for nu, nv in ((c, s), (-c, -s), (-s, c), (s, -c)):
        us = u - nv * along
        vs = v + nu * along
        if all(
            np.all(_sample_mask(smooth, us + nu * out, vs + nv * out))
            for out in (side / 2 + 3.0, 3 * side / 4)
        ):
            yield nu, nv, us, vs


def image_lightness(image: np.ndarray) -> np.ndarray:
    """CIELAB L* (0–100, float32) of an RGB image (H × W × 3, 8-bit):
    :attr:`~demoplan.perception.image_measures.ImageMeasures.lightness`."""
    return ImageMeasures(image).lightness


def _sample_mask(alpha: np.ndarray, us: np.ndarray, vs: np.ndarray) -> np.ndarray:
    """Whether the mask holds (α > ½) at the points (us, vs) of its crop (outside: no)."""
    height, width = alpha.shape
    cols, rows = np.floor(us).astype(np.intp), np.floor(height - vs).astype(np.intp)
    within = (rows >= 0) & (rows < height) & (cols >= 0) & (cols < width)
    held = np.zeros(us.shape, dtype=bool)
    held[within] = alpha[rows[within], cols[within]] > 0.5
    return held


def _sample(image: np.ndarray, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """``image`` (one channel, float32) at the points (xs, ys) in pixels (x right, y
    down, pixel centres at whole numbers), bilinearly; the border repeated."""
    sampled = cv2.remap(
        image,
        xs.astype(np.float32).reshape(1, -1),
        ys.astype(np.float32).reshape(1, -1),
        cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_REPLICATE,
    )
    return np.asarray(sampled, dtype=float).ravel()
