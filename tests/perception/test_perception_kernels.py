"""The compiled inner loops of perception against the NumPy formulas they replace: the
square fit's cost, normal equations, 4 × 4 solve and Levenberg–Marquardt steps
(demoplan.perception.fit_kernel, to rounding: the sums run in another order) and the
Hough vote's counts (demoplan.perception.hough_kernel, to the last bit: the same
sums in the same order)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.perception import fit_kernel, hough
from demoplan.perception.hough_kernel import vote_counts
from demoplan.perception.square_fit import SquareModel, square_alpha, square_window

SCALE = np.array([1.0, 1.0, 2.0, 1.0])

squares = st.tuples(
    st.floats(30.0, 50.0),  # u
    st.floats(30.0, 50.0),  # v
    st.floats(0.0, 90.0),  # θ
    st.floats(8.0, 40.0),  # side
)
offsets = st.tuples(st.floats(-3.0, 3.0), st.floats(-3.0, 3.0), st.floats(-6.0, 6.0))


def _pixels(
    square: tuple[float, float, float, float], noise: float, seed: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(u, v, mask value) of the pixels near a noisy soft square (as a fit takes them)."""
    params = np.array(square)
    grown = params + [0.0, 0.0, 0.0, 5.0]
    uu, vv, _ = square_window((90, 90), grown, grown[3])
    near = square_alpha(grown, uu, vv) > 0
    alpha = square_alpha(params, uu, vv)
    alpha = np.clip(alpha + np.random.default_rng(seed).normal(0.0, noise, alpha.shape), 0, 1)
    us, vs = (np.broadcast_to(grid, near.shape)[near] for grid in (uu, vv))
    return us, vs, alpha[near]


def _numpy_least_squares(
    model: SquareModel, start: np.ndarray, tolerance: float, max_steps: int
) -> tuple[np.ndarray, float]:
    """The fit's Levenberg–Marquardt in NumPy (the code the kernel replaced)."""
    params = start.astype(float)
    cost, matrix, gradient = model.normal_equations(params)
    metric = 1.0 / np.square(SCALE)
    damping = 1e-3 * float(np.max(np.diag(matrix) / metric, initial=0.0)) or 1e-3
    growth = 2.0
    for _ in range(max_steps):
        if not gradient.any():
            break
        try:
            step = np.linalg.solve(matrix + damping * np.diag(metric), -gradient)
        except np.linalg.LinAlgError:
            damping *= growth
            growth *= 2.0
            continue
        trial = params + step
        trial_cost, _, _ = model.normal_equations(trial)
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
        scaled_step, scaled = step / SCALE, params / SCALE
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


@settings(max_examples=60, deadline=None)
@given(squares, offsets, st.sampled_from([1.0, 2.0, 4.0]), st.floats(0.0, 0.2), st.integers(0, 999))
def test_the_compiled_cost_and_normal_equations_are_the_numpy_formulas(
    square: tuple[float, float, float, float],
    offset: tuple[float, float, float],
    ramp: float,
    noise: float,
    seed: int,
) -> None:
    """At a square off the mask's (some pixels on its ramp, some not), the kernel's
    robust cost, JᵀWJ and JᵀWr are SquareModel's NumPy ones to rounding (each
    term is at most ~1: a few ulps of the pixels' count)."""
    us, vs, target = _pixels(square, noise, seed)
    model = SquareModel(us, vs, target, f_scale=0.3, ramp=ramp)
    params = np.array(square) + [*offset, 0.0]
    cost, matrix, gradient = model.normal_equations(params)
    kernel_cost, kernel_matrix, kernel_gradient = fit_kernel.normal_equations(
        us, vs, target, 0.3, ramp, params
    )
    rounding = 1e-12 * us.size
    assert kernel_cost == pytest.approx(cost, rel=1e-12, abs=rounding)
    assert model.cost(params) == kernel_cost
    np.testing.assert_allclose(kernel_matrix, matrix, rtol=1e-12, atol=rounding)
    np.testing.assert_allclose(kernel_gradient, gradient, rtol=1e-12, atol=rounding)


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from([None, 0, 1, 2, 3]))
def test_the_compiled_solve_is_numpys(seed: int, zero_column: int | None) -> None:
    """The 4 × 4 solve of each step: numpy.linalg.solve's answer to rounding on a damped
    Gauss–Newton-like matrix; no answer where numpy's LAPACK finds it singular (a
    column of zeros: an exactly zero pivot)."""
    rng = np.random.default_rng(seed)
    jac = rng.normal(size=(12, 4))
    matrix = jac.T @ jac + np.diag(rng.uniform(0.0, 1.0, 4))
    rhs = rng.normal(size=4)
    if zero_column is not None:
        matrix[:, zero_column] = 0.0
        with pytest.raises(np.linalg.LinAlgError):
            np.linalg.solve(matrix, rhs)
        assert fit_kernel.solve4(matrix, rhs) is None
        return
    solved = fit_kernel.solve4(matrix, rhs)
    assert solved is not None
    np.testing.assert_allclose(solved, np.linalg.solve(matrix, rhs), rtol=1e-9, atol=1e-12)


@settings(max_examples=40, deadline=None)
@given(squares, offsets, st.sampled_from([1.0, 4.0]), st.floats(0.0, 0.2), st.integers(0, 999))
def test_the_compiled_fit_steps_as_the_numpy_one(
    square: tuple[float, float, float, float],
    offset: tuple[float, float, float],
    ramp: float,
    noise: float,
    seed: int,
) -> None:
    """From a start off the square, the compiled Levenberg–Marquardt ends where the
    NumPy one (the same rules on SquareModel's normal equations and
    numpy.linalg.solve) ends, with the same cost, to rounding."""
    us, vs, target = _pixels(square, noise, seed)
    model = SquareModel(us, vs, target, f_scale=0.3, ramp=ramp)
    start = np.array(square) + [*offset, 0.0]
    theirs, their_cost = _numpy_least_squares(model, start, 1e-6, 100)
    mine, cost = fit_kernel.robust_least_squares(
        us, vs, target, 0.3, ramp, start, SCALE, 1e-6, 100
    )
    np.testing.assert_allclose(mine, theirs, rtol=0, atol=1e-7)
    assert cost == pytest.approx(their_cost, rel=1e-9, abs=1e-12 * us.size)


def _numpy_counts(
    edges: tuple[np.ndarray, ...],
    theta_bin: np.ndarray,
    sides: np.ndarray,
    steps: list[np.ndarray],
    crop: tuple[int, int],
) -> tuple[np.ndarray, tuple[int, int]] | None:
    """The vote's counts in NumPy (the code the kernel replaced): every (edge, side,
    step) pair's centre, those inside the crop binned in their window, bincount."""
    u, v, nu, nv, g = edges
    n_theta = round(90.0 / hough.THETA_BIN)
    n_y, n_x = crop
    side_of = np.repeat(np.arange(sides.size), [len(s) for s in steps])
    along = np.concatenate(steps) / hough.XY_BIN
    half = sides / 2
    cx = ((u[:, None] - half[None, :] * nu[:, None]) / hough.XY_BIN)[:, side_of]
    cx -= along[None, :] * nv[:, None]
    cy = ((v[:, None] - half[None, :] * nv[:, None]) / hough.XY_BIN)[:, side_of]
    cy += along[None, :] * nu[:, None]
    inside = (cx >= 0) & (cx < n_x) & (cy >= 0) & (cy < n_y)
    col = cx[inside].astype(np.intp)
    row = cy[inside].astype(np.intp)
    if col.size == 0:
        return None
    row0, col0 = max(0, int(row.min()) - 1), max(0, int(col.min()) - 1)
    n_y = min(n_y, int(row.max()) + 2) - row0
    n_x = min(n_x, int(col.max()) + 2) - col0
    slice_of = side_of[None, :] * (n_theta + 2) + theta_bin[:, None] + 1
    index = slice_of[inside] * (n_y + 1)
    index += row - row0
    index *= n_x
    index += col - col0
    weight = np.broadcast_to(g[:, None], inside.shape)[inside]
    cells = sides.size * (n_theta + 2) * (n_y + 1) * n_x
    total = np.bincount(index, weights=weight, minlength=cells).astype(np.float32)
    return total.reshape(sides.size, n_theta + 2, n_y + 1, n_x), (row0, col0)


@settings(max_examples=60, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.integers(0, 60),
    st.floats(4.0, 30.0),
    st.integers(1, 4),
    st.tuples(st.integers(1, 40), st.integers(1, 40)),
)
def test_the_compiled_vote_counts_are_numpys_to_the_last_bit(
    seed: int, points: int, low: float, n_sides: int, crop: tuple[int, int]
) -> None:
    """Edge points anywhere near a crop (some of their votes inside it, some not, or
    none): the same window, and the same single-precision counts bin for bin."""
    rng = np.random.default_rng(seed)
    n_y, n_x = crop
    u = rng.uniform(-10.0, 2 * n_x + 10.0, points)
    v = rng.uniform(-10.0, 2 * n_y + 10.0, points)
    angle = rng.uniform(0.0, 2 * math.pi, points)
    nu, nv, g = np.cos(angle), np.sin(angle), rng.uniform(0.1, 2.0, points)
    theta_bin = np.floor(np.degrees(angle) % 90.0 / hough.THETA_BIN + 0.5).astype(np.intp) % 30
    sides = hough.side_bins(low, low * 1.5)[:n_sides]
    steps = [np.arange(-s / 2 + hough.XY_BIN / 2, s / 2, hough.XY_BIN) for s in sides]
    side_of = np.repeat(np.arange(sides.size), [len(s) for s in steps])
    along = np.concatenate(steps) / hough.XY_BIN
    edges = (u, v, nu, nv, g)
    theirs = _numpy_counts(edges, theta_bin, sides, steps, crop)
    mine = vote_counts(edges, theta_bin, sides, along, side_of, 30, crop, hough.XY_BIN)
    if theirs is None:
        assert mine is None
        return
    assert mine is not None
    assert mine[1] == theirs[1]
    assert mine[0].dtype == np.float32
    np.testing.assert_array_equal(mine[0], theirs[0])
