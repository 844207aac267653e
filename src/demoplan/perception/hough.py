"""The paper's four-dimensional Hough transform for square blocks (§V.B).

Every edge pixel of a soft mask votes for the squares it could lie on: with
outward normal n (from the mask's gradient) the square's orientation is
θ = angle(n) mod 90°, and for every side length s its centre lies s/2 inside
along −n and anywhere up to s/2 along the edge. The votes, weighted by the
gradient's strength, go into an accumulator over (θ, s, y, x) — 3° × 2 px ×
2 px × 2 px bins, dense over the region only — whose maxima (one per
neighbourhood) are the best-supported squares. They are starting points: the
sub-pixel fit (:mod:`demoplan.perception.blocks`) takes them from there and
keeps those the mask bears out.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

__all__ = ["Hypothesis", "hough_squares"]

THETA_BIN = 3.0  # degrees
XY_BIN = 2.0  # px
S_BIN = 2.0  # px


@dataclass(frozen=True, slots=True)
class Hypothesis:
    """A square in crop pixels (u right, v up from the crop's bottom-left), θ in
    [0, 90) degrees, side s; ``votes``: accumulated edge strength."""

    u: float
    v: float
    theta: float
    side: float
    votes: float


def edge_pixels(alpha: np.ndarray, fraction: float = 0.25) -> tuple[np.ndarray, ...]:
    """Edge pixels of a soft mask: (u, v, n_u, n_v, strength), n the outward normal."""
    gx = ndimage.sobel(alpha, axis=1) / 8.0
    gy = -ndimage.sobel(alpha, axis=0) / 8.0  # rows run down; v runs up
    strength = np.hypot(gx, gy)
    if strength.max() <= 0:
        empty = np.empty(0)
        return empty, empty, empty, empty, empty
    rows, cols = np.nonzero(strength > fraction * strength.max())
    height = alpha.shape[0]
    u = cols + 0.5
    v = height - rows - 0.5
    g = strength[rows, cols]
    return u, v, -gx[rows, cols] / g, -gy[rows, cols] / g, g


def hough_squares(
    alpha: np.ndarray, side_range: tuple[float, float], peaks: int = 4
) -> list[Hypothesis]:
    """The ``peaks`` best-supported squares in ``alpha`` with a side in ``side_range``
    (px), strongest first, at distinct centres.

    The accumulator is filled one side length at a time (its θ × y × x slice: the
    shared votes below never cross side bins), so memory stays at one slice
    whatever the range of sides; the votes of a slice are one vectorised
    ``bincount``."""
    u, v, nu, nv, g = edge_pixels(alpha)
    if u.size == 0:
        return []
    height, width = alpha.shape
    theta = np.degrees(np.arctan2(nv, nu)) % 90.0
    sides = np.arange(side_range[0], side_range[1] + S_BIN / 2, S_BIN)
    n_theta = round(90.0 / THETA_BIN)
    n_x = int(np.ceil(width / XY_BIN))
    n_y = int(np.ceil(height / XY_BIN))
    theta_bin = np.floor(theta / THETA_BIN + 0.5).astype(int) % n_theta
    tangent_u, tangent_v = -nv, nu
    size = n_theta * n_y * n_x
    candidates: list[Hypothesis] = []
    for s in sides:
        steps = np.arange(-s / 2 + XY_BIN / 2, s / 2, XY_BIN)
        cu = u[:, None] - (s / 2) * nu[:, None] + steps[None, :] * tangent_u[:, None]
        cv = v[:, None] - (s / 2) * nv[:, None] + steps[None, :] * tangent_v[:, None]
        xb = (cu / XY_BIN).astype(int)
        yb = (cv / XY_BIN).astype(int)
        inside = (cu >= 0) & (xb < n_x) & (cv >= 0) & (yb < n_y)
        index = (theta_bin[:, None] * n_y + yb) * n_x + xb
        weight = np.broadcast_to(g[:, None], index.shape)[inside]
        total = np.bincount(index[inside], weights=weight, minlength=size)
        accumulator = total.reshape(n_theta, n_y, n_x)
        # neighbouring θ bins share an edge's votes when θ falls near a bin border
        accumulator = accumulator + 0.5 * (
            np.roll(accumulator, 1, axis=0) + np.roll(accumulator, -1, axis=0)
        )
        # and so do neighbouring centre bins: a centre on a bin border (a square whose
        # edges lie on pixel borders, as a render of a block at round coordinates has
        # them) splits its votes over four bins, and a square with only two of its
        # sides in the crop, sitting in one bin, would outvote it
        for axis in (1, 2):
            accumulator = ndimage.convolve1d(
                accumulator, [0.5, 1.0, 0.5], axis=axis, mode="constant"
            )
        # the best θ at each centre, then the best centres
        strongest = accumulator.max(axis=0).reshape(-1)
        best_theta = accumulator.argmax(axis=0).reshape(-1)
        best = min(10 * peaks, strongest.size)
        top = np.argpartition(strongest, strongest.size - best)[strongest.size - best :]
        for position in top:
            if strongest[position] <= 0:
                continue
            yb_, xb_ = (int(i) for i in np.unravel_index(int(position), (n_y, n_x)))
            candidates.append(
                Hypothesis(
                    u=(xb_ + 0.5) * XY_BIN,
                    v=(yb_ + 0.5) * XY_BIN,
                    theta=int(best_theta[position]) * THETA_BIN,
                    side=float(s),
                    votes=float(strongest[position]),
                )
            )
    candidates.sort(key=lambda c: -c.votes)
    found: list[Hypothesis] = []
    for candidate in candidates[: 50 * peaks]:
        if len(found) == peaks:
            break
        # non-maximum suppression: one hypothesis per neighbourhood
        if any(
            abs(c.u - candidate.u) <= 3 * XY_BIN and abs(c.v - candidate.v) <= 3 * XY_BIN
            for c in found
        ):
            continue
        found.append(candidate)
    return found
