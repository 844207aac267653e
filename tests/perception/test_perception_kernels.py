"""The compiled inner loops of perception against the NumPy formulas they replace: the
square fit's cost, normal equations, 4 × 4 solve and Levenberg–Marquardt steps
(demoplan.perception.fit_kernel, to rounding: the sums run in another order)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.perception import fit_kernel
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
        model.normal_equations(trial)
        trial_cost = model._last_cost
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
