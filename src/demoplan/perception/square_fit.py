"""The sub-pixel square fit (step 3 of :mod:`demoplan.perception.blocks`).

A square whose edges ramp over one pixel (what a camera's pixel integrates) is
fitted to a soft mask by robust least squares over (x, y, θ, s) — on the
square's own pixels and a ring around it, from a Hough start
(:mod:`demoplan.perception.hough`) — first to blurred squares (wider ramps, which
pull from farther away), then sharp; and the fit's measures: interior coverage,
RMS misfit over its pixels, share of free outline.
"""

from __future__ import annotations

import math

import numpy as np

from demoplan.perception.fit_kernel import robust_cost, robust_least_squares
from demoplan.perception.hough import Hypothesis

__all__ = [
    "COARSE_RAMPS",
    "COARSE_TOLERANCE",
    "HOPELESS_COVERAGE",
    "HOPELESS_MISFIT",
    "MIN_CORE_COVERAGE",
    "SquareModel",
    "core_coverage",
    "fit_square",
    "least_squares",
    "measures",
    "outline_free",
    "outline_points",
    "square_alpha",
    "square_window",
]


def square_alpha(params: np.ndarray, uu: np.ndarray, vv: np.ndarray) -> np.ndarray:
    u, v, theta, side = params
    c, s = math.cos(math.radians(theta)), math.sin(math.radians(theta))
    du, dv = uu - u, vv - v
    qu = np.abs(c * du + s * dv)
    qv = np.abs(-s * du + c * dv)
    distance = np.maximum(qu, qv) - side / 2  # ≈ signed distance to the outline
    ramp: np.ndarray = np.clip(0.5 - distance, 0.0, 1.0)
    return ramp


def outline_points(params: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The points (u, v) 2 px outside the outline of the square ``params``: nine
    along each side (from −0.4 to 0.4 of the side about its middle), the four sides
    one after the other — where :func:`outline_free` and
    :func:`demoplan.perception.acceptance.free_outline_seen` look for table."""
    u, v, theta, side = (float(p) for p in params)
    c, s = math.cos(math.radians(theta)), math.sin(math.radians(theta))
    along = np.linspace(-0.4, 0.4, 9) * side
    out = side / 2 + 2.0
    normals = np.array([(c, s), (-c, -s), (-s, c), (s, -c)])
    nu, nv = normals[:, :1], normals[:, 1:]
    pu = ((u + out * nu) - along * nv).ravel()
    pv = ((v + out * nv) + along * nu).ravel()
    return pu, pv


def outline_free(alpha: np.ndarray, params: np.ndarray) -> float:
    """Share of points just outside the square's outline (2 px out) where the mask
    is empty: a block has free sides, a square fitted inside a bigger blob has none."""
    pu, pv = outline_points(params)
    height, width = alpha.shape
    cols, rows = pu.astype(np.intp), (height - pv).astype(np.intp)  # truncated, as int()
    within = (rows >= 0) & (rows < height) & (cols >= 0) & (cols < width)
    free: np.ndarray = ~within
    free[within] = alpha[rows[within], cols[within]] < 0.5
    return int(np.count_nonzero(free)) / int(free.size)


def square_window(
    shape: tuple[int, ...], params: np.ndarray, side: float
) -> tuple[np.ndarray, np.ndarray, tuple[slice, slice]]:
    """The pixel centres (u, v) of the part of a crop of ``shape`` that holds every
    pixel a square at ``params``'s centre with ``side`` touches (its one-pixel ramp
    included), and those rows and columns: a fit's sums over that part are its sums
    over the crop, the same values in the same order. u is one row (1 × columns), v
    one column (rows × 1): they broadcast to the part's pixels (an expression of
    both, as :func:`square_alpha`, has its values pixel for pixel; the grid of both
    is not built)."""
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
    uu = (np.arange(cols.start, cols.stop) + 0.5)[None, :]
    vv = (height - np.arange(rows.start, rows.stop) - 0.5)[:, None]
    return uu, vv, (rows, cols)


class SquareModel:
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
        """(q_u, q_v, distance, residual, √(1 + (r / f)²)) at ``params``."""
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
        return qu, qv, distance, residual, root

    def cost(self, params: np.ndarray) -> float:
        """½ f² Σ ρ((r / f)²): the robust cost (SciPy's ``soft_l1``, ``f_scale`` f),
        compiled (:func:`demoplan.perception.fit_kernel.robust_cost`; the same
        formula as :meth:`normal_equations`' cost, summed in another order)."""
        return robust_cost(self.us, self.vs, self.target, self.f_scale, self.ramp, params)

    def normal_equations(self, params: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
        """(cost, JᵀWJ, JᵀWr) at ``params``: W the iteratively reweighted least
        squares weights ρ'(z) = 1 / √(1 + z) of the soft-L1 loss, J = ∂r / ∂(u, v, θ, s)
        exact — on the one-pixel ramp the model is ½ − (max(|q_u|, |q_v|) − s/2),
        q the pixel in the square's own frame; off it, constant (scaled by the
        ramp's width when it is wider). In NumPy: the formulas the compiled fit
        (:mod:`demoplan.perception.fit_kernel`) is tested against."""
        qu, qv, distance, residual, root = self._evaluated(params)
        cost = float(self.f_scale**2 * (root - 1.0).sum())
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


def least_squares(
    model: SquareModel,
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
    it. Compiled (:func:`demoplan.perception.fit_kernel.robust_least_squares`): a
    photograph's fits are thousands of steps over a few thousand pixels each."""
    pixels = model.us, model.vs, model.target
    return robust_least_squares(
        *pixels, model.f_scale, model.ramp, start, scale, tolerance, max_steps
    )


def fit_square(
    alpha: np.ndarray,
    start: Hypothesis,
    band: float | None = None,
    turns: tuple[float, ...] = (0.0,),
    good_enough: float = 0.08,
    tolerance: float = 1e-6,
    ignore: np.ndarray | None = None,
) -> tuple[np.ndarray, float, float, float]:
    """Robust least-squares fit of a one-pixel-ramp square to the soft mask near
    ``start`` (:func:`least_squares`): (u, v, θ, s), the interior coverage, the RMS
    misfit over the square's own pixels, and the share of free outline. With
    ``band`` (px) only the pixels that far from the starting outline take part
    (inside, a good start's square and the mask agree anyway): a large block
    costs its outline, not its area. Only the part of the crop near the square is
    looked at (:func:`square_window`). ``turns``: angles (deg) added to the start's θ
    to fit from as well until a fit's RMS is under ``good_enough`` (the best
    kept); none by default — the blurred squares find θ from a Hough bin away.

    A start whose central half (a quarter of its area) the mask covers less than
    :data:`MIN_CORE_COVERAGE` is not fitted: its own measures are returned; one the
    blurred squares leave hopeless (:data:`HOPELESS_COVERAGE`) is not fitted sharp."""
    core = np.array([start.u, start.v, start.theta, start.side / 2])
    if core_coverage(alpha, core) < MIN_CORE_COVERAGE:
        return measures(alpha, np.array([start.u, start.v, start.theta, start.side]))
    grown = np.array([start.u, start.v, start.theta, start.side + 5.0])
    if band is None:
        uu, vv, window = square_window(alpha.shape, grown, grown[3])
        near = square_alpha(grown, uu, vv) > 0
    else:
        outline = np.array([start.u, start.v, start.theta, start.side + 2 * band])
        inner = np.array([start.u, start.v, start.theta, max(start.side - 2 * band, 0.0)])
        uu, vv, window = square_window(alpha.shape, outline, outline[3])
        near = (square_alpha(outline, uu, vv) > 0) & (square_alpha(inner, uu, vv) < 1)
    near = near if ignore is None else near & ~ignore[window]  # hidden (occlusion.py)
    target = alpha[window][near]
    us, vs = (np.broadcast_to(grid, near.shape)[near] for grid in (uu, vv))
    model = SquareModel(us, vs, target, f_scale=0.3)
    scale = np.array([1.0, 1.0, 2.0, 1.0])
    first = np.array([start.u, start.v, start.theta, start.side])
    if band is None:
        # first to where a blurred square fits (it pulls from farther away), unless
        # the start itself fits the sharp square better: a blurred square's fit to a
        # sharp edge is a fraction of a pixel off, and may fall where the sharp one
        # is stuck (its cost has kinks where pixels enter and leave the ramp)
        moved = first
        for ramp in COARSE_RAMPS:
            blurred = SquareModel(model.us, model.vs, target, model.f_scale, ramp)
            moved, _ = least_squares(blurred, moved, scale, COARSE_TOLERANCE, max_steps=30)
        first = min((first, moved), key=model.cost)
        measured = measures(alpha, first)
        if measured[1] < HOPELESS_COVERAGE or measured[2] > HOPELESS_MISFIT:
            return measured
    best: tuple[np.ndarray, float] | None = None
    for turn in turns:
        x0 = first + np.array([0.0, 0.0, turn, 0.0])
        params, cost = least_squares(model, x0, scale, tolerance)
        if best is None or cost < best[1]:
            best = params, cost
        if math.sqrt(2 * cost / max(target.size, 1)) < good_enough:
            break  # a good fit from the Hough estimate: no need to try other angles
    assert best is not None
    return measures(alpha, best[0])


def core_coverage(alpha: np.ndarray, params: np.ndarray) -> float:
    """The mean of the mask over the pixels the square ``params`` covers wholly."""
    uu, vv, window = square_window(alpha.shape, params, params[3])
    inside = square_alpha(params, uu, vv) > 0.99
    return float(alpha[window][inside].mean()) if inside.any() else 0.0


def measures(alpha: np.ndarray, params: np.ndarray) -> tuple[np.ndarray, float, float, float]:
    """``params`` with the square's interior coverage, its RMS misfit over its own
    pixels and its share of free outline."""
    uu, vv, window = square_window(alpha.shape, params, params[3])
    mask = alpha[window]
    fitted = square_alpha(params, uu, vv)
    inside = fitted > 0.99
    coverage = float(mask[inside].mean()) if inside.any() else 0.0
    own = fitted > 0.01
    rms = float(np.sqrt(np.mean((fitted[own] - mask[own]) ** 2))) if own.any() else 1.0
    return params, coverage, rms, outline_free(alpha, params)
