"""K-means and the cluster-count selection of eq. (2)."""

from __future__ import annotations

import math
from contextlib import AbstractContextManager
from types import ModuleType
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.learning.clustering import (
    CONSISTENCY_LEVEL,
    PositionSpace,
    RotationSpace,
    kmeans,
    select_clustering,
    spread_of,
)
from demoplan.rotations import quat_from_yaw


def _scikit_learn() -> tuple[ModuleType, ModuleType]:
    """scikit-learn's clustering and metrics, the cross-check, imported by the
    tests that use them (it brings scipy.stats: ~1 s at every worker's
    collection otherwise), skipping only them where it is missing."""
    reason = "scikit-learn is the cross-check"
    return (
        pytest.importorskip("sklearn.cluster", reason=reason),
        pytest.importorskip("sklearn.metrics", reason=reason),
    )


def _on_one_thread() -> AbstractContextManager[Any]:
    """scikit-learn's K-means on one OpenMP thread (threadpoolctl comes with
    scikit-learn): on problems of a few dozen points the other threads only wait,
    spinning — the 150 fits below took 7-8 s of CPU on two threads and 0.3 s on
    one, with the same labels and inertias equal to 1e-15."""
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=1, user_api="openmp")


def _blobs(rng: np.random.Generator, centres: int, per: int, spread: float) -> np.ndarray:
    means = rng.uniform(-1, 1, (centres, 3))
    return np.concatenate([m + rng.normal(0, spread, (per, 3)) for m in means])


@pytest.mark.parametrize("seed", range(10))
def test_kmeans_matches_scikit_learn_on_separated_blobs(seed: int) -> None:
    sklearn_cluster, sklearn_metrics = _scikit_learn()
    rng = np.random.default_rng(seed)
    c = int(rng.integers(2, 6))
    points = _blobs(rng, c, int(rng.integers(2, 12)), 0.01)
    ours = kmeans(points, c, rng=seed)
    with _on_one_thread():
        theirs = sklearn_cluster.KMeans(n_clusters=c, n_init=4, random_state=seed).fit(points)
    assert ours.inertia <= theirs.inertia_ * (1 + 1e-9) + 1e-12
    if ours.inertia == pytest.approx(theirs.inertia_, rel=1e-9):
        assert sklearn_metrics.adjusted_rand_score(theirs.labels_, ours.labels) == 1.0


def test_kmeans_is_as_good_as_scikit_learn_on_arbitrary_data() -> None:
    """Lloyd's algorithm finds local optima; over many random problems ours
    (8 vectorised restarts) is at least as good as scikit-learn's (4 restarts)
    on the median, and rarely much worse on any one."""
    sklearn_cluster, _ = _scikit_learn()
    ratios = []
    for seed in range(150):
        rng = np.random.default_rng(seed)
        n = int(rng.integers(3, 30))
        c = int(rng.integers(2, min(6, n) + 1))
        points = rng.normal(size=(n, 3))
        ours = kmeans(points, c, rng=seed)
        with _on_one_thread():
            theirs = sklearn_cluster.KMeans(n_clusters=c, n_init=4, random_state=0).fit(points)
        assert len(np.unique(ours.labels)) == c
        recomputed = sum(
            ((points[ours.labels == k] - ours.centres[k]) ** 2).sum() for k in range(c)
        )
        assert ours.inertia == pytest.approx(recomputed)
        if theirs.inertia_ > 0:
            ratios.append(ours.inertia / theirs.inertia_)
    assert np.median(ratios) <= 1.0 + 1e-9
    assert np.quantile(ratios, 0.95) <= 1.05


@pytest.mark.parametrize("seed", range(20))
def test_kmeans_finds_the_optimum_of_tiny_two_cluster_problems(seed: int) -> None:
    """Brute force over every 2-partition of up to 9 points (state generation's usual size)."""
    import itertools

    rng = np.random.default_rng(seed)
    points = rng.normal(size=(int(rng.integers(3, 10)), 2))
    optimum = min(
        sum(((points[labels == k] - points[labels == k].mean(axis=0)) ** 2).sum() for k in (0, 1))
        for labels in map(np.array, itertools.product((0, 1), repeat=len(points)))
        if 0 < labels.sum() < len(points)
    )
    assert kmeans(points, 2, rng=seed).inertia == pytest.approx(optimum)


def test_spread_is_the_trace_of_the_sample_covariance() -> None:
    rng = np.random.default_rng(0)
    values = rng.normal(size=(7, 3))
    assert spread_of(values) == pytest.approx(np.trace(np.cov(values.T, ddof=1)))
    assert spread_of(values[:1]) == 0.0


def _full_scan(space: PositionSpace, separation: float, noise: float) -> tuple[int, float]:
    """Eq. (2) literally: every c in 1..N, no early stop."""
    results = []
    for c in range(1, len(space) + 1):
        if c > len(np.unique(space.embedded, axis=0)):
            break
        labels = kmeans(space.embedded, c, rng=c).labels if c > 1 else np.zeros(len(space), int)
        stats = [space.stats(np.flatnonzero(labels == k)) for k in np.unique(labels)]
        means = [m for m, _ in stats]
        if (
            c > 1
            and min(math.dist(a, b) for i, a in enumerate(means) for b in means[i + 1 :])
            < separation
        ):
            continue
        results.append((c, max(s for _, s in stats)))
    best = min(math.sqrt(s) for _, s in results)
    return next((c, s) for c, s in results if math.sqrt(s) - best < noise)


def _full_scan_by_the_rules(
    space: PositionSpace, separation: float, noise: float
) -> tuple[int, float]:
    """Eq. (2) with docs/learning.md's acceptance rules, every c in 1..N, no early stop.

    As the scan of :func:`select_clustering` judges each c (``_Scan.consider``):
    a cluster of one placement has the precision's spread (``noise²``) and no
    c > 1 with a cluster of one is a clustering (a place seen once is no
    state); nor is one whose clusters scatter beyond the precision (χ² test at
    ``CONSISTENCY_LEVEL``); ties (RMS within ``noise``) go to fewer clusters.
    """
    from scipy.stats import chi2

    def consistent(spread: float, size: int) -> bool:
        df = (size - 1) * space.dims
        return spread <= noise * noise * float(chi2.ppf(1.0 - CONSISTENCY_LEVEL, df)) / df

    results = []
    for c in range(1, len(space) + 1):
        if c > len(np.unique(space.embedded, axis=0)):
            break
        labels = kmeans(space.embedded, c, rng=c).labels if c > 1 else np.zeros(len(space), int)
        members = [np.flatnonzero(labels == k) for k in np.unique(labels)]
        stats = [space.stats(m) for m in members]
        means = [m for m, _ in stats]
        spreads = [
            noise * noise if len(m) < 2 else s for m, (_, s) in zip(members, stats, strict=True)
        ]
        if c > 1 and (
            min(math.dist(a, b) for i, a in enumerate(means) for b in means[i + 1 :]) < separation
            or min(len(m) for m in members) < 2
            or not all(consistent(s, len(m)) for m, (_, s) in zip(members, stats, strict=True))
        ):
            continue
        results.append((c, max(spreads)))
    best = min(math.sqrt(s) for _, s in results)
    return next((c, s) for c, s in results if math.sqrt(s) - best < noise)


@given(
    st.integers(0, 2**32 - 1),
    st.integers(1, 4),
    st.integers(1, 6),
    st.floats(0.0005, 0.01),
)
@settings(max_examples=80, deadline=None)
def test_early_stop_agrees_with_the_full_scan_on_separated_placements(
    seed: int, groups: int, per: int, scatter: float
) -> None:
    """Where placements form groups (here ≥ 1.2× the separation apart), the scan
    that stops after a few rejected cluster counts gives the full scan's answer
    under the same rules (docs/learning.md: clusters of one are no state, clusters are
    consistent with the precision)."""
    rng = np.random.default_rng(seed)
    means = [rng.uniform(-0.5, 0.5, 3) * [1, 1, 0]]
    while len(means) < groups:
        candidate = rng.uniform(-0.5, 0.5, 3) * [1, 1, 0]
        if all(math.dist(candidate, m) > 0.06 for m in means):
            means.append(candidate)
    values = np.concatenate([m + rng.normal(0, scatter, (per, 3)) * [1, 1, 0] for m in means])
    space = PositionSpace(values)
    chosen = select_clustering(space, separation=0.05, noise=0.003, seed=0, significance=0.05)
    c, score = _full_scan_by_the_rules(space, 0.05, 0.003)
    assert chosen.n_clusters == c
    assert math.sqrt(chosen.score) == pytest.approx(math.sqrt(score), abs=0.003)


def test_early_stop_keeps_continuous_scatter_coarse() -> None:
    """Groups scattered over about the separation: the literal full scan chops
    them into more clusters, the early stop keeps the coarser clustering."""
    rng = np.random.default_rng(6)  # three groups scattered by 2.3 cm, found by hypothesis
    means = rng.uniform(-0.3, 0.3, (3, 3)) * [1, 1, 0]
    values = np.concatenate([m + rng.normal(0, 0.0234375, (5, 3)) * [1, 1, 0] for m in means])
    space = PositionSpace(values)
    chosen = select_clustering(space, separation=0.05, noise=0.003, seed=0)
    full_c, _ = _full_scan(space, 0.05, 0.003)
    assert chosen.n_clusters < full_c


@pytest.mark.parametrize("corners", [3, 4])
def test_groups_at_the_corners_of_a_polygon_are_found(corners: int) -> None:
    """Three (four) spots 5.5 cm apart: the merged clusterings of two (three)
    groups are rejected, c = 3 (4) is not — the scan must not stop early."""
    rng = np.random.default_rng(0)
    radius = 0.055 / (2 * math.sin(math.pi / corners))
    spots = [
        [
            radius * math.cos(2 * math.pi * k / corners),
            radius * math.sin(2 * math.pi * k / corners),
            0,
        ]
        for k in range(corners)
    ]
    values = np.concatenate([s + rng.normal(0, 0.0005, (3, 3)) * [1, 1, 0] for s in spots])
    chosen = select_clustering(PositionSpace(values), separation=0.05, noise=0.003)
    assert chosen.n_clusters == corners
    assert _full_scan(PositionSpace(values), 0.05, 0.003)[0] == corners


def test_two_groups_ten_centimetres_apart_become_two_clusters() -> None:
    rng = np.random.default_rng(1)
    values = np.concatenate(
        [
            [0.0, 0.14, 0.0] + rng.normal(0, 0.002, (3, 3)),
            [0.14, 0.0, 0.0] + rng.normal(0, 0.002, (2, 3)),
        ]
    )
    chosen = select_clustering(PositionSpace(values), separation=0.05, noise=0.003)
    assert chosen.n_clusters == 2
    assert len(set(chosen.labels[:3])) == 1 and chosen.labels[0] != chosen.labels[3]


def test_clusters_closer_than_the_separation_are_rejected() -> None:
    values = np.array([[0.0, 0.0, 0.0], [0.001, 0.0, 0.0], [0.03, 0.0, 0.0], [0.031, 0.0, 0.0]])
    chosen = select_clustering(PositionSpace(values), separation=0.05, noise=0.003)
    assert chosen.n_clusters == 1
    assert dict(chosen.tried)[2] is None  # rejected, not merely worse
    looser = select_clustering(PositionSpace(values), separation=0.02, noise=0.003)
    assert looser.n_clusters == 2


def test_yaw_179_and_minus_179_are_one_cluster() -> None:
    quats = np.array([quat_from_yaw(y) for y in (179.0, -179.0, 178.5, -178.0)])
    chosen = select_clustering(RotationSpace(quats), separation=15.0, noise=0.5)
    assert chosen.n_clusters == 1
    assert math.sqrt(chosen.score) < 2.0


def test_result_does_not_depend_on_the_order_of_values() -> None:
    rng = np.random.default_rng(2)
    values = rng.uniform(-0.2, 0.2, (9, 3))
    a = select_clustering(PositionSpace(values), separation=0.05, noise=0.003)
    order = rng.permutation(9)
    b = select_clustering(PositionSpace(values[order]), separation=0.05, noise=0.003)
    assert a.n_clusters == b.n_clusters and a.score == pytest.approx(b.score)
    partition_a = {frozenset(np.flatnonzero(np.array(a.labels) == k)) for k in set(a.labels)}
    partition_b = {frozenset(order[np.flatnonzero(np.array(b.labels) == k)]) for k in set(b.labels)}
    assert partition_a == partition_b


def _ring(centre: tuple[float, float], radius: float, count: int) -> np.ndarray:
    angles = np.linspace(0.0, 2.0 * math.pi, count, endpoint=False)
    return np.stack(
        [centre[0] + radius * np.cos(angles), centre[1] + radius * np.sin(angles), 0 * angles], 1
    )


def test_a_place_seen_twice_is_a_state_where_one_cluster_does_not_fit_the_precision() -> None:
    """Eight placements scattered by 2 cm around one spot, two 3.6 cm apart
    around another 11 cm away: as one cluster they scatter by ~51 mm. Against a precision of
    19 mm estimated from 20 degrees of freedom that is no state's scatter, and
    the two clusters each fit it: two states — though the wider cluster holds
    two placements, too few for the F test against it (critical ratio ≈ 19).
    Against a precision estimated from 2 degrees of freedom, one state."""
    values = np.concatenate([_ring((0.0, 0.0), 0.02, 8), _ring((0.11, 0.0), 0.018, 2)])
    space = PositionSpace(values)
    chosen = select_clustering(space, separation=0.05, noise=0.019, noise_df=20, significance=0.05)
    assert chosen.n_clusters == 2
    assert dict(chosen.tried)[1] is not None and math.sqrt(dict(chosen.tried)[1]) > 0.045
    doubtful = select_clustering(space, separation=0.05, noise=0.019, noise_df=2, significance=0.05)
    assert doubtful.n_clusters == 1


def test_a_cluster_a_little_wider_than_an_estimated_precision_is_not_a_continuum() -> None:
    """Two spots 12 cm apart, 100 placements each scattered by exactly 22.6 mm
    RMS, against a precision of 19.1 mm estimated with 398 degrees of freedom:
    the variance ratio, 1.40, lies below the F test's 0.1 % point (1.45) and
    above the χ² test's (1.34) — the consistency check keeps both clusters
    only when it takes the precision as the estimate it is."""
    rng = np.random.default_rng(3)
    clusters = []
    for spot in ([0.0, 0.0, 0.0], [0.12, 0.0, 0.0]):
        scatter = rng.normal(0, 1, (100, 3)) * [1, 1, 0]
        scatter -= scatter.mean(axis=0)
        scatter *= 0.0226 / math.sqrt(spread_of(scatter))
        clusters.append(np.array(spot) + scatter)
    space = PositionSpace(np.concatenate(clusters))
    estimated = select_clustering(
        space, separation=0.05, noise=0.0191, noise_df=398, significance=0.05
    )
    assert estimated.n_clusters == 2
    exact = select_clustering(space, separation=0.05, noise=0.0191, significance=0.05)
    assert exact.n_clusters == 1
    assert CONSISTENCY_LEVEL == 0.001
