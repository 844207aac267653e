"""The colour classes of one foreground region (:mod:`~demoplan.perception.colours`).

A region's confidently coloured ("core") pixels are named by the palette
(:func:`~demoplan.perception.palette.classify`); the unnamed ones parted by colour
(:func:`unnamed_split`), each pixel's class smoothed over its neighbours
(:func:`smoothed_classes`), the classes of one colour merged
(:func:`one_colour_merged`) and rims and strips given to the faces
(:func:`without_rims`). A class's lightness modes tell its top face from its side
faces (:func:`lightness_modes`); every pixel then goes to the nearest class
(:func:`nearest_class`) and a soft mask loses the strands hanging on its faces
(:func:`without_strands`).
"""

from __future__ import annotations

import math

import numpy as np

from demoplan.perception.exposure import chroma_apart
from demoplan.perception.masks import CROSS, distances, erode
from demoplan.perception.opencv import cv2
from demoplan.perception.palette import MIN_CHROMA, SIDE_FACE_GAP, SPECIAL_NAMES, UNNAMED


def present_classes(
    classes: np.ndarray, names: list[str], min_area: float, coloured_image: bool
) -> list[tuple[str, np.ndarray]]:
    """The colours of a region's core pixels (``classes``, per pixel) that cover
    at least ``min_area``, each with its pixels; in a coloured image not the
    dark or grey ones (a coloured region's side faces, its shadow)."""
    present = []
    for label in np.unique(classes):
        if label in (-2, -3) and coloured_image:
            continue
        chosen = classes == label
        if chosen.sum() >= min_area:
            colour = names[label] if label >= 0 else SPECIAL_NAMES[max(int(label), UNNAMED)]
            present.append((colour, chosen))
    return present


FULL_LEVEL_SHARE = 0.25
"""A class's soft mask is 1 from the level this share of its core pixels falls
under (its top face's texture, grain and shading make the rest brighter or more
coloured than the mean, the mean itself short of full for a quarter to half of the
face); a pixel mixed with the table is below it."""

CLASS_SMOOTHING = 5
"""Side (px) of the square over which a pixel's distances to the classes are
averaged before the nearest is taken: two near hues (blue and violet cubes side by
side) are told apart by their faces, not pixel by pixel through the noise."""


def full_level(values: np.ndarray) -> float:
    """The level of a soft mask's measure (a projection on the class's colour change)
    that counts as fully covered: :data:`FULL_LEVEL_SHARE`'s quantile of the class's
    core pixels, at most 1 (the class's mean change) and at least 0.5."""
    if values.size == 0:
        return 1.0
    return float(np.clip(np.quantile(values, FULL_LEVEL_SHARE), 0.5, 1.0))


def smoothed_classes(classes: np.ndarray, core: np.ndarray) -> np.ndarray:
    """The core pixels' classes (``classes``, over ``core``'s pixels), each the
    most common among the core pixels of :data:`CLASS_SMOOTHING`'s square around
    it (counted in 8 bits): a face's pixels whose colour the noise or the texture
    put nearer another palette colour (a blue cube's speckles of violet) take their face's."""
    labels = np.unique(classes)
    if labels.size < 2:
        return classes
    size = (CLASS_SMOOTHING, CLASS_SMOOTHING)
    votes = []
    for label in labels:
        mask = np.zeros(core.shape, dtype=np.uint8)
        mask[core] = classes == label
        votes.append(np.asarray(cv2.boxFilter(mask, -1, size, normalize=False))[core])
    smoothed: np.ndarray = labels[np.argmax(np.stack(votes, axis=1), axis=1)]
    return smoothed


def without_strands(alpha: np.ndarray, min_area: float) -> np.ndarray:
    """``alpha`` without the strands that hang on its faces — a pen line drawn on
    the board, a cable, a thin shadow or a sliver of side face: the parts of its
    mask (α > ½) that an opening by a disc a sixth of the smallest block's side
    across removes, regrown by that much within the mask (a square's corners come
    back; a strand keeps a stub) and a pixel more for the soft edge."""
    steps = max(1, round(math.sqrt(min_area / 0.3) / 6))
    mask = (alpha > 0.5).astype(np.uint8)
    disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * steps + 1, 2 * steps + 1))
    kept = cv2.morphologyEx(mask, cv2.MORPH_OPEN, disc)
    if np.array_equal(kept, mask):
        return alpha
    for _ in range(steps + 1):
        kept = cv2.bitwise_and(cv2.dilate(kept, CROSS), mask)
    kept = cv2.dilate(kept, CROSS, iterations=2)
    trimmed: np.ndarray = alpha * kept
    return trimmed


def one_colour_merged(
    present: list[tuple[str, np.ndarray]], core_chroma: np.ndarray, light: np.ndarray
) -> list[tuple[str, np.ndarray]]:
    """The classes of a region with those of one colour merged: two classes whose
    mean a*b* (core pixels: ``core_chroma``, N × 2) lie less than :data:`MIN_CHROMA`
    apart (two unnamed ones as lit to mid grey: L* ``light``, :mod:`~.exposure`) —
    no farther than the table is from a block — are one colour that falls between
    two palette names (a dark red between red and wood), its pixels split by the
    noise; the merged class takes the name of the larger."""
    groups = sorted(present, key=lambda group: -int(group[1].sum()))  # the larger first
    merged = True
    while merged and len(groups) > 1:
        means = [np.mean(core_chroma[chosen], axis=0) for _, chosen in groups]
        lit = [float(np.mean(light[c])) if n == "block" else 100.0 for n, c in groups]
        pairs = [
            (i, j)
            for i in range(len(groups))
            for j in range(i + 1, len(groups))
            if not chroma_apart(means[i], means[j], (lit[i], lit[j]), MIN_CHROMA)
        ]
        merged = bool(pairs)
        if merged:
            first, second = pairs[0]
            groups[first] = (groups[first][0], groups[first][1] | groups[second][1])
            del groups[second]
    return groups


def unnamed_split(
    classes: np.ndarray, core_chroma: np.ndarray, min_area: float, light: np.ndarray
) -> np.ndarray:
    """The core pixels' classes (``classes``) with those no plain colour is near
    (:data:`UNNAMED`) parted by colour: halved again and again along their a*b*
    (``core_chroma``, N × 2) by two-means while the halves' means lie at least
    :data:`MIN_CHROMA` apart as lit to mid grey (:func:`~.exposure.chroma_apart`;
    L* ``light``) — two colours, as far apart as a block from the table —
    and each half holds ``min_area`` pixels; the parts are the classes −4, −5, ….
    A dark red cube beside a bluish green one, neither near a palette colour, is
    then two classes, not one whose darker part (the red top) would be taken for
    its side faces; one colour's noise splits it into halves far closer than that."""
    unnamed = np.flatnonzero(classes == UNNAMED)
    parts = [unnamed]
    done: list[np.ndarray] = []
    while parts:
        part = parts.pop()
        halves = _two_means(core_chroma[part])
        if halves is None or min(halves.sum(), (~halves).sum()) < min_area:
            done.append(part)
            continue
        means = [core_chroma[part][half].mean(axis=0) for half in (halves, ~halves)]
        lights = [float(light[part][half].mean()) for half in (halves, ~halves)]
        if not chroma_apart(means[0], means[1], (lights[0], lights[1]), MIN_CHROMA):
            done.append(part)
            continue
        parts += [part[halves], part[~halves]]
    split = classes.copy()
    for number, part in enumerate(sorted(done, key=len, reverse=True)):
        split[part] = UNNAMED - number
    return split


def _two_means(points: np.ndarray, steps: int = 10) -> np.ndarray | None:
    """Which of ``points`` (N × 2) fall in the first of two clusters (Lloyd's
    iterations from the two ends of their principal axis; deterministic), or
    ``None`` when fewer than two points differ."""
    if len(points) < 2:
        return None
    centred = points - points.mean(axis=0)
    _, _, axes = np.linalg.svd(centred[:: max(1, len(points) // 4000)], full_matrices=False)
    along = centred @ axes[0]
    if float(along.max() - along.min()) <= 0:
        return None
    centres = np.stack([points[np.argmin(along)], points[np.argmax(along)]])
    first = np.ones(len(points), dtype=bool)
    for _ in range(steps):
        distance = distances(points, centres)
        first = distance[:, 0] <= distance[:, 1]
        if first.all() or not first.any():
            return None
        moved = np.stack([points[first].mean(axis=0), points[~first].mean(axis=0)])
        if np.all(np.abs(moved - centres) <= 1e-8 + 1e-5 * np.abs(centres)):  # np.allclose's test
            break
        centres = moved
    return first


NEUTRAL_CORE_SHARE = 0.5
"""A region whose clearly coloured pixels the palette finds grey (no hue, light
enough to tell: :func:`~demoplan.perception.palette.classify`'s −3) over this share,
in an image with colour, is a white or grey cube on a coloured table when no class
of it holds a face (:func:`without_rims`): its top and side faces have no chroma,
only its rim, where its edges blur into the table and its shadow, has some. Pixels
too dark to show a hue (−2) do not count: a dark green cube in a dim photograph is
mostly such pixels, its green class a thin rim, and a block."""


def without_rims(
    present: list[tuple[str, np.ndarray]], core: np.ndarray, min_area: float, neutral: float = 0.0
) -> list[tuple[str, np.ndarray]]:
    """The classes of a region that hold a face: a class whose core pixels
    (``chosen``, over ``core``'s pixels) vanish when eroded by a sixth of the
    smallest block's side is a rim or a strip — a block's edge where its colour
    mixes with the table's (a violet block's rim looks blue), a side face of
    another hue — and its pixels go to the classes that remain (the largest class
    stays when none holds a face). None when none holds a face and over
    :data:`NEUTRAL_CORE_SHARE` of the core is ``neutral`` (its share of grey
    pixels, without hue): a white cube on a blue table is foreground by its chroma, but its
    only class is its rim's, the table's blue mixed with the cube's edge and shadow
    — whose soft mask, filling the white top and its grey side face as a glint of
    the rim, was one region of both, "not filled" by a square (the patterned family's
    draw 162408); the black, white and grey search finds the cube by its lightness."""
    rims_only = neutral > NEUTRAL_CORE_SHARE
    if len(present) < 2 and not (rims_only and present):
        return present
    steps = max(1, round(math.sqrt(min_area / 0.3) / 6))
    faces = []
    for colour, chosen in present:
        mask = np.zeros_like(core)
        mask[core] = chosen
        if erode(mask, steps).sum() >= min_area / 4:
            faces.append((colour, chosen))
    if faces or rims_only:
        return faces
    return [max(present, key=lambda found: int(found[1].sum()))]


def nearest_class(
    offsets: np.ndarray, changes: list[np.ndarray], shape: tuple[int, ...]
) -> np.ndarray:
    """Per pixel of a crop of ``shape`` (its colour change from the table, N × 3),
    the class whose change (``changes``) it is nearest to: off the change's line,
    less a bonus for going far along it, averaged over :data:`CLASS_SMOOTHING`'s
    square. All 0 with one class (nothing to compare)."""
    if len(changes) == 1:
        return np.zeros(shape, dtype=np.intp)
    scores = np.stack([_class_score(offsets, c) for c in changes], axis=1).reshape(
        *shape, len(changes)
    )
    size = (CLASS_SMOOTHING, CLASS_SMOOTHING)
    smoothed = np.stack(
        [cv2.blur(scores[..., k].astype(np.float32), size) for k in range(len(changes))], axis=-1
    )
    nearest: np.ndarray = np.argmin(smoothed, axis=-1)
    return nearest


def _class_score(offsets: np.ndarray, change: np.ndarray) -> np.ndarray:
    """Per colour change from the table (``offsets``, N × 3): its distance off the
    line of ``change`` less a quarter of how far it goes along it. The values of
    ``norm(o − (o·c / c·c) c) − ¼ o·c / |c|`` to the last bit, at a fifth of the cost:
    the dot product taken once, the residual's squares summed column by column
    (as NumPy's norm sums the three in order) rather than through N × 3 temporaries."""
    along = offsets @ change
    length2 = max(float(change @ change), 1e-9)
    t = along / length2
    squares = np.zeros(offsets.shape[0])
    for k in range(offsets.shape[1]):
        off_line = offsets[:, k] - t * change[k]
        squares += off_line * off_line
    score: np.ndarray = np.sqrt(squares) - 0.25 * along / math.sqrt(length2)
    return score


def lightness_modes(values: np.ndarray) -> tuple[float, float | None]:
    """The top face's lightness (L*) and, when the class's lightness falls into two
    modes at least :data:`SIDE_FACE_GAP` apart (Otsu's split), the side faces'."""
    if values.size < 8:
        return float(np.median(values)) if values.size else 0.0, None
    as_bytes = np.clip(values * 2.55, 0, 255).astype(np.uint8).reshape(-1, 1)
    split, _ = cv2.threshold(as_bytes, 0, 255, cv2.THRESH_BINARY | cv2.THRESH_OTSU)
    cut = split / 2.55
    upper, lower = values[values > cut], values[values <= cut]
    if upper.size < 8 or lower.size < 8:
        return float(np.median(values)), None
    top, side = float(np.median(upper)), float(np.median(lower))
    if top - side < SIDE_FACE_GAP or upper.size < lower.size / 4:
        return float(np.median(values)), None
    return top, side
