"""What lies on a coloured top face though it is not the face's colour: a
specular highlight (white added to the face's colour) and what is printed on it,
found by :mod:`demoplan.perception.colours` as holes in a region's clearly
coloured pixels and given back to the top that encloses them; and a frame printed
round a white top's face (:func:`framed_on_white`), which
:mod:`demoplan.perception.achromatic` gives back to the top."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from demoplan.perception.masks import dilate, fill_holes, labelled_parts, small_parts
from demoplan.perception.opencv import cv2

__all__ = [
    "FRAMED_BRIGHT_SHARE",
    "GLARE_SLACK",
    "PRINTED_CONTRAST",
    "framed_on_white",
    "glare",
    "highlights",
    "hole_owners",
    "printed",
]

GLARE_SLACK = 8.0
"""Grey levels a highlight's channel may fall under the top face's mean (noise)."""


def hole_owners(core: np.ndarray, nearest: np.ndarray) -> np.ndarray:
    """Per pixel of the holes in a region's clearly coloured pixels (``core``,
    closed by a 5 × 5 square: the faint seam between two classes would open a hole
    next to it to the outside), the class (``nearest``) that holds most of the ring
    two pixels around its hole, −1 elsewhere: whose top a glint there is on."""
    owners = np.full(core.shape, -1, dtype=np.intp)
    # the seam between two classes (their mixed colours faint) closed first
    closed = cv2.morphologyEx(core.astype(np.uint8), cv2.MORPH_CLOSE, np.ones((5, 5), np.uint8))
    holes = fill_holes(np.asarray(closed, dtype=bool)) & ~core
    if not holes.any():
        return owners
    for rows, cols, hole, ring in _holes_and_rings(holes, core):
        if ring.any():
            owners[rows, cols][hole] = int(np.bincount(nearest[rows, cols][ring]).argmax())
    return owners


def _holes_and_rings(
    holes: np.ndarray, core: np.ndarray
) -> Iterator[tuple[slice, slice, np.ndarray, np.ndarray]]:
    """Each connected hole of ``holes`` in the window of its box and 2 px around it
    (the dilation reaches no farther): the window's rows and columns, the hole there,
    and its ring — the pixels of ``core`` within 2 px of it."""
    count, labels, stats = labelled_parts(holes)
    height, width = core.shape
    for index in range(1, count):
        x, y, w, h = (int(value) for value in stats[index, :4])
        rows = slice(max(0, y - 2), min(height, y + h + 2))
        cols = slice(max(0, x - 2), min(width, x + w + 2))
        hole = labels[rows, cols] == index
        yield rows, cols, hole, dilate(hole, 2) & core[rows, cols]


def highlights(
    crop: np.ndarray,
    lightness: np.ndarray,
    top: tuple[float, np.ndarray],
    core: np.ndarray,
    min_area: float,
) -> np.ndarray:
    """Which pixels of a one-class region's crop (RGB ``crop``, L* ``lightness``)
    are a specular highlight on its block, so covered by its top face: the top
    face's colour (``top``: its L* and mean RGB) with white added — every channel
    at least the top's, brighter than it — enclosed by the block's
    clearly coloured pixels (``core``; a region may hold patches of a grey table,
    faintly tinted, beside a dark or saturated block), holes in those smaller than a
    block (a marker drawn on the block, a glint's white centre)."""
    top_face, top_rgb = top
    floor = top_rgb - GLARE_SLACK
    whiter = lightness > top_face
    for channel in range(crop.shape[-1]):  # every channel at least the top's: one at a time
        whiter &= crop[..., channel] >= floor[channel]
    enclosed = fill_holes(core)
    on_top: np.ndarray = (whiter & _ringed_by_the_face(core, enclosed)) | small_parts(
        enclosed & ~core, min_area
    )
    return on_top


STRAND = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))
"""The disc whose opening takes a strand of a class's clearly coloured pixels off its
face: a pen line or a cable a few px wide (the strands' opening of a top's mask,
a third of the smallest side across, also takes the band of face between a
letter printed on a top and its edge)."""


def _ringed_by_the_face(core: np.ndarray, enclosed: np.ndarray) -> np.ndarray:
    """``enclosed`` (``core`` with its holes filled) without the holes beside a face
    of ``core`` that a strand of it rings more than the face does: over half of the
    two pixels of core round the hole are pixels an opening by :data:`STRAND`
    removes, and some are the face's (a class that is all strand, a thin rim round
    a face its colour's other shade took, rings that face). A glint lies on the
    top, its face round it; table seen between a top and a pen line of its colour
    drawn up to its corners is ringed by the line, far thinner than a side (a blue
    top's line enclosed a patch of tinted table, lighter than the top in every
    channel, which was filled as a glint: a rectangle 1.9 sides long, "not
    square"). A hole whose convex hull holds more of the face
    than the hole's own area goes round a piece of the face: a frame printed on
    the top (a white one, its rim outside thinner than :data:`STRAND`, the ring
    whole or broken where the rim and the face inside it meet), it stays."""
    holes = enclosed & ~core
    if not holes.any():
        return enclosed
    face = np.asarray(cv2.morphologyEx(core.astype(np.uint8), cv2.MORPH_OPEN, STRAND), dtype=bool)
    strands = core & ~face
    if not strands.any():
        return enclosed
    kept = enclosed.copy()
    for rows, cols, hole, ring in _holes_and_rings(holes, core):
        hull = np.zeros(hole.shape, dtype=np.uint8)
        cv2.fillConvexPoly(hull, cv2.convexHull(cv2.findNonZero(hole.astype(np.uint8))), 1)
        if np.count_nonzero((hull > 0) & face[rows, cols]) >= np.count_nonzero(hole):
            continue  # round a piece of the face larger than itself: a frame printed on it
        stranded = int(np.count_nonzero(ring & strands[rows, cols]))
        if 2 * stranded > int(np.count_nonzero(ring)) and (ring & face[rows, cols]).any():
            kept[rows, cols] &= ~hole  # beside a face, ringed by a strand of it: table
    return kept


PRINTED_CONTRAST = 12.0
"""L* by which a hole in a top's coloured pixels differs from the table around the
region (its median), at least, to be printed on the top rather than table seen
through a ring of blocks (a black letter on a yellow top is 50 L* or more under
white paper, a white one on a red top as far over a blue table)."""


def printed(
    alpha: np.ndarray,
    lightness: np.ndarray,
    table_lightness: float,
    elsewhere: np.ndarray | None = None,
    touching: np.ndarray | None = None,
) -> np.ndarray:
    """The holes in a top's soft mask (``alpha`` over ½) that are something printed
    on it — a letter, dots, dark on a pale top or pale on a dark one, which a top's
    colour does not cover: each hole in one piece round no piece of the mask, or
    round a piece at least its own size (a frame printed round a top rings the
    plain face inside it, 1.9 times the frame's area; the dark code of an AprilTag
    on a tinted card rings the card's white centre, half its own area in
    mrhan_stacks, and is not filled: a false block), covering under half of the
    mask with its holes filled (a letter is a small share of its face), whose median L*
    (``lightness``) differs from the table's around the region
    (``table_lightness``) by :data:`PRINTED_CONTRAST` or more (table seen within a
    ring of blocks, or between a block and a pen line drawn up to it, is the
    table's lightness). A hole mostly of ``elsewhere`` (the clearly coloured pixels
    of the region's other classes) is their face, not printed on this one: a yellow
    face inside a dark frame printed on it, the frame's blurred colour a class of
    its own. With ``touching``, only the holes with a pixel of it are judged (those
    the glint rule changed: the others were judged as it left them)."""
    mask = alpha > 0.5
    enclosed = fill_holes(mask)
    holes = enclosed & ~mask
    found = np.zeros(holes.shape, dtype=bool)
    if not holes.any():
        return found
    _, labels, stats = labelled_parts(holes)
    limit = 0.5 * float(enclosed.sum())
    for index in np.flatnonzero(stats[1:, cv2.CC_STAT_AREA] < limit) + 1:
        x, y, w, h, _ = (int(value) for value in stats[index])
        rows, cols = slice(y, y + h), slice(x, x + w)
        hole = labels[rows, cols] == index
        if touching is not None and not touching[rows, cols][hole].any():
            continue
        ringed = int(fill_holes(hole).sum()) - int(hole.sum())
        if 0 < ringed < hole.sum():
            continue  # a ring round a smaller piece of the top: a marker's code on a card
        if elsewhere is not None and 2 * int(elsewhere[rows, cols][hole].sum()) >= hole.sum():
            continue  # another class's face
        if abs(float(np.median(lightness[rows, cols][hole])) - table_lightness) >= PRINTED_CONTRAST:
            found[rows, cols] |= hole
    return found


def glare(
    classes: np.ndarray, lightness: np.ndarray, core: np.ndarray, min_area: float
) -> np.ndarray:
    """Which core pixels are a specular highlight: brighter than most of the region
    (white mixed in; it may then look like another colour, a glint on yellow like
    wood), in patches smaller than a block (a yellow block beside a blue one is a
    block's size)."""
    core_lightness = lightness[core]
    bright: np.ndarray = core_lightness > np.median(core_lightness) + 4.0
    candidates = np.zeros(core.shape, dtype=bool)
    candidates[core] = bright
    if np.count_nonzero(bright) < 1.5 * min_area:  # every patch smaller than them all
        return bright
    count, labels = cv2.connectedComponents(candidates.astype(np.uint8), connectivity=4)
    if count == 1:  # the background alone
        return np.zeros(classes.shape, dtype=bool)
    sizes = np.bincount(labels.ravel(), minlength=count)
    small = sizes < 1.5 * min_area
    small[0] = False
    found: np.ndarray = small[labels][core]
    return found


def fill_glints_and_prints(
    alpha: np.ndarray,
    glints: np.ndarray,
    lightness: np.ndarray,
    table_lightness: float,
    elsewhere: np.ndarray | None,
) -> None:
    """Fills, in a top's soft mask ``alpha``, the ``glints`` (:func:`highlights`)
    and what is printed on the top (:func:`printed`), its holes judged as the glint
    rule left them and, where that rule filled any, as they were before it: a
    letter's body, no colour, is a hole in the top's coloured pixels that the glint
    rule fills, and its blurred edge (the top's colour mixed with black, under half
    the top's) is left a broken ring of thin holes, each as light as a grey board."""
    unlit = alpha.copy() if (glints & (alpha <= 0.5)).any() else None
    alpha[glints] = 1.0
    alpha[printed(alpha, lightness, table_lightness, elsewhere)] = 1.0
    if unlit is not None:  # judged as they were too, only the holes the rule changed
        changed = glints & (unlit <= 0.5)
        alpha[printed(unlit, lightness, table_lightness, elsewhere, changed)] = 1.0


FRAMED_BRIGHT_SHARE = 0.5
"""A dark ring's hole is a white top's face inside a frame printed on it when this
share of the hole or more is bright (the face, its blurred edge beside the frame
aside: 81-87 % of a generated frame's hole)."""


def framed_on_white(bright: np.ndarray, dark: np.ndarray, side_px: float) -> np.ndarray:
    """The frames printed round white tops' faces, each with its hole and the two
    pixels of blur round it (between the frame and the top's rim, neither dark nor
    bright): a part of ``dark`` that rings one hole of a block's size
    or less (``side_px``, the smallest block's side) which is :data:`FRAMED_BRIGHT_SHARE`
    ``bright`` or more, and covers less than that hole (a frame is a thin ring of
    one width along the top's outline; a black top's glint, a marker's white cells
    are holes smaller than the dark round them). On white paper the top's rim
    outside the frame is as light as the paper and the frame is thinner than the
    opening of :func:`~demoplan.perception.achromatic.achromatic_regions` takes: the
    white face inside it alone, 0.68 of the side, is too small a top; the frame's
    outside is the top's (0.84 of the side on a generated top, its rim beyond it)."""
    found = np.zeros(bright.shape, dtype=bool)
    count, labels, stats = labelled_parts(~dark, connectivity=4)
    sizes = stats[:, cv2.CC_STAT_AREA]
    lit = np.bincount(labels[bright & ~dark], minlength=count)
    taken = (sizes < side_px**2) & (lit >= FRAMED_BRIGHT_SHARE * sizes)
    taken[0] = False  # the dark pixels themselves
    taken[np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]])] = False
    if not taken.any():
        return found
    _, rings, ring_stats = labelled_parts(dark)
    height, width = dark.shape
    for index in np.flatnonzero(taken):
        x, y, w, h = (int(value) for value in stats[index, :4])
        pad = max(3, round(0.2 * side_px))  # the ring's width, and its blur, round the hole
        rows = slice(max(0, y - pad), min(height, y + h + pad))
        cols = slice(max(0, x - pad), min(width, x + w + pad))
        hole = labels[rows, cols] == index
        around = np.unique(rings[rows, cols][dilate(hole, 1) & dark[rows, cols]])
        if around.size != 1 or ring_stats[around[0], cv2.CC_STAT_AREA] >= sizes[index]:
            continue  # no one ring round it, or one as large as the hole: no frame
        ring = rings[rows, cols] == around[0]
        found[rows, cols] |= fill_holes(dilate(ring, 2) | hole)
    return found
