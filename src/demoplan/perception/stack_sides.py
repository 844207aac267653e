"""The side faces of a stack's lower cubes, told by one perspective over the whole
photograph.

A camera above the table sees a standing cube's side faces between its top and
the camera's nadir (the image point straight below the camera): its vertical
edges point at the nadir, and its side strip grows with the distance from it.
Each top's own side strip — its material lit less, beside it — is measured
(:func:`side_strip`: the strip is the top's outline swept towards the nadir, so
its centroid lies on the line from the top's centre to the nadir); the nadir is
where the strips' lines meet (:func:`nadir_of`: of the lines' crossings, the one
most strips point at, refitted by least squares to those), one point for every
standing cube of the photograph.

A tall stack seen off the nadir shows a long strip of side faces running from
its top towards the nadir: its top cube's side face in the top's colour, then
its lower cubes' side faces in theirs (mrhan_stacks, bottom right: green tops
above green, orange and blue side faces, about 100 mm and 185 mm high in the
photograph's aligned depth frame). A lower cube's side face, squarish in its
foreshortened view, fits a square as a top does. :func:`lower_side_faces` tells
it: it lies on the line from a top to the nadir, nearer the nadir, where that top
shows its own side strip (so nothing touches the top there), on foreground that
runs on from the top without a gap of table. (A cube standing against a stack's
foot on the nadir's side, of another colour than its top, would be taken for its
side face: only heights — a depth frame — would tell them apart.)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from demoplan.perception.colours import foreground
from demoplan.perception.image_measures import ImageMeasures, measures_of
from demoplan.perception.opencv import cv2
from demoplan.perception.palette import MIN_CHROMA, SIDE_FACE_GAP
from demoplan.perception.side_faces import MAX_HUE_TURN, ImageSquare

__all__ = [
    "Nadir",
    "SideStrip",
    "lower_side_faces",
    "nadir_of",
    "side_strip",
    "standing_tops",
    "upturned_faces",
]

_RAYS = (-0.25, 0.0, 0.25)
"""Parallel rays (shares of the top's side across the way to the nadir) whose median
run of foreground is the stack's."""
MIN_STRIP = 0.1
"""The least length (share of the top's side) of a side strip that shows a direction."""
PAST_OUTLINE = 1.1
"""How far out (a share of the half side, from the top's centre) a side strip's
pixels are counted: an outline's blend with the table or a shadow beside it is as
dark as a side face, and of the top's hue."""
MAX_MISS = 15.0
"""Degrees by which a strip's direction may miss the nadir and count in its fit."""
STRIP_GAP = SIDE_FACE_GAP / 2
"""L* by which a side strip's pixels are darker than their top at least: a face
turned to the light may be lit nearly as a top (mrhan_stacks' 180 mm stack: its
top at L* 42, its side faces at 32 and 20)."""

MAX_SEAM = 0.2
"""The widest gap (share of the top's side) in the foreground along a stack's side
strip: a dark, dull side face between two cubes (mrhan_stacks' 100 mm stack: L* 17,
chroma 21 between its green top and a blue cube) may not stand out from the table."""


class SideStrip(NamedTuple):
    """A top's own side strip: its direction (radians; image x right, y down) and its
    length (px) from the top's edge."""

    direction: float
    length: float


class Nadir(NamedTuple):
    """The image point below the camera (x right, y down; px)."""

    x: float
    y: float


def _lab(image: np.ndarray) -> np.ndarray:
    """CIELAB (L* 0–100) of ``image`` (H × W × 3, 8-bit RGB), smoothed over 3 × 3 px
    (:attr:`~demoplan.perception.image_measures.ImageMeasures.smooth_lab`)."""
    return ImageMeasures(image).smooth_lab


def _at(values: np.ndarray, xs: np.ndarray, ys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``values`` at the image points (xs, ys), and which of them lie on the image."""
    height, width = values.shape[:2]
    cols, rows = np.floor(xs).astype(np.intp), np.floor(ys).astype(np.intp)
    inside = (rows >= 0) & (rows < height) & (cols >= 0) & (cols < width)
    return values[np.clip(rows, 0, height - 1), np.clip(cols, 0, width - 1)], inside


def _runs(held: np.ndarray, first: int, gap: int) -> np.ndarray:
    """Per row of ``held`` (rays × steps of 1 px): the steps to where its run ends,
    the run begun within ``first`` steps and gaps of up to ``gap`` px bridged (0 when
    no run begins there)."""
    lengths = np.zeros(held.shape[0])
    for row, line in enumerate(held):
        hits = np.flatnonzero(line)
        if not hits.size or hits[0] > first:
            continue
        breaks = np.flatnonzero(np.diff(hits) > gap + 1)
        last = hits[breaks[0]] if breaks.size else hits[-1]
        lengths[row] = last + 1
    return lengths


def _measurable(square: ImageSquare) -> bool:
    """Whether ``square`` has a size and is finite: one to measure."""
    return all(math.isfinite(value) for value in square) and square[3] > 0


def _top_colour(lab: np.ndarray, square: ImageSquare) -> tuple[float, float, float]:
    """The L*, a*, b* of ``square``'s top: over 8 × 8 points on its central half, the
    upper quartile of L* of the more coloured half of them (a fit that covers some of
    its own side strip is read by its lit part; a glint, white added, is no lit part:
    on a purple top in a row it read the top 12 L* over its neighbour, which was then
    taken for a stack's side face) and the median a*, b* (black for a square not
    :func:`_measurable`)."""
    if not _measurable(square):
        return 0.0, 0.0, 0.0
    x, y, theta, side = square
    c, s = math.cos(math.radians(theta)), math.sin(math.radians(theta))
    steps = ((np.arange(8) + 0.5) / 8 * 0.5 - 0.25) * side
    along, across = np.meshgrid(steps, steps)
    seen, inside = _at(lab, x + c * along - s * across, y - (s * along + c * across))
    points = seen[inside]
    if not points.size:
        return 0.0, 0.0, 0.0
    chroma = np.hypot(points[:, 1], points[:, 2])
    lit = points[chroma >= np.median(chroma)]  # a glint whitens, a side strip darkens
    return (
        float(np.percentile(lit[:, 0], 75)),
        float(np.median(points[:, 1])),
        float(np.median(points[:, 2])),
    )


def side_strip(
    lab: np.ndarray,
    square: ImageSquare,
    top: tuple[float, float, float] | None = None,
    others: Sequence[ImageSquare] = (),
) -> SideStrip | None:
    """``square``'s own side strip in ``lab`` (:func:`_lab` of the image): the pixels
    of its material lit less (L* at least
    :data:`STRIP_GAP` below its top's — ``top``, or :func:`_top_colour` — hue within
    :data:`~demoplan.perception.side_faces.MAX_HUE_TURN`) connected to its outline
    (from 0.8 of its half side out: the fit may cover the strip's start), counted
    from :data:`PAST_OUTLINE` out. The strip
    is the outline swept towards the nadir, so its centroid lies on that line
    through the top's centre; its length is how far it reaches past the outline
    (95th percentile; seen along the nadir's way past a side, across it past a
    corner). The ``others`` squares' insides are no strip: a touching
    neighbour's top of the hue, a little darker, would point along its row
    (touching_rows), not at the nadir. ``None`` for an achromatic top, a strip
    under :data:`MIN_STRIP` of its side, or a square of no size or not wholly
    finite (nothing to measure)."""
    if not _measurable(square):
        return None
    x, y, _, side = square
    lightness, a, b = _top_colour(lab, square) if top is None else top
    if math.hypot(a, b) < MIN_CHROMA:
        return None
    reach = math.ceil(2 * side)  # a strip up to 1.3 sides past a corner, 1.5 past a side
    rows = slice(max(0, math.floor(y) - reach), min(lab.shape[0], math.floor(y) + reach))
    cols = slice(max(0, math.floor(x) - reach), min(lab.shape[1], math.floor(x) + reach))
    crop = lab[rows, cols]
    chroma = np.hypot(crop[..., 1], crop[..., 2])
    turned = crop[..., 1] * a + crop[..., 2] * b  # the cosine of the hue turn, scaled
    hue_cosine = turned / (math.hypot(a, b) * np.maximum(chroma, 1e-6))
    material = (
        (crop[..., 0] <= lightness - STRIP_GAP)
        & (chroma >= MIN_CHROMA)
        & (hue_cosine >= math.cos(math.radians(MAX_HUE_TURN)))
    )
    yy, xx = np.mgrid[rows, cols]
    box = _box(xx, yy, square)
    dx, dy = xx + 0.5 - x, yy + 0.5 - y
    for other in others:
        if _measurable(other):
            _outside(material, other, rows.start, cols.start)
    # opened: a top's outline drawn darker (a render's edge, a bevel) is no strip
    opened = cv2.morphologyEx(material.astype(np.uint8), cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))
    material = opened > 0
    count, labels = cv2.connectedComponents(opened, connectivity=8)
    touching = np.unique(labels[material & (box >= 0.8) & (box <= 1.2)])
    strip = np.isin(labels, touching[touching > 0]) & (box >= PAST_OUTLINE)
    if count <= 1 or np.count_nonzero(strip) < MIN_STRIP * side * side / 2:
        return None
    centroid = np.array([dx[strip].mean(), dy[strip].mean()])
    direction = math.atan2(float(centroid[1]), float(centroid[0]))
    length = float(np.percentile(box[strip] - 1.0, 95)) * side / 2  # past the outline
    return SideStrip(direction, length) if length >= MIN_STRIP * side else None


def _outside(held: np.ndarray, square: ImageSquare, row0: int, col0: int) -> None:
    """``held`` (a crop whose first row and column are ``row0``, ``col0`` of the
    image) left only outside ``square`` (or on its outline: :func:`_box` ≥ 1), in
    place. Only the crop's pixels within the square's reach (its centre's distance
    to a corner, and a pixel more) are looked at: a pixel farther out is outside
    it, whatever its turn — the same mask as :func:`_box` over the whole crop."""
    x, y, _, side = square
    reach = side / math.sqrt(2) + 1.0
    rows = slice(max(row0, math.floor(y - reach)), min(row0 + held.shape[0], math.ceil(y + reach)))
    cols = slice(max(col0, math.floor(x - reach)), min(col0 + held.shape[1], math.ceil(x + reach)))
    if rows.start >= rows.stop or cols.start >= cols.stop:
        return
    yy, xx = np.mgrid[rows, cols]
    held[rows.start - row0 : rows.stop - row0, cols.start - col0 : cols.stop - col0] &= (
        _box(xx, yy, square) >= 1.0
    )


def _box(xx: np.ndarray, yy: np.ndarray, square: ImageSquare) -> np.ndarray:
    """Per pixel (columns ``xx``, rows ``yy``): its distance from ``square``'s centre
    in the square's own axes (the larger of the two), a share of the half side (1:
    on the outline)."""
    x, y, theta, side = square
    dx, dy = xx + 0.5 - x, yy + 0.5 - y
    c, s = math.cos(math.radians(theta)), math.sin(math.radians(theta))
    box: np.ndarray = np.maximum(np.abs(c * dx - s * dy), np.abs(s * dx + c * dy)) / (side / 2)
    return box


def nadir_of(
    squares: Sequence[ImageSquare], strips: Sequence[SideStrip | None]
) -> Nadir | None:
    """The point where the lines of the tops' side strips meet: of the points where
    two of them cross, the one the most strips point at (within :data:`MAX_MISS`;
    ties: the least total miss), refitted by least squares (over the lines'
    perpendicular distances) to the strips pointing at it; ``None`` unless two
    strips, not parallel, point at it."""
    lines = [
        (np.array(square[:2]), _unit(strip.direction))
        for square, strip in zip(squares, strips, strict=True)
        if strip is not None
    ]
    if len(lines) < 2:
        return None
    starts = np.array([start for start, _ in lines])
    directions = np.array([direction for _, direction in lines])
    crossings = _crossings(starts, directions)
    if not len(crossings):
        return None
    ways = crossings[:, None, :] - starts[None, :, :]  # crossing × line × 2
    cosines = np.einsum("kij,ij->ki", ways, directions) / np.maximum(
        np.linalg.norm(ways, axis=2), 1e-9
    )
    misses = np.degrees(np.arccos(np.clip(cosines, -1.0, 1.0)))
    counts = np.count_nonzero(misses <= MAX_MISS, axis=1)
    totals = np.minimum(misses, 90.0).sum(axis=1)
    chosen = int(np.lexsort((totals, -counts))[0])  # the most strips, then the least miss
    best = (int(counts[chosen]), crossings[chosen])
    if best[0] < 2:
        return None
    point = best[1]
    for _ in range(2):  # the strips pointing at it, and at their own meeting point
        pointing = _misses(starts, directions, point) <= MAX_MISS
        inliers = [line for line, held in zip(lines, pointing, strict=True) if held]
        refitted = _meeting(inliers) if len(inliers) >= 2 else None
        if refitted is None:
            break
        point = refitted
    return Nadir(float(point[0]), float(point[1]))


def _crossings(starts: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """The points (k × 2) where two of the lines (``starts``, unit ``directions``:
    n × 2 each) cross, of every pair not nearly parallel (under 1° apart)."""
    first, second = np.triu_indices(len(starts), k=1)
    d1, d2 = directions[first], directions[second]
    cross = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    apart = starts[second] - starts[first]
    crossing = np.abs(cross) > math.sin(math.radians(1.0))
    along = (apart[:, 0] * d2[:, 1] - apart[:, 1] * d2[:, 0])[crossing] / cross[crossing]
    points: np.ndarray = starts[first][crossing] + along[:, None] * d1[crossing]
    return points


def _meeting(lines: Sequence[tuple[np.ndarray, np.ndarray]]) -> np.ndarray | None:
    """The point nearest ``lines`` (each a point and a unit direction) by least
    squares over the perpendicular distances; ``None`` when they are parallel."""
    normal = np.zeros((2, 2))
    target = np.zeros(2)
    for point, direction in lines:
        across = np.eye(2) - np.outer(direction, direction)
        normal += across
        target += across @ point
    if np.linalg.cond(normal) > 1e4:
        return None  # parallel: they meet nowhere in particular
    meeting: np.ndarray = np.linalg.solve(normal, target)
    return meeting


def _misses(starts: np.ndarray, directions: np.ndarray, point: np.ndarray) -> np.ndarray:
    """Degrees between each of ``directions`` and the way from its start to ``point``."""
    ways = point[None, :] - starts
    lengths = np.maximum(np.linalg.norm(ways, axis=1), 1e-9)
    cosines = np.einsum("ij,ij->i", directions, ways) / lengths
    misses: np.ndarray = np.degrees(np.arccos(np.clip(cosines, -1.0, 1.0)))
    return misses


def _miss(start: np.ndarray, direction: np.ndarray, point: np.ndarray) -> float:
    """Degrees between ``direction`` and the way from ``start`` to ``point``."""
    way = point - start
    cosine = float(direction @ way) / max(float(np.linalg.norm(way)), 1e-9)
    return math.degrees(math.acos(max(-1.0, min(1.0, cosine))))


def lower_side_faces(
    image: np.ndarray | ImageMeasures,
    squares: Sequence[ImageSquare],
    held: np.ndarray | None = None,
) -> dict[int, str]:
    """The indices of ``squares`` (accepted in ``image``) that are side faces of a
    stack's lower cubes, each with why: a square whose centre lies on the line from
    a top to the nadir (within half the top's side of it), nearer the nadir than the
    top (overlapping it by a quarter of its side at most: the fit may take in the
    top's own strip), the top's own side strip pointing at the nadir (within
    :data:`MAX_MISS`: nothing touches the top there, and it stands as the other
    cubes do) and the square's not (:func:`_stands`: a standing cube's top shows
    its own strip there; a lower cube's side face has the next cube's side below
    it, or the table), the square not lit as a neighbour's top of its hue
    (:func:`_neighbour_top`), and within the foreground
    (:func:`~demoplan.perception.colours.foreground`) that runs on from the top
    towards the nadir without a gap (``held``, when the caller has it). Nothing
    without a nadir (:func:`nadir_of`). ``image``: the photograph, or its measures
    (:mod:`demoplan.perception.image_measures`)."""
    if len(squares) < 3:
        return {}
    measures = measures_of(image)
    lab = measures.smooth_lab
    colours = [_top_colour(lab, square) for square in squares]
    strips, nadir = _strips_and_nadir(measures, squares, colours)
    if nadir is None:
        return {}
    held = foreground(measures.image) if held is None else held
    standing = [_stands(sq, strip, nadir) for sq, strip in zip(squares, strips, strict=True)]
    found: dict[int, str] = {}
    for top, upright, colour in zip(squares, standing, colours, strict=True):
        if not upright:
            continue
        way = np.array([nadir.x - top[0], nadir.y - top[1]])
        distance = float(np.linalg.norm(way))
        toward = way / distance
        extent = _foreground_run(held, top, toward, distance)
        for index, face in enumerate(squares):
            if standing[index] or _neighbour_top(colour, colours[index]):
                continue  # a top: its own strip hangs below it, or it is lit as one
            offset = np.array([face[0] - top[0], face[1] - top[1]])
            along = float(offset @ toward)
            aside = abs(float(offset[0] * toward[1] - offset[1] * toward[0]))
            if aside <= top[3] / 2 and along - face[3] / 2 >= top[3] / 4 and along <= extent:
                found.setdefault(
                    index,
                    f"a stack's side face: on the line from a top at ({top[0]:.0f}, "
                    f"{top[1]:.0f}) px towards the camera's nadir at ({nadir.x:.0f}, "
                    f"{nadir.y:.0f}), beside that top's side strip",
                )
    return found


def _strips_and_nadir(
    measures: ImageMeasures,
    squares: Sequence[ImageSquare],
    colours: Sequence[tuple[float, float, float]],
) -> tuple[tuple[SideStrip | None, ...], Nadir | None]:
    """Each of ``squares``' own side strip (:func:`side_strip`, the insides of the
    others lit as a neighbour's top of its hue left out: :func:`_neighbour_top`)
    and the nadir they point at (:func:`nadir_of`). A lower cube's side face,
    darker, stays in: the fit of one may take in the top's own strip. Made once
    per photograph and squares (``measures.answers``): the detector asks
    :func:`upturned_faces` and then :func:`lower_side_faces` of the same squares."""
    key = ("stack_sides.strips", tuple(squares))
    known: tuple[tuple[SideStrip | None, ...], Nadir | None] | None = measures.answers.get(key)
    if known is not None:
        return known
    lab = measures.smooth_lab
    strips = tuple(
        side_strip(
            lab,
            sq,
            colour,
            [
                other
                for index, other in enumerate(squares)
                if index != own and _neighbour_top(colour, colours[index])
            ],
        )
        for own, (sq, colour) in enumerate(zip(squares, colours, strict=True))
    )
    known = strips, nadir_of(squares, strips)
    measures.answers[key] = known
    return known


def standing_tops(
    image: np.ndarray | ImageMeasures, squares: Sequence[ImageSquare]
) -> frozenset[int]:
    """The indices of ``squares`` (accepted in ``image``) that stand as the
    photograph's cubes do: each shows its own side strip towards the nadir the
    strips of all of them point at (:func:`nadir_of`) — it has a height, so it is
    no flat patch. None without a nadir. ``image``: the photograph, or its measures
    (:mod:`demoplan.perception.image_measures`)."""
    if len(squares) < 3:
        return frozenset()
    measures = measures_of(image)
    colours = [_top_colour(measures.smooth_lab, square) for square in squares]
    strips, nadir = _strips_and_nadir(measures, squares, colours)
    if nadir is None:
        return frozenset()
    return frozenset(
        index
        for index, (square, strip) in enumerate(zip(squares, strips, strict=True))
        if _stands(square, strip, nadir)
    )


WIDEST_VIEW = 90.0
"""Degrees: the widest field of view across an image's longer side taken for its
camera (a phone's or a depth camera's is 60–75°): its focal length is at least
half that side, the least for which :func:`upturned_faces` bounds a side strip."""


def upturned_faces(
    image: np.ndarray | ImageMeasures, squares: Sequence[ImageSquare]
) -> dict[int, str]:
    """The indices of ``squares`` (accepted in ``image``) whose own side strip no
    standing cube shows there, each with why: a face turned up on something lying
    on the table (a row of cubes tipped over shows each cube's lit face and a deep,
    darker strip beside it). A standing cube's top of side ``a`` px, ``r`` px from
    the nadir, shows its side face as a strip towards the nadir ``a · r / f`` px
    deep (``f``: the focal length in px; the strip is the cube's height seen from
    the camera's height, as the top's side is its width); ``f`` is at least half
    the image's longer side (:data:`WIDEST_VIEW`). A strip that points away from
    the nadir (over 90°) and runs deeper than ``r / f`` of the side, and
    :data:`MIN_STRIP` more (the fit's and the outline's slack), but less than
    0.71 of the side and :data:`MIN_STRIP` more (one face of a cube lying on an
    edge is under 0.71 of the side across; a deeper strip is more than one face
    — a neighbour's top of its hue darker), is not a top's.
    Judged only where three strips or more meet at no nadir (:func:`nadir_of`):
    the nadir is then taken at the image's centre, the camera straight down, as
    the scale from the cube size takes it. (A lone cube's strip says nothing of
    the camera: a phone held at an angle shows a side face half a side deep on
    any side of a top; where a tilted camera's cubes show strips, they meet.)
    (Where they meet, rows of touching cubes may have put it hundreds of px off
    — their strips are the next cube's top — and a row's middle cube, a strip
    deep, would be taken for a face turned up.)"""
    if not squares:
        return {}
    measures = measures_of(image)
    lab = measures.smooth_lab
    colours = [_top_colour(lab, square) for square in squares]
    strips, found = _strips_and_nadir(measures, squares, colours)
    if found is not None or sum(strip is not None for strip in strips) < 3:
        return {}  # the strips' own nadir (lower_side_faces judges by it), or too few
    height, width = lab.shape[:2]
    nadir = Nadir(width / 2, height / 2)
    focal = max(height, width) / 2 / math.tan(math.radians(WIDEST_VIEW / 2))
    upturned: dict[int, str] = {}
    for index, (square, strip) in enumerate(zip(squares, strips, strict=True)):
        if strip is None:
            continue
        distance = math.hypot(nadir.x - square[0], nadir.y - square[1])
        deepest = distance / focal + MIN_STRIP
        miss = _miss(np.array(square[:2]), _unit(strip.direction), np.array(nadir))
        if miss > 90.0 and deepest * square[3] < strip.length < (0.71 + MIN_STRIP) * square[3]:
            upturned[index] = (
                f"a face turned up, no top: its darker strip {strip.length:.0f} px deep "
                f"points away from the camera's nadir at ({nadir.x:.0f}, {nadir.y:.0f}), "
                f"where a standing cube's shows {deepest * square[3]:.0f} px at most"
            )
    return upturned


def _neighbour_top(top: tuple[float, float, float], face: tuple[float, float, float]) -> bool:
    """Whether ``face`` (L*, a*, b*) may be the top of a cube touching ``top``'s, in
    less light: both coloured, of one hue (within
    :data:`~demoplan.perception.side_faces.MAX_HUE_TURN`) and less than
    :data:`~demoplan.perception.palette.SIDE_FACE_GAP` L* darker — not lit as a
    side face is (touching_rows: a row of one colour, its far cubes darker)."""
    if min(math.hypot(top[1], top[2]), math.hypot(face[1], face[2])) < MIN_CHROMA:
        return False
    turn = math.degrees(math.atan2(face[2], face[1]) - math.atan2(top[2], top[1]))
    same_hue = abs((turn + 180.0) % 360.0 - 180.0) <= MAX_HUE_TURN
    return same_hue and top[0] - face[0] < SIDE_FACE_GAP


def _stands(square: ImageSquare, strip: SideStrip | None, nadir: Nadir) -> bool:
    """Whether ``square`` shows its own side strip towards ``nadir`` (within
    :data:`MAX_MISS`), as a standing cube's top does, and lies a side or more from it."""
    way = np.array([nadir.x - square[0], nadir.y - square[1]])
    if strip is None or float(np.linalg.norm(way)) < square[3]:
        return False
    return _miss(np.array(square[:2]), _unit(strip.direction), np.array(nadir)) <= MAX_MISS


def _unit(angle: float) -> np.ndarray:
    """The unit vector at ``angle`` (radians)."""
    return np.array([math.cos(angle), math.sin(angle)])


def _foreground_run(
    held: np.ndarray, top: ImageSquare, toward: np.ndarray, distance: float
) -> float:
    """How far (px from ``top``'s centre) the foreground ``held`` runs on from it towards
    the nadir (``toward``, ``distance`` px away), gaps of up to :data:`MAX_SEAM` of
    its side bridged: the median over three parallel rays. The rays are walked to
    the nadir or off the image, whichever comes first: strips a degree apart meet
    hundreds of thousands of pixels away, and no foreground runs past the border."""
    off_image = math.hypot(*held.shape[:2]) + top[3]  # from a centre on the image
    steps = np.arange(0.0, min(distance, off_image))
    across = np.multiply(_RAYS, top[3])[:, None]
    xs = top[0] + toward[0] * steps[None, :] - toward[1] * across
    ys = top[1] + toward[1] * steps[None, :] + toward[0] * across
    seen, inside = _at(held, xs, ys)
    bridged = max(2, round(MAX_SEAM * top[3]))
    runs = _runs(seen & inside, 2, bridged)
    return float(np.median(runs))
