"""A straight dark line fused to a dark top: a board's grid line a few pixels off a
black cube's edge joins it through the blurred board between them, and the dark
part is then the top and a band of the line (not square: the grid line runs at a
few degrees to the edge, so the band is a wedge or a corner's blob).

A line is told from the top's side by running on past the part at both ends: the
thin dark pixels the opening of :mod:`demoplan.perception.achromatic` took away
(the line's visible stretches beyond the top) lie on one straight line through
the part. The band of that line along the part's outline is dropped from the
part when the line runs nearly along one of the part's sides (a line crossing a
side at a large angle — under a top turned on the grid, at its corner — is no
band along it: cutting it notches the top) and the part is squarer without it.
"""

from __future__ import annotations

import math

import numpy as np

from demoplan.perception.masks import dilate
from demoplan.perception.opencv import cv2

__all__ = ["LINE_PAST", "MAX_LINES", "MAX_LINE_TURN", "fused_lines"]

MAX_LINES = 8
"""The Hough lines judged per part, the most voted first: a part has four sides,
each beside one or two of a board's lines (a larger residue — a phone's shadow,
a cable — gives thousands of weak lines, each a pass over the crop)."""
LINE_PAST = 0.25
"""Shares of the smallest block's side a line's thin pixels reach past the part at
each end, at least: a grid line runs on across the board; a top's side face or
shadow ends at its corner."""
MAX_LINE_TURN = 10.0
"""Degrees between a fused line and the part's nearest side, at most: a line
fuses along a side only nearly parallel to it (within a few px over a side's
length); one at a larger angle meets the part at a corner, where it may as well
pass under the top."""
SQUARER = 0.02
"""By how much the part's smallest rectangle's length over width must fall when a
band is dropped (and its fill not fall): the band made the part longer."""


def fused_lines(
    labels: np.ndarray,
    index: int,
    mask: np.ndarray,
    crop: tuple[slice, slice],
    side_px: float,
) -> np.ndarray:
    """The pixels of part ``index`` (of the opened ``labels``; ``mask`` the dark
    mask before the opening) within ``crop`` that are a straight line's band
    fused to it (module docstring), as a mask of ``crop``'s shape. ``side_px``:
    the smallest block's side. Lines are OpenCV's Hough lines over the thin dark
    pixels within 0.6 of a side round the part (:data:`MAX_LINES`); a band is the line's width and a
    half (its blur) either side of it, where it lies within that of the part's
    outline."""
    rows, cols = crop
    height, width = mask.shape
    x0, y0 = cols.start, rows.start
    pad = round(0.6 * side_px)
    top, left = max(0, y0 - pad), max(0, x0 - pad)
    big = slice(top, min(height, rows.stop + pad)), slice(left, min(width, cols.stop + pad))
    body = labels[big] == index
    residue = (mask[big] & ~dilate(body, 2)).astype(np.uint8)
    out = np.zeros((rows.stop - rows.start, cols.stop - cols.start), dtype=bool)
    if residue.sum() < side_px:
        return out
    lines = cv2.HoughLines(residue * 255, 1, math.pi / 180, round(0.5 * side_px))
    if lines is None:
        return out
    depth = cv2.distanceTransform(body.astype(np.uint8), cv2.DIST_L2, 3)
    half_widths = cv2.distanceTransform(residue, cv2.DIST_L2, 3)
    reach = math.hypot(*body.shape)
    steps = np.arange(-reach, reach + 1.0)
    cut = np.zeros(body.shape, dtype=bool)
    for rho, theta in lines.reshape(-1, 2)[:MAX_LINES]:
        c, s = math.cos(theta), math.sin(theta)
        # the line's axis, 3 px wide, walked one px at a time
        xs = (rho + np.array([-1.0, 0.0, 1.0]))[:, None] * c - steps[None, :] * s
        ys = (rho + np.array([-1.0, 0.0, 1.0]))[:, None] * s + steps[None, :] * c
        cols_, rows_ = np.rint(xs).astype(np.intp), np.rint(ys).astype(np.intp)
        on = (rows_ >= 0) & (rows_ < body.shape[0]) & (cols_ >= 0) & (cols_ < body.shape[1])
        along = np.broadcast_to(steps, xs.shape)[on]
        seen = residue[rows_[on], cols_[on]] > 0
        within = along[body[rows_[on], cols_[on]]]
        if not seen.any() or not within.size:
            continue
        beyond = along[seen]
        past = LINE_PAST * side_px
        if (beyond < within.min() - 2).sum() < past or (beyond > within.max() + 2).sum() < past:
            continue  # it does not run on past the part at both ends
        band_width = 3.0 * max(1.0, float(np.median(half_widths[rows_[on][seen], cols_[on][seen]])))
        yy, xx = np.mgrid[0 : body.shape[0], 0 : body.shape[1]]
        across = np.abs(xx * c + yy * s - rho)
        band = (across <= band_width) & body & ~cut & (depth <= band_width + 2)
        if band.any() and _squarer(body & ~cut, band, math.degrees(theta) + 90.0):
            cut |= band
    return cut[y0 - top : y0 - top + out.shape[0], x0 - left : x0 - left + out.shape[1]]


def _squarer(part: np.ndarray, band: np.ndarray, direction: float) -> bool:
    """Whether ``band`` (a line's at ``direction`` degrees) runs within
    :data:`MAX_LINE_TURN` of a side of ``part``'s smallest rectangle, and ``part``
    without it is squarer (:data:`SQUARER`) and fills its rectangle no less."""
    points = _outline(part)
    if points is None:
        return False
    _, _, angle = cv2.minAreaRect(points)
    turn = (direction - angle) % 90.0
    if min(turn, 90.0 - turn) > MAX_LINE_TURN:
        return False
    before, after = _rectangle(part), _rectangle(part & ~band)
    return after[0] < before[0] - SQUARER and after[1] >= before[1]


def _rectangle(part: np.ndarray) -> tuple[float, float]:
    """``part``'s smallest rectangle's length over width, and the share of it the
    part fills (as :func:`demoplan.perception.achromatic._compactness` measures)."""
    points = _outline(part)
    if points is None:
        return math.inf, 0.0
    (_, _), (w, h), _ = cv2.minAreaRect(points)
    fill = float(part.sum()) / max((w + 1) * (h + 1), 1.0)
    return (max(w, h) + 1) / (min(w, h) + 1), fill


def _outline(part: np.ndarray) -> np.ndarray | None:
    """The outer outline's points of ``part``'s pieces (all of them: the smallest
    rectangle round them is the pixels'), ``None`` when it has none."""
    contours, _ = cv2.findContours(
        part.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE
    )
    if not contours:
        return None
    points: np.ndarray = np.concatenate(contours)
    return points
