"""The Hough vote's counting, compiled (numba): each edge point's votes for the centres
of the squares it could lie on, summed into the accumulator's bins
(:func:`demoplan.perception.hough._votes`).

In NumPy the votes were arrays of every (edge point, side, step) pair — their centres,
which fall inside, their bins — and one ``bincount``: a dozen passes over arrays of
hundreds of thousands of pairs, and their memory. Here they are two passes over the
pairs and none of those arrays: the first finds the window of bins the votes fall in,
the second adds each vote to its bin, in ``bincount``'s order (the pairs' order), in
double precision — the same sums to the last bit.
"""

from __future__ import annotations

import numpy as np

from demoplan.perception.jit import compiled

__all__ = ["vote_counts"]


@compiled
def _counts(
    u: np.ndarray,
    v: np.ndarray,
    nu: np.ndarray,
    nv: np.ndarray,
    g: np.ndarray,
    theta_bin: np.ndarray,
    half: np.ndarray,
    side_of: np.ndarray,
    along: np.ndarray,
    n_theta: int,
    n_y: int,
    n_x: int,
    xy_bin: float,
) -> tuple[np.ndarray, int, int, int, int]:
    """The counts (flat, single precision), the window's first row and column and its
    rows and columns; an empty array where no vote falls inside the crop."""
    # first the window: the least and greatest row and column the votes fall in
    row_min, col_min, row_max, col_max = n_y, n_x, -1, -1
    for e in range(u.size):
        for p in range(side_of.size):
            s = side_of[p]
            cx = (u[e] - half[s] * nu[e]) / xy_bin - along[p] * nv[e]
            cy = (v[e] - half[s] * nv[e]) / xy_bin + along[p] * nu[e]
            if cx >= 0 and cx < n_x and cy >= 0 and cy < n_y:
                col, row = int(cx), int(cy)
                row_min = min(row_min, row)
                row_max = max(row_max, row)
                col_min = min(col_min, col)
                col_max = max(col_max, col)
    if row_min > row_max:
        return np.empty(0, dtype=np.float32), 0, 0, 0, 0
    row0, col0 = max(0, row_min - 1), max(0, col_min - 1)
    rows = min(n_y, row_max + 2) - row0
    cols = min(n_x, col_max + 2) - col0
    # then each vote into its bin, in the pairs' order
    total = np.zeros(half.size * (n_theta + 2) * (rows + 1) * cols)
    for e in range(u.size):
        for p in range(side_of.size):
            s = side_of[p]
            cx = (u[e] - half[s] * nu[e]) / xy_bin - along[p] * nv[e]
            cy = (v[e] - half[s] * nv[e]) / xy_bin + along[p] * nu[e]
            if cx >= 0 and cx < n_x and cy >= 0 and cy < n_y:
                slice_of = s * (n_theta + 2) + theta_bin[e] + 1
                index = (slice_of * (rows + 1) + (int(cy) - row0)) * cols + (int(cx) - col0)
                total[index] += g[e]
    counts = np.empty(total.size, dtype=np.float32)
    for i in range(total.size):
        counts[i] = total[i]
    return counts, row0, col0, rows, cols


def vote_counts(
    edges: tuple[np.ndarray, ...],
    theta_bin: np.ndarray,
    sides: np.ndarray,
    along: np.ndarray,
    side_of: np.ndarray,
    n_theta: int,
    crop: tuple[int, int],
    xy_bin: float,
) -> tuple[np.ndarray, tuple[int, int]] | None:
    """The votes of the edge points ``edges`` (u, v, n_u, n_v, g; θ bins ``theta_bin``)
    for the centres s/2 inside along −n and ``along`` (bins) along the edge, side
    s = ``sides[side_of[p]]`` for each step p, counted in the window of centre bins
    they fall in within ``crop`` (rows, columns) and one bin around it: the
    accumulator over (side, θ with a wrapped bin either side, row with an empty one
    after, column), in single precision, and its first row and column; None when no
    vote falls inside the crop."""
    u, v, nu, nv, g = (np.ascontiguousarray(a, dtype=np.float64) for a in edges)
    half = np.ascontiguousarray(sides / 2, dtype=np.float64)
    side_of = np.ascontiguousarray(side_of, dtype=np.intp)
    along = np.ascontiguousarray(along, dtype=np.float64)
    theta_bin = np.ascontiguousarray(theta_bin, dtype=np.intp)
    n_y, n_x = crop
    counts, row0, col0, rows, cols = _counts(
        u, v, nu, nv, g, theta_bin, half, side_of, along, n_theta, n_y, n_x, float(xy_bin)
    )
    if counts.size == 0:
        return None
    return counts.reshape(sides.size, n_theta + 2, rows + 1, cols), (row0, col0)
