"""White tops on white paper lit as the paper: found by their outline, not their lightness.

A white cube on white paper under even light stands out from the paper by two or
three L*, under the bright contrast of :mod:`demoplan.perception.achromatic`. A
person still sees it at once, by what only a standing cube has round its top:

- *a shaded band of real width along at least one edge*: the side faces turned
  away from the light, or the cube's shadow on the paper, a share of the paper's
  light taken away (L* under :data:`SHADE_RATIO` of the table's) over a band at
  least :data:`BAND_SIDES` of a block's side wide;
- *the top's shading edge all round*: the few pixels just outside the top are
  darker than the table (the far edges' rim in shade, the near edges' side faces).

A board's cell lit a little brighter is bounded by thin dark lines (1–2 px) all
round too, but no band of a side face's width: its lines drop out of the band's
opening. A faint part is taken only when both hold, and only where no bright part
holds it already (a white top lit brighter than the paper is found as before); the
part is then judged as any bright part is (compact, square, not too long).
"""

from __future__ import annotations

import numpy as np

from demoplan.perception.masks import dilate, fill_holes, labelled_parts
from demoplan.perception.opencv import cv2

__all__ = ["BAND_SIDES", "EDGE_SHARE", "SHADE_RATIO", "faint_white_tops"]

FAINT_SHARE = 0.5
"""A faint top's pixels stand out from the table by this share of the bright
contrast (a white top lit as the paper: 2-3 L* over it, the contrast 3 L*)."""
SHADE_RATIO = 0.85
"""A side face in shade or a shadow keeps at most this share of the table's L*
(a room's light: two thirds of it; the top's rim in shade a little more)."""
BAND_SIDES = 0.15
"""The shaded band's least width, in the smallest block's sides: a side face seen
from a camera 10° or more off the vertical, a shadow; a board's grid line, a pen
line (1-2 px) is narrower."""
BAND_SHARE = 0.2
"""The share of a faint part's outline the band must line (one edge of four: a
quarter, less its corners)."""
EDGE_SHARE = 0.8
"""The share of a faint part's outline (2 px out) that must be darker than the
table: the top's shading edge all round."""
MAX_FAINT = 2.0
"""A faint part whose median L* over the table is this many times the bright
contrast or more is bright, not faint: were it a top, a bright part would hold it;
none does, so it is thin (a marker card's white frame and the ring inside it)."""
EVEN_CONTRAST = 3.0
"""The bright contrast on a table as even as paper (achromatic.MIN_BRIGHT_CONTRAST):
the only table this module is asked about — where the table's own lightness varies
more (a board's grid, a marker's card, wood's grain) a few L* over it are the
table's, not a top."""
MAX_INKED = 0.3
"""A faint part (its holes filled) more than this share dark is a fiducial marker's
card, its black cells (achromatic.MARKER_DARK_SHARE), not a top with a glyph."""
HELD_SHARE = 0.5
"""A faint part this share of which a bright part (opened as they are) covers is
that bright part's: found as before."""
EDGE_REACH = 3
"""The top's shading edge lies within this many px of the faint part (its blurred
rim between, under the faint contrast)."""
MAX_TOP_SIDES = 4.0
"""A faint part wider than this many of the smallest block's sides (its area over
their square) is no single top (a sheet, a lit patch of the table): the sizes
looked for without ``--side`` span 2 to 8 cm."""


def faint_white_tops(
    difference: np.ndarray,
    lightness: np.ndarray,
    table: np.ndarray,
    free: np.ndarray,
    bright: np.ndarray,
    dark: np.ndarray,
    markers: np.ndarray,
    side_px: float,
) -> np.ndarray:
    """The faint white tops (a mask) on a table as even as paper (the only one it is
    asked about: :data:`EVEN_CONTRAST`): parts of the ``free`` pixels whose L* over
    the ``table``'s (``difference``; ``lightness`` their L*) is :data:`FAINT_SHARE`
    of the bright contrast, holes filled (a glyph), of a block's size (``side_px``
    the smallest block's side), under :data:`HELD_SHARE` of it held by a part of
    ``bright`` pixels, faint (:data:`MAX_FAINT`), at most :data:`MAX_INKED` ``dark``
    and meeting none of the ``markers`` (a marker's card), with the top's shading
    edge all round and a shaded band of a side face's width along one edge at least
    (:func:`_outlined`)."""
    faint = (difference > FAINT_SHARE * EVEN_CONTRAST) & free
    steps = max(1, round(side_px * 0.3 / 2))
    disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * steps + 1, 2 * steps + 1))
    # a letter or dots printed on the top are holes in it
    opened = cv2.morphologyEx(fill_holes(faint).astype(np.uint8), cv2.MORPH_OPEN, disc)
    count, labels, stats = labelled_parts(opened)
    tops = np.zeros(faint.shape, dtype=bool)
    height, width = faint.shape
    band_steps = max(2, round(side_px * BAND_SIDES / 2))
    band_disc = cv2.getStructuringElement(
        cv2.MORPH_ELLIPSE, (2 * band_steps + 1, 2 * band_steps + 1)
    )
    pad = 2 * band_steps + 6
    for index in range(1, count):
        x, y, w, h, area = (int(value) for value in stats[index])
        if not 0.5 * side_px**2 <= area <= (MAX_TOP_SIDES * side_px) ** 2:
            continue
        if x < pad or y < pad or x + w + pad > width or y + h + pad > height:
            continue  # at the border: left to the bright parts' own refusal
        rows, cols = slice(y - pad, y + h + pad), slice(x - pad, x + w + pad)
        part = dilate(labels[rows, cols] == index, steps) & fill_holes(faint[rows, cols])
        held = cv2.morphologyEx(bright[rows, cols].astype(np.uint8), cv2.MORPH_OPEN, disc)
        if held.astype(bool)[part].mean() >= HELD_SHARE:
            continue  # a bright part holds it: found as before
        darker = FAINT_SHARE * EVEN_CONTRAST
        if float(np.median(difference[rows, cols][part])) >= MAX_FAINT * EVEN_CONTRAST:
            continue  # bright, yet no bright part holds it: thin, a card's frame
        if dark[rows, cols][part].mean() > MAX_INKED or markers[rows, cols][part].any():
            continue  # a marker's card: its black cells more than a glyph's
        shade = (lightness[rows, cols] < SHADE_RATIO * table[rows, cols]) & free[rows, cols]
        if _outlined(part, difference[rows, cols], shade, band_disc, darker):
            tops[rows, cols] |= part & faint[rows, cols]
    return tops


def _outlined(
    part: np.ndarray, difference: np.ndarray, shade: np.ndarray, band: np.ndarray, darker: float
) -> bool:
    """Whether ``part`` has the top's shading edge all round (:data:`EDGE_SHARE` of
    its outline has a pixel ``darker`` than the table — ``difference`` its L* over
    the table's — within :data:`EDGE_REACH` px out: the top's blurred rim lies
    between) and a band of ``shade`` (neutral, under :data:`SHADE_RATIO` of the
    table's L*: a coloured frame or block beside it is none) opened by the ``band``
    disc lining :data:`BAND_SHARE` of its outline within the band's width."""
    reach = cv2.getStructuringElement(cv2.MORPH_RECT, (2 * EDGE_REACH + 1, 2 * EDGE_REACH + 1))
    least = cv2.erode(difference.astype(np.float32), reach)
    edge = dilate(part, 1) & ~part
    if float(np.mean(least[edge] < -darker)) < EDGE_SHARE:
        return False
    wide = cv2.morphologyEx(shade.astype(np.uint8), cv2.MORPH_OPEN, band).astype(bool)
    width = band.shape[0]
    near = dilate(wide, width) & dilate(part, width) & ~part  # the band beside the top
    lined = dilate(near, 1) & edge
    return float(lined.sum()) >= BAND_SHARE * float(edge.sum())
