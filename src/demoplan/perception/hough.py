"""The paper's four-dimensional Hough transform for square blocks (§V.B).

Every edge pixel of a soft mask votes for the squares it could lie on: with
outward normal n (from the mask's gradient) the square's orientation is
θ = angle(n) mod 90°, and for every side length s its centre lies s/2 inside
along −n and anywhere up to s/2 along the edge. The votes, weighted by the
gradient's strength, go into an accumulator over (θ, s, y, x) — 3° × 2 px ×
2 px bins of θ, y and x, sides 2 px apart up to 20 px and a tenth of the side
apart above (:func:`side_bins`), dense over the region only, and over each group of
edge points apart when the parts of a region lie farther apart than the largest side
(:func:`_clusters`) — whose maxima (one per neighbourhood) are the best-supported
squares. They are starting points: the sub-pixel fit
(:mod:`demoplan.perception.blocks`) takes them from there and keeps those the mask
bears out.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from demoplan.perception.hough_kernel import vote_counts
from demoplan.perception.opencv import cv2

__all__ = ["Hypothesis", "hough_squares", "side_bins"]

_ONE = np.array([1.0], dtype=np.float32)

THETA_BIN = 3.0  # degrees
XY_BIN = 2.0  # px
S_BIN = 2.0  # px
SIDE_STEP = 0.1
"""Side bins are :data:`S_BIN` apart, or this share of the side where that is more:
the fit takes a side a few percent off to the block's in its first, blurred steps
(a 4 px ramp), and a vote costs its sides' perimeters — 2 px bins spent most of it
on the largest sides (16–50 px: 18 sides, 13 so; the vote's time on the
development photographs down by a third)."""
MAX_CELLS = 1 << 18
"""Accumulator bins (and votes) filled at once: sides are taken in blocks of at most
this many. A block's bins and their counts in double precision (2 MB) stay in the
processor's cache while they are counted and filtered: the same values as in blocks
of 1 << 20, the development photographs' votes replayed alone a third faster (a few
percent of a whole photograph's vote, whose other stages use the cache too)."""


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
    # Sobel as scipy.ndimage.sobel computes it (its border mirrors the edge pixel)
    reflect = cv2.BORDER_REFLECT
    gx = np.asarray(cv2.Sobel(alpha, cv2.CV_64F, 1, 0, ksize=3, borderType=reflect)) / 8.0
    # rows run down; v runs up
    gy = -np.asarray(cv2.Sobel(alpha, cv2.CV_64F, 0, 1, ksize=3, borderType=reflect)) / 8.0
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
    alpha: np.ndarray,
    side_range: tuple[float, float],
    peaks: int = 4,
    check: Callable[[], None] | None = None,
) -> list[Hypothesis]:
    """The ``peaks`` best-supported squares in ``alpha`` with a side in ``side_range``
    (px), strongest first, at distinct centres.

    The accumulator is filled for several side lengths at once (a block of
    (s, θ, y, x) bins: votes never cross side bins, so each side's θ × y × x
    slice is what it would be alone), as many sides as keep the block and the
    votes under :data:`MAX_CELLS`, so memory stays bounded whatever the range
    of sides; the votes of a block are one vectorised ``bincount``. ``check``
    is called before each block (a time budget's clock: a large region's vote
    is many blocks, each some milliseconds)."""
    u, v, nu, nv, g = edge_pixels(alpha)
    sides = side_bins(*side_range)
    if u.size == 0 or sides.size == 0:
        return []
    height, width = alpha.shape
    theta = np.degrees(np.arctan2(nv, nu)) % 90.0
    n_theta = round(90.0 / THETA_BIN)
    shape = (n_theta, int(np.ceil(height / XY_BIN)), int(np.ceil(width / XY_BIN)))
    theta_bin = np.floor(theta / THETA_BIN + 0.5).astype(np.intp) % n_theta
    found: list[tuple[np.ndarray, ...]] = []
    for cluster in _clusters(u, v, float(sides[-1]), shape):
        edges = tuple(a[cluster] for a in (u, v, nu, nv, g))
        found += _cluster_maxima(edges, theta_bin[cluster], sides, shape, 10 * peaks, check)
    votes, rows, cols, thetas, side_index = _strongest_per_side(found, 10 * peaks)
    kept = np.flatnonzero(votes > 0)
    order = kept[np.argsort(-votes[kept], kind="stable")][: 50 * peaks]
    centre_u = (cols[order] + 0.5) * XY_BIN
    centre_v = (rows[order] + 0.5) * XY_BIN
    # non-maximum suppression: one hypothesis per neighbourhood — the strongest
    # candidate left is taken and its neighbours dropped, until there are enough
    left = np.ones(order.size, dtype=bool)
    best: list[Hypothesis] = []
    while len(best) < peaks and left.any():
        first = int(np.argmax(left))
        i = order[first]
        best.append(
            Hypothesis(
                u=float(centre_u[first]),
                v=float(centre_v[first]),
                theta=int(thetas[i]) * THETA_BIN,
                side=float(sides[side_index[i]]),
                votes=float(votes[i]),
            )
        )
        left &= (np.abs(centre_u - centre_u[first]) > 3 * XY_BIN) | (
            np.abs(centre_v - centre_v[first]) > 3 * XY_BIN
        )
    return best


def _clusters(
    u: np.ndarray, v: np.ndarray, largest: float, shape: tuple[int, int, int]
) -> list[np.ndarray]:
    """The edge points (u, v) in groups whose votes, for sides up to ``largest``,
    and the bins they are shared with fall in centre bins no other group's do: the
    parts of a mask farther apart than that side (blocks of a region far apart, the
    two arms of an L round the table). Each group is voted for in a window of its
    own (:func:`_votes`): the bins between the groups, which no vote reaches, are
    not filled — the same values bin for bin as one window over them all."""
    _, n_y, n_x = shape
    # a centre lies within s/√2 of its edge point; its bin and the point's one more
    # each, and the shared votes one more again (:func:`_votes`)
    reach = math.ceil(largest / math.sqrt(2) / XY_BIN) + 3
    rows = np.clip((v / XY_BIN).astype(np.intp), 0, n_y - 1)
    cols = np.clip((u / XY_BIN).astype(np.intp), 0, n_x - 1)
    occupied = np.zeros((n_y, n_x), dtype=np.uint8)
    occupied[rows, cols] = 1
    # two points whose reaches (squares of ``reach`` bins either way) touch are joined
    kernel = np.ones((2 * reach + 1, 2 * reach + 1), dtype=np.uint8)
    grown = cv2.dilate(occupied, kernel, borderType=cv2.BORDER_CONSTANT, borderValue=0)
    count, labels = cv2.connectedComponents(np.asarray(grown), connectivity=8)
    if count <= 2:
        return [np.arange(u.size)]
    of_point = np.asarray(labels)[rows, cols]
    order = np.argsort(of_point, kind="stable")
    starts = np.searchsorted(of_point[order], np.arange(1, count))
    return [group for group in np.split(order, starts[1:]) if group.size]


def _cluster_maxima(
    edges: tuple[np.ndarray, ...],
    theta_bin: np.ndarray,
    sides: np.ndarray,
    shape: tuple[int, int, int],
    best: int,
    check: Callable[[], None] | None,
) -> list[tuple[np.ndarray, ...]]:
    """The ``best`` strongest centres per side of the edge points ``edges`` (u, v,
    n_u, n_v, g): (votes, rows, columns, θ bins, sides), side by side, the votes
    filled for blocks of sides at once (:data:`MAX_CELLS`); ``check`` before each."""
    u, v, nu, nv, _ = edges
    n_theta = shape[0]
    # the centres an edge point votes for, for side s: every 2 px along the edge within s/2
    steps = [np.arange(-s / 2 + XY_BIN / 2, s / 2, XY_BIN) for s in sides]
    reach = _reach((u, v, nu, nv), (float(sides[0]), float(sides[-1])), shape)
    window_cells = (reach[1] - reach[0]) * (reach[3] - reach[2])
    per_side = max((n_theta + 2) * window_cells, u.size * max(map(len, steps)))
    chunk = max(1, MAX_CELLS // per_side)
    found: list[tuple[np.ndarray, ...]] = []
    for first in range(0, sides.size, chunk):
        if check is not None:
            check()
        block = slice(first, first + chunk)
        accumulator, (row0, col0) = _votes(edges, theta_bin, sides[block], steps[block], shape)
        votes, rows, cols, thetas = _side_maxima(accumulator, best)
        rows += row0
        cols += col0
        side = np.broadcast_to(np.arange(sides.size)[block, None], votes.shape)
        found += [(votes[i], rows[i], cols[i], thetas[i], side[i]) for i in range(votes.shape[0])]
    return found


def _strongest_per_side(
    found: list[tuple[np.ndarray, ...]], best: int
) -> tuple[np.ndarray, ...]:
    """The ``best`` strongest of ``found`` (votes, rows, columns, θ bins, side indices,
    of one side each) per side, side by side: strongest first, equal votes in the
    order of their rows and columns (as one window over every group's would give)."""
    votes, rows, cols, thetas, side = (np.concatenate(a) for a in zip(*found, strict=True))
    order = np.lexsort((cols, rows, -votes, side))
    in_order = side[order]
    rank = np.arange(order.size) - np.searchsorted(in_order, in_order)  # place in its side
    kept = order[rank < best]
    return votes[kept], rows[kept], cols[kept], thetas[kept], side[kept]


def side_bins(low: float, high: float) -> np.ndarray:
    """The sides voted for in the range [``low``, ``high``] (px): from ``low`` on,
    each :data:`S_BIN` or :data:`SIDE_STEP` of it (the more) past the one before,
    up to the first within half a step of ``high`` or beyond it; none when the
    range is empty."""
    sides: list[float] = []
    side = low
    while True:
        step = max(S_BIN, SIDE_STEP * side)
        if not side < high + step / 2:
            return np.array(sides, dtype=float)
        sides.append(side)
        side += step


def _reach(
    edges: tuple[np.ndarray, ...], sides: tuple[float, float], shape: tuple[int, int, int]
) -> tuple[int, int, int, int]:
    """The centre bins (first and past-the-last row, then column) that the edge points
    (u, v, n_u, n_v) can vote for with a side in ``sides``, and their neighbours,
    within the crop's ``shape``: for side s a point's centres run along the segment
    s/2 inside, s/2 either way, so those for every side lie between the segments of
    the smallest and the largest side. An estimate (the block's own votes set
    its window, :func:`_votes`), which sizes the blocks of sides."""
    u, v, nu, nv = edges
    corners_u, corners_v = [], []
    for side in sides:
        for along in (-side / 2, side / 2):
            corners_u.append(u - side / 2 * nu - along * nv)
            corners_v.append(v - side / 2 * nv + along * nu)
    all_u, all_v = np.concatenate(corners_u), np.concatenate(corners_v)
    _, n_y, n_x = shape
    row0 = min(n_y, max(0, math.floor(float(all_v.min()) / XY_BIN) - 1))
    row1 = max(row0, min(n_y, math.floor(float(all_v.max()) / XY_BIN) + 2))
    col0 = min(n_x, max(0, math.floor(float(all_u.min()) / XY_BIN) - 1))
    col1 = max(col0, min(n_x, math.floor(float(all_u.max()) / XY_BIN) + 2))
    return row0, row1, col0, col1


def _votes(
    edges: tuple[np.ndarray, ...],
    theta_bin: np.ndarray,
    sides: np.ndarray,
    steps: list[np.ndarray],
    shape: tuple[int, int, int],
) -> tuple[np.ndarray, tuple[int, int]]:
    """The accumulator over (s, θ, y, x) for ``sides``, its votes shared with the
    neighbouring θ and centre bins: edge point (u, v) with outward normal n votes,
    for each side s, for the centres s/2 inside it along −n and ``steps`` along
    the edge, weighted by its gradient ``g``.

    Only the window of centre bins the votes fall in, and one bin around it, is
    filled and filtered — every bin outside it gets no share of any vote — and
    returned with its first row and column: a region whose outline is a small part
    of its crop (a ring, a thin L round the table, a few blocks far apart) costs
    its votes' reach, not its crop's area. The values are those of the whole
    crop's accumulator, bin for bin."""
    n_theta, n_y, n_x = shape
    # (edge, (side, step)) pairs; in bins (halving is exact: these are the
    # centres' coordinates / XY_BIN to the last bit)
    side_of = np.repeat(np.arange(sides.size), [len(s) for s in steps])
    along = np.concatenate(steps) / XY_BIN
    counted = vote_counts(edges, theta_bin, sides, along, side_of, n_theta, (n_y, n_x), XY_BIN)
    if counted is None:  # no centre inside the crop: one empty bin per side
        return np.zeros((sides.size, n_theta, 1, 1), dtype=np.float32), (0, 0)
    # bins (s, θ, y, x) with a θ bin before and after (wrapped copies) and an empty
    # row after each θ slice, so that two 2-D filters do the sharing below; the
    # votes summed in double precision and filtered in single: half the memory to
    # stream through (the votes are sums of gradient strengths, ~1 each; 24 bits
    # keep them to a millionth)
    accumulator, (row0, col0) = counted
    n_y, n_x = accumulator.shape[2] - 1, accumulator.shape[3]
    # neighbouring θ bins share an edge's votes when θ falls near a bin border (θ wraps)
    accumulator[:, 0] = accumulator[:, n_theta]
    accumulator[:, n_theta + 1] = accumulator[:, 1]
    share = np.array([0.5, 1.0, 0.5], dtype=np.float32)
    by_theta = accumulator.reshape(sides.size * (n_theta + 2), (n_y + 1) * n_x)
    border = cv2.BORDER_CONSTANT
    by_theta = np.asarray(cv2.sepFilter2D(by_theta, cv2.CV_32F, _ONE, share, borderType=border))
    # and so do neighbouring centre bins: a centre on a bin border (a square whose
    # edges lie on pixel borders, as a render of a block at round coordinates has
    # them) splits its votes over four bins, and a square with only two of its
    # sides in the crop, sitting in one bin, would outvote it (the empty rows keep
    # the θ slices apart)
    rows = cv2.sepFilter2D(by_theta.reshape(-1, n_x), cv2.CV_32F, share, share, borderType=border)
    shared: np.ndarray = np.asarray(rows).reshape(accumulator.shape)[:, 1 : n_theta + 1, :n_y]
    return shared, (row0, col0)


def _side_maxima(accumulator: np.ndarray, best: int) -> tuple[np.ndarray, ...]:
    """Per side, the ``best`` strongest centres: their votes, rows and columns (bins,
    from the bottom) and their best θ bin; strongest first, equal votes in the order
    of their rows and columns (the same whatever window of bins was filled)."""
    n_sides, _, n_y, n_x = accumulator.shape
    strongest = accumulator.max(axis=1).reshape(n_sides, -1)
    best = min(best, n_y * n_x)
    # the ``best`` largest as the ``best`` smallest of the negated votes: selecting
    # near the end of an array of mostly equal values (a region's empty bins) is
    # NumPy's introselect's slow case, ten times slower on an accumulator
    top = np.argpartition(-strongest, best - 1, axis=1)[:, :best]
    least = np.take_along_axis(strongest, top, axis=1).min(axis=1)
    for tied in np.flatnonzero(np.count_nonzero(strongest >= least[:, None], axis=1) > best):
        # more bins hold the least vote taken than were taken: the first of them in order
        above = np.flatnonzero(strongest[tied] > least[tied])
        equal = np.flatnonzero(strongest[tied] == least[tied])
        top[tied] = np.concatenate([above, equal[: best - above.size]])
    votes = np.take_along_axis(strongest, top, axis=1)
    order = np.lexsort((top, -votes), axis=1)
    top = np.take_along_axis(top, order, axis=1)
    rows, cols = np.divmod(top, n_x)
    side = np.arange(n_sides)[:, None]
    thetas = accumulator[side, :, rows, cols].argmax(axis=2)  # the best θ at each
    return np.take_along_axis(votes, order, axis=1), rows, cols, thetas
