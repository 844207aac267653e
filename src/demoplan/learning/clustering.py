"""K-means and the cluster-count selection of the paper's eq. (2).

State generation clusters a handful of placements thousands of times (every
object × every candidate reference × every cluster count), so K-means here is
a small vectorised NumPy implementation that runs all seeded restarts at once;
scikit-learn's ``KMeans`` is used as a cross-check in the tests only (it costs
1.5–2 ms a call on such data, 5–9 times this one, see ``benchmarks/learning.py``).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from demoplan import rotations
from demoplan.budget import check_time

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]

__all__ = [
    "Clustering",
    "KMeansResult",
    "PositionSpace",
    "RotationSpace",
    "Space",
    "closest_pair",
    "cluster_stats",
    "f_critical",
    "kmeans",
    "kmeans_batch",
    "outscores",
    "select_clustering",
    "select_clusterings",
    "spread_of",
]


@dataclass(frozen=True, slots=True)
class KMeansResult:
    """Best of the restarts: labels ``(n,)``, centres ``(c, d)``, inertia (sum of squares)."""

    labels: IntArray
    centres: FloatArray
    inertia: float


def kmeans(
    points: FloatArray,
    n_clusters: int,
    *,
    n_init: int = 8,
    max_iter: int = 100,
    rng: np.random.Generator | int | None = None,
) -> KMeansResult:
    """Lloyd's K-means with greedy k-means++ seeding and Hartigan refinement.

    Parameters
    ----------
    points : array of shape (n, d)
    n_clusters : number of clusters c, ``1 <= c <= n``
    n_init : number of seeded restarts, run side by side; the lowest inertia wins
    rng : generator or seed for the seeding
    """
    x = np.asarray(points, dtype=float)
    n = x.shape[0]
    if not 1 <= n_clusters <= n:
        raise ValueError(f"n_clusters must be in 1..{n}, got {n_clusters}")
    if n_clusters == 1:
        labels = np.zeros(n, dtype=np.intp)
    else:
        generator = np.random.default_rng(rng)
        labels = kmeans_batch(x[None], n_clusters, n_init, max_iter, generator)[0]
    centres = np.stack([x[labels == k].mean(axis=0) for k in range(n_clusters)])
    residual = x - centres[labels]
    return KMeansResult(labels, centres, float((residual * residual).sum()))


def kmeans_batch(
    points: FloatArray,
    n_clusters: int,
    n_init: int,
    max_iter: int,
    generator: np.random.Generator,
) -> IntArray:
    """K-means on B data sets of equal shape at once: ``(B, n, d)`` → labels ``(B, n)``.

    State generation clusters one object's placements towards every candidate
    reference for the same c; running them (and every restart) as one batch
    of array operations removes most of NumPy's per-call overhead.
    """
    batch, n, _ = points.shape
    x = np.repeat(points, n_init, axis=0)  # (B·R, n, d): every restart its own copy
    items = np.arange(batch * n_init)[:, None]
    sq_norms = (x * x).sum(axis=2)
    centres = _kmeans_plus_plus(x, sq_norms, n_clusters, generator)
    labels = np.full((batch * n_init, n), -1, dtype=np.intp)
    moving = np.arange(batch * n_init)  # restarts whose labels still change
    for _ in range(max_iter):
        xs, cs = x[moving], centres[moving]
        # Squared distances (moving, n, c) without forming differences.
        dist = (
            sq_norms[moving][:, :, None]
            - 2.0 * np.matmul(xs, cs.transpose(0, 2, 1))
            + (cs * cs).sum(axis=2)[:, None, :]
        )
        new_labels = dist.argmin(axis=2)
        changed = (new_labels != labels[moving]).any(axis=1)
        if not changed.any():
            break
        moving, xs, dist, new_labels = (
            moving[changed],
            xs[changed],
            dist[changed],
            new_labels[changed],
        )
        labels[moving] = new_labels
        rows = np.arange(len(moving))[:, None]
        # Per-cluster counts and sums of every moving restart in one bincount each.
        flat = (rows * n_clusters + new_labels).ravel()
        size = len(moving) * n_clusters
        counts = np.bincount(flat, minlength=size).reshape(len(moving), n_clusters).astype(float)
        sums = np.stack(
            [
                np.bincount(flat, weights=xs[:, :, k].ravel(), minlength=size)
                for k in range(xs.shape[2])
            ],
            axis=1,
        ).reshape(len(moving), n_clusters, xs.shape[2])
        empty = counts == 0
        if empty.any():
            # Re-seed an empty cluster at the point farthest from its centre.
            nearest = dist[rows, np.arange(n)[None, :], new_labels]
            for r, c in zip(*np.nonzero(empty), strict=True):
                far = int(nearest[r].argmax())
                sums[r, c] = xs[r, far]
                counts[r, c] = 1.0
                nearest[r, far] = -1.0
        centres[moving] = sums / counts[:, :, None]
    diffs = x - centres[items, labels]
    inertia = (diffs * diffs).sum(axis=(1, 2)).reshape(batch, n_init)
    best = inertia.argmin(axis=1) + np.arange(batch) * n_init
    return np.stack(
        [_hartigan_refine(points[b], labels[best[b]].copy(), n_clusters) for b in range(batch)]
    )


def _hartigan_refine(x: FloatArray, labels: IntArray, n_clusters: int) -> IntArray:
    """Hartigan's single-point transfers after Lloyd's algorithm.

    Moving point p from cluster j to k changes the inertia by
    ``n_k/(n_k+1)·|p−μ_k|² − n_j/(n_j−1)·|p−μ_j|²``; the best improving move is
    made until none is left. Lloyd's fixed points are often not Hartigan's, and
    on the handful of placements state generation clusters this reaches the
    optimum far more often than more restarts do.
    """
    counts = np.bincount(labels, minlength=n_clusters).astype(float)
    if (counts == 0).any():
        return labels
    sums = np.zeros((n_clusters, x.shape[1]))
    np.add.at(sums, labels, x)
    points = np.arange(len(x))
    for _ in range(10 * len(x)):
        means = sums / counts[:, None]
        sq = ((x[:, None, :] - means[None, :, :]) ** 2).sum(axis=2)
        own = counts[labels]
        with np.errstate(divide="ignore", invalid="ignore"):
            # A point alone in its cluster stays (its cluster would empty).
            removal = np.where(own > 1, own / (own - 1) * sq[points, labels], -np.inf)
        addition = counts / (counts + 1) * sq
        addition[points, labels] = np.inf
        gain = addition - removal[:, None]
        p, k = np.unravel_index(int(gain.argmin()), gain.shape)
        if gain[p, k] >= -1e-12:
            break
        j = labels[p]
        counts[j] -= 1
        counts[k] += 1
        sums[j] -= x[p]
        sums[k] += x[p]
        labels[p] = k
    return labels


def _kmeans_plus_plus(
    x: FloatArray,
    sq_norms: FloatArray,
    n_clusters: int,
    generator: np.random.Generator,
) -> FloatArray:
    """Greedy k-means++ seeding (as scikit-learn) for ``(items, n, d)`` data: each
    new centre is the best of ``2 + ln(c)`` candidates drawn ∝ squared distance."""
    items, n, d = x.shape
    trials = 2 + int(math.log(n_clusters))
    rows = np.arange(items)
    centres = np.empty((items, n_clusters, d))
    centres[:, 0] = x[rows, generator.integers(n, size=items)]
    closest = np.maximum(
        sq_norms
        - 2.0 * np.einsum("ind,id->in", x, centres[:, 0])
        + (centres[:, 0] ** 2).sum(axis=1)[:, None],
        0.0,
    )
    for k in range(1, n_clusters):
        totals = closest.sum(axis=1, keepdims=True)
        cumulative = np.cumsum(closest, axis=1)
        u = generator.random((items, trials)) * totals
        picks = np.minimum((cumulative[:, None, :] < u[:, :, None]).sum(axis=2), n - 1)
        picks[totals[:, 0] <= 0] = k % n  # every point already sits on a centre
        candidates = x[rows[:, None], picks]  # (items, trials, d)
        distances = np.maximum(
            sq_norms[:, None, :]
            - 2.0 * np.matmul(candidates, x.transpose(0, 2, 1))
            + (candidates**2).sum(axis=2)[:, :, None],
            0.0,
        )
        updated = np.minimum(closest[:, None, :], distances)
        best = updated.sum(axis=2).argmin(axis=1)
        centres[:, k] = candidates[rows, best]
        closest = updated[rows, best]
    return centres


def spread_of(deviations: FloatArray) -> float:
    """Trace of the sample covariance (n − 1 in the denominator); 0 for one sample.

    Our reading of the paper's |cov|: the determinant degenerates when
    there are no more demonstrations than dimensions, the trace does not.
    """
    n = deviations.shape[0]
    if n < 2:
        return 0.0
    centred = deviations - deviations.mean(axis=0)
    return float((centred * centred).sum() / (n - 1))


UNBOUNDED_DF = 1e6
"""Degrees of freedom of a spread held at the precision floor (a known variance)."""


def outscores(
    worse: tuple[float, float],
    better: tuple[float, float],
    *,
    noise: float,
    significance: float,
    noise_df: float = UNBOUNDED_DF,
    against_precision: bool = True,
) -> bool:
    """Whether a clustering scoring ``better`` = (spread, degrees of freedom) is
    supported by the data over one scoring ``worse`` (docs/learning.md: a decision only
    beyond the placement precision).

    Their RMS spreads must differ by at least ``noise``, and — unless
    ``significance`` is 0 (the paper's plain rule) — ``worse`` must be
    rejected at that level by an F test: against ``better`` (two placements
    that happen to agree better relative to one candidate than to another are
    no evidence, a dozen are), or — with ``against_precision`` — against the
    precision itself, an estimate with ``noise_df`` degrees of freedom
    (unbounded: set by the user), where ``better`` passes the consistency
    check at that precision (``CONSISTENCY_LEVEL``, as a clustering must). The
    second test serves where ``better`` rests on few placements — the widest
    of two clusters holds two — while ``worse`` scatters far beyond what the
    demonstrations' precision allows.
    """
    if math.sqrt(worse[0]) - math.sqrt(better[0]) < noise:
        return False
    if significance <= 0:
        return True
    if worse[0] >= f_critical(significance, worse[1], better[1]) * better[0]:
        return True
    variance = noise * noise
    return (
        against_precision
        and worse[0] >= f_critical(significance, worse[1], noise_df) * variance
        and better[0] <= f_critical(CONSISTENCY_LEVEL, better[1], noise_df) * variance
    )


@functools.lru_cache(maxsize=4096)
def f_critical(significance: float, dfn: float, dfd: float) -> float:
    """The F distribution's upper ``significance`` quantile (cached: learning asks
    for the same few degrees of freedom thousands of times). ``scipy.special.fdtri``
    is the function ``scipy.stats.f.ppf`` evaluates (the same value, nan and inf
    alike), without importing ``scipy.stats``: ~0.3-1.2 s of CPU in every process
    that learns."""
    from scipy.special import fdtri  # deferred: SciPy's import is slow

    return float(fdtri(dfn, dfd, 1.0 - significance))


class Space:
    """Values to cluster: their K-means embedding, cluster means and spreads."""

    values: FloatArray
    embedded: FloatArray
    dims: int = 1
    """Axes along which the values vary at all (a table-top placement: x, y)."""

    def __len__(self) -> int:
        return int(self.embedded.shape[0])

    def stats(self, members: IntArray) -> tuple[tuple[float, ...], float]:
        """Mean and spread of the values at ``members``."""
        raise NotImplementedError

    def distance(self, a: Sequence[float], b: Sequence[float]) -> float:
        """Distance between two means (for the separation threshold)."""
        raise NotImplementedError

    def link(self, separation: float) -> float:
        """The separation as a distance in the K-means embedding."""
        raise NotImplementedError


class PositionSpace(Space):
    """Relative positions ``(n, 3)`` in metres; spread in m²."""

    def __init__(self, values: FloatArray):
        self.values = np.asarray(values, dtype=float)
        self.embedded = self.values
        self.dims = _varying_axes(self.values, 1e-6)

    def stats(self, members: IntArray) -> tuple[tuple[float, ...], float]:
        subset = self.values[members]
        mean = subset.mean(axis=0)
        return tuple(float(v) for v in mean), spread_of(subset)

    def distance(self, a: Sequence[float], b: Sequence[float]) -> float:
        return math.dist(a, b)

    def link(self, separation: float) -> float:
        return separation


class RotationSpace(Space):
    """Relative orientations ``(n, 4)`` as quaternions; spread in deg².

    Clustered in the chordal embedding (flattened matrices); a cluster's mean
    is the chordal L2 mean rotation and its spread the trace of the sample
    covariance of the members' rotation vectors about that mean (degrees).
    """

    def __init__(self, quats: FloatArray):
        self.values = np.asarray(quats, dtype=float)
        self.embedded = rotations.matrices_from_quats(self.values)
        self.dims = _varying_axes(np.degrees(rotations.rotvecs_from_quats(self.values)), 0.01)

    def stats(self, members: IntArray) -> tuple[tuple[float, ...], float]:
        subset = self.values[members]
        mean = rotations.mean_quat(subset)
        return mean, spread_of(rotations.deviations_from_mean(subset, mean))

    def distance(self, a: Sequence[float], b: Sequence[float]) -> float:
        return rotations.angle_between(a, b)

    def link(self, separation: float) -> float:
        # Chordal distance of two rotations ``separation`` degrees apart.
        return 2.0 * math.sqrt(2.0) * math.sin(math.radians(min(separation, 180.0)) / 2.0)


@dataclass(frozen=True, slots=True)
class Clustering:
    """The chosen clustering of one object's placements towards one reference.

    ``score`` is the paper's eq. (2) inner term: the largest per-cluster spread.
    ``tried`` maps each cluster count that was evaluated to its score, or to
    ``None`` when its centres lay closer than the separation threshold.
    """

    n_clusters: int
    labels: tuple[int, ...]
    means: tuple[tuple[float, ...], ...]
    spreads: tuple[float, ...]
    score: float
    tried: tuple[tuple[int, float | None], ...]
    df: float = UNBOUNDED_DF
    """Degrees of freedom of ``score``: (members − 1) × varying axes of the widest
    cluster, unbounded for a cluster of one (its spread is the known precision)."""


def select_clustering(
    space: Space,
    *,
    separation: float,
    noise: float,
    n_init: int = 8,
    seed: int = 0,
    significance: float = 0.0,
    noise_df: float = UNBOUNDED_DF,
) -> Clustering:
    """Pick the cluster count c ∈ 1..N for one reference (paper eq. 2).

    For c = 1, 2, … the values are clustered with K-means; a clustering whose
    means lie closer than ``separation`` is rejected, and the one with the
    lowest maximum per-cluster spread wins. A cluster of one placement has
    the precision's spread ``noise²``, not none; spreads whose square roots
    (RMS deviations) differ by less than ``noise`` are ties, and ties go to
    fewer clusters. The scan stops once a score is at the noise level (no larger
    c could then win), and at a rejected c unless the values still fall into
    more than c groups (:meth:`_Scan.groups`), after at most :data:`PATIENCE`
    rejected counts in a row: more centres on the same data only crowd closer. Where placements form
    groups this gives the full scan's answer (``tests/learning/test_clustering.py``
    checks it); where they spread continuously over more than the separation,
    the literal full scan chops them into many small clusters (singletons
    have zero spread), and stopping early deliberately keeps a coarser one.

    The values are put in a canonical (sorted) order before clustering, so the
    result does not depend on the order the demonstrations arrived in.
    """
    (clustering,) = select_clusterings(
        [space],
        separation=separation,
        noise=noise,
        n_init=n_init,
        seed=seed,
        significance=significance,
        noise_df=noise_df,
    )
    return clustering


PATIENCE = 3
"""Rejected cluster counts in a row after which the scan of eq. (2) stops."""


class _Scan:
    """One space's progress through the cluster counts of :func:`select_clusterings`."""

    def __init__(self, space: Space):
        self.space = space
        order = np.lexsort(space.embedded.T[::-1])
        self.inverse = np.empty_like(order)
        self.inverse[order] = np.arange(order.size)
        self.canonical = space.embedded[order]
        steps = np.any(np.diff(self.canonical, axis=0) != 0, axis=1)
        self.n_distinct = 1 + int(np.count_nonzero(steps))
        self.accepted: list[tuple[int, IntArray, list[tuple[float, ...]], list[float], float]] = []
        self.tried: list[tuple[int, float | None]] = []
        self.rejected_in_a_row = 0
        self.done = False
        self._groups: int | None = None

    def consider(
        self,
        c: int,
        sorted_labels: IntArray,
        separation: float,
        noise: float,
        significance: float = 0.0,
        noise_df: float = UNBOUNDED_DF,
    ) -> None:
        labels = sorted_labels[self.inverse]
        present = np.bincount(labels, minlength=c) > 0
        if not present.all():  # compact the labels if a cluster ended empty
            labels = (np.cumsum(present) - 1)[labels]
        means, raw = cluster_stats(self.space, labels, int(present.sum()))
        # A cluster of one placement does not show "no spread" (docs/learning.md): it has
        # the placement precision's.
        sizes = np.bincount(labels, minlength=len(raw))
        spreads = [noise * noise if n < 2 else v for v, n in zip(raw, sizes, strict=True)]
        if c > 1 and (
            closest_pair(self.space.distance, means) < separation
            # A cluster of one placement shows no spread, not a state: a place
            # seen once is no evidence of a second state (docs/learning.md).
            or np.bincount(labels).min() < 2
            # Nor do clusters that scatter far beyond the placement precision:
            # splitting a continuum is not finding states.
            # (The paper's plain comparison, significance 0, has no such test.)
            or (
                significance > 0
                and not _within_precision(
                    raw, np.bincount(labels), self.space.dims, noise, noise_df
                )
            )
        ):
            self.tried.append((c, None))
            self.rejected_in_a_row += 1
            self.done = (
                self.rejected_in_a_row >= PATIENCE
                or c + 1 > self.n_distinct
                or c >= self.groups(separation)
            )
            return
        self.rejected_in_a_row = 0
        score = max(spreads)
        widest = int(np.argmax(spreads))
        members = int(np.count_nonzero(labels == widest))
        df = UNBOUNDED_DF if members < 2 else (members - 1) * self.space.dims
        self.tried.append((c, score))
        self.accepted.append((c, labels, means, spreads, df))
        self.done = math.sqrt(score) <= noise or c + 1 > self.n_distinct

    def groups(self, separation: float) -> int:
        """Connected components of the values linked when closer than the separation.

        After a rejected c the scan goes on only while there are more such
        groups than c: points spread as one chain (a continuum) stop it at the
        first rejection, distinct spots (a triangle of spots 5.5 cm apart, which
        rejects c = 2) let it reach c = 3.
        """
        if self._groups is None:
            x = self.canonical
            sq = (x * x).sum(axis=1)
            linked = sq[:, None] - 2.0 * x @ x.T + sq[None, :] < self.space.link(separation) ** 2
            label = np.arange(len(x))
            while True:  # propagate the smallest label along links until stable
                spread = np.where(linked, label[None, :], len(x)).min(axis=1)
                if np.array_equal(spread, label):
                    break
                label = spread
            self._groups = len(np.unique(label))
        return self._groups

    def result(self, noise: float, significance: float, noise_df: float) -> Clustering:
        best = min(self.accepted, key=lambda a: max(a[3]))
        for c, labels, means, spreads, df in self.accepted:  # ascending c: ties go to fewer
            if not outscores(
                (max(spreads), df),
                (max(best[3]), best[4]),
                noise=noise,
                significance=significance,
                noise_df=noise_df,
            ):
                return Clustering(
                    n_clusters=c,
                    labels=tuple(int(v) for v in labels),
                    means=tuple(means),
                    spreads=tuple(spreads),
                    score=max(spreads),
                    tried=tuple(self.tried),
                    df=df,
                )
        raise AssertionError("unreachable: the minimum is always within noise of itself")


def select_clusterings(
    spaces: Sequence[Space],
    *,
    separation: float,
    noise: float,
    n_init: int = 8,
    seed: int = 0,
    max_clusters: int = 0,
    significance: float = 0.0,
    noise_df: float = UNBOUNDED_DF,
) -> list[Clustering]:
    """:func:`select_clustering` for several spaces of the same size and kind at
    once (one object towards every candidate reference), K-means batched.

    ``max_clusters`` > 0 caps c (the paper scans c = 1..N, 0 keeps that);
    ``significance`` > 0 also asks more clusters to pass :func:`outscores`' F test;
    ``noise_df`` is how many degrees of freedom the precision ``noise`` was
    estimated with (unbounded: known).
    """
    scans = [_Scan(space) for space in spaces]
    n = len(spaces[0]) if spaces else 0
    for c in range(1, (min(n, max_clusters) if max_clusters > 0 else n) + 1):
        active = [scan for scan in scans if not scan.done]
        if not active:
            break
        check_time()  # the learning budget (demoplan.budget), if one is set
        if c == 1:
            batch_labels = np.zeros((len(active), n), dtype=np.intp)
        else:
            generator = np.random.default_rng(seed + c)
            data = np.stack([scan.canonical for scan in active])
            batch_labels = kmeans_batch(data, c, n_init, 100, generator)
        for scan, labels in zip(active, batch_labels, strict=True):
            scan.consider(c, labels, separation, noise, significance, noise_df)
    return [scan.result(noise, significance, noise_df) for scan in scans]


CONSISTENCY_LEVEL = 0.001
"""A cluster scatters beyond the precision when its spread passes the F test
against the precision at this level (0.1 %: only clear cases)."""


def _within_precision(
    spreads: Sequence[float], sizes: IntArray, dims: int, noise: float, noise_df: float
) -> bool:
    """Whether every cluster of two or more placements scatters as placements of one
    state would, given the precision ``noise`` (RMS), itself estimated with
    ``noise_df`` degrees of freedom: an F test, not a χ² one that would take an
    estimate for the truth (200 placements scattering 18 % wider than the
    median object's estimate are not a continuum)."""
    for spread, size in zip(spreads, sizes, strict=True):
        if size < 2:
            continue
        df = (int(size) - 1) * dims
        if spread > noise * noise * f_critical(CONSISTENCY_LEVEL, df, noise_df):
            return False
    return True


def _varying_axes(values: FloatArray, tolerance: float) -> int:
    """How many coordinates vary by more than ``tolerance`` and more than 5 % of the
    most varying one (RMS) — at least one: placements on a table vary in x and y,
    a turned object in yaw, and the rest is noise, not freedom."""
    if len(values) < 2:
        return 1
    std = values.std(axis=0)
    return max(1, int(np.count_nonzero((std > tolerance) & (std > 0.05 * std.max()))))


def cluster_stats(
    space: Space, labels: IntArray, n_clusters: int
) -> tuple[list[tuple[float, ...]], list[float]]:
    means: list[tuple[float, ...]] = []
    spreads: list[float] = []
    for k in range(n_clusters):
        mean, spread = space.stats(np.flatnonzero(labels == k))
        means.append(mean)
        spreads.append(spread)
    return means, spreads


def closest_pair(
    distance: Callable[[Sequence[float], Sequence[float]], float],
    means: Sequence[Sequence[float]],
) -> float:
    return min(
        distance(means[a], means[b]) for a in range(len(means)) for b in range(a + 1, len(means))
    )
