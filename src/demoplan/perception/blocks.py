"""Blocks from a top-view image: colours, the Hough transform, a sub-pixel fit.

1. Colour regions and their soft masks (:mod:`demoplan.perception.colours`):
   blocks of different colours are separated even when they touch — the
   paper's failure case, where the Hough maxima of neighbours interfered.
2. In each region, the Hough transform over (x, y, θ, s)
   (:mod:`demoplan.perception.hough`) proposes the best-supported square.
3. The proposal is fitted to the soft mask to a fraction of a pixel
   (:mod:`demoplan.perception.square_fit`): robust
   least squares between the mask and a rendered square whose edges ramp
   over one pixel (what a camera's pixel integrates), over (x, y, θ, s), on
   the square's own pixels and a 2.5 px ring (a touching neighbour's pixels
   then pull at one side only, and the robust loss caps them).
4. A fit the mask bears out — its interior covered, its own pixels matched,
   at least two sides bordering on table — is a block; its area is cut out of
   the mask and the rest is searched again, so touching blocks of one colour
   are found one after the other. The next Hough maxima are tried when the
   strongest one is not borne out.
5. Squares that together cover less than half of their region are dropped
   (:data:`MIN_EXPLAINED_SHARE`): the region is something larger.

Names are colour names (``red``, ``wood``…), ``red2`` for a second red one
(blocks of one named colour are instances of one type in the scene
:func:`~demoplan.perception.stacking.scene_document` writes); yaw is given in
[−45°, 45°) (a cube looks the same every 90°).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from demoplan.budget import check_time, report_progress
from demoplan.perception.acceptance import (
    MAX_BEYOND_SHARE,
    MIN_EXPLAINED_SHARE,
    beyond_image,
    explained_share,
    free_outline_seen,
    rounded_misfit,
    runs_on_along_border,
    shares_a_side,
)
from demoplan.perception.camera import Camera
from demoplan.perception.colours import (
    REPORTED_SHARE,
    ColourRegion,
    RejectedPart,
    colour_regions,
    outlines,
)
from demoplan.perception.hough import Hypothesis, hough_squares
from demoplan.perception.image_measures import ImageMeasures
from demoplan.perception.occlusion import Candidate, tops_behind
from demoplan.perception.seams import seam_lines, seamless_side
from demoplan.perception.shapes import square_shaped
from demoplan.perception.side_faces import (
    ImageSquare,
    corners_in_image,
    side_faces_beside_tops,
    table_shadows,
)
from demoplan.perception.side_groups import SIDE_TOLERANCE, block_sizes
from demoplan.perception.square_fit import fit_square, square_alpha, square_window
from demoplan.perception.stack_sides import lower_side_faces, upturned_faces

__all__ = ["DetectedBlock", "PerceptionSettings", "Rejection", "detect_blocks", "named_by_colour"]


@dataclass(frozen=True, slots=True)
class PerceptionSettings:
    """Sizes in metres; coverage and residual limits of an accepted fit."""

    min_side: float = 0.02
    max_side: float = 0.08
    min_coverage: float = 0.85
    """Share of a fitted square's pixels the mask must cover."""
    max_residual: float = 0.2
    """RMS difference between mask and fitted square over its pixels, in coverage units
    (a lone square's corners rounded as a cube's may be:
    :data:`~demoplan.perception.acceptance.CORNER_ROUNDING`)."""
    min_free_outline: float = 0.4
    """Share of the outline that must border on table (at least ~2 free sides)."""
    colours: Mapping[str, tuple[float, float, float]] = field(default_factory=dict)
    """Colours added to the palette (:func:`~demoplan.perception.colours.load_palette`)."""
    sides: tuple[float, ...] = ()
    """The blocks' sides when given (``--side``, one or several sizes): squares are
    looked for within :data:`~demoplan.perception.side_groups.SIDE_TOLERANCE` of
    each, not between them; ``min_side`` and ``max_side`` are then not read."""


TIMES = "\u00d7"  # the multiplication sign

HOUGH_SIDE_PX = 20.0
"""The Hough transform runs on the masks shrunk by a whole factor so that the
smallest side it looks for is at least this many pixels (and under twice it);
the fit then refines at full resolution. Larger sides are looked for an octave
at a time, each at twice the previous factor (:func:`_hough_starts`)."""
OCTAVE_END = 2.5
"""An octave of sides ends at this many times :data:`HOUGH_SIDE_PX` on its shrunk
mask: the next, at twice the factor, starts at 25 px there. (Ending at 2, where
a side at the next factor would be 20 px, moved the starts of 40–50 px cubes of
the real photographs, a few of which were then not found.)"""
OCTAVE_SLACK = 1.25
"""An octave of sides takes the rest of the range when that ends within this
factor of the octave's end: a narrow range (``--side``, a small region) is one
Hough transform."""
HOUGH_PEAKS = 4
"""Hough maxima tried as starts, strongest first, per search of a region."""


@dataclass(frozen=True, slots=True)
class DetectedBlock:
    """A block found in an image: world centre (m), yaw (deg, [−45, 45)), side (m)."""

    name: str
    colour: str
    x: float
    y: float
    yaw: float
    side: float
    rgb: tuple[float, float, float]
    coverage: float
    residual: float


@dataclass(frozen=True, slots=True)
class Rejection:
    """A coloured region (or part of one) the detector found to be no block, and
    why: ``reason`` a short phrase (docs/perception.md "Overlays": ``too small``,
    ``thin or faint``, ``side face or shadow``, ``no block colour``, ``side
    face``, ``table``, ``no square``, ``too large``, ``not filled``, ``not
    square``, ``no free sides``, ``cut by the border``, ``no seam``, ``larger than its
    squares``, ``shadow``; ``covered`` from the tracker), ``detail`` the measure behind
    it; ``outlines`` its pieces' outlines (one, mostly) in world (x, y),
    metres, on the plane the image shows."""

    reason: str
    detail: str
    colour: str
    outlines: tuple[tuple[tuple[float, float], ...], ...]


def _failure(
    params: np.ndarray,
    coverage: float,
    rms: float,
    free: float,
    windows: Sequence[tuple[float, float]],
    settings: PerceptionSettings,
    px_per_m: float,
    beyond: float = 0.0,
) -> tuple[str, str] | None:
    """Why a fitted square is no block (the acceptance of :func:`detect_blocks`,
    checked in its order), or ``None``: it is one. ``windows``: the sides searched
    (px), one range or a given ``--side``'s each."""
    off = _off_size(float(params[3]), windows)
    if off is not None:
        allowed = " / ".join(
            f"{low * 0.8 / px_per_m * 1000:.0f}–{high * 1.2 / px_per_m * 1000:.0f}"
            for low, high in windows
        )
        return off, f"side {params[3] / px_per_m * 1000:.0f} mm, {allowed} mm allowed"
    if coverage < settings.min_coverage:
        return "not filled", f"{coverage:.0%} of the square covered"
    if rms > settings.max_residual:
        return "not square", f"misfit {rms:.2f}"
    if free < settings.min_free_outline:
        return "no free sides", f"{free:.0%} of the outline on table"
    if beyond > MAX_BEYOND_SHARE:
        return "cut by the border", (
            "its centre beyond the image" if beyond >= 1 else f"{beyond:.0%} of it beyond the image"
        )
    return None


def _off_size(side: float, windows: Sequence[tuple[float, float]]) -> str | None:
    """``too small`` or ``too large`` for a square of ``side`` (px) outside every
    window of sides searched (each from 0.8 of its smallest to 1.2 of its largest:
    a fit may end a little off the vote's sides), or ``None``: within one. Between
    two windows it is too large for the one below when nearer to it (in ratio)."""
    spans = [(0.8 * low, 1.2 * high) for low, high in windows]
    if any(low <= side <= high for low, high in spans):
        return None
    below = [high for _, high in spans if high < side]
    above = [low for low, _ in spans if low > side]
    if not below:
        return "too small"
    if not above:
        return "too large"
    return "too large" if side / max(below) < min(above) / side else "too small"


def _unfit(
    alpha: np.ndarray, region: ColourRegion, failures: list[tuple[str, str]], min_area: float
) -> list[RejectedPart]:
    """The rest of a region in which no square was borne out, as rejected parts:
    why the best fit failed (the strongest Hough candidate's first failed check)."""
    reason, detail = failures[0] if failures else ("no square", "no edges to vote")
    row0, col0 = region.offset
    shift = np.array([col0, row0])
    pieces = tuple(o + shift for o in outlines(alpha > 0.5, REPORTED_SHARE * min_area))
    return [RejectedPart(reason, detail, region.colour, pieces)] if pieces else []


def _in_world(parts: list[RejectedPart], camera: Camera, height: int) -> list[Rejection]:
    """Rejected parts' outlines from image pixels (x right, y down) to the world: the
    points of all converted at once (a photograph's thousand parts, one by one, cost
    half as much again), then parted by outline."""
    outlines = [np.asarray(o, dtype=float).reshape(-1, 2) for p in parts for o in p.outlines]
    points = np.concatenate(outlines) if outlines else np.zeros((0, 2))
    world = camera.image_outline_to_world(points, height)
    rejections, start, first = [], 0, 0
    for part in parts:
        pieces = []
        for outline in outlines[first : first + len(part.outlines)]:
            pieces.append(world[start : start + len(outline)])
            start += len(outline)
        first += len(part.outlines)
        rejections.append(Rejection(part.reason, part.detail, part.colour, tuple(pieces)))
    return rejections


def _shrink(alpha: np.ndarray, factor: int) -> np.ndarray:
    """``alpha`` averaged over ``factor`` × ``factor`` pixel blocks; padded at the
    top and right, so coordinates from the bottom-left corner scale by ``factor``."""
    if factor == 1:
        return alpha
    height, width = alpha.shape
    rows, cols = -(-height // factor) * factor, -(-width // factor) * factor
    padded = np.zeros((rows, cols), dtype=float)
    padded[rows - height :, :width] = alpha
    shrunk: np.ndarray = padded.reshape(rows // factor, factor, cols // factor, factor).mean(
        axis=(1, 3)
    )
    return shrunk


FIT_BAND = 3.0
"""Px either side of a start's outline that a fit refined from a shrunk mask looks at."""


def _octaves(sides: tuple[float, float], base: int) -> list[tuple[int, float, float]]:
    """The side range ``sides`` (px) cut into octaves searched on masks shrunk by
    ``base``, twice that, … : (factor, smallest, largest side in px), each from
    where the previous ends up to :data:`OCTAVE_END` × :data:`HOUGH_SIDE_PX` × its
    factor (the last one to the end of the range when that is near,
    :data:`OCTAVE_SLACK`)."""
    low, high = sides
    octaves = []
    factor = base
    while True:
        end = OCTAVE_END * HOUGH_SIDE_PX * factor
        if high <= OCTAVE_SLACK * end:
            octaves.append((factor, low, high))
            return octaves
        octaves.append((factor, low, end))
        low, factor = end, 2 * factor


def _hough_starts(
    alpha: np.ndarray, sides: tuple[float, float], base: int, where: str
) -> list[tuple[Hypothesis, int, np.ndarray]]:
    """The best-supported squares in ``alpha`` with a side in ``sides`` (px),
    strongest first, each with the factor its mask was shrunk by for the vote and
    that mask: every octave of sides (:func:`_octaves`) voted on at its own
    resolution — a large square costs its size over the factor squared, so the
    accumulator of an octave has about as many cells at any size — and its
    :data:`HOUGH_PEAKS` maxima taken. The votes (edge strength summed over an
    outline's pixels, fewer pixels on a shrunk mask) are scaled by the factor to
    be compared across octaves. The budget (``where``) is read before each vote and
    within it (:func:`~demoplan.perception.hough.hough_squares`)."""
    found: list[tuple[Hypothesis, int, np.ndarray]] = []
    for factor, low, high in _octaves(sides, base):
        coarse = _shrink(alpha, factor)
        check_time(where)
        shrunk_sides = (low / factor, high / factor)
        for start in hough_squares(coarse, shrunk_sides, HOUGH_PEAKS, lambda: check_time(where)):
            found.append((start, factor, coarse))
    found.sort(key=lambda f: -f[0].votes * f[1])
    return found


_Square = tuple[np.ndarray, float, float]  # (u, v, θ, s) on its crop, coverage, RMS misfit


@dataclass(frozen=True, slots=True)
class _SquareSearch:
    """What fitting squares in any region of one image needs."""

    image_shape: tuple[int, ...]
    lightness: np.ndarray
    windows: tuple[tuple[float, float], ...]
    """The sides searched (px), smallest first: one range, or a given side's each."""
    min_area: float
    settings: PerceptionSettings
    px_per_m: float
    hidden: list[Candidate] = field(default_factory=list)  # see tops_behind

    @property
    def side_px(self) -> tuple[float, float]:
        """The smallest and the largest side searched (px)."""
        return self.windows[0][0], self.windows[-1][1]


def _fit_from(
    alpha: np.ndarray, start: Hypothesis, factor: int, coarse: np.ndarray
) -> tuple[np.ndarray, float, float, float]:
    """:func:`~demoplan.perception.square_fit.fit_square` from a Hough start (on a mask
    shrunk by ``factor``: refined at full size)."""
    if factor == 1:
        return fit_square(alpha, start)
    params, *_ = fit_square(coarse, start, good_enough=0.15, tolerance=1e-4)
    u, v, theta, side = params
    full = Hypothesis(u * factor, v * factor, theta, side * factor, start.votes)
    return fit_square(alpha, full, FIT_BAND, turns=(0.0,))


def _why_no_block(
    search: _SquareSearch,
    region: ColourRegion,
    alpha: np.ndarray,
    fit: tuple[np.ndarray, float, float, float],
) -> tuple[str, str] | None:
    """Why a fitted square is no block, in order: :func:`_failure` (its free outline
    counted where the image shows it), a region running on along the image's border,
    no seam parting it from the rest; ``None``: it is one."""
    params, coverage, rms, _ = fit
    shape, settings, windows = search.image_shape, search.settings, search.windows
    free = free_outline_seen(alpha, params, region.offset, shape)
    beyond = beyond_image(params, region.offset, alpha.shape, shape)
    why = _failure(params, coverage, rms, free, windows, settings, search.px_per_m, beyond)
    if why is None and runs_on_along_border(region.alpha, params, region.offset, shape):
        why = "cut by the border", "its region runs on along the image's border"
    if why is None:
        seamless = seamless_side(search.lightness, alpha, region.offset, params)
        why = None if seamless is None else ("no seam", seamless)
    return why


def _with_rounded_corners(
    alpha: np.ndarray, fit: tuple[np.ndarray, float, float, float], search: _SquareSearch
) -> tuple[np.ndarray, float, float, float]:
    """``fit`` with its misfit measured against its square's corners rounded as a
    photographed cube's are (:func:`~demoplan.perception.acceptance.rounded_misfit`)
    when the sharp square misfits and no side of it is shared with the rest of its
    region (:func:`~demoplan.perception.acceptance.shares_a_side`) — and only then
    decides (its size and coverage, checked first, pass)."""
    params, coverage, rms, free = fit
    settings = search.settings
    if rms <= settings.max_residual or coverage < settings.min_coverage:
        return fit
    if _off_size(float(params[3]), search.windows) is not None or shares_a_side(alpha, params):
        return fit
    return params, coverage, min(rms, rounded_misfit(alpha, params)), free


SEAM_INSIDE = 2.0
"""Px inside a square's side that the groove of a seam along it may lie and the
side still be taken as on it (the groove's darkest line and its blurred rims)."""


def _on_its_seams(
    search: _SquareSearch,
    region: ColourRegion,
    alpha: np.ndarray,
    fit: tuple[np.ndarray, float, float, float],
) -> tuple[np.ndarray, float, float, float]:
    """``fit``, a block, fitted again up to the seams along the sides it shares with
    the rest of its region when a seam's groove lies inside it by more than
    :data:`SEAM_INSIDE`: beyond a seam is the next cube's top, so the mask there is
    left out of the fit (a half-plane past the groove's line). In a row of one
    colour the mask runs on across the seams and holds the cubes' side faces across
    the row: a square fitted at the row's end took the row's width as its side and
    reached past the seam into the next top, which was then cut short by it
    (``touching_rows`` seed 6 with ``--side``: 68 px squares on 62 px tops, the
    middle one lost). The new fit is kept when it is a block too."""
    params = fit[0]
    seams = [
        seam
        for seam in seam_lines(search.lightness, alpha, region.offset, params)
        if seam[2] < -SEAM_INSIDE
    ]
    if not seams:
        return fit
    u, v, theta, side = (float(p) for p in params)
    height, width = alpha.shape
    uu = np.arange(width) + 0.5
    vv = height - np.arange(height)[:, None] - 0.5
    cut = alpha.astype(float)
    start_u, start_v, start_side = u, v, side
    for nu, nv, where in seams:
        line = side / 2 + where  # from the centre along the side's outward normal
        cut[(uu - u) * nu + (vv - v) * nv > line] = 0.0
        start_u, start_v, start_side = (
            start_u + nu * where / 2,
            start_v + nv * where / 2,
            start_side + where,
        )
    start = Hypothesis(start_u, start_v, theta, start_side, 0.0)
    refit = fit_square(cut, start)
    if _why_no_block(search, region, alpha, refit) is not None:
        return fit
    return refit


def _next_square(
    search: _SquareSearch, region: ColourRegion, alpha: np.ndarray, where: str
) -> tuple[_Square | None, list[tuple[str, str]]]:
    """The first Hough candidate in ``alpha`` fitting a block (or ``None``); why others did not."""
    # a region of area A holds squares no larger than √A
    largest = min(search.side_px[1], 1.2 * math.sqrt(float(alpha.sum())))
    starts: list[tuple[Hypothesis, int, np.ndarray]] = []
    for number, (low, high) in enumerate(search.windows):
        if number and low > largest:
            break
        base = max(1, int(low // HOUGH_SIDE_PX))
        starts += _hough_starts(alpha, (low, max(low, min(high, largest))), base, where)
    starts.sort(key=lambda f: -f[0].votes * f[1])
    failures: list[tuple[str, str]] = []
    for start, factor, coarse in starts:
        check_time(where)
        fit = _with_rounded_corners(alpha, _fit_from(alpha, start, factor, coarse), search)
        why = _why_no_block(search, region, alpha, fit)
        if why is None:
            return _on_its_seams(search, region, alpha, fit)[:3], failures
        if why[0] in ("not square", "not filled"):
            search.hidden.append((region, alpha, fit))
        failures.append(why)
    return None, failures


def _without_square(alpha: np.ndarray, params: np.ndarray) -> np.ndarray:
    """``alpha`` with the square ``params``, grown by 3 px, taken out (only the
    pixels it touches change: :func:`square_window`)."""
    grown = params.copy()
    grown[3] += 3.0
    uu, vv, window = square_window(alpha.shape, grown, grown[3])
    without: np.ndarray = alpha.astype(float)
    without[window] *= 1.0 - square_alpha(grown, uu, vv)
    return without


def _squares_in_region(
    search: _SquareSearch, region: ColourRegion, where: str, parts: list[RejectedPart] | None
) -> tuple[list[_Square], bool]:
    """The blocks' squares in a colour region, each taken out before the next is sought;
    none when they explain too little of it or are not square-shaped. What is left
    unfit goes to ``parts``. Second: whether any square was fitted (a region whose
    squares were then judged no blocks was seen to be something else)."""
    alpha = region.alpha.copy()
    squares: list[_Square] = []
    for attempt in range(8):
        if (alpha > 0.5).sum() < search.min_area:
            if parts is not None and attempt == 0:  # its side faces left too little
                small = ("too small", f"{int((alpha > 0.5).sum())} px of top face")
                parts += _unfit(alpha, region, [small], search.min_area)
            break
        square, failures = _next_square(search, region, alpha, where)
        if square is None:
            if parts is not None:
                parts += _unfit(alpha, region, failures, search.min_area)
            break
        squares.append(square)
        alpha = _without_square(alpha, square[0])
    fitted = bool(squares)
    squares = square_shaped(region, squares, parts)
    row0, col0 = region.offset
    rows, cols = region.alpha.shape
    lightness = search.lightness[row0 : row0 + rows, col0 : col0 + cols]
    explained = explained_share(region.counted, [params for params, _, _ in squares], lightness)
    if explained < MIN_EXPLAINED_SHARE:
        if parts is not None:
            why = ("larger than its squares", f"its squares cover {explained:.0%} of it")
            parts += _unfit(region.alpha, region, [why], search.min_area)
        return [], fitted
    return squares, fitted


def detect_blocks(
    image: np.ndarray,
    camera: Camera,
    settings: PerceptionSettings = PerceptionSettings(),
    rejected: list[Rejection] | None = None,
    measures: ImageMeasures | None = None,
) -> list[DetectedBlock]:
    """Every square block in ``image`` (H × W × 3, top view), in world coordinates;
    ``rejected``, when given, gets the coloured regions found to be no block, each
    with why (:class:`Rejection`). ``measures``: the image's
    (:mod:`demoplan.perception.image_measures`), when the caller shares them with
    stages of its own; each stage here takes its conversions of the image from them."""
    measures = ImageMeasures(image) if measures is None else measures
    image = measures.image  # its colour cast divided out (demoplan.perception.white_balance)
    windows = _side_windows(settings, camera.px_per_m)
    side_px = (windows[0][0], windows[-1][1])
    min_area = 0.3 * side_px[0] ** 2
    parts: list[RejectedPart] | None = None if rejected is None else []
    regions, _ = colour_regions(
        image,
        min_area=min_area,
        palette=settings.colours,
        rejected=parts,
        largest_block=side_px[1] ** 2,
        second_tables=(tables := np.zeros(image.shape[:2], dtype=bool)),
        held=(held := np.zeros(image.shape[:2], dtype=bool)),
        lab8=measures.lab8,
    )
    lightness = measures.lightness
    search = _SquareSearch(image.shape, lightness, windows, min_area, settings, camera.px_per_m)
    found: list[tuple[ColourRegion, np.ndarray, float, float]] = []
    region_parts: list[list[RejectedPart] | None] = []
    unfitted: list[int] = []  # regions in which no square was fitted
    for done, region in enumerate(regions):
        # a budget set by the caller (demoplan.budget), if any, read before every
        # Hough transform and fit: one large region costs many of them
        crop_rows, crop_cols = region.alpha.shape
        where = (
            f" fitting squares in colour region {done + 1} of {len(regions)} ({region.colour}, "
            f"{crop_cols} {TIMES} {crop_rows} px; {len(found)} blocks found before it)"
        )
        check_time(where)
        report_progress("colour regions", done, len(regions))
        region_parts.append(None if parts is None else [])
        squares, fitted = _squares_in_region(search, region, where, region_parts[-1])
        found += [(region, params, coverage, rms) for params, coverage, rms in squares]
        if not fitted:
            unfitted.append(done)
    found += _second_look(search, regions, unfitted, found, region_parts)
    if parts is not None:
        parts += [part for own in region_parts if own is not None for part in own]
    found += tops_behind(search, regions, tables, found, _why_no_block, fit_square, parts)
    found = _without_side_faces(measures, found, parts, held)
    if rejected is not None and parts is not None:
        rejected += _in_world(parts, camera, image.shape[0])
    return _named_in_world(found, camera, image.shape[0])


def _side_windows(settings: PerceptionSettings, px_per_m: float) -> tuple[tuple[float, float], ...]:
    """The sides searched (px), smallest first: from ``min_side`` to ``max_side``, or
    each given side (``sides``) ± :data:`~demoplan.perception.side_groups.SIDE_TOLERANCE`,
    windows that overlap joined."""
    if not settings.sides:
        return ((settings.min_side * px_per_m, settings.max_side * px_per_m),)
    windows: list[tuple[float, float]] = []
    for side in sorted(settings.sides):
        low, high = (1 - SIDE_TOLERANCE) * side * px_per_m, (1 + SIDE_TOLERANCE) * side * px_per_m
        if windows and low <= windows[-1][1]:
            windows[-1] = (windows[-1][0], max(high, windows[-1][1]))
        else:
            windows.append((low, high))
    return tuple(windows)


_Found = tuple[ColourRegion, np.ndarray, float, float]  # a square on its region's crop


SECOND_LOOK_SQUARES = 3
"""Squares found of the photograph's block sizes before the regions with none are
searched again at those sizes (:func:`_second_look`): a size seen once may be a
patch's."""
SEVERAL_CUBES = 1.5
"""A region looked at again holds at least this many tops of the smallest block
size (in area): a region of one top's size or less was searched at that size
already, the wide range included it; only where several cubes make one region
does the vote over the wide range prefer squares across them."""
SECOND_LOOK_NARROWER = 1.25
"""How many times narrower (largest over smallest side) the block sizes' span must
be than the range searched for the second look to see anything new."""


def _second_look(
    search: _SquareSearch,
    regions: Sequence[ColourRegion],
    unfitted: Sequence[int],
    found: list[_Found],
    region_parts: list[list[RejectedPart] | None],
) -> list[_Found]:
    """The squares of the photograph's block sizes in the regions in which the
    first search, over the whole range of sides, fitted none (``unfitted``):
    searched again with the sides narrowed to the block sizes of the squares found
    elsewhere (:func:`~demoplan.perception.side_groups.block_sizes`) — from the
    smallest size's median less 15 % to the largest's plus 15 %, as a given
    ``--side`` narrows them about its side. Two cubes of one colour face
    to face are one region; over a wide range of sides the vote's strongest
    squares are the pair's (a square across both, misfit 0.2) and no single cube
    is tried, where at the cubes' own size each is (the ``small`` family: 25 mm
    cubes in pairs, found with ``--side``, missed without).

    Not looked at again: a region whose squares explained too little of it or
    whose outline has other corners (it was seen to be something else: a
    marker and its grid lines, a pentagon), and a region of less than
    :data:`SEVERAL_CUBES` tops' area (a cube lying tipped over shows a face
    smaller than a top, a rectangle that a square of the cubes' size takes for
    one). Nothing changes when the range was that narrow already (``--side``)
    or fewer than :data:`SECOND_LOOK_SQUARES` of the squares found lie in it. A region
    found no block again keeps its first reasons; one in which squares are found
    now has the second search's (``region_parts``, per region, replaced)."""
    sides = [float(params[3]) for _, params, _, _ in found]
    sizes = block_sizes(sides)
    if not sizes or search.settings.sides:  # given sides are the block sizes
        return []
    low = min(size[0] for size in sizes) * (1 - SIDE_TOLERANCE)
    high = max(size[0] for size in sizes) * (1 + SIDE_TOLERANCE)
    low, high = max(low, search.side_px[0]), min(high, search.side_px[1])
    searched = search.side_px[1] / search.side_px[0]
    shared = sum(low <= side <= high for side in sides)
    if shared < SECOND_LOOK_SQUARES or low >= high or high / low * SECOND_LOOK_NARROWER > searched:
        return []
    narrowed = replace(search, windows=((low, high),))
    several = SEVERAL_CUBES * min(size[0] for size in sizes) ** 2
    more: list[_Found] = []
    for index in unfitted:
        region = regions[index]
        if (region.alpha > 0.5).sum() < several:
            continue
        where = f" looking again at colour region {index + 1} of {len(regions)} at the blocks' size"
        check_time(where)
        own: list[RejectedPart] | None = None if region_parts[index] is None else []
        hidden = len(search.hidden)
        squares, _ = _squares_in_region(narrowed, region, where, own)
        if not squares:
            del search.hidden[hidden:]  # the first search's failures stand for it
            continue
        # the first search's failures give way to the second's
        search.hidden[:] = [
            entry for entry in search.hidden[:hidden] if entry[0] is not region
        ] + search.hidden[hidden:]
        region_parts[index] = own
        more += [(region, params, coverage, rms) for params, coverage, rms in squares]
    return more


def _in_image(region: ColourRegion, params: np.ndarray) -> ImageSquare:
    """A square on its region's crop (u right, v up from the crop's bottom) in the
    image: its centre x right, y down (px), θ, side."""
    row0, col0 = region.offset
    u, v, theta, side = (float(p) for p in params)
    return col0 + u, row0 + region.alpha.shape[0] - v, theta, side


def _without_side_faces(
    measures: ImageMeasures, found: list[_Found], parts: list[RejectedPart] | None, held: np.ndarray
) -> list[_Found]:
    """``found`` without the shadows on a coloured table, the side faces beside
    their tops (:mod:`demoplan.perception.side_faces`) and the side faces of a
    stack's lower cubes (:mod:`demoplan.perception.stack_sides`), which go to
    ``parts`` (``held``: the image's foreground,
    :func:`~demoplan.perception.colours.foreground`)."""
    in_image = [_in_image(region, params) for region, params, _, _ in found]
    colours = [np.asarray(region.rgb) for region, _, _, _ in found]
    shadows = table_shadows(measures.image, in_image, colours)
    side_faces = side_faces_beside_tops(measures.image, in_image)
    dropped = {index: ("shadow", why) for index, why in shadows.items()}
    dropped |= {i: ("side face", why) for i, why in side_faces.items() if i not in dropped}
    kept = [index for index in range(len(found)) if index not in dropped]
    upturned = upturned_faces(measures, [in_image[index] for index in kept])
    dropped |= {kept[i]: ("side face", why) for i, why in upturned.items()}
    kept = [index for index in kept if index not in dropped]
    lower = lower_side_faces(measures, [in_image[index] for index in kept], held)
    dropped |= {kept[i]: ("side face", why) for i, why in lower.items()}
    if parts is not None:
        for index, (reason, detail) in dropped.items():
            corners = corners_in_image(in_image[index])
            parts.append(RejectedPart(reason, detail, found[index][0].colour, (corners,)))
    return [square for index, square in enumerate(found) if index not in dropped]


def _named_in_world(
    found: list[tuple[ColourRegion, np.ndarray, float, float]], camera: Camera, height: int
) -> list[DetectedBlock]:
    """The squares fitted in their regions' crops (``height``: the image's rows)
    as blocks on the table, named by colour in the order found."""
    blocks = []
    for region, params, coverage, rms in found:
        row0, col0 = region.offset
        crop_height = region.alpha.shape[0]
        u = col0 + params[0]
        v = (height - row0 - crop_height) + params[1]
        x, y = camera.to_world(u, v)
        yaw = ((params[2] + 45.0) % 90.0) - 45.0
        side = params[3] / camera.px_per_m
        blocks.append(DetectedBlock("", region.colour, x, y, yaw, side, region.rgb, coverage, rms))
    return named_by_colour(blocks)


def named_by_colour(blocks: Sequence[DetectedBlock]) -> list[DetectedBlock]:
    """``blocks`` named by colour in their order (docs/formats.md): a plain colour
    names its first block and ``red2``… the others; unnamed colours are
    ``block1``, ``block2``…"""
    counts: dict[str, int] = {}
    named = []
    for block in blocks:
        counts[block.colour] = counts.get(block.colour, 0) + 1
        count = counts[block.colour]
        name = (
            f"block{count}"
            if block.colour == "block"
            else (block.colour if count == 1 else f"{block.colour}{count}")
        )
        named.append(replace(block, name=name))
    return named
