"""The square fit's inner loop, compiled (numba): the robust cost of a one-pixel-ramp
square and its Levenberg–Marquardt minimisation (:mod:`demoplan.perception.square_fit`).

A fit on a photograph is thousands of steps, each over a few thousand pixels: in
NumPy each step is some thirty array calls, and their overhead, not the
arithmetic, was its time. Here one step is one pass over the pixels. The
arithmetic is :class:`demoplan.perception.square_fit.SquareModel`'s, operation
for operation, except the order of the sums (sequential here, pairwise and BLAS
there) and the 4 × 4 solve (partial-pivoting LU written out here, LAPACK there):
results agree to rounding, which the tests check against the NumPy formulas.

Compiled on first use and cached (:mod:`demoplan.perception.jit`).
"""

from __future__ import annotations

import math

import numpy as np

from demoplan.perception.jit import compiled

__all__ = ["normal_equations", "robust_cost", "robust_least_squares", "solve4"]

_DEG = math.pi / 180.0
_UNIT_SCALE = np.ones(4)


@compiled
def _evaluate(
    us: np.ndarray,
    vs: np.ndarray,
    target: np.ndarray,
    f_scale: float,
    ramp: float,
    params: np.ndarray,
    matrix: np.ndarray,
    gradient: np.ndarray,
    normal: bool,
) -> float:
    """The robust cost ½ f² Σ ρ((r / f)²) at ``params``; with ``normal``, also JᵀWJ
    and JᵀWr into ``matrix`` and ``gradient`` (overwritten): the formulas of
    ``SquareModel.cost`` and ``SquareModel.normal_equations``."""
    u, v, theta, side = params[0], params[1], params[2], params[3]
    c, s = math.cos(theta * _DEG), math.sin(theta * _DEG)
    half = side / 2
    on_ramp = 0.5 * ramp
    unit = ramp == 1.0
    j3 = 0.5 / ramp
    if normal:
        for a in range(4):
            gradient[a] = 0.0
            for b in range(4):
                matrix[a, b] = 0.0
    total = 0.0
    for i in range(us.size):
        du, dv = us[i] - u, vs[i] - v
        qu = c * du
        qu += s * dv
        qv = -s * du
        qv += c * dv
        aqu, aqv = abs(qu), abs(qv)
        distance = (aqu if aqu >= aqv else aqv) - half
        residual = 0.5 - (distance if unit else distance / ramp)
        residual = max(residual, 0.0)
        residual = min(residual, 1.0)
        residual -= target[i]
        root = residual / f_scale
        root = math.sqrt(root * root + 1.0)
        total += root - 1.0
        if normal and abs(distance) <= on_ramp:
            if aqu >= aqv:
                sign = (1.0 if qu > 0 else (-1.0 if qu < 0 else 0.0)) / ramp
                j0, j1, j2 = c * sign, s * sign, -qv * sign * _DEG
            else:
                sign = (1.0 if qv > 0 else (-1.0 if qv < 0 else 0.0)) / ramp
                j0, j1, j2 = -s * sign, c * sign, qu * sign * _DEG
            weight = 1.0 / root
            wr = weight * residual
            w0, w1, w2, w3 = j0 * weight, j1 * weight, j2 * weight, j3 * weight
            matrix[0, 0] += w0 * j0
            matrix[0, 1] += w0 * j1
            matrix[0, 2] += w0 * j2
            matrix[0, 3] += w0 * j3
            matrix[1, 1] += w1 * j1
            matrix[1, 2] += w1 * j2
            matrix[1, 3] += w1 * j3
            matrix[2, 2] += w2 * j2
            matrix[2, 3] += w2 * j3
            matrix[3, 3] += w3 * j3
            gradient[0] += j0 * wr
            gradient[1] += j1 * wr
            gradient[2] += j2 * wr
            gradient[3] += j3 * wr
    if normal:
        for a in range(4):
            for b in range(a):
                matrix[a, b] = matrix[b, a]
    return f_scale**2 * total


@compiled
def _solve(matrix: np.ndarray, rhs: np.ndarray, out: np.ndarray) -> bool:
    """``out`` = ``matrix``⁻¹ ``rhs`` (4 × 4) by LU with partial pivoting (LAPACK's
    dgesv's steps); False, ``out`` undefined, where a pivot is exactly zero
    (where dgesv reports the matrix singular)."""
    n = 4
    a = np.empty((n, n))
    for i in range(n):
        out[i] = rhs[i]
        for j in range(n):
            a[i, j] = matrix[i, j]
    for k in range(n):
        pivot = k
        for i in range(k + 1, n):
            if abs(a[i, k]) > abs(a[pivot, k]):
                pivot = i
        if a[pivot, k] == 0.0:
            return False
        if pivot != k:
            for j in range(n):
                swapped = a[k, j]
                a[k, j] = a[pivot, j]
                a[pivot, j] = swapped
            swapped = out[k]
            out[k] = out[pivot]
            out[pivot] = swapped
        inverse = 1.0 / a[k, k]
        for i in range(k + 1, n):
            a[i, k] *= inverse
            for j in range(k + 1, n):
                a[i, j] -= a[i, k] * a[k, j]
            out[i] -= out[k] * a[i, k]
    for k in range(n - 1, -1, -1):
        out[k] /= a[k, k]
        for i in range(k):
            out[i] -= out[k] * a[i, k]
    return True


@compiled
def _least_squares(
    us: np.ndarray,
    vs: np.ndarray,
    target: np.ndarray,
    f_scale: float,
    ramp: float,
    start: np.ndarray,
    scale: np.ndarray,
    tolerance: float,
    max_steps: int,
) -> tuple[np.ndarray, float]:
    """Levenberg–Marquardt on the reweighted normal equations (see
    :func:`demoplan.perception.square_fit.least_squares`)."""
    params, metric = np.empty(4), np.empty(4)
    matrix, gradient = np.empty((4, 4)), np.empty(4)
    trial_matrix, trial_gradient = np.empty((4, 4)), np.empty(4)
    damped, step, trial, rhs = np.empty((4, 4)), np.empty(4), np.empty(4), np.empty(4)
    for i in range(4):
        params[i] = start[i]
        metric[i] = 1.0 / (scale[i] * scale[i])
    cost = _evaluate(us, vs, target, f_scale, ramp, params, matrix, gradient, True)
    damping = 0.0
    for i in range(4):
        damping = max(damping, matrix[i, i] / metric[i])
    damping = 1e-3 * damping
    if damping == 0.0:
        damping = 1e-3
    growth = 2.0
    for _ in range(max_steps):
        moving = False
        for i in range(4):
            if gradient[i] != 0.0:
                moving = True
        if not moving:
            break  # no pixel on the ramp (or all matched): nothing moves the square
        for i in range(4):
            for j in range(4):
                damped[i, j] = matrix[i, j]
            damped[i, i] = matrix[i, i] + damping * metric[i]
            rhs[i] = -gradient[i]
        if not _solve(damped, rhs, step):
            damping *= growth
            growth *= 2.0
            continue
        for i in range(4):
            trial[i] = params[i] + step[i]
        trial_cost = _evaluate(
            us, vs, target, f_scale, ramp, trial, trial_matrix, trial_gradient, True
        )
        predicted = 0.0
        for i in range(4):
            predicted += step[i] * (damping * metric[i] * step[i] - gradient[i])
        predicted *= 0.5
        if not trial_cost < cost:
            damping *= growth
            growth *= 2.0
            if damping > 1e12:
                break
            continue
        ratio = (cost - trial_cost) / predicted if predicted > 0 else 1.0
        damping *= max(1.0 / 3.0, 1.0 - math.pow(2.0 * ratio - 1.0, 3.0))  # as CPython's **
        growth = 2.0
        step_norm, size = 0.0, 0.0
        for i in range(4):
            step_norm += (step[i] / scale[i]) ** 2
            size += (params[i] / scale[i]) ** 2
        small_step = math.sqrt(step_norm) < tolerance * (tolerance + math.sqrt(size))
        small_change = max(cost - trial_cost, predicted) < tolerance * cost
        cost = trial_cost
        for i in range(4):
            params[i] = trial[i]
            gradient[i] = trial_gradient[i]
            for j in range(4):
                matrix[i, j] = trial_matrix[i, j]
        if small_step or small_change:
            break
    return params, cost


def _float64(values: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(values, dtype=np.float64)


def robust_cost(
    us: np.ndarray,
    vs: np.ndarray,
    target: np.ndarray,
    f_scale: float,
    ramp: float,
    params: np.ndarray,
) -> float:
    """½ f² Σ ρ((r / f)²), ρ(z) = 2(√(1 + z) − 1), of the residuals r of the square
    ``params`` (u, v, θ, s) with an edge ramping over ``ramp`` px at the points
    (``us``, ``vs``) against the mask values ``target``."""
    _, cost = _least_squares(  # no step: the cost at ``params``
        _float64(us),
        _float64(vs),
        _float64(target),
        float(f_scale),
        float(ramp),
        _float64(params),
        _UNIT_SCALE,
        0.0,
        0,
    )
    return float(cost)


def normal_equations(
    us: np.ndarray,
    vs: np.ndarray,
    target: np.ndarray,
    f_scale: float,
    ramp: float,
    params: np.ndarray,
) -> tuple[float, np.ndarray, np.ndarray]:
    """(cost, JᵀWJ, JᵀWr) at ``params``, as each step of :func:`robust_least_squares`
    computes them (``SquareModel.normal_equations``' formulas)."""
    matrix, gradient = np.empty((4, 4)), np.empty(4)
    cost = _evaluate(
        _float64(us),
        _float64(vs),
        _float64(target),
        float(f_scale),
        float(ramp),
        _float64(params),
        matrix,
        gradient,
        True,
    )
    return float(cost), matrix, gradient


def solve4(matrix: np.ndarray, rhs: np.ndarray) -> np.ndarray | None:
    """``matrix``⁻¹ ``rhs`` for a 4 × 4 ``matrix`` as each step solves it; None where
    a pivot is exactly zero (where ``numpy.linalg.solve`` raises)."""
    out = np.empty(4)
    return out if _solve(_float64(matrix), _float64(rhs), out) else None


def robust_least_squares(
    us: np.ndarray,
    vs: np.ndarray,
    target: np.ndarray,
    f_scale: float,
    ramp: float,
    start: np.ndarray,
    scale: np.ndarray,
    tolerance: float,
    max_steps: int,
) -> tuple[np.ndarray, float]:
    """The parameters near ``start`` minimising :func:`robust_cost`, and that cost."""
    params, cost = _least_squares(
        _float64(us),
        _float64(vs),
        _float64(target),
        float(f_scale),
        float(ramp),
        _float64(start).copy(),
        _float64(scale),
        float(tolerance),
        int(max_steps),
    )
    return params, float(cost)
