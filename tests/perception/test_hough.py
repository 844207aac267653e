"""The Hough transform over (x, y, θ, s) and the sub-pixel fit, on soft masks of one
square: the vote does not depend on how many side lengths are filled at once, and
the fit, which looks only at the crop's part near the square, reports the whole
crop's coverage and misfit."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.perception import hough
from demoplan.perception.blocks import _fit, _square_alpha
from demoplan.perception.hough import Hypothesis, hough_squares


def square_mask(
    u: float, v: float, theta: float, side: float, shape: tuple[int, int]
) -> np.ndarray:
    """A soft mask of one square (u, v from the crop's bottom-left corner, px)."""
    height, width = shape
    uu, vv = np.meshgrid(np.arange(width) + 0.5, height - np.arange(height) - 0.5)
    return _square_alpha(np.array([u, v, theta, side]), uu, vv)


squares = st.tuples(
    st.floats(40.0, 60.0),  # u
    st.floats(35.0, 50.0),  # v
    st.floats(0.0, 89.9),  # θ
    st.floats(22.0, 36.0),  # side
)


@settings(max_examples=15, deadline=None)
@given(squares)
def test_the_vote_is_the_same_one_side_at_a_time(
    square: tuple[float, float, float, float],
) -> None:
    """Sides voted for in one block of bins or one at a time (a tiny MAX_CELLS):
    the same hypotheses; the strongest is the square to two bins in each of
    (x, y, θ, s): votes shared with the neighbouring bins may move the peak by
    one (a 22 px square at 68.5° peaked 3.5° off, with θ bins of 3°)."""
    mask = square_mask(*square, shape=(90, 110))
    together = hough_squares(mask, (20.0, 40.0))
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(hough, "MAX_CELLS", 1)
        alone = hough_squares(mask, (20.0, 40.0))
    assert alone == together
    best = together[0]
    u, v, theta, side = square
    assert abs(best.u - u) <= 2 * hough.XY_BIN and abs(best.v - v) <= 2 * hough.XY_BIN
    turn = abs(((best.theta - theta + 45.0) % 90.0) - 45.0)
    assert turn <= 2 * hough.THETA_BIN
    assert abs(best.side - side) <= 2 * hough.S_BIN


def test_no_edges_no_hypotheses() -> None:
    assert hough_squares(np.zeros((40, 40)), (20.0, 30.0)) == []
    assert hough_squares(np.ones((40, 40)), (20.0, 30.0)) == []


@settings(max_examples=15, deadline=None)
@given(squares, st.integers(0, 60), st.integers(0, 60))
def test_the_fit_reports_the_whole_crop(
    square: tuple[float, float, float, float], left: int, below: int
) -> None:
    """A square anywhere in a crop with empty table around it (``left`` and ``below``
    px more of it): found to a hundredth of a pixel, and its coverage, misfit and free
    outline are those computed over the whole crop."""
    u, v, theta, side = square
    mask = square_mask(u + left, v + below, theta, side, shape=(100 + below, 120 + left))
    start = Hypothesis(u + left + 1.0, v + below - 1.0, theta + 1.0, side + 1.0, 1.0)
    params, coverage, rms, free = _fit(mask, start)
    assert math.dist(params[:2], (u + left, v + below)) < 0.01
    assert abs(params[3] - side) < 0.01
    height, width = mask.shape
    uu, vv = np.meshgrid(np.arange(width) + 0.5, height - np.arange(height) - 0.5)
    model = _square_alpha(params, uu, vv)
    assert coverage == pytest.approx(float(mask[model > 0.99].mean()), abs=1e-12)
    own = model > 0.01
    assert rms == pytest.approx(float(np.sqrt(np.mean((model[own] - mask[own]) ** 2))), abs=1e-12)
    assert free == 1.0  # nothing but table around it
