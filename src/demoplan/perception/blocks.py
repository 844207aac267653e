"""Blocks from a top-view image: colours, the Hough transform, a sub-pixel fit.

1. Colour regions and their soft masks (:mod:`demoplan.perception.colours`):
   blocks of different colours are separated even when they touch — the
   paper's failure case, where the Hough maxima of neighbours interfered.
2. In each region, the Hough transform over (x, y, θ, s)
   (:mod:`demoplan.perception.hough`) proposes the best-supported square.
3. The proposal is fitted to the soft mask to a fraction of a pixel: robust
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
from demoplan.perception.occlusion import Candidate, tops_behind
from demoplan.perception.seams import image_lightness, seamless_side
from demoplan.perception.shapes import square_shaped
from demoplan.perception.side_faces import (
    ImageSquare,
    corners_in_image,
    side_faces_beside_tops,
    table_shadows,
)
from demoplan.perception.stack_sides import lower_side_faces

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
    side_px: tuple[float, float],
    settings: PerceptionSettings,
    px_per_m: float,
    beyond: float = 0.0,
) -> tuple[str, str] | None:
    """Why a fitted square is no block (the acceptance of :func:`detect_blocks`,
    checked in its order), or ``None``: it is one."""
    side_mm = params[3] / px_per_m * 1000
    allowed = f"{side_px[0] * 0.8 / px_per_m * 1000:.0f}–{side_px[1] * 1.2 / px_per_m * 1000:.0f}"
    if params[3] < side_px[0] * 0.8:
        return "too small", f"side {side_mm:.0f} mm, {allowed} mm allowed"
    if params[3] > side_px[1] * 1.2:
        return "too large", f"side {side_mm:.0f} mm, {allowed} mm allowed"
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


def _in_world(part: RejectedPart, camera: Camera, height: int) -> Rejection:
    """A rejected part's outlines from image pixels (x right, y down) to the world."""
    pieces = tuple(camera.image_outline_to_world(outline, height) for outline in part.outlines)
    return Rejection(part.reason, part.detail, part.colour, pieces)


def _square_alpha(params: np.ndarray, uu: np.ndarray, vv: np.ndarray) -> np.ndarray:
    u, v, theta, side = params
    c, s = math.cos(math.radians(theta)), math.sin(math.radians(theta))
    du, dv = uu - u, vv - v
    qu = np.abs(c * du + s * dv)
    qv = np.abs(-s * du + c * dv)
    distance = np.maximum(qu, qv) - side / 2  # ≈ signed distance to the outline
    ramp: np.ndarray = np.clip(0.5 - distance, 0.0, 1.0)
    return ramp


def _outline_free(alpha: np.ndarray, params: np.ndarray) -> float:
    """Share of points just outside the square's outline (2 px out) where the mask
    is empty: a block has free sides, a square fitted inside a bigger blob has none."""
    u, v, theta, side = params
    c, s = math.cos(math.radians(theta)), math.sin(math.radians(theta))
    t = np.linspace(-0.4, 0.4, 9) * side
    out = side / 2 + 2.0
    normals = np.array([(c, s), (-c, -s), (-s, c), (s, -c)])
    nu, nv = normals[:, :1], normals[:, 1:]
    pu = ((u + out * nu) - t * nv).ravel()
    pv = ((v + out * nv) + t * nu).ravel()
    height, width = alpha.shape
    cols, rows = pu.astype(np.intp), (height - pv).astype(np.intp)  # truncated, as int()
    within = (rows >= 0) & (rows < height) & (cols >= 0) & (cols < width)
    free: np.ndarray = ~within
    free[within] = alpha[rows[within], cols[within]] < 0.5
    return int(np.count_nonzero(free)) / int(free.size)


def _window(
    shape: tuple[int, ...], params: np.ndarray, side: float
) -> tuple[np.ndarray, np.ndarray, tuple[slice, slice]]:
    """The pixel centres (u, v) of the part of a crop of ``shape`` that holds every
    pixel a square at ``params``'s centre with ``side`` touches (its one-pixel ramp
    included), and those rows and columns: a fit's sums over that part are its sums
    over the crop, the same values in the same order."""
    height, width = shape
    reach = (abs(side) / 2 + 0.5) * math.sqrt(2) + 2.0
    u, v = float(params[0]), float(params[1])
    if not all(map(math.isfinite, (u, v, reach))):
        rows, cols = slice(0, height), slice(0, width)
    else:
        row = height - v
        rows = slice(
            min(height, max(0, math.floor(row - reach))),
            max(0, min(height, math.ceil(row + reach))),
        )
        cols = slice(
            min(width, max(0, math.floor(u - reach))), max(0, min(width, math.ceil(u + reach)))
        )
    uu, vv = np.meshgrid(
        np.arange(cols.start, cols.stop) + 0.5, height - np.arange(rows.start, rows.stop) - 0.5
    )
    return uu, vv, (rows, cols)


class _SquareModel:
    """The one-pixel-ramp square at the points (us, vs) against the mask values
    ``target`` there, under the soft-L1 loss ρ(z) = 2(√(1 + z) − 1), z = (r / f)²
    of the residuals r (f = ``f_scale``): its cost, and the gradient and
    Gauss–Newton matrix of the cost (the Jacobian is exact and non-zero on the
    one-pixel ramp only, so only those pixels enter them)."""

    def __init__(
        self, us: np.ndarray, vs: np.ndarray, target: np.ndarray, f_scale: float, ramp: float = 1.0
    ) -> None:
        self.us, self.vs, self.target, self.f_scale = us, vs, target, f_scale
        self.ramp = ramp
        """The width (px) over which the square's edge ramps from 1 to 0."""
        self._last: tuple[bytes, tuple[np.ndarray, ...]] | None = None
        self._last_cost = math.nan
        """The cost at the last parameters (:meth:`cost`)."""

    def frame(self, params: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q_u, q_v, distance): the points in the square's frame, and their
        ≈ signed distance to its outline."""
        u, v, theta, side = params.tolist()  # Python floats: cheaper scalars
        c, s = math.cos(math.radians(theta)), math.sin(math.radians(theta))
        # the expressions c·du + s·dv, −s·du + c·dv, max(|q_u|, |q_v|) − s/2 with
        # their temporaries reused (thousands of calls on a photograph: same values)
        du, dv = self.us - u, self.vs - v
        qu = c * du
        qu += s * dv
        qv = -s * du
        qv += c * dv
        distance = np.abs(qu)
        np.maximum(distance, np.abs(qv), out=distance)
        distance -= side / 2
        return qu, qv, distance

    def residual(self, params: np.ndarray) -> np.ndarray:
        return self._evaluated(params)[3]

    def _evaluated(self, params: np.ndarray) -> tuple[np.ndarray, ...]:
        """(q_u, q_v, distance, residual, √(1 + (r / f)²)) at ``params``; those of
        the last parameters asked for are kept: Levenberg–Marquardt asks for the
        normal equations where it has just measured the cost of a step it takes."""
        key = params.tobytes()
        if self._last is not None and self._last[0] == key:
            return self._last[1]
        qu, qv, distance = self.frame(params)
        # min(max(½ − d / ramp, 0), 1) − target and √(1 + (r / f)²), in place
        residual = 0.5 - (distance if self.ramp == 1.0 else distance / self.ramp)
        np.maximum(residual, 0.0, out=residual)
        np.minimum(residual, 1.0, out=residual)
        residual -= self.target
        root = residual / self.f_scale
        np.square(root, out=root)
        root += 1.0
        np.sqrt(root, out=root)
        self._last = key, (qu, qv, distance, residual, root)
        self._last_cost = float(self.f_scale**2 * (root - 1.0).sum())
        return self._last[1]

    def cost(self, params: np.ndarray) -> float:
        """½ f² Σ ρ((r / f)²): the robust cost (SciPy's ``soft_l1``, ``f_scale`` f)."""
        self._evaluated(params)
        return self._last_cost

    def normal_equations(self, params: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
        """(cost, JᵀWJ, JᵀWr) at ``params``: W the iteratively reweighted least
        squares weights ρ'(z) = 1 / √(1 + z) of the soft-L1 loss, J = ∂r / ∂(u, v, θ, s)
        exact — on the one-pixel ramp the model is ½ − (max(|q_u|, |q_v|) − s/2),
        q the pixel in the square's own frame; off it, constant (scaled by the
        ramp's width when it is wider)."""
        qu, qv, distance, residual, root = self._evaluated(params)
        cost = self._last_cost
        # the ramp's ends included (one-sided there): a square whose edges lie on
        # pixel borders, as a Hough bin's centre at 0° puts them, has every pixel
        # centre at an end, and would see no gradient at all
        on_ramp = np.abs(distance) <= 0.5 * self.ramp
        qu, qv = qu[on_ramp], qv[on_ramp]
        c, s = math.cos(math.radians(params[2])), math.sin(math.radians(params[2]))
        along_u = np.abs(qu) >= np.abs(qv)
        sign = np.where(along_u, np.sign(qu), np.sign(qv))
        sign /= self.ramp
        jac = np.empty((qu.size, 4))
        jac[:, 0] = np.where(along_u, c, -s) * sign
        jac[:, 1] = np.where(along_u, s, c) * sign
        jac[:, 2] = np.where(along_u, -qv, qu) * sign * (math.pi / 180.0)
        jac[:, 3] = 0.5 / self.ramp
        weight = 1.0 / root[on_ramp]
        matrix: np.ndarray = (jac * weight[:, None]).T @ jac
        gradient: np.ndarray = jac.T @ (weight * residual[on_ramp])
        return cost, matrix, gradient


MIN_CORE_COVERAGE = 0.3
"""A block's square is at least 85 % covered (:attr:`PerceptionSettings.min_coverage`),
so at most 15 % of its area is uncovered: the central half of a start within a
quarter side of it (a quarter of its area, inside it) is then at least
1 − 0.15 / 0.25 = 40 % covered — on the pixel grid, counting the pixels each
square covers wholly ((s − 1)² and (s/2 − 1)²), at least 1 − 0.15 (s − 1)² / (s/2 − 1)²:
30 % for a side s of 14 px and more. A start whose central half is covered less
is no block's (and the start square itself is less than 85 % covered): the fit,
the costly step on real photographs, is not run from it."""

COARSE_RAMPS = (4.0, 2.0)
"""Px over which the edges of the blurred squares a fit starts with ramp, in turn."""
COARSE_TOLERANCE = 1e-3
HOPELESS_COVERAGE = 0.7
HOPELESS_MISFIT = 0.4
"""Where the blurred squares leave a fit (its sharp square's interior coverage and RMS
misfit) with less coverage or more misfit than these, the sharp fit is not run: its
measures there are the fit's. A block's square is 85 % covered and misfits 0.2 at
most (:class:`PerceptionSettings`), and where the blurred squares leave it (the
development photographs' 67 blocks) 91 % covered at least, misfitting 0.23 at most;
the sharp fit is a third of a photograph's fitting time, and most of it was spent
on such hopeless starts (89 of the 240 sharp fits there)."""


def _least_squares(
    model: _SquareModel,
    start: np.ndarray,
    scale: np.ndarray,
    tolerance: float,
    max_steps: int = 100,
) -> tuple[np.ndarray, float]:
    """The parameters near ``start`` that minimise ``model``'s robust cost, and that
    cost: Levenberg–Marquardt on the reweighted normal equations, the damping
    (in the units ``scale``) set from how well each step's predicted drop in cost
    came true (Nielsen's rule), a step kept only when it lowers the cost. Stops
    when a kept step moves the scaled parameters by less than ``tolerance`` of
    their size, or lowers the cost by less than ``tolerance`` of it as predicted
    (SciPy's ``xtol`` and ``ftol``), or when no damping makes a step that lowers
    it."""
    params = start.astype(float)
    cost, matrix, gradient = model.normal_equations(params)
    metric = 1.0 / np.square(scale)
    metric_matrix = np.diag(metric)
    damping = 1e-3 * float(np.max(np.diag(matrix) / metric, initial=0.0)) or 1e-3
    growth = 2.0
    # np.any and np.linalg.norm's values without their wrappers (thousands of steps)
    for _ in range(max_steps):
        if not gradient.any():
            break  # no pixel on the ramp (or all matched): nothing moves the square
        try:
            step = np.linalg.solve(matrix + damping * metric_matrix, -gradient)
        except np.linalg.LinAlgError:
            damping *= growth
            growth *= 2.0
            continue
        trial = params + step
        trial_cost = model.cost(trial)
        predicted = 0.5 * float(step @ (damping * metric * step - gradient))
        if not trial_cost < cost:
            damping *= growth
            growth *= 2.0
            if damping > 1e12:
                break
            continue
        ratio = (cost - trial_cost) / predicted if predicted > 0 else 1.0
        damping *= max(1.0 / 3.0, 1.0 - (2.0 * ratio - 1.0) ** 3)
        growth = 2.0
        scaled_step, scaled = step / scale, params / scale
        small_step = math.sqrt(scaled_step @ scaled_step) < tolerance * (
            tolerance + math.sqrt(scaled @ scaled)
        )
        small_change = max(cost - trial_cost, predicted) < tolerance * cost
        params = trial
        if small_step or small_change:
            cost = trial_cost
            break
        cost, matrix, gradient = model.normal_equations(params)
    return params, cost


def _fit(
    alpha: np.ndarray,
    start: Hypothesis,
    band: float | None = None,
    turns: tuple[float, ...] = (0.0,),
    good_enough: float = 0.08,
    tolerance: float = 1e-6,
    ignore: np.ndarray | None = None,
) -> tuple[np.ndarray, float, float, float]:
    """Robust least-squares fit of a one-pixel-ramp square to the soft mask near
    ``start`` (:func:`_least_squares`): (u, v, θ, s), the interior coverage, the RMS
    misfit over the square's own pixels, and the share of free outline. With
    ``band`` (px) only the pixels that far from the starting outline take part
    (inside, a good start's square and the mask agree anyway): a large block
    costs its outline, not its area. Only the part of the crop near the square is
    looked at (:func:`_window`). ``turns``: angles (deg) added to the start's θ
    to fit from as well until a fit's RMS is under ``good_enough`` (the best
    kept); none by default — the blurred squares find θ from a Hough bin away.

    A start whose central half (a quarter of its area) the mask covers less than
    :data:`MIN_CORE_COVERAGE` is not fitted: its own measures are returned; one the
    blurred squares leave hopeless (:data:`HOPELESS_COVERAGE`) is not fitted sharp."""
    core = np.array([start.u, start.v, start.theta, start.side / 2])
    if _coverage(alpha, core) < MIN_CORE_COVERAGE:
        return _measures(alpha, np.array([start.u, start.v, start.theta, start.side]))
    grown = np.array([start.u, start.v, start.theta, start.side + 5.0])
    if band is None:
        uu, vv, window = _window(alpha.shape, grown, grown[3])
        near = _square_alpha(grown, uu, vv) > 0
    else:
        outline = np.array([start.u, start.v, start.theta, start.side + 2 * band])
        inner = np.array([start.u, start.v, start.theta, max(start.side - 2 * band, 0.0)])
        uu, vv, window = _window(alpha.shape, outline, outline[3])
        near = (_square_alpha(outline, uu, vv) > 0) & (_square_alpha(inner, uu, vv) < 1)
    near = near if ignore is None else near & ~ignore[window]  # hidden (occlusion.py)
    target = alpha[window][near]
    model = _SquareModel(uu[near], vv[near], target, f_scale=0.3)
    scale = np.array([1.0, 1.0, 2.0, 1.0])
    first = np.array([start.u, start.v, start.theta, start.side])
    if band is None:
        # first to where a blurred square fits (it pulls from farther away), unless
        # the start itself fits the sharp square better: a blurred square's fit to a
        # sharp edge is a fraction of a pixel off, and may fall where the sharp one
        # is stuck (its cost has kinks where pixels enter and leave the ramp)
        moved = first
        for ramp in COARSE_RAMPS:
            blurred = _SquareModel(model.us, model.vs, target, model.f_scale, ramp)
            moved, _ = _least_squares(blurred, moved, scale, COARSE_TOLERANCE, max_steps=30)
        first = min((first, moved), key=model.cost)
        measured = _measures(alpha, first)
        if measured[1] < HOPELESS_COVERAGE or measured[2] > HOPELESS_MISFIT:
            return measured
    best: tuple[np.ndarray, float] | None = None
    for turn in turns:
        x0 = first + np.array([0.0, 0.0, turn, 0.0])
        params, cost = _least_squares(model, x0, scale, tolerance)
        if best is None or cost < best[1]:
            best = params, cost
        if math.sqrt(2 * cost / max(target.size, 1)) < good_enough:
            break  # a good fit from the Hough estimate: no need to try other angles
    assert best is not None
    return _measures(alpha, best[0])


def _coverage(alpha: np.ndarray, params: np.ndarray) -> float:
    """The mean of the mask over the pixels the square ``params`` covers wholly."""
    uu, vv, window = _window(alpha.shape, params, params[3])
    inside = _square_alpha(params, uu, vv) > 0.99
    return float(alpha[window][inside].mean()) if inside.any() else 0.0


def _measures(alpha: np.ndarray, params: np.ndarray) -> tuple[np.ndarray, float, float, float]:
    """``params`` with the square's interior coverage, its RMS misfit over its own
    pixels and its share of free outline."""
    uu, vv, window = _window(alpha.shape, params, params[3])
    mask = alpha[window]
    fitted = _square_alpha(params, uu, vv)
    inside = fitted > 0.99
    coverage = float(mask[inside].mean()) if inside.any() else 0.0
    own = fitted > 0.01
    rms = float(np.sqrt(np.mean((fitted[own] - mask[own]) ** 2))) if own.any() else 1.0
    return params, coverage, rms, _outline_free(alpha, params)


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
    side_px: tuple[float, float]
    min_area: float
    settings: PerceptionSettings
    px_per_m: float
    hidden: list[Candidate] = field(default_factory=list)  # see tops_behind


def _fit_from(
    alpha: np.ndarray, start: Hypothesis, factor: int, coarse: np.ndarray
) -> tuple[np.ndarray, float, float, float]:
    """:func:`_fit` from a Hough start (on a mask shrunk by ``factor``: refined at full size)."""
    if factor == 1:
        return _fit(alpha, start)
    params, *_ = _fit(coarse, start, good_enough=0.15, tolerance=1e-4)
    u, v, theta, side = params
    full = Hypothesis(u * factor, v * factor, theta, side * factor, start.votes)
    return _fit(alpha, full, FIT_BAND, turns=(0.0,))


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
    shape, settings, side_px = search.image_shape, search.settings, search.side_px
    free = free_outline_seen(alpha, params, region.offset, shape)
    beyond = beyond_image(params, region.offset, alpha.shape, shape)
    why = _failure(params, coverage, rms, free, side_px, settings, search.px_per_m, beyond)
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
    low, high = search.side_px
    settings = search.settings
    if rms <= settings.max_residual or coverage < settings.min_coverage:
        return fit
    if not 0.8 * low <= params[3] <= 1.2 * high or shares_a_side(alpha, params):
        return fit
    return params, coverage, min(rms, rounded_misfit(alpha, params)), free


def _next_square(
    search: _SquareSearch, region: ColourRegion, alpha: np.ndarray, where: str
) -> tuple[_Square | None, list[tuple[str, str]]]:
    """The first Hough candidate in ``alpha`` fitting a block (or ``None``); why others did not."""
    # a region of area A holds squares no larger than √A
    largest = min(search.side_px[1], 1.2 * math.sqrt(float(alpha.sum())))
    sides = (search.side_px[0], max(search.side_px[0], largest))
    base = max(1, int(search.side_px[0] // HOUGH_SIDE_PX))
    failures: list[tuple[str, str]] = []
    for start, factor, coarse in _hough_starts(alpha, sides, base, where):
        check_time(where)
        fit = _with_rounded_corners(alpha, _fit_from(alpha, start, factor, coarse), search)
        why = _why_no_block(search, region, alpha, fit)
        if why is None:
            return fit[:3], failures
        if why[0] in ("not square", "not filled"):
            search.hidden.append((region, alpha, fit))
        failures.append(why)
    return None, failures


def _without_square(alpha: np.ndarray, params: np.ndarray) -> np.ndarray:
    """``alpha`` with the square ``params``, grown by 3 px, taken out."""
    height, width = alpha.shape
    uu, vv = np.meshgrid(np.arange(width) + 0.5, height - np.arange(height) - 0.5)
    grown = params.copy()
    grown[3] += 3.0
    return alpha * (1.0 - _square_alpha(grown, uu, vv))


def _squares_in_region(
    search: _SquareSearch, region: ColourRegion, where: str, parts: list[RejectedPart] | None
) -> list[_Square]:
    """The blocks' squares in a colour region, each taken out before the next is sought;
    none when they explain too little of it. What is left unfit goes to ``parts``."""
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
    squares = square_shaped(region, squares, parts)
    row0, col0 = region.offset
    rows, cols = region.alpha.shape
    lightness = search.lightness[row0 : row0 + rows, col0 : col0 + cols]
    explained = explained_share(region.counted, [params for params, _, _ in squares], lightness)
    if explained < MIN_EXPLAINED_SHARE:
        if parts is not None:
            why = ("larger than its squares", f"its squares cover {explained:.0%} of it")
            parts += _unfit(region.alpha, region, [why], search.min_area)
        return []
    return squares


def detect_blocks(
    image: np.ndarray,
    camera: Camera,
    settings: PerceptionSettings = PerceptionSettings(),
    rejected: list[Rejection] | None = None,
) -> list[DetectedBlock]:
    """Every square block in ``image`` (H × W × 3, top view), in world coordinates;
    ``rejected``, when given, gets the coloured regions found to be no block, each
    with why (:class:`Rejection`)."""
    side_px = (settings.min_side * camera.px_per_m, settings.max_side * camera.px_per_m)
    min_area = 0.3 * side_px[0] ** 2
    parts: list[RejectedPart] | None = None if rejected is None else []
    regions, _ = colour_regions(
        image,
        min_area=min_area,
        palette=settings.colours,
        rejected=parts,
        largest_block=side_px[1] ** 2,
        second_tables=(tables := np.zeros(image.shape[:2], dtype=bool)),
    )
    lightness = image_lightness(image)
    search = _SquareSearch(image.shape, lightness, side_px, min_area, settings, camera.px_per_m)
    found: list[tuple[ColourRegion, np.ndarray, float, float]] = []
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
        squares = _squares_in_region(search, region, where, parts)
        found += [(region, params, coverage, rms) for params, coverage, rms in squares]
    found += tops_behind(search, regions, tables, found, _why_no_block, _fit, parts)
    found = _without_side_faces(image, found, parts)
    if rejected is not None and parts is not None:
        rejected += [_in_world(part, camera, image.shape[0]) for part in parts]
    return _named_in_world(found, camera, image.shape[0])


_Found = tuple[ColourRegion, np.ndarray, float, float]  # a square on its region's crop


def _in_image(region: ColourRegion, params: np.ndarray) -> ImageSquare:
    """A square on its region's crop (u right, v up from the crop's bottom) in the
    image: its centre x right, y down (px), θ, side."""
    row0, col0 = region.offset
    u, v, theta, side = (float(p) for p in params)
    return col0 + u, row0 + region.alpha.shape[0] - v, theta, side


def _without_side_faces(
    image: np.ndarray, found: list[_Found], parts: list[RejectedPart] | None
) -> list[_Found]:
    """``found`` without the shadows on a coloured table, the side faces beside
    their tops (:mod:`demoplan.perception.side_faces`) and the side faces of a
    stack's lower cubes (:mod:`demoplan.perception.stack_sides`), which go to
    ``parts``."""
    in_image = [_in_image(region, params) for region, params, _, _ in found]
    colours = [np.asarray(region.rgb) for region, _, _, _ in found]
    shadows = table_shadows(image, in_image, colours)
    side_faces = side_faces_beside_tops(image, in_image)
    dropped = {index: ("shadow", why) for index, why in shadows.items()}
    dropped |= {i: ("side face", why) for i, why in side_faces.items() if i not in dropped}
    kept = [index for index in range(len(found)) if index not in dropped]
    lower = lower_side_faces(image, [in_image[index] for index in kept])
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
