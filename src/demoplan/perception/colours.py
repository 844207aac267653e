"""Foreground, colour classes and soft masks of a top-view image.

A pixel is foreground when its colour stands out from the table's: its distance
in the CIELAB a*b* plane (chroma, brightness left out) from the table's a*b* —
the median over the image, most of which is table — exceeds
``max(min_chroma, 6 σ)``, σ the noise of that distance between neighbouring pixels. Lightness plays
no part, so a grey board, black grid lines, black and white markers, shadows and
grey or dark machinery are table, and a block in a shadow is still a block (an
image without any colour — all channels equal — is judged by lightness instead;
black, white and grey blocks in an image with colour are found by lightness in
:mod:`demoplan.perception.achromatic`). Each connected foreground region
(OpenCV's connected components; regions smaller than a block are dropped at
once) has its enclosed holes filled — a specular highlight is white, so not
coloured, but lies inside the block (the top's colour with white added, or a
hole smaller than a block in its clearly coloured pixels). The region is split
by colour: its confidently coloured ("core") pixels are named by the nearest
palette colour in brightness-free chromaticity (RGB divided by its largest
channel, so shading does not change it), each colour with enough core pixels
becomes a class, and every pixel of the region goes to the nearest class.

For each class, a *soft mask* α ∈ [0, 1] says how much of a pixel the block's
top face covers: where the pixel's colour lies between the table's around the
region (the median of a ring just outside it) and the class's (an edge pixel
half covered is a half-mix). A cube seen off-centre shows side faces of its
own colour, darker than its top (lit from above): when a class's lightness
falls into two modes far apart, the brighter is the top face and α also ramps
from the darker mode's lightness (0) to the brighter's (1), so the side faces
drop out and the top face, whose size is the block's side, is what the Hough transform sees.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from demoplan.budget import check_time
from demoplan.perception.achromatic import achromatic_regions
from demoplan.perception.colour_classes import (
    FULL_LEVEL_SHARE,
    full_level,
    lightness_modes,
    nearest_class,
    one_colour_merged,
    present_classes,
    smoothed_classes,
    unnamed_split,
    without_rims,
    without_strands,
)
from demoplan.perception.highlights import fill_glints_and_prints, glare, highlights, hole_owners
from demoplan.perception.image_measures import ImageMeasures
from demoplan.perception.masks import (
    TableReach,
    dilate,
    erode,
    fill_holes,
    labelled_parts,
)
from demoplan.perception.opencv import cv2
from demoplan.perception.palette import (
    MIN_CHROMA,
    MIN_LIGHTNESS_CONTRAST,
    PALETTE,
    Palette,
    classify,
    load_palette,
    name_colour,
    palette_arrays,
)
from demoplan.perception.rejected_parts import REPORTED_SHARE, PartRecorder, RejectedPart, outlines

__all__ = [
    "PALETTE",
    "REPORTED_SHARE",
    "ColourRegion",
    "RejectedPart",
    "colour_regions",
    "foreground",
    "load_palette",
    "name_colour",
    "outlines",
]
TABLE_BLOCKS = 8.0
"""A foreground region that touches the image's border, covers more than this many
of the largest blocks' areas and is mostly of one colour is a second table (the
floor or a table around a board, the board being the image's median colour): no
group of blocks is that large and of one colour; its pixels of that colour are
table too."""


@dataclass(frozen=True, slots=True)
class ColourRegion:
    """One colour class within one connected foreground region.

    ``alpha`` is the soft mask on the crop ``rows × cols`` of the image
    (``offset`` = its top-left pixel); ``rgb`` the class's mean colour (its top
    face's when side faces were told apart)."""

    colour: str
    rgb: tuple[float, float, float]
    offset: tuple[int, int]
    alpha: np.ndarray
    strays: np.ndarray | None = None

    @property
    def counted(self) -> np.ndarray:
        """``alpha`` less its ``strays`` (:class:`~.masks.TableReach`): what its size is."""
        return self.alpha if self.strays is None else self.alpha * ~self.strays


_LAB_SCALE = np.array(
    [[100.0 / 255.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, -128.0], [0.0, 0.0, 1.0, -128.0]],
    dtype=np.float32,
)
"""OpenCV's 8-bit CIELAB to L* in 0–100 and a*, b* around 0 (as cv2.transform's matrix)."""


def _largest_channel_spread(pixels: np.ndarray) -> int:
    """The largest difference between two colour channels of one pixel (0 when grey)."""
    red, green, blue = cv2.split(np.ascontiguousarray(pixels, dtype=np.uint8))
    spread = cv2.subtract(cv2.max(cv2.max(red, green), blue), cv2.min(cv2.min(red, green), blue))
    return int(np.asarray(spread).max(initial=0))


def _distinctness(
    image: np.ndarray, lab8: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, float, bool]:
    """Per pixel, how far its colour stands out from the table's (CIELAB a*b*
    distance; L* difference in an image without colour), the image in CIELAB, and the
    foreground threshold; whether the image has colour at all. ``lab8``: the image's
    8-bit CIELAB, when measured before
    (:attr:`~demoplan.perception.image_measures.ImageMeasures.lab8`); else measured
    here, of the image with its table's colour cast divided out, as the detector
    sees it (:mod:`~demoplan.perception.white_balance`)."""
    # 8-bit conversion (a table lookup, fast): L* scaled by 255/100, a* and b* by 1, +128;
    # scaled back by one affine transform of the pixels
    if lab8 is None:
        measures = ImageMeasures(image)
        image, lab8 = measures.image, measures.lab8
    lab = np.asarray(cv2.transform(lab8.astype(np.float32), _LAB_SCALE))
    sample = lab[::4, ::4].reshape(-1, 3)
    coloured = _largest_channel_spread(image[::4, ::4]) > 2
    if coloured:
        table_a, table_b = np.median(sample[:, 1]), np.median(sample[:, 2])
        distinct = np.hypot(lab[..., 1] - table_a, lab[..., 2] - table_b)
        floor = MIN_CHROMA
    else:
        distinct = np.abs(lab[..., 0] - np.median(sample[:, 0]))
        floor = MIN_LIGHTNESS_CONTRAST
    # noise: neighbouring pixels' differences, robustly (edges are few)
    steps = np.abs(np.diff(distinct[::4, :], axis=1))
    sigma = 1.4826 * float(np.median(steps)) / np.sqrt(2)
    return distinct, lab, max(floor, 6 * sigma), coloured


def foreground(image: np.ndarray) -> np.ndarray:
    """Which pixels of ``image`` (H × W × 3) clearly stand out from the table (as
    the core of :func:`colour_regions`' regions), specks of noise removed (an
    opening by a 3 × 3 square)."""
    distinct, _, threshold, _ = _distinctness(image)
    return _foreground(distinct, threshold)


def _foreground(distinct: np.ndarray, threshold: float) -> np.ndarray:
    """:func:`foreground` from the image's :func:`_distinctness` and its threshold."""
    mask = (distinct > threshold).astype(np.uint8)
    opened = cv2.morphologyEx(mask, cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))
    return np.asarray(opened, dtype=bool)


def _second_tables(
    distinct: np.ndarray,
    lab: np.ndarray,
    threshold: float,
    largest_block: float,
    record: PartRecorder,
    into: np.ndarray | None = None,
) -> bool:
    """Lowers ``distinct`` (in place) to the a*b* distance from a second table's
    colour over every region of :data:`TABLE_BLOCKS`' kind (a large, one-coloured
    region at the border); whether there was one. Their pixels are set in
    ``into`` (bool, the image's rows × columns) when it is given."""
    foreground = (distinct > threshold / 2).astype(np.uint8)
    # joined over thin dark lines (a table ruled into squares, a plank's seams):
    # closed by a 7 × 7 square first
    joined = cv2.morphologyEx(foreground, cv2.MORPH_CLOSE, np.ones((7, 7), np.uint8))
    count, labels, stats = labelled_parts(joined)
    height, width = labels.shape
    found = False
    for index in range(1, count):
        x, y, w, h, area = (int(value) for value in stats[index])
        at_border = x == 0 or y == 0 or x + w == width or y + h == height
        if not at_border or area <= TABLE_BLOCKS * largest_block:
            continue
        rows, cols = slice(y, y + h), slice(x, x + w)
        member = (labels[rows, cols] == index) & (foreground[rows, cols] > 0)
        area = int(member.sum())
        if area <= TABLE_BLOCKS * largest_block:
            continue
        taken = np.divmod(np.flatnonzero(member)[:: max(1, area // 20000)], member.shape[1])
        colour = np.median(lab[rows, cols][taken][:, 1:], axis=0)  # every (area // 20000)th
        distance = np.hypot(*(lab[rows, cols, k][member] - colour[k - 1] for k in (1, 2)))
        near = member.copy()
        near[member] = distance <= threshold
        if near.sum() < 0.5 * area:  # of many colours: not a table
            continue
        found = True
        a, b = (float(c) for c in colour)
        why = f"a*b* ({a:.0f}, {b:.0f}) over {area / largest_block:.0f} largest blocks' area"
        record(near, rows, cols, "table", why)
        if into is not None:
            into[rows, cols] |= near
        crop = distinct[rows, cols]
        crop[member] = np.minimum(crop[member], distance)
    return found


@dataclass(frozen=True, slots=True)
class _ImageColours:
    """What the regions of every connected component of an image are found from."""

    image: np.ndarray
    lab: np.ndarray
    distinct: np.ndarray
    threshold: float
    table: np.ndarray
    names: list[str]
    chroma: np.ndarray
    coloured_image: bool
    min_area: float
    record: PartRecorder
    reach: TableReach | None = None  # near a second table, if any


@dataclass(frozen=True, slots=True)
class _Crop:
    """A connected component's box (5 px around it): its pixels (RGB, a*b*, L*), its
    core pixels and the table's colour in a ring around it (RGB, a*b*, L*); ``offsets``
    the pixels' RGB change from that table colour (every face's soft mask and the
    nearest class read it: taken once)."""

    rows: slice
    cols: slice
    member: np.ndarray
    pixels: np.ndarray
    chroma: np.ndarray
    lightness: np.ndarray
    core: np.ndarray
    ground: np.ndarray
    ground_ab: np.ndarray
    ground_lightness: float
    offsets: np.ndarray


# A colour's top face: colour, mean RGB, RGB change from the table, L* of the top and
# side faces (None: none seen), a*b* change, its core pixels named its colour (crop).
_Face = tuple[str, np.ndarray, np.ndarray, float, float | None, np.ndarray, np.ndarray]


def _component_crop(
    c: _ImageColours, labels: np.ndarray, index: int, box: tuple[int, int, int, int]
) -> _Crop | None:
    """Component ``index``'s crop, or ``None`` (recorded) when too little of it is
    clearly coloured."""
    x, y, w, h = box
    height, width = labels.shape
    rows = slice(max(0, y - 5), min(height, y + h + 5))
    cols = slice(max(0, x - 5), min(width, x + w + 5))
    member = labels[rows, cols] == index
    # core: clearly foreground and two pixels in from the region's rim, where
    # anti-aliased pixels mix the table's colour into the object's
    core = erode(member, 2) & (c.distinct[rows, cols] > c.threshold)
    if core.sum() < c.min_area:
        c.record(member, rows, cols, "thin or faint", f"{int(core.sum())} clearly coloured px")
        return None
    pixels = c.image[rows, cols].astype(float)
    filled = fill_holes(member)
    ring = dilate(filled, 4) & ~dilate(filled, 1)
    ground = np.median(c.image[rows, cols][ring].T, axis=1) if ring.any() else c.table
    chroma = c.lab[rows, cols, 1:]
    ground_ab = np.median(chroma[ring].T, axis=1) if ring.any() else np.zeros(2)
    lightness = c.lab[rows, cols, 0]
    ground_lightness = float(np.median(lightness[ring])) if ring.any() else 50.0
    offsets = pixels - ground
    seen = (rows, cols, member, pixels, chroma, lightness, core)
    return _Crop(*seen, ground, ground_ab, ground_lightness, offsets)


def _block_colours(c: _ImageColours, k: _Crop) -> list[tuple[str, np.ndarray]]:
    """The colours of a component's core pixels that may be a block's (each with
    its core pixels); shades and glare left out."""
    classified = classify(k.pixels[k.core], c.chroma)
    classes = unnamed_split(classified, k.chroma[k.core], c.min_area, k.lightness[k.core])
    if c.coloured_image:
        c.record.shade(classes, k.core, k.lightness, k.rows, k.cols)
        classes[glare(classes, k.lightness, k.core, c.min_area)] = -3
    classes = smoothed_classes(classes, k.core)
    present = present_classes(classes, c.names, c.min_area, c.coloured_image)
    # one colour between two names first: its two halves, speckled through each
    # other by the noise, would each erode away as a rim
    present = one_colour_merged(present, k.chroma[k.core], k.lightness[k.core])
    # a white or grey cube on a coloured table: coloured at its rim alone
    neutral = float(np.mean(classified == -3)) if c.coloured_image else 0.0
    return without_rims(_without_shadows(c, k, present), k.core, c.min_area, neutral)


SHADOW_LIGHT = (0.35, 0.85)
"""A shadow on a coloured table keeps this share of the table's light, every
channel alike within :data:`SHADOW_TINT` (a shadow darkens, it does not tint)."""
SHADOW_TINT = 1.2


def _without_shadows(
    c: _ImageColours, k: _Crop, present: list[tuple[str, np.ndarray]]
) -> list[tuple[str, np.ndarray]]:
    """``present`` without the colours that are the coloured table's around the
    component, darker (:data:`SHADOW_LIGHT`, :data:`SHADOW_TINT`): a cube's shadow on
    a blue table is foreground by its chroma, and as a class of the component it
    took the pixels of a white or grey top beside it, which has no chroma of its own
    (the top then went to the black, white and grey regions' search)."""
    if math.hypot(*(float(v) for v in k.ground_ab)) < MIN_CHROMA or k.ground.min() <= 0:
        return present
    kept = []
    for colour, chosen in present:
        shares = k.pixels[k.core][chosen].mean(axis=0) / k.ground
        light, tint = float(shares.mean()), float(shares.max() / max(float(shares.min()), 1e-9))
        if SHADOW_LIGHT[0] <= light <= SHADOW_LIGHT[1] and tint <= SHADOW_TINT:
            held = np.zeros(k.core.shape, dtype=bool)
            held[k.core] = chosen
            c.record(
                held, k.rows, k.cols, "shadow", f"the table's colour at {light:.0%} of its light"
            )
        else:
            kept.append((colour, chosen))
    return kept


def _top_faces(c: _ImageColours, k: _Crop, present: list[tuple[str, np.ndarray]]) -> list[_Face]:
    """Each colour's top face; its side faces (darker by L*) are recorded as dropped."""
    core_pixels, core_chroma = k.pixels[k.core], k.chroma[k.core]
    core_offsets, core_lightness = k.offsets[k.core], k.lightness[k.core]
    faces: list[_Face] = []
    for colour, chosen in one_colour_merged(present, core_chroma, core_lightness):
        top_face, side_faces = lightness_modes(core_lightness[chosen])
        on_top = chosen.copy()
        if side_faces is not None:
            on_top[chosen] = core_lightness[chosen] >= (top_face + side_faces) / 2
            why = f"L* {side_faces:.0f} under {top_face:.0f}"
            c.record.side_faces(k.core, chosen & ~on_top, (k.rows, k.cols), why, colour)
        change = core_offsets[on_top].mean(axis=0)
        mean_rgb = core_pixels[on_top].mean(axis=0)
        change_ab = (core_chroma[on_top] - k.ground_ab).mean(axis=0)
        named = np.zeros(k.core.shape, dtype=bool)
        named[k.core] = chosen
        faces.append((colour, mean_rgb, change, top_face, side_faces, change_ab, named))
    return faces


def _face_alpha(c: _ImageColours, k: _Crop, face: _Face, on_class: np.ndarray) -> np.ndarray:
    """How much each pixel of the crop is ``face``'s (0–1): its colour change from
    the table against the face's, in chroma too, and its L* from side to top face
    (full from the lower quartile of the top's core pixels, :data:`FULL_LEVEL_SHARE`)."""
    _, _, change, top_face, side_faces, change_ab, _ = face
    projection = (k.offsets @ change) / max(float(change @ change), 1e-9)
    alpha: np.ndarray = np.clip(projection / full_level(projection[on_class]), 0.0, 1.0)
    if c.coloured_image:
        # and in chroma alone: a shadow beside the block darkens the table,
        # which the RGB projection would take for a part of a dark block
        chroma_part = ((k.chroma - k.ground_ab) @ change_ab) / max(
            float(change_ab @ change_ab), 1e-9
        )
        chroma_alpha = chroma_part / full_level(chroma_part[on_class])
        alpha = np.minimum(alpha, np.clip(chroma_alpha, 0.0, 1.0))
    if side_faces is not None:
        on_top = on_class & (k.lightness >= (top_face + side_faces) / 2)
        full = np.quantile(k.lightness[on_top], FULL_LEVEL_SHARE) if on_top.any() else top_face
        ramp = (k.lightness - side_faces) / max(float(full) - side_faces, 1e-9)
        alpha = np.minimum(alpha, np.clip(ramp, 0.0, 1.0))
    return alpha


def _component_regions(
    c: _ImageColours, labels: np.ndarray, index: int, box: tuple[int, int, int, int]
) -> list[ColourRegion]:
    """The colour regions of one connected component: one per colour with a top face."""
    k = _component_crop(c, labels, index, box)
    if k is None:
        return []
    present = _block_colours(c, k)
    if not present:
        c.record(k.member, k.rows, k.cols, "no block colour", "dark, grey or mixed colours")
        return []
    faces = _top_faces(c, k, present)
    # nearest class, judged on the colour change from the table under each pixel
    offsets = k.offsets.reshape(-1, 3)
    nearest = nearest_class(offsets, [face[2] for face in faces], k.member.shape)
    grown = dilate(k.member, 1)
    owners = hole_owners(k.core, nearest) if len(faces) > 1 else None
    regions: list[ColourRegion] = []
    for n, face in enumerate(faces):
        colour, centre, top_face = face[0], face[1], face[3]
        on_class = k.core & (nearest == n)
        alpha = _face_alpha(c, k, face, on_class) * (nearest == n) * grown
        # enclosed by this class's own clearly coloured pixels: a glint on a red
        # cube in a row of yellow ones is the red top's, the yellow beside it not;
        # or by the region's, bordered mostly by this class (a glint near the
        # seam, the rim between it and the neighbour thinner than the core's)
        enclosing = on_class if owners is None else on_class | (owners == n)
        on_top = highlights(k.pixels, k.lightness, (top_face, centre), enclosing, c.min_area)
        others = None if len(faces) == 1 else k.core & (nearest != n)
        fill_glints_and_prints(alpha, on_top, k.lightness, k.ground_lightness, others)
        alpha = without_strands(alpha, c.min_area)
        rgb = (float(centre[0]), float(centre[1]), float(centre[2]))
        strays = None if c.reach is None else c.reach.strays(k.rows, k.cols, face[6])
        regions.append(ColourRegion(colour, rgb, (k.rows.start, k.cols.start), alpha, strays))
    return regions


def colour_regions(
    image: np.ndarray,
    *,
    min_area: float,
    palette: Palette | None = None,
    rejected: list[RejectedPart] | None = None,
    largest_block: float | None = None,
    second_tables: np.ndarray | None = None,
    held: np.ndarray | None = None,
    lab8: np.ndarray | None = None,
) -> tuple[list[ColourRegion], np.ndarray]:
    """The colour regions of ``image`` (H × W × 3) with at least ``min_area`` core
    pixels, and the table colour (the median colour of the image); ``rejected``,
    when given, gets the parts dropped on the way, each with why. With
    ``largest_block`` (the largest block's area, px²) a second table around the
    first (:data:`TABLE_BLOCKS`) is table too, its pixels set in ``second_tables``
    (bool, the image's rows × columns) when that is given: a hand and forearm
    reaching in from the border may be one, and hide a top
    (:mod:`demoplan.perception.occlusion`). ``held`` (bool, rows × columns), when
    given, is set to :func:`foreground` (measured once for both); ``lab8``: the
    image's 8-bit CIELAB, when measured before (:func:`_distinctness`) of ``image`` as
    given; without it, ``image`` is taken with its table's colour cast divided out
    (:mod:`~demoplan.perception.white_balance`), as the detector takes it."""
    if lab8 is None:
        measures = ImageMeasures(image)
        image, lab8 = measures.image, measures.lab8
    where = f" finding coloured regions in {image.shape[1]} × {image.shape[0]} pixels"
    table = np.median(image[::4, ::4].reshape(-1, 3), axis=0).astype(float)
    check_time(where)  # a budget set by the caller (demoplan.budget), if any
    distinct, lab, threshold, coloured_image = _distinctness(image, lab8)
    record = PartRecorder(rejected, min_area)
    if held is not None:  # before a second table lowers ``distinct``
        held[...] = _foreground(distinct, threshold)
    tables = np.zeros(image.shape[:2], dtype=bool) if second_tables is None else second_tables
    reach = None
    if largest_block is not None and coloured_image:  # noqa: SIM102 (mypy narrows largest_block)
        if _second_tables(distinct, lab, threshold, largest_block, record, tables):
            reach = TableReach(tables, math.sqrt(largest_block))
    foreground = (distinct > threshold / 2).astype(np.uint8)
    check_time(where)
    count, labels, stats = labelled_parts(foreground)
    names, chroma = palette_arrays(palette)
    colours = _ImageColours(
        image, lab, distinct, threshold, table, names, chroma, coloured_image, min_area, record
    )
    colours = replace(colours, reach=reach)
    areas = stats[1:count, cv2.CC_STAT_AREA]
    if rejected is not None:  # smaller than a block: noise, a speck (reported from a size on)
        specks = (areas < min_area) & (areas >= REPORTED_SHARE * min_area)
        for index in np.flatnonzero(specks) + 1:
            record.speck(labels, int(index), tuple(int(v) for v in stats[index]))
    regions: list[ColourRegion] = []
    for index in np.flatnonzero(areas >= min_area) + 1:
        x, y, w, h, _ = (int(value) for value in stats[index])
        check_time(where)
        regions += _component_regions(colours, labels, int(index), (x, y, w, h))
    if coloured_image:  # black, white and grey blocks by lightness (without colour: above)
        check_time(where)
        for colour, rgb, offset, alpha in achromatic_regions(
            image, lab, _covered(regions, foreground.shape), min_area, record
        ):
            regions.append(ColourRegion(colour, rgb, offset, alpha))
    return regions, table


def _covered(regions: list[ColourRegion], shape: tuple[int, ...]) -> np.ndarray:
    """The pixels of an image of ``shape`` that ``regions`` hold (α > ½)."""
    covered = np.zeros(shape[:2], dtype=bool)
    for region in regions:
        (row, col), (rows, cols) = region.offset, region.alpha.shape
        covered[row : row + rows, col : col + cols] |= region.alpha > 0.5
    return covered
