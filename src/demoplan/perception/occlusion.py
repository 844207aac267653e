"""Occlusion: a top partly hidden by something in front of it that is no block.

A fingertip over a cube's top (a hand placing or taking a block, an arm, a
cable) takes a bite out of the top's mask, and the bitten pixels count against
the square fitted to the rest — a fingertip over a tenth of the top lifts the
fit's RMS misfit over 0.2 or takes its covered share under 85 %, and the top is
rejected as ``not square`` or ``not filled``
(:class:`~demoplan.perception.blocks.PerceptionSettings`); they also pull the
fit away from the bite.

What hides a top is seen in the photograph: it is foreground — a colour region
of its own — that no block found explains (a hand, an arm, a sleeve; not a
neighbouring cube, which is found, nor the table or a shadow, which are no
region). Once every region has been searched, a square rejected that way is
fitted again and measured over its *seen* pixels only: those that such an
occluder covers, where its own mask is empty, take no part, and the square is a
block when the seen pixels bear it out as any block's must (the same checks, the
hidden pixels counted as held, not as table) and at most
:data:`MAX_HIDDEN_SHARE` of it is hidden. The occluder itself stays no
block (a hand is rejected for its own reasons: not square, cut by the border).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Protocol

import numpy as np

from demoplan.perception.colours import ColourRegion, RejectedPart
from demoplan.perception.hough import Hypothesis
from demoplan.perception.shapes import in_image, square_pixels
from demoplan.perception.square_fit import square_window

__all__ = [
    "MAX_HIDDEN_SHARE",
    "OCCLUDER_BLOCKS",
    "Candidate",
    "Fit",
    "Search",
    "occluders",
    "seen_fit",
    "tops_behind",
]

MAX_HIDDEN_SHARE = 0.25
"""The largest share of a top's square an occluder may hide for the rest to make it
a block: with a quarter hidden, three quarters of the outline still place it."""

OCCLUDER_BLOCKS = 2.0
"""An occluder's unexplained area, in the largest block's areas, above which it is
one: a cube shows at most its top and side faces, under two tops' area to any
camera of the generated families (a face of a cube tipped over in a row of others
of other colours, unexplained, was taken for an occluder of its neighbour at one
block's area: ``tipped_rows`` seed 5, with ``--side``); a hand with its forearm
shows several (the ``hands`` family's palm alone is 4.5 tops of a 40 mm cube)."""

Fit = tuple[np.ndarray, float, float, float]
"""A fitted square on its region's crop (u, v, θ, s), its interior coverage, its RMS
misfit and its share of free outline."""
Candidate = tuple[ColourRegion, np.ndarray, Fit]
"""A square rejected as not square or not filled: its region, the region's mask when
it was fitted (the squares found before it taken out) and the fit."""
Found = tuple[ColourRegion, np.ndarray, float, float]


def occluders(
    shape: tuple[int, ...],
    regions: Sequence[ColourRegion],
    found: Sequence[Found],
    largest_block: float,
) -> np.ndarray:
    """The pixels of an image of ``shape`` that a colour region holds (α > ½) and no
    block of ``found`` explains (its square grown by 3 px), of the regions whose
    unexplained pixels outnumber :data:`OCCLUDER_BLOCKS` times ``largest_block``
    (the largest block's area, px²): a hand with its arm is larger, and the faces
    of a cube in view — its top and side faces; a cube lying tipped over in a row
    of others — are not (they stand beside a top, not in front of it)."""
    held = np.zeros(shape[:2], dtype=bool)
    for region in regions:
        (row, col), (rows, cols) = region.offset, region.alpha.shape
        unexplained = region.alpha > 0.5
        for other, params, _, _ in found:
            if other is region:
                unexplained &= ~square_pixels((rows, cols), params)
        if np.count_nonzero(unexplained) > OCCLUDER_BLOCKS * largest_block:
            held[row : row + rows, col : col + cols] |= unexplained
    for region, params, _, _ in found:
        (row, col), (rows, cols) = region.offset, region.alpha.shape
        held[row : row + rows, col : col + cols] &= ~square_pixels((rows, cols), params)
    return held


def seen_fit(alpha: np.ndarray, fit: Fit, hidden: np.ndarray) -> Fit | None:
    """``fit`` with its coverage and misfit measured over the pixels of its square
    that ``hidden`` (bool, on the crop of ``alpha``) does not hide; ``None`` when
    none is hidden or more than :data:`MAX_HIDDEN_SHARE` of it is. Measured over the
    part of the crop the square touches (:func:`~demoplan.perception.square_fit.square_window`)."""
    params, _, _, free = fit
    u, v, theta, side = (float(p) for p in params)
    uu, vv, window = square_window(alpha.shape, params, side)
    alpha, hidden = alpha[window], hidden[window]
    c, s = math.cos(math.radians(theta)), math.sin(math.radians(theta))
    du, dv = uu - u, vv - v
    distance = np.maximum(np.abs(c * du + s * dv), np.abs(-s * du + c * dv)) - side / 2
    fitted = np.clip(0.5 - distance, 0.0, 1.0)  # the one-pixel-ramp square of the fit
    inside, own = fitted > 0.99, fitted > 0.01
    covered_up = hidden & own
    if not inside.any() or not covered_up.any():
        return None
    if np.count_nonzero(covered_up & inside) > MAX_HIDDEN_SHARE * np.count_nonzero(inside):
        return None
    seen_inside, seen_own = inside & ~hidden, own & ~hidden
    coverage = float(alpha[seen_inside].mean())
    rms = float(np.sqrt(np.mean((fitted[seen_own] - alpha[seen_own]) ** 2)))
    return params, coverage, rms, free


class Search(Protocol):
    """What :func:`tops_behind` reads of a search of an image's regions for squares
    (``demoplan.perception.blocks._SquareSearch``)."""

    @property
    def image_shape(self) -> tuple[int, ...]: ...
    @property
    def side_px(self) -> tuple[float, float]: ...
    @property
    def hidden(self) -> list[Candidate]: ...


def tops_behind(
    search: Search,
    regions: Sequence[ColourRegion],
    tables: np.ndarray,
    found: Sequence[Found],
    judge: Callable[..., tuple[str, str] | None],
    refit: Callable[..., Fit],
    parts: list[RejectedPart] | None,
) -> list[Found]:
    """The squares the ``search`` rejected (``search.hidden``) that are blocks
    partly hidden by an occluder (:func:`occluders` of ``regions`` and of the second
    tables ``tables`` — a hand and forearm reaching in from the border may be
    one, and a table is never in front of a top — beside the blocks ``found``;
    :func:`seen_fit`): each fitted again from where it was without the hidden
    pixels (``refit(alpha, start, ignore=hidden)``: a bite pulls a square fitted
    to it away), ``judge(search, region, alpha, fit)`` (why a fit is no block, or
    ``None``) bearing it out over its seen pixels (the hidden ones held: no free
    outline there), none within a side of another block. The parts of ``parts``
    their squares hold (rejected before) are taken out."""
    table = ColourRegion("table", (0.0, 0.0, 0.0), (0, 0), tables.astype(float))
    largest_block = search.side_px[1] ** 2
    shape = search.image_shape
    hidden_by = occluders(shape, [*regions, table], found, largest_block)
    centres = [in_image(region, params) for region, params, _, _ in found]
    behind: list[Found] = []
    for region, alpha, fit in search.hidden:
        (row, col), (rows, cols) = region.offset, alpha.shape
        hidden = hidden_by[row : row + rows, col : col + cols] & (alpha < 0.5)
        if seen_fit(alpha, fit, hidden) is None:
            continue
        u, v, theta, side = (float(p) for p in fit[0])
        seen = seen_fit(
            alpha, refit(alpha, Hypothesis(u, v, theta, side, 0.0), ignore=hidden), hidden
        )
        # judged with the hidden pixels held: an occluder is no table beside the
        # top, so a square fitted into one thing beside another (two colours of
        # an arm) has no free sides there, nor a seam
        if seen is None or judge(search, region, np.where(hidden, 1.0, alpha), seen) is not None:
            continue
        x, y, theta, side = in_image(region, seen[0])
        if any(math.dist((x, y), other[:2]) < max(side, other[3]) for other in centres):
            continue
        centres.append((x, y, theta, side))
        behind.append((region, seen[0], seen[1], seen[2]))
        if parts is not None:
            parts[:] = [p for p in parts if not _holds(region.colour, (x, y, theta, side), p)]
    return behind


def _holds(colour: str, square: tuple[float, float, float, float], part: RejectedPart) -> bool:
    """Whether ``part`` is of ``colour`` and its outline's mean lies in ``square``."""
    if part.colour != colour or not part.outlines:
        return False
    x, y, theta, side = square
    mean = np.concatenate([np.asarray(o, dtype=float) for o in part.outlines]).mean(axis=0)
    c, s = math.cos(math.radians(theta)), math.sin(math.radians(theta))
    du, dv = mean[0] - x, -(mean[1] - y)  # v up, as the fit's
    return bool(max(abs(c * du + s * dv), abs(-s * du + c * dv)) <= side / 2)
