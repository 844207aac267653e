"""The sub-pixel square fit of demoplan.perception.square_fit: its own robust
least-squares solver against SciPy's on the same objective, where it converges
from, and the coverage test that spares it the hopeless starts."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import optimize

from demoplan.perception import square_fit
from demoplan.perception.acceptance import rounded_misfit
from demoplan.perception.blocks import PerceptionSettings
from demoplan.perception.hough import Hypothesis
from demoplan.perception.square_fit import (
    MIN_CORE_COVERAGE,
    SquareModel,
    core_coverage,
    fit_square,
    least_squares,
    square_alpha,
    square_window,
)

SHAPE = (110, 130)


def _grid(shape: tuple[int, int] = SHAPE) -> tuple[np.ndarray, np.ndarray]:
    height, width = shape
    return np.meshgrid(np.arange(width) + 0.5, height - np.arange(height) - 0.5)


def _noisy_square(square: tuple[float, float, float, float], noise: float, seed: int) -> np.ndarray:
    """A soft mask of one square with sensor-like noise, clipped to [0, 1]."""
    uu, vv = _grid()
    alpha = square_alpha(np.array(square), uu, vv)
    noisy = alpha + np.random.default_rng(seed).normal(0.0, noise, alpha.shape)
    clipped: np.ndarray = np.clip(noisy, 0.0, 1.0)
    return clipped


squares = st.tuples(
    st.floats(50.0, 80.0),  # u
    st.floats(45.0, 65.0),  # v
    st.floats(0.0, 89.9),  # θ
    st.floats(20.0, 40.0),  # side
)


@settings(max_examples=20, deadline=None)
@given(
    st.tuples(
        st.floats(50.0, 80.0), st.floats(45.0, 65.0), st.floats(5.0, 85.0), st.floats(20.0, 40.0)
    ),
    st.tuples(
        st.floats(-2.0, 2.0),
        st.floats(-2.0, 2.0),
        st.floats(-2.0, 2.0),
    ),
    st.floats(0.0, 0.1),
    st.integers(0, 2**16),
)
def test_the_solver_reaches_scipys_minimum_of_the_same_robust_cost(
    square: tuple[float, float, float, float],
    offset: tuple[float, float, float],
    noise: float,
    seed: int,
) -> None:
    """From one start, the Levenberg–Marquardt of the fit and SciPy's
    ``least_squares`` (soft-L1, f_scale 0.3, the exact Jacobian) on the same
    pixels: it ends on the true square to a tenth of a pixel, never more than
    0.02 px farther from it than SciPy's. (On a noisy mask the cost has kinks
    where pixels enter and leave the one-pixel ramp, and shallow local minima a
    few hundredths of a pixel apart: two solvers stop in neighbouring ones; and
    SciPy's trust region sometimes stops at the start.) Squares turned 5° or
    more: near 0° a whole row of pixels enters the ramp at once, a kink this
    solver can stop at up to a pixel off from a start 2 px away; the fit comes to
    the sharp square through blurred ones first, at any angle — the next test."""
    alpha = _noisy_square(square, noise, seed)
    uu, vv = _grid()
    u, v, theta, side = square
    start = np.array([u + offset[0], v + offset[1], theta + offset[2], side])
    near = square_alpha(start + [0.0, 0.0, 0.0, 5.0], uu, vv) > 0
    model = SquareModel(uu[near], vv[near], alpha[near], f_scale=0.3)
    scale = np.array([1.0, 1.0, 2.0, 1.0])
    mine, cost = least_squares(model, start, scale, 1e-8)

    def jacobian(params: np.ndarray) -> np.ndarray:
        """The residual's Jacobian, dense, from the model's frame."""
        qu, qv, distance = model.frame(params)
        c, s = math.cos(math.radians(params[2])), math.sin(math.radians(params[2]))
        on = np.abs(distance) <= 0.5
        along_u = np.abs(qu) >= np.abs(qv)
        sign = np.where(along_u, np.sign(qu), np.sign(qv)) * on
        return np.stack(
            [
                np.where(along_u, c, -s) * sign,
                np.where(along_u, s, c) * sign,
                np.where(along_u, -qv, qu) * sign * math.pi / 180.0,
                0.5 * on,
            ],
            axis=1,
        )

    theirs = optimize.least_squares(
        model.residual,
        start,
        jac=jacobian,
        x_scale=scale,
        xtol=1e-8,
        ftol=1e-8,
        loss="soft_l1",
        f_scale=0.3,
        max_nfev=500,
    )
    assert cost == model.cost(mine) <= model.cost(start)
    error = math.dist(mine[:2], (u, v))
    assert error < 0.1
    assert abs(mine[3] - side) < 0.1
    assert error <= math.dist(theirs.x[:2], (u, v)) + 0.02


@settings(max_examples=25, deadline=None)
@given(
    squares,
    st.floats(0.0, 2 * math.pi),
    st.floats(0.0, 1.0),
    st.floats(-3.0, 3.0),
    st.floats(-2.0, 2.0),
    st.integers(0, 2**16),
)
def test_the_fit_finds_the_square_from_a_start_a_hough_bin_off(
    square: tuple[float, float, float, float],
    direction: float,
    share: float,
    turn: float,
    grow: float,
    seed: int,
) -> None:
    """A start up to a Hough bin off a noisy square (2 px of centre, 3°, 2 px of
    side; the fit looks at the pixels up to 2.5 px outside the start's outline):
    the fit ends on the square to a tenth of a pixel and a third of a degree, and
    the mask bears it out."""
    alpha = _noisy_square(square, 0.05, seed)
    u, v, theta, side = square
    reach = 2.0 * share
    start = Hypothesis(
        u + reach * math.cos(direction),
        v + reach * math.sin(direction),
        theta + turn,
        side + grow,
        1.0,
    )
    params, coverage, rms, free = fit_square(alpha, start)
    assert math.dist(params[:2], (u, v)) < 0.1
    assert abs(params[3] - side) < 0.1
    assert abs((params[2] - theta + 45.0) % 90.0 - 45.0) < 1 / 3
    settings_ = PerceptionSettings()
    assert coverage >= settings_.min_coverage
    assert rms <= settings_.max_residual
    assert free == 1.0


@settings(max_examples=40, deadline=None)
@given(
    squares,
    st.floats(-0.25, 0.25),
    st.floats(-0.25, 0.25),
    st.floats(0.0, 1.0),
    st.floats(0.0, 1.0),
    st.floats(0.0, 1.0),
)
def test_a_start_within_a_quarter_side_of_a_block_is_fitted(
    square: tuple[float, float, float, float],
    along: float,
    across: float,
    where_u: float,
    where_v: float,
    aspect: float,
) -> None:
    """The bound behind MIN_CORE_COVERAGE: a block's square with 15 % of its
    interior uncovered (a rectangle of it erased, anywhere: the worst place is
    the start's core) and a start of its side and angle whose centre lies
    within a quarter side of its centre along its axes: the start's central half
    is covered at least MIN_CORE_COVERAGE, so the fit runs from it."""
    u, v, theta, side = square
    c, s = math.cos(math.radians(theta)), math.sin(math.radians(theta))
    uu, vv = _grid()
    qu = c * (uu - u) + s * (vv - v)  # the pixels in the square's frame
    qv = -s * (uu - u) + c * (vv - v)
    # an erased rectangle of 15 % of the square's area, of any aspect in [0.15, 1]
    width = side * (0.15 + 0.85 * aspect)
    height = 0.15 * side * side / width
    low_u = -side / 2 + where_u * (side - width)
    low_v = -side / 2 + where_v * (side - height)
    # erased: the pixels whose centre lies in it (about its area, to a pixel's rim)
    erased = (qu >= low_u) & (qu < low_u + width) & (qv >= low_v) & (qv < low_v + height)
    whole = square_alpha(np.array(square), uu, vv)
    alpha = np.where(erased, 0.0, whole)
    inside = whole > 0.99
    if alpha[inside].mean() < PerceptionSettings().min_coverage:
        return  # the pixel grid erased a little more than 15 % of the interior
    centre = (u + side * (along * c - across * s), v + side * (along * s + across * c))
    core = np.array([*centre, theta, side / 2])
    assert core_coverage(alpha, core) >= MIN_CORE_COVERAGE


def test_a_start_on_table_is_not_fitted_and_reports_its_own_square() -> None:
    """A start whose centre lies on empty table beside a square: not fitted (its
    central half is uncovered); the measures are those of the start's square,
    which fails the coverage a block needs."""
    alpha = _noisy_square((60.0, 55.0, 10.0, 30.0), 0.0, 0)
    start = Hypothesis(100.0, 55.0, 10.0, 30.0, 1.0)
    params, coverage, rms, _ = fit_square(alpha, start)
    assert list(params) == [100.0, 55.0, 10.0, 30.0]
    assert coverage < PerceptionSettings().min_coverage
    assert rms > PerceptionSettings().max_residual


def _shape_mask(kind: str, side: float, theta: float, width: float) -> np.ndarray:
    """A soft mask of a shape that is no block, centred in the crop: a square's
    outline ``width`` px wide (a ring), a disc, an L of two bars, a bar — or a block:
    a square with 15 % of it cut away at a corner, ``width`` px wide."""
    uu, vv = _grid()
    u, v = SHAPE[1] / 2, SHAPE[0] / 2
    c, s = math.cos(math.radians(theta)), math.sin(math.radians(theta))
    qu, qv = c * (uu - u) + s * (vv - v), -s * (uu - u) + c * (vv - v)
    outside = np.maximum(np.abs(qu), np.abs(qv)) - side / 2  # ≈ signed distance
    if kind == "ring":
        distance = np.maximum(outside, -width - outside)
    elif kind == "disc":
        distance = np.hypot(qu, qv) - side / 2
    elif kind == "L":
        bar_u = np.maximum(np.abs(qu) - side / 2, np.abs(qv + side / 2 - width / 2) - width / 2)
        bar_v = np.maximum(np.abs(qv) - side / 2, np.abs(qu + side / 2 - width / 2) - width / 2)
        distance = np.minimum(bar_u, bar_v)
    elif kind == "block":
        height = 0.15 * side * side / width
        notch = np.maximum(qu - (side / 2 - width), qv - (side / 2 - height))
        distance = np.maximum(outside, -notch)
    else:  # a bar across
        distance = np.maximum(np.abs(qu) - side, np.abs(qv) - width / 2)
    soft: np.ndarray = np.clip(0.5 - distance, 0.0, 1.0)
    return soft


@settings(max_examples=40, deadline=None)
@given(
    st.sampled_from(["ring", "disc", "L", "bar", "block"]),
    st.floats(20.0, 40.0),  # side
    st.floats(0.0, 89.9),  # θ
    st.floats(0.15, 0.45),  # bar or ring width, a share of the side
    st.tuples(st.floats(-0.25, 0.25), st.floats(-0.25, 0.25), st.floats(-3.0, 3.0)),
)
def test_a_fit_stopped_as_hopeless_would_have_found_no_block(
    kind: str,
    side: float,
    theta: float,
    width: float,
    offset: tuple[float, float, float],
) -> None:
    """Shapes that are no block and blocks with a corner cut away, started from a
    Hough-like square a quarter side off at most: where the fit stops after its
    blurred squares (no sharp fit run), the sharp fit it skipped (the stop switched
    off) ends in no block either — far from the start's size (the sides a vote
    looks for: within 20 %), too little covered, or misfitting even against rounded
    corners; and what the stopped fit reports fails the block's limits too."""
    alpha = _shape_mask(kind, side, theta, width * side)
    u, v = SHAPE[1] / 2 + offset[0] * side, SHAPE[0] / 2 + offset[1] * side
    start = Hypothesis(u, v, theta + offset[2], side, 1.0)
    limits = PerceptionSettings()
    tolerances: list[float] = []

    def recorded(*args: object, **kwargs: object) -> tuple[np.ndarray, float]:
        tolerances.append(float(args[3]))  # type: ignore[arg-type]
        return least_squares(*args, **kwargs)  # type: ignore[arg-type]

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(square_fit, "least_squares", recorded)
        stopped = fit_square(alpha, start)
    if 1e-6 in tolerances or not tolerances:
        return  # fitted sharp (or not fitted at all: its core uncovered)
    _, coverage, rms, _ = stopped
    assert coverage < limits.min_coverage or rms > limits.max_residual
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(square_fit, "HOPELESS_COVERAGE", 0.0)
        patch.setattr(square_fit, "HOPELESS_MISFIT", math.inf)
        params, coverage, rms, _ = fit_square(alpha, start)
    misfit = min(rms, rounded_misfit(alpha, params))
    sized = 0.8 * side <= params[3] <= 1.2 * side  # a size the vote looked for
    assert not sized or coverage < limits.min_coverage or misfit > limits.max_residual, (
        params,
        coverage,
        rms,
    )


@settings(max_examples=60, deadline=None)
@given(
    square=st.tuples(
        st.floats(-30, 160), st.floats(-30, 140), st.floats(0, 90), st.floats(0.5, 90)
    )
)
def test_a_squares_window_holds_every_pixel_it_touches_with_the_same_values(
    square: tuple[float, float, float, float],
) -> None:
    """The fit, the cut-out of a found square and the occluded tops' measures look at
    the part of a crop square_window gives: the square over it (its u a row, its v
    a column, broadcast) is the square over the whole crop there, value for value,
    and nothing of the square lies outside it."""
    params = np.array(square)
    uu, vv = _grid()
    whole = square_alpha(params, uu, vv)
    part_u, part_v, window = square_window(SHAPE, params, params[3])
    assert np.array_equal(square_alpha(params, part_u, part_v), whole[window])
    outside = np.ones(SHAPE, dtype=bool)
    outside[window] = False
    assert not whole[outside].any()
