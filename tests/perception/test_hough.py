"""The Hough transform over (x, y, θ, s) and the sub-pixel fit, on soft masks of one
square: the vote does not depend on how many side lengths are filled at once, and
the fit, which looks only at the crop's part near the square, reports the whole
crop's coverage and misfit; large sides are voted for an octave at a time on
shrunk masks and fitted at full resolution."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.perception import blocks, hough
from demoplan.perception.blocks import (
    HOUGH_SIDE_PX,
    OCTAVE_END,
    OCTAVE_SLACK,
    PerceptionSettings,
    _octaves,
    detect_blocks,
)
from demoplan.perception.camera import Camera
from demoplan.perception.hough import Hypothesis, hough_squares
from demoplan.perception.square_fit import fit_square, square_alpha
from demoplan.perception.synthetic import SyntheticBlock, render_blocks


def square_mask(
    u: float, v: float, theta: float, side: float, shape: tuple[int, int]
) -> np.ndarray:
    """A soft mask of one square (u, v from the crop's bottom-left corner, px)."""
    height, width = shape
    uu, vv = np.meshgrid(np.arange(width) + 0.5, height - np.arange(height) - 0.5)
    return square_alpha(np.array([u, v, theta, side]), uu, vv)


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
    assert abs(best.side - side) <= 2 * max(hough.S_BIN, hough.SIDE_STEP * side)  # two bins


@settings(max_examples=10, deadline=None)
@given(squares, st.integers(1, 400), st.integers(1, 400))
def test_the_empty_part_of_a_crop_neither_changes_the_vote_nor_costs_bins(
    square: tuple[float, float, float, float], above: int, right: int
) -> None:
    """A square's mask with empty rows added above it and columns to its right (its
    pixels keep their coordinates, counted from the bottom-left): the same
    hypotheses, votes and all, from an accumulator of as many bins — only the
    window the votes fall in is filled (a region's crop is mostly empty when its
    outline is a ring or a thin L round the table)."""
    mask = square_mask(*square, shape=(90, 110))
    padded = np.pad(mask, ((above, 0), (0, right)))
    assert hough_squares(padded, (20.0, 40.0)) == hough_squares(mask, (20.0, 40.0))
    bins = []
    for crop in (mask, padded):
        u, v, nu, nv, g = hough.edge_pixels(crop)
        theta_bin = np.floor((np.degrees(np.arctan2(nv, nu)) % 90.0) / hough.THETA_BIN + 0.5)
        height, width = crop.shape
        shape = (30, -(-height // 2), -(-width // 2))
        steps = [np.arange(-15.0 + 1.0, 15.0, 2.0)]
        sides = np.array([30.0])
        accumulator, corner = hough._votes(
            (u, v, nu, nv, g), theta_bin.astype(np.intp) % 30, sides, steps, shape
        )
        bins.append((accumulator.shape, corner))
    assert bins[0] == bins[1]


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
    params, coverage, rms, free = fit_square(mask, start)
    assert math.dist(params[:2], (u + left, v + below)) < 0.01
    assert abs(params[3] - side) < 0.01
    height, width = mask.shape
    uu, vv = np.meshgrid(np.arange(width) + 0.5, height - np.arange(height) - 0.5)
    model = square_alpha(params, uu, vv)
    assert coverage == pytest.approx(float(mask[model > 0.99].mean()), abs=1e-12)
    own = model > 0.01
    assert rms == pytest.approx(float(np.sqrt(np.mean((model[own] - mask[own]) ** 2))), abs=1e-12)
    assert free == 1.0  # nothing but table around it


@settings(max_examples=60, deadline=None)
@given(st.floats(16.0, 400.0), st.floats(1.0, 20.0))
def test_the_octaves_cover_the_sides_each_at_least_the_vote_s_size(
    low: float, ratio: float
) -> None:
    """The octaves of a side range follow each other without gap from its smallest
    side to its largest, each at twice the previous factor, and every side of every
    octave is at least :data:`HOUGH_SIDE_PX` (px) on its shrunk mask and at most
    ``OCTAVE_END`` × ``OCTAVE_SLACK`` times that: the vote sees every square at
    about the same size in pixels."""
    high = low * ratio
    base = max(1, int(low // HOUGH_SIDE_PX))
    octaves = _octaves((low, high), base)
    assert octaves[0][:2] == (base, low)
    assert octaves[-1][2] == high
    for (factor, _, end), (following, start, _) in itertools.pairwise(octaves):
        assert start == end
        assert following == 2 * factor
    for factor, first, last in octaves:
        assert first <= last
        assert first / factor >= min(HOUGH_SIDE_PX, low)
        assert last / factor <= OCTAVE_END * OCTAVE_SLACK * HOUGH_SIDE_PX + 1e-9


@settings(max_examples=5, deadline=None)
@given(st.integers(0, 10_000))
def test_a_large_block_is_voted_for_on_a_shrunk_mask_and_fitted_at_full_resolution(
    seed: int,
) -> None:
    """A block of 9–15 cm at 1 px = 1 mm among sizes of 2–16 cm: its side is voted
    for on a mask shrunk by 2 or 4 (its octave), and the fit at full resolution
    finds it as exactly as a small block's: its centre to a fiftieth of a pixel, its
    corners to a twentieth (the turn), its side to a tenth (the render's edge pixels
    are sampled)."""
    rng = np.random.default_rng(seed)
    camera = Camera(1000.0, (0.0, 0.0))
    side = float(rng.uniform(0.09, 0.15))
    x, yaw = float(rng.uniform(0.18, 0.22)), float(rng.uniform(-45, 45))
    truth = SyntheticBlock("red", x, 0.15, yaw, side)
    image = render_blocks([truth], camera, width=400, height=300, noise=2.0, shading=0.1, rng=rng)
    voted: list[tuple[int, int]] = []

    def spied(alpha: np.ndarray, *args: object, **kwargs: object) -> list[Hypothesis]:
        voted.append(alpha.shape)
        return hough_squares(alpha, *args, **kwargs)  # type: ignore[arg-type]

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(blocks, "hough_squares", spied)
        found = detect_blocks(image, camera, PerceptionSettings(min_side=0.02, max_side=0.16))
    assert len(set(voted)) > 1  # the same crop at more than one resolution
    assert len(found) == 1
    block = found[0]
    assert math.dist((block.x, block.y), (truth.x, truth.y)) < 2e-5
    turn = math.radians(abs(((block.yaw - truth.yaw + 45.0) % 90.0) - 45.0))
    assert turn * side / 2 * camera.px_per_m < 0.05
    assert abs(block.side - side) < 1e-4


@settings(max_examples=15, deadline=None)
@given(squares, squares, st.integers(0, 200), st.integers(0, 120))
def test_parts_of_a_mask_far_apart_are_voted_for_apart_with_the_same_result(
    first: tuple[float, float, float, float],
    second: tuple[float, float, float, float],
    right: int,
    up: int,
) -> None:
    """Two squares in one crop, the second ``right`` and ``up`` px off: their edge
    points are voted for in groups of their own when no vote of one reaches the
    other's bins (:func:`hough._clusters`), and the hypotheses, votes and all, are
    those of one window over both (every edge point in one group)."""
    shape = (100 + up, 110 + right)
    u, v, theta, side = second
    mask = np.maximum(
        square_mask(*first, shape=shape), square_mask(u + right, v + up, theta, side, shape)
    )
    sides = (20.0, 40.0)
    edges = hough.edge_pixels(mask)
    bins = (30, -(-shape[0] // 2), -(-shape[1] // 2))
    groups = hough._clusters(edges[0], edges[1], 40.0, bins)
    assert sorted(np.concatenate(groups).tolist()) == list(range(edges[0].size))
    if math.hypot(right, up) > 110 + 2 * 40.0:  # farther than both reaches (and the squares)
        assert len(groups) == 2
    alone = hough_squares(mask, sides)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(hough, "_clusters", lambda u, *_: [np.arange(u.size)])
        together = hough_squares(mask, sides)
    assert alone == together
