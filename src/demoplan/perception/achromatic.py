"""Candidate regions of black, white and grey blocks: lightness against the local table.

:mod:`demoplan.perception.colours` finds blocks by their chroma, so a black,
white or grey cube — no chroma — is table to it. Here such a block is found by
its lightness (CIELAB L*) against the table's *around it*: the table's level is
the median L* over a window several blocks wide (:data:`TABLE_WINDOW_SIDES`; a
median, so a block, a grid line or a shadow in it does not move it), which
follows a light's fall-off across the table.

- *Bright* (a white cube): L* above the local table's by :data:`MIN_BRIGHT_CONTRAST`
  (a white cube on white paper stands out by a few L* only).
- *Dark* (a black or grey cube): L* under :data:`DARK_RATIO` of the local table's.
  A shadow dims the table it falls on by a share (the light it takes away), to
  about two thirds of it in a room's light, a black cube to a tenth: the ratio,
  not a difference, parts them on a bright table and a dark one alike.

Each part is opened by a disc a quarter of the smallest block's side across, so
that the grid lines of a board, a pen line or a cable (thinner than that) drop
out, and pixels already in a coloured region (and two pixels around them) are
not taken again. A part with its holes filled (a glint on a black top, a glyph
printed on a white one) is a candidate unless it is a fiducial marker: a bright
square more than :data:`MARKER_DARK_SHARE` of which is dark inside (the
black cells of an AprilTag or ArUco marker). Its soft mask is the lightness
ramp from the table's level (0) to the lower quartile of its pixels' (1) for a
bright part; for a dark one from the ratio's level to its upper quartile, so a
shadow's half-tone beside a grey cube stays out of it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from demoplan.perception.faint_white import faint_white_tops
from demoplan.perception.fused_lines import fused_lines
from demoplan.perception.highlights import framed_on_white
from demoplan.perception.masks import close, dilate, erode, fill_holes, labelled_parts
from demoplan.perception.opencv import cv2
from demoplan.perception.rejected_parts import PartRecorder

__all__ = [
    "DARK_RATIO",
    "MARKER_DARK_SHARE",
    "MIN_BRIGHT_CONTRAST",
    "TABLE_WINDOW_SIDES",
    "AchromaticRegion",
    "achromatic_regions",
    "local_table_lightness",
]

MAX_CHROMA = 12.0
"""A black, white or grey block's pixels lie this close to neutral in CIELAB's
a*b* plane (a coloured block's side face in shade is dark but keeps its hue)."""
TABLE_WINDOW_SIDES = 5.0
"""The local table's window: this many of the smallest block's sides across (at
least a third of the image's shorter side), so that a block covers a small
share of it."""
MIN_BRIGHT_CONTRAST = 3.0
"""L* by which a white block's pixels must outshine the local table at least."""
TABLE_SPREADS = 4.0
"""…and this many times the spread of the table's lightness about its local level."""
DARK_RATIO = 0.6
"""A dark block's pixels have at most this share of the local table's L* (a
shadow in a room's light keeps about two thirds; a grey cube on white paper half,
a black cube a tenth)."""
MARKER_DARK_SHARE = 0.3
"""A bright part whose filled outline is more than this share dark (under
:data:`DARK_RATIO` of the table) is a fiducial marker, not a white block with
a glyph printed on it (a frame, dots, a letter: a fifth of it or less)."""
BESIDE_COLOURED = 0.25
"""A part with this share of its rim on a coloured region is that block's side
face or its shadow (dark) or glare (bright)."""
MARKER_FRAME_CONTRAST = 10.0
"""A dark part whose surroundings (1–4 px out) are this much brighter than the
table, L* in the median, is a marker's black square in its white frame (a black
cube stands on the table or its own shadow); a frame too faint to be a bright
part of its own (an over-exposed photograph, the table as pale) still shows so."""
MARKER_CELL_SHARE = 0.25
"""…or a dark part whose holes cover this share of it: a marker's white cells (its
frame lost in a table as white: an over-exposed photograph). A glint on a black
top is a hole of a few per cent."""
MARKER_CELLS_SHARE = 0.15
"""…or two holes or more covering this share of it (a glint is one hole)."""
MIN_SOLIDITY = 0.85
"""A part (its holes filled) covering less of its convex hull is no block's top nor
a row of them: a board's line crossings, an arm, a cable, a shadow's L."""
MIN_RECT_FILL = 0.8
"""…or less of its smallest enclosing rectangle (a disc covers π/4 of it)."""
MIN_TOP_SHARE = 0.5
"""A part smaller than this share of the smallest block's area is a fragment (a
board's cell lit a little brighter in one corner), not a top: a black or white
top stands out whole."""
OPENING_SIDES = 0.3
"""The disc a part is opened by, in the smallest block's sides across: a board's
grid lines, a pen line, a cable, a strip of shadow (all narrower) drop out; the
opening's rounded corners are given back (its dilation within the part)."""
SIDE_FACE_RATIO = 1.5
"""A dark part's brighter lightness mode at least this many times its darker one:
the darker is the block's side faces (in shade under the light from above)."""
MAX_ASPECT = 1.5
"""A part whose rectangle is longer than this over its width is no block's top (a
black box, a phone, a white sheet, a tag's strip). A row of black or white cubes
touching is one such part too: it is not split into its cubes yet."""
BLACK_BELOW = 25.0
"""A dark block whose top's L* is under this is named ``black``, else ``grey``."""


AchromaticRegion = tuple[str, tuple[float, float, float], tuple[int, int], np.ndarray]
"""A candidate region: its colour name (``white``, ``black`` or ``grey``), mean RGB,
the top-left pixel (row, column) of its crop and its soft mask on the crop."""


@dataclass(frozen=True, slots=True)
class _Refusal:
    """Why a part is no candidate: the reason (as a RejectedPart's) and the
    measure behind it."""

    reason: str
    detail: str


def local_table_lightness(lightness: np.ndarray, side_px: float) -> np.ndarray:
    """The table's L* around every pixel: the median of L* (``lightness``, 0–100)
    over a square :data:`TABLE_WINDOW_SIDES` block sides (``side_px``) across, taken
    on the image shrunk four times (its thin dark lines — a board's grid — closed
    first, so that they do not pull the median down where a block adds its own
    dark pixels) and enlarged back (OpenCV's median filter)."""
    height, width = lightness.shape
    window = max(TABLE_WINDOW_SIDES * side_px, min(height, width) / 3) / 4
    shrunk = np.clip(lightness[::4, ::4] * 2.55, 0, 255).astype(np.uint8)
    lines = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))
    closed = cv2.morphologyEx(shrunk, cv2.MORPH_CLOSE, lines)
    # reflected at the border, not repeated: a grid line along the image's edge
    # repeated would fill half a window there
    # at most twice the shrunk image across: an absurd --px-per-m asked for a
    # window of kilometres (62 GB in OpenCV); wider adds only reflections
    size = min(int(window), 2 * max(shrunk.shape) + 1) | 1
    half = size // 2
    padded = cv2.copyMakeBorder(closed, half, half, half, half, cv2.BORDER_REFLECT_101)
    median = cv2.medianBlur(padded, size)[half:-half, half:-half]
    table = cv2.resize(median, (width, height), interpolation=cv2.INTER_LINEAR)
    level: np.ndarray = np.asarray(table, dtype=np.float32) / np.float32(2.55)
    return level


def _bright_contrast(difference: np.ndarray) -> float:
    """The L* over the local table's from which a pixel is bright: at least
    :data:`MIN_BRIGHT_CONTRAST` and :data:`TABLE_SPREADS` times the spread of the
    table's own lightness about its local level (``difference``, over the whole
    image: its median absolute deviation, scaled to a normal σ) — a board's
    cells lit unevenly, a wooden table's grain are brighter than their
    surroundings by that much, a white cube on paper in even light by a few L*."""
    sample = difference[::4, ::4]
    spread = 1.4826 * float(np.median(np.abs(sample - np.median(sample))))
    return max(MIN_BRIGHT_CONTRAST, TABLE_SPREADS * spread)


def achromatic_regions(
    image: np.ndarray,
    lab: np.ndarray,
    coloured: np.ndarray,
    min_area: float,
    record: PartRecorder,
) -> list[AchromaticRegion]:
    """The candidate regions of black, white and grey blocks in ``image`` (RGB,
    H × W × 3; ``lab`` its CIELAB, L* 0–100), of neutral pixels (:data:`MAX_CHROMA`)
    outside the ``coloured`` ones (the coloured regions' masks), each with at least
    ``min_area`` pixels (0.3 of the smallest block's area); the parts dropped (markers,
    parts not compact, at the border, beside a coloured block) go to ``record``."""
    side_px = float(np.sqrt(min_area / 0.3))
    if side_px > min(image.shape[:2]):
        return []  # no block fits in the image (an absurd --px-per-m or --side)
    blurred = np.asarray(cv2.blur(lab.astype(np.float32), (3, 3)))  # over the noise
    lightness = blurred[..., 0]
    table = local_table_lightness(lightness, side_px)
    difference = lightness - table
    neutral = np.hypot(blurred[..., 1], blurred[..., 2]) < MAX_CHROMA
    free = ~dilate(coloured, 2) & neutral
    contrast = _bright_contrast(difference)
    bright = (difference > contrast) & free
    dark = (lightness < DARK_RATIO * table) & free
    smallest_top = MIN_TOP_SHARE * side_px**2
    markers = _markers(bright, lightness, table, smallest_top, record)
    if contrast <= MIN_BRIGHT_CONTRAST:  # a table as even as paper (faint_white)
        faint = (difference, lightness, table, free)
        bright |= faint_white_tops(*faint, bright, dark, dilate(markers, 2), side_px) & ~dark
    steps = max(1, round(side_px * OPENING_SIDES / 2))
    disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * steps + 1, 2 * steps + 1))
    height, width = lightness.shape
    regions: list[AchromaticRegion] = []
    framed = np.zeros(bright.shape, dtype=bool)
    for is_bright, mask in ((True, bright), (False, dark)):
        mask &= ~dilate(markers, 2)  # a marker's white and black cells are no blocks
        if is_bright:
            framed = framed_on_white(mask, dark, side_px)  # held whole: see _Part
            mask |= _printed_on_white(mask, dark, side_px) | framed
        opened = cv2.morphologyEx(mask.astype(np.uint8), cv2.MORPH_OPEN, disc)
        count, labels, stats = labelled_parts(opened)
        for index in range(1, count):
            x, y, w, h, area = (int(value) for value in stats[index])
            if area < smallest_top:
                continue  # a fragment: a whole top stands out, not a part of one
            rows, cols = slice(y, y + h), slice(x, x + w)
            if x == 0 or y == 0 or x + w == width or y + h == height:
                why = "a black, white or grey part at the image's border"
                record(labels[rows, cols] == index, rows, cols, "cut by the border", why)
                continue
            held = framed if is_bright else None
            part = _Part(labels, index, (x, y, w, h), mask, (steps + 1) // 2, held, side_px)
            found = _region(image, lightness, table, part, is_bright, coloured)
            if isinstance(found, _Refusal):
                record(labels[rows, cols] == index, rows, cols, found.reason, found.detail)
            else:
                regions.append(found)
    return regions


def _markers(
    bright: np.ndarray,
    lightness: np.ndarray,
    table: np.ndarray,
    smallest_top: float,
    record: PartRecorder,
) -> np.ndarray:
    """The fiducial markers among the ``bright`` parts (before any opening: a
    marker's white frame is thin): those of at least ``smallest_top`` pixels
    whose convex hull (a frame broken where the table's level rose beside it still
    holds its cells) is more than :data:`MARKER_DARK_SHARE` dark inside (L* under
    :data:`DARK_RATIO` of the ``table``'s); their hulls, each recorded."""
    markers = np.zeros(bright.shape, dtype=bool)
    _, labels, stats = labelled_parts(bright)
    for index in np.flatnonzero(stats[1:, cv2.CC_STAT_AREA] >= smallest_top / 2) + 1:
        x, y, w, h, _ = (int(value) for value in stats[index])
        rows, cols = slice(y, y + h), slice(x, x + w)
        filled = _convex_hull(labels[rows, cols] == index)
        if filled.sum() < smallest_top:
            continue
        dark = lightness[rows, cols][filled] < DARK_RATIO * table[rows, cols][filled]
        if dark.mean() > MARKER_DARK_SHARE:
            markers[rows, cols] |= filled
            record(filled, rows, cols, "marker", f"a bright square {dark.mean():.0%} dark inside")
    return markers


PRINTED_DARK_SHARE = 0.5
"""A hole in a white part is a letter printed on a white top when this share of it
or more is dark (under :data:`DARK_RATIO` of the table): a letter's bars are dark
through, their blurred rims aside (three quarters of a generated letter's hole);
the code of a small marker on a white card, its ring blurred into its white
centre, is dark over a third of its hole (the development set's AprilTags)."""


def _printed_on_white(bright: np.ndarray, dark: np.ndarray, side_px: float) -> np.ndarray:
    """What is printed on white tops (a letter, dots: dark, so no part of the
    ``bright`` mask): the holes of a bright part that are letters — each
    :data:`PRINTED_DARK_SHARE` ``dark`` or more and ringing nothing (a small marker's
    code on a white card rings the card's white cells) — or spots
    (:func:`_spots`, among the holes smaller than a block of the smallest side,
    ``side_px``), where their dark pixels (the ink) cover under
    :data:`MARKER_DARK_SHARE` of the part with its holes filled (a marker's black
    cells cover more). A letter is not bounded by the smallest block: printed on a
    larger top it is larger (an H on a 4 cm top, 1,050 px with its blurred rim, over
    the 930 px of a 2 cm block without ``--side``). One labelling of the image's
    non-bright pixels finds the holes (those not reaching the border), their sizes
    and dark shares; the parts are labelled only when a hole is taken."""
    # the sizes counted from the labels: the image is mostly not bright, and OpenCV's
    # stats of so many labelled pixels cost more than the count
    count, labels = cv2.connectedComponents((~bright).astype(np.uint8), connectivity=4)
    sizes = np.bincount(labels.ravel(), minlength=count)
    darker = np.bincount(labels[dark & ~bright], minlength=count)
    enclosed = np.ones(count, dtype=bool)
    enclosed[np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]])] = False
    letters = enclosed & (darker >= PRINTED_DARK_SHARE * sizes)
    if letters.any():  # none ringing a piece of white: a marker's code rings its cells
        inked = letters[labels]
        ringed = fill_holes(inked) & ~inked
        letters[labels[dilate(ringed, 1) & inked]] = False
    small = enclosed & (sizes < side_px**2)
    if not (letters.any() or small.any()):
        return np.zeros(bright.shape, dtype=bool)
    taken = letters | (_spots(bright, labels, small, sizes) if small.any() else small)
    if not taken.any():
        return np.zeros(bright.shape, dtype=bool)
    holes: np.ndarray = taken[labels]
    count, parts, stats = labelled_parts(bright | holes)
    areas = stats[:, cv2.CC_STAT_AREA]
    held = np.bincount(parts[holes & dark], minlength=count)  # their ink
    printed: np.ndarray = holes & (held < MARKER_DARK_SHARE * areas)[parts]
    return printed


PRINTED_SPOT_SHARE = 0.1
"""A hole in a white part covering under this share of the part (its holes filled)
is a spot printed on a white top whatever its darkness: blurred, a dot's dark core
is a third of its hole (a generated top's five dots: 4-5 % of the top each),
under :data:`PRINTED_DARK_SHARE`; a small marker's code on a white card is as
dark a share but covers 29-50 % of the card (the development set's AprilTags)."""


def _spots(
    bright: np.ndarray, labels: np.ndarray, small: np.ndarray, sizes: np.ndarray
) -> np.ndarray:
    """Which of the holes (``labels`` of the non-``bright`` pixels, ``small`` those
    of a block's size or less, ``sizes`` their areas) cover under
    :data:`PRINTED_SPOT_SHARE` of the bright part round them, its small holes filled."""
    holes = small[labels]
    _, parts, stats = labelled_parts(bright | holes)
    areas = stats[:, cv2.CC_STAT_AREA]
    part_of = np.zeros(small.shape[0], dtype=np.intp)
    part_of[labels[holes]] = parts[holes]
    spots: np.ndarray = small & (sizes < PRINTED_SPOT_SHARE * areas[part_of])
    return spots


def _opened_at_own_scale(part: np.ndarray) -> np.ndarray:
    """``part`` opened again by a disc :data:`OPENING_SIDES` of its own size across
    (the square root of its area: the first opening was at the smallest block's
    scale), its largest piece — what its compactness is judged on: the feet of a
    board's lines where they leave a block go (its mask keeps its corners)."""
    steps = max(1, round(math.sqrt(float(part.sum())) * OPENING_SIDES / 2))
    disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * steps + 1, 2 * steps + 1))
    opened = cv2.morphologyEx(part.astype(np.uint8), cv2.MORPH_OPEN, disc)
    count, labels, stats = labelled_parts(opened)
    if count < 2:
        return part
    largest: np.ndarray = labels == 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    return largest


def _white_cells(member: np.ndarray, filled: np.ndarray) -> tuple[int, float]:
    """How many holes a dark part (``member``; ``filled`` its holes filled) has
    and the share of its filled outline they cover (a marker's white cells)."""
    holes = (filled & ~member).astype(np.uint8)
    _, _, stats = labelled_parts(holes)
    sizable = stats[1:, cv2.CC_STAT_AREA] >= 0.01 * float(filled.sum())
    return int(sizable.sum()), float(holes.sum()) / max(float(filled.sum()), 1.0)


def _convex_hull(mask: np.ndarray) -> np.ndarray:
    """The convex hull of ``mask``'s pixels, as a mask of its shape."""
    hull = cv2.convexHull(cv2.findNonZero(mask.astype(np.uint8)))
    filled = np.zeros(mask.shape, dtype=np.uint8)
    cv2.fillConvexPoly(filled, hull, 1)
    return filled.astype(bool)


def _compactness(mask: np.ndarray) -> tuple[float, float, float]:
    """The share of its convex hull and of its smallest enclosing rectangle that
    ``mask`` (one part) covers — both 1 for a square seen from any side, less for a
    cross, an arm, a cable's loop, a disc (π/4 of its square) — and that
    rectangle's length over its width."""
    points = cv2.findNonZero(mask.astype(np.uint8))
    hull = cv2.convexHull(points)
    (_, _), (width, height), _ = cv2.minAreaRect(points)
    area = float(mask.sum())
    solidity = area / max(float(cv2.contourArea(hull)) + len(hull) / 2, 1.0)
    rect_fill = area / max((width + 1) * (height + 1), 1.0)
    return solidity, rect_fill, (max(width, height) + 1) / (min(width, height) + 1)


def _without_side_faces(member: np.ndarray, lightness: np.ndarray, steps: int) -> np.ndarray:
    """A dark part (``member``, L* ``lightness``) without its block's side faces:
    lit from above, a black or grey cube's top is brighter than its sides, by a
    share (a black top at L* 10 over sides at 5) rather than by a difference. When
    the part's L* (a pixel in from its rim, its brightest tenth — a glint's rim —
    left out) falls into two modes (Otsu's split) the brighter of which is
    :data:`SIDE_FACE_RATIO` times the darker and holds a quarter of the pixels or
    more, the darker are side faces: the part is its brighter pixels, opened by
    ``steps`` (strips of the sides' edges left out), its largest piece."""
    values = lightness[erode(member, 1)]
    if values.size < 16:
        return member
    values = values[values <= np.quantile(values, 0.9)]  # not a glint's rim, the outline
    scaled = np.clip(values * 2.55, 0, 255).astype(np.uint8).reshape(-1, 1)
    cut, _ = cv2.threshold(scaled, 0, 255, cv2.THRESH_BINARY | cv2.THRESH_OTSU)
    upper, lower = values[values > cut / 2.55], values[values <= cut / 2.55]
    if upper.size < max(8, values.size / 4) or lower.size < 8:
        return member
    if np.median(upper) < SIDE_FACE_RATIO * max(float(np.median(lower)), 1.0):
        return member
    top = fill_holes(member & (lightness > cut / 2.55))  # a glint within stays
    disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * steps + 1, 2 * steps + 1))
    opened = cv2.morphologyEx(top.astype(np.uint8), cv2.MORPH_OPEN, disc)
    count, labels, stats = labelled_parts(opened)
    if count < 2:
        return member
    largest = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    kept: np.ndarray = dilate(labels == largest, steps) & top
    return kept


def _square_of(body: np.ndarray) -> np.ndarray:
    """The smallest rectangle round ``body``'s pixels, as a mask of its shape."""
    box = cv2.boxPoints(cv2.minAreaRect(cv2.findNonZero(body.astype(np.uint8))))
    square = np.zeros(body.shape, dtype=np.uint8)
    cv2.fillConvexPoly(square, np.rint(box).astype(np.int32), 1)
    return square.astype(bool)


def _rims_given_back(
    member: np.ndarray, body: np.ndarray, part: _Part, crop: tuple[slice, slice], lines: np.ndarray
) -> np.ndarray | None:
    """The dark pixels (of ``part.mask``, not a fused line's) within the smallest
    rectangle round a dark part's ``body`` when with ``member`` they enclose a glint
    that ``member`` leaves open: a glint near a black or grey top's edge, whose rim
    of top between it and the edge is thinner than the opening (which broke it: the
    glint's hole became a notch). A glint is a round spot inside the top: a new hole
    inside the rectangle less its margin (a gap between a grid line and the top lies
    along the top's side) and no longer than :data:`MAX_ASPECT` times its width (a
    gap between a line and a side face is a strip). ``None`` when there is none."""
    rows, cols = crop
    grow = part.regrown + 1
    square = _square_of(body)
    given: np.ndarray = part.mask[rows, cols] & dilate(square, grow) & ~lines
    again = member | given
    holes = fill_holes(again) & ~again & ~fill_holes(member)
    if not holes.any():
        return None
    inside = erode(square, grow)
    count, labels, stats = labelled_parts(holes)
    for index in range(1, count):
        hole = labels == index
        if 2 * int((hole & inside).sum()) <= int(stats[index, cv2.CC_STAT_AREA]):
            continue
        (_, _), (width, height), _ = cv2.minAreaRect(cv2.findNonZero(hole.astype(np.uint8)))
        if max(width, height) + 1 <= MAX_ASPECT * (min(width, height) + 1):
            return given
    return None


@dataclass(frozen=True, slots=True)
class _Part:
    """One part of the opened mask: its ``index`` in ``labels`` and its ``box``
    (x, y, w, h); ``mask`` the mask before the opening and ``regrown`` how many
    steps its corners are grown back into it; ``framed`` (a bright part's) the
    frames printed on white tops with what they ring
    (:func:`~demoplan.perception.highlights.framed_on_white`): wholly its top, though
    dark (a frame's outer edge lies within a few px of the top's outline, where the
    soft mask follows the lightness); ``side_px`` the smallest block's side."""

    labels: np.ndarray
    index: int
    box: tuple[int, int, int, int]
    mask: np.ndarray
    regrown: int
    framed: np.ndarray | None = None
    side_px: float = 0.0


def _region(
    image: np.ndarray,
    lightness: np.ndarray,
    table: np.ndarray,
    part: _Part,
    bright: bool,
    coloured: np.ndarray,
) -> AchromaticRegion | _Refusal:
    """Part ``index``'s candidate region, or why it is none (the reason, the
    measure): ``not compact``, ``elongated``, or ``side face or shadow`` of a coloured
    block (:data:`BESIDE_COLOURED` of its rim on ``coloured`` pixels)."""
    x, y, w, h = part.box
    height, width = part.labels.shape
    pad = 5 + part.regrown
    rows = slice(max(0, y - pad), min(height, y + h + pad))
    cols = slice(max(0, x - pad), min(width, x + w + pad))
    opened = part.labels[rows, cols] == part.index
    if not bright:  # a grid line fused along a black top's side is no part of it
        lines = fused_lines(part.labels, part.index, part.mask, (rows, cols), part.side_px)
        opened &= ~lines
    # the opening's rounded corners given back (and short stubs of the lines it cut)
    member = dilate(opened, part.regrown) & part.mask[rows, cols]
    if not bright:
        member &= ~lines
    crop_l, crop_table = lightness[rows, cols], table[rows, cols]
    if not bright:
        member = _without_side_faces(member, crop_l, part.regrown)
        opened &= member
    # a glint's rim at a black top's edge opens its hole to the outside: closed too
    closed = fill_holes(close(opened, 2 * part.regrown))
    body = _opened_at_own_scale(closed)
    solidity, rect_fill, aspect = _compactness(body)
    if not bright:
        given = _rims_given_back(member, body, part, (rows, cols), lines)
        if given is not None:
            member |= given
            closed = fill_holes(close(opened | given, 2 * part.regrown))
            solidity, rect_fill, aspect = _compactness(_opened_at_own_scale(closed))
    # a glint's hole, opened to the outside by a crack of its rim, closed
    filled = fill_holes(close(member, 2 * part.regrown))
    if solidity < MIN_SOLIDITY or rect_fill < MIN_RECT_FILL:
        return _Refusal("not compact", f"solidity {solidity:.2f}, {rect_fill:.0%} of its rectangle")
    if aspect > MAX_ASPECT:
        return _Refusal("elongated", f"a rectangle {aspect:.1f} times as long as wide")
    if not bright:
        frame = dilate(filled, 4) & ~dilate(filled, 1)
        framed = float(np.median(crop_l[frame] - crop_table[frame]))
        if framed >= MARKER_FRAME_CONTRAST:
            return _Refusal("marker", f"a dark square framed L* {framed:.0f} over the table")
        cells, share = _white_cells(member, filled)
        if share >= MARKER_CELL_SHARE or (cells >= 2 and share >= MARKER_CELLS_SHARE):
            return _Refusal("marker", f"a dark square with {cells} white cells ({share:.0%})")
    rim = dilate(member, 3) & ~member
    beside = float(np.mean(coloured[rows, cols][rim]))
    if beside >= BESIDE_COLOURED:
        return _Refusal("side face or shadow", f"beside a coloured block ({beside:.0%} of its rim)")
    core = erode(member, 2)
    if not core.any():
        core = member
    if bright:
        full = np.quantile(crop_l[core] - crop_table[core], 0.25)
        alpha = (crop_l - crop_table) / max(float(full), 1e-6)
    else:
        cut = DARK_RATIO * crop_table
        full = np.quantile(crop_l[core] - cut[core], 0.75)
        alpha = (crop_l - cut) / min(float(full), -1e-6)
    alpha = np.clip(alpha, 0.0, 1.0) * dilate(filled, 1)
    alpha[erode(filled, 2)] = 1.0  # within: a glint, a glyph, the top's shading
    if part.framed is not None:
        alpha[part.framed[rows, cols] & filled] = 1.0
    top = float(np.median(crop_l[core]))
    colour = "white" if bright else "black" if top < BLACK_BELOW else "grey"
    mean = image[rows, cols][core].mean(axis=0)
    rgb = (float(mean[0]), float(mean[1]), float(mean[2]))
    return colour, rgb, (rows.start, cols.start), alpha.astype(np.float64)
