"""When a square fitted in a colour region is a block, beyond its own fit: its
corners rounded as a photographed cube's are, the image's border (a square past
it, a region running on along it, an outline past it that shows no table) and the
share of its region that the squares accepted in it explain.

:func:`demoplan.perception.blocks.detect_blocks` checks a fit's coverage, misfit
and free outline first, then these.
"""

from __future__ import annotations

import math

import numpy as np

from demoplan.perception.opencv import cv2
from demoplan.perception.palette import SIDE_FACE_GAP
from demoplan.perception.square_fit import outline_points

__all__ = [
    "CORNER_ROUNDING",
    "MAX_BEYOND_SHARE",
    "MIN_EXPLAINED_SHARE",
    "beyond_image",
    "explained_share",
    "free_outline_seen",
    "rounded_misfit",
    "runs_on_along_border",
    "shares_a_side",
]


MAX_BEYOND_SHARE = 0.5
"""A fitted square whose centre lies past the image's border (more than half of it
beyond, for a square along the border) is no block: what the image shows is a
part of whatever is there (a block, a strip of table ruled into squares, cut by
the border), its size and centre not seen — and the fit, run off the image, has
nothing there to check it. A block cut less (a clipped corner, a side) keeps its
centre in view and is fitted from what shows."""

_SAMPLES = (np.arange(32) + 0.5) / 32 - 0.5
"""Points across a square (as fractions of its side) that measure its share beyond the image."""


def beyond_image(
    params: np.ndarray, offset: tuple[int, int], crop: tuple[int, ...], image: tuple[int, ...]
) -> float:
    """The share of the square ``params`` (on a crop of ``crop`` rows × columns at
    ``offset`` in an image of ``image`` rows × columns) that lies past the image's
    border (0 when it lies inside), from 32 × 32 points over it; 1 when its centre
    does."""
    u, v, theta, side = (float(p) for p in params)
    c, s = math.cos(math.radians(theta)), math.sin(math.radians(theta))
    row0, col0 = offset
    height, width = image[0], image[1]
    reach = abs(side) * math.sqrt(0.5)
    x, y = col0 + u, row0 + crop[0] - v  # image x (right), y (down) of the centre
    if reach <= min(x, y, width - x, height - y):
        return 0.0
    if not (0 <= x <= width and 0 <= y <= height):
        return 1.0  # the centre is out of view (more than half, along a border)
    along, across = np.meshgrid(_SAMPLES * side, _SAMPLES * side)
    xs = x + c * along - s * across
    ys = y - (s * along + c * across)
    outside = (xs < 0) | (xs > width) | (ys < 0) | (ys > height)
    return float(outside.mean())


_BORDER_BAND = 3.0
"""Px in from the image's border in which a square's stretch along it is taken, and
the least depth in which its region is looked at beside it."""


def runs_on_along_border(
    alpha: np.ndarray, params: np.ndarray, offset: tuple[int, int], image: tuple[int, ...]
) -> bool:
    """Whether the square ``params`` (on the crop ``alpha`` at ``offset`` in an image
    of ``image`` rows × columns) reaches past a border of the image, or comes within
    the depth its region is looked at beside it, along which its region runs on
    beyond it: the mask holds (α > ½) within a quarter side (at least
    :data:`_BORDER_BAND` px) of that border over most of a stretch a quarter side long
    (at least 3 px), 2 px past either end of the square's own stretch there (its
    points within :data:`_BORDER_BAND` px of the border, or of its nearest to it
    when it stays inside). Such a
    square is a piece of something cut by the border — a strip of table, a board's
    edge, a row of things, an arm reaching in — not a block whose top shows whole: a
    block poking past the border ends with the square along it. (Not only the pixels
    at the border: there a pale or glaring part of an arm may fray the mask, as at
    the top of langtable_real — and a square fitted into the arm then stops short of
    the frayed band, its side there seen on "table" that is the arm's glare; the
    band is as deep as the region is looked at beside the square, so a square within
    it is checked as one past the border.)"""
    u, v, theta, side = (float(p) for p in params)
    c, s = math.cos(math.radians(theta)), math.sin(math.radians(theta))
    row0, col0 = offset
    crop_rows, crop_cols = alpha.shape
    height, width = image[0], image[1]
    x, y = col0 + u, row0 + crop_rows - v
    along, across = np.meshgrid(_SAMPLES * side, _SAMPLES * side)
    xs = (x + c * along - s * across).ravel()
    ys = (y - (s * along + c * across)).ravel()
    reach = max(3.0, side / 4)
    stretch = np.arange(2.0, 2.0 + reach) + 0.5
    depths = np.arange(max(_BORDER_BAND, reach)) + 0.5
    # each border: the points' depth in from it and place along it; whether it is
    # upright (left, right) and the image's extent there (0 for left and top)
    edges = (
        (xs, ys, True, 0),
        (width - xs, ys, True, width),
        (ys, xs, False, 0),
        (height - ys, xs, False, height),
    )
    for depth, place, upright, far in edges:
        if not np.any(depth < depths[-1]):
            continue  # the square stays further from this border than its region is looked at
        near = place[depth < max(0.0, float(depth.min())) + _BORDER_BAND]
        length = height if upright else width
        for ends in (near.min() - stretch, near.max() + stretch):
            points_along, points_in = np.meshgrid(ends, np.abs(far - depths))
            px, py = (points_in, points_along) if upright else (points_along, points_in)
            cols = np.floor(px - col0).astype(np.intp)
            rows = np.floor(py - row0).astype(np.intp)
            within = (
                (rows >= 0)
                & (rows < crop_rows)
                & (cols >= 0)
                & (cols < crop_cols)
                & (points_along >= 0)
                & (points_along < length)
            )
            # the square's own pixels (2 px around it too) are not its region beside it
            du, dv = px - x, y - py
            own = np.maximum(np.abs(c * du + s * dv), np.abs(c * dv - s * du)) < side / 2 + 2
            within &= ~own
            held = np.zeros(px.shape, dtype=bool)
            held[within] = alpha[rows[within], cols[within]] > 0.5
            if held.any(axis=0).mean() > 0.5:
                return True
    return False


MIN_EXPLAINED_SHARE = 0.5
"""The least share of a colour region the squares accepted in it must cover
(their areas over its pixels with α > ½) for them to stand. Seen from above, a
block's region is its top face and what shows of its sides in its colour (less
than its top; most of it the side-face test drops), so its top covers at least
half of it, and touching blocks of one colour each cover their part. A region
mostly left when its squares are cut out is something larger — a wooden board,
a table patch crossed by cables — in which squares were fitted between its
marks: it holds no block (``larger than its squares``).

A camera low and off to the side sees a cube's side faces as large as its top or
larger (the `side_faces` family: 0.45 m up, its axis beyond the image), and when
they stay in the top's colour class the top alone covers under half of its
region. Those side faces are the top's material lit less: the region's pixels
:data:`~demoplan.perception.palette.SIDE_FACE_GAP` L* or more darker than the
squares' own faces are taken for side faces, explained by the squares beside
them (:func:`explained_share`); a board's or a table patch's body, as light as
the squares fitted in it, stays unexplained."""


MIN_TOP_SHARE = 0.2
"""The least share of its region a cube's top covers by itself, its side faces in
the region too: the `side_faces` family's camera (0.45 m up, focal length 630 px
or more, its axis up to 300 px beyond the image) sweeps a top's side faces at most
about 2.9 sides towards it, so top and side faces cover at most 1 + 2.9 × √2 ≈ 5
tops. Under that, darker pixels are not counted as side faces: a wooden table
with shadowed grain (mrhan_touching, right: a square of its light wood fitted
between dark things covers 6 % of it) stays ``larger than its squares``."""


def explained_share(
    alpha: np.ndarray, squares: list[np.ndarray], lightness: np.ndarray | None = None
) -> float:
    """The share of the region ``alpha`` (pixels with α > ½) that the ``squares``
    (u, v, θ, s each) cover by their areas; 1 when none were found (nothing to judge).
    With ``lightness`` (CIELAB L* over the same crop), the region's pixels
    :data:`~demoplan.perception.palette.SIDE_FACE_GAP` L* or more darker than the
    median over the squares' central halves are side faces of the squares' cubes and
    count as explained (:data:`MIN_EXPLAINED_SHARE`) — when the squares cover at least
    :data:`MIN_TOP_SHARE` of it by themselves."""
    if not squares:
        return 1.0
    held = alpha > 0.5
    area = int(np.count_nonzero(held))
    covered = sum(float(square[3]) ** 2 for square in squares)
    if lightness is not None and covered >= MIN_TOP_SHARE * area:
        faces = np.concatenate([_central_half(lightness, square) for square in squares])
        if faces.size:
            darker = held & (lightness <= float(np.median(faces)) - SIDE_FACE_GAP)
            return min(1.0, (covered + int(np.count_nonzero(darker))) / max(area, 1))
    return covered / max(area, 1)


def _central_half(values: np.ndarray, square: np.ndarray) -> np.ndarray:
    """``values`` (a crop) at 8 × 8 points over the central half (by side) of the
    square (u, v, θ, s; u right, v up from the crop's bottom) that lie on the crop."""
    u, v, theta, side = (float(p) for p in square)
    c, s = math.cos(math.radians(theta)), math.sin(math.radians(theta))
    steps = ((np.arange(8) + 0.5) / 8 * 0.5 - 0.25) * side
    along, across = np.meshgrid(steps, steps)
    cols = np.floor(u + c * along - s * across).astype(np.intp).ravel()
    rows = np.floor(values.shape[0] - (v + s * along + c * across)).astype(np.intp).ravel()
    within = (rows >= 0) & (rows < values.shape[0]) & (cols >= 0) & (cols < values.shape[1])
    inside: np.ndarray = values[rows[within], cols[within]]
    return inside


def free_outline_seen(
    alpha: np.ndarray, params: np.ndarray, offset: tuple[int, int], image: tuple[int, ...]
) -> float:
    """The share of the square ``params``'s outline (on the crop ``alpha`` at
    ``offset`` in an image of ``image`` rows × columns) that is seen to border on
    table: of its points 2 px out (nine along each side), all of them, those within
    the image where the mask is empty (α < ½; past the crop is table). A point past
    the image's border shows nothing: a square fitted inside something larger that
    the border cuts (a robot arm reaching in from the edge) has its side there on the
    border, not on table. Such a point counts as not free, and it stays in the
    count: the share is of the whole outline, as for a square inside the image, so
    the least free share asks for as many free sides there. (Counted over the
    points seen only, one free side of the three seen beside a border is a third
    of them, and two corners where a rounded arm's end turns away from the other
    sides lift it over the least free share.)"""
    pu, pv = outline_points(params)
    crop_rows, crop_cols = alpha.shape
    row0, col0 = offset
    xs, ys = col0 + pu, row0 + crop_rows - pv  # image x (right), y (down)
    seen = (xs >= 0) & (xs < image[1]) & (ys >= 0) & (ys < image[0])
    cols, rows = pu.astype(np.intp), (crop_rows - pv).astype(np.intp)  # as the fit's own
    within = seen & (rows >= 0) & (rows < crop_rows) & (cols >= 0) & (cols < crop_cols)
    held = np.zeros(pu.shape, dtype=bool)
    held[within] = alpha[rows[within], cols[within]] >= 0.5
    return int(np.count_nonzero(seen & ~held)) / int(pu.size)


CORNER_ROUNDING = (0.05, 0.1, 0.15)
"""Radii (shares of the side) of the rounded corners a lone square's misfit is also
measured against, the least misfit taken (:func:`rounded_misfit`): a photographed
wooden cube's top has its corners rounded by its bevel and the lens's blur, where
the sharp square misfits it most (seven lone squares of armlab_mrhan4 misfit at
0.203–0.224, at most 0.200 so; four more of its cubes found). A disc's rounding is
half its side, far past the largest."""


def rounded_misfit(alpha: np.ndarray, params: np.ndarray) -> float:
    """The least RMS misfit of the mask ``alpha`` against the square ``params``
    (u, v, θ, s on the crop; u right, v up from its bottom) with its corners
    rounded at the radii :data:`CORNER_ROUNDING`, its edges ramping over one pixel,
    over each rounded square's own pixels (those it covers at all)."""
    u, v, theta, side = (float(p) for p in params)
    c, s = math.cos(math.radians(theta)), math.sin(math.radians(theta))
    height, width = alpha.shape
    reach = (abs(side) / 2 + 0.5) * math.sqrt(2) + 2.0
    row = height - v
    rows = slice(max(0, math.floor(row - reach)), max(0, min(height, math.ceil(row + reach))))
    cols = slice(max(0, math.floor(u - reach)), max(0, min(width, math.ceil(u + reach))))
    uu, vv = np.meshgrid(
        np.arange(cols.start, cols.stop) + 0.5, height - np.arange(rows.start, rows.stop) - 0.5
    )
    mask = alpha[rows, cols]
    qu, qv = np.abs(c * (uu - u) + s * (vv - v)), np.abs(-s * (uu - u) + c * (vv - v))
    best = 1.0
    for share in CORNER_ROUNDING:
        radius = share * side
        du = np.maximum(qu - (side / 2 - radius), 0.0)
        dv = np.maximum(qv - (side / 2 - radius), 0.0)
        corner = (du > 0) & (dv > 0)
        distance = np.where(corner, np.hypot(du, dv) - radius, np.maximum(qu, qv) - side / 2)
        fitted = np.clip(0.5 - distance, 0.0, 1.0)
        own = fitted > 0.01
        if own.any():
            best = min(best, float(np.sqrt(np.mean((fitted[own] - mask[own]) ** 2))))
    return best


_SIDE_POINTS = np.linspace(-0.4, 0.4, 17)
"""Points along a side (shares of the side) at which the region is looked for beyond it."""


def shares_a_side(alpha: np.ndarray, params: np.ndarray) -> bool:
    """Whether the region ``alpha`` (its mask smoothed over 5 × 5 px) holds beyond a
    whole side of the square ``params`` — at every point along it to a tenth of a
    side from the corners, both 3 px and a quarter side out — as
    :func:`~demoplan.perception.seams.seamless_side` asks before it looks for a
    seam. Such a square is a piece of something longer (a 2:1 brick, a row of one
    colour; a square across the seam of two flush cubes): its corners there are no
    cube's corners, and it is judged sharp."""
    u, v, theta, side = (float(p) for p in params)
    c, s = math.cos(math.radians(theta)), math.sin(math.radians(theta))
    smooth = cv2.blur(alpha.astype(np.float32), (5, 5))
    height, width = alpha.shape
    along = _SIDE_POINTS * side
    for nu, nv in ((c, s), (-c, -s), (-s, c), (s, -c)):
        held = True
        for out in (side / 2 + 3.0, 3 * side / 4):
            us = u - nv * along + nu * out
            vs = v + nu * along + nv * out
            cols, rows = np.floor(us).astype(np.intp), np.floor(height - vs).astype(np.intp)
            within = (rows >= 0) & (rows < height) & (cols >= 0) & (cols < width)
            if not within.all() or not np.all(smooth[rows, cols] > 0.5):
                held = False
                break
        if held:
            return True
    return False
