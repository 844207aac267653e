"""The placement precision the state generation's decisions are measured against
(paper §IV.A: the position and orientation noise of a placement, RMS), estimated
from the demonstrations — the tightest consistent spread of any object's
placements, relative to any reference — or set by the user."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, NamedTuple

import numpy as np

from demoplan.learning.clustering import (
    CONSISTENCY_LEVEL,
    UNBOUNDED_DF,
    PositionSpace,
    RotationSpace,
    Space,
    closest_pair,
    cluster_stats,
    f_critical,
    kmeans_batch,
    spread_of,
)
from demoplan.learning.settings import LearningSettings as StateGenerationSettings

__all__ = ["Precision", "estimate_precision"]

Kind = Literal["position", "orientation"]
KINDS: tuple[Kind, ...] = ("position", "orientation")


@dataclass(frozen=True, slots=True)
class Precision:
    """The placement precision decisions were measured against (RMS; m and degrees)
    and whether each was estimated from the demonstrations or set by the user."""

    position: float
    orientation: float
    position_estimated: bool = True
    orientation_estimated: bool = True
    position_df: float = UNBOUNDED_DF
    """Degrees of freedom of the estimate (unbounded where the user set it)."""
    orientation_df: float = UNBOUNDED_DF


class _Spread(NamedTuple):
    """An RMS spread (m or degrees) and the degrees of freedom it was measured with."""

    rms: float
    df: float


OWN_PRECISION_DF = 6
"""Degrees of freedom from which an object's own tightest spread may be its
precision (four placements on a table): fewer agree as closely as chance
makes them (:func:`_own_precisions`)."""
SIMILAR_PRECISION = 2.0
"""An object's own precision counts where another object's lies within this
factor of it (:func:`_own_precisions`)."""
MIN_POSITION_PRECISION = 1e-4  # m: noise-free data still has a scale for ties
MIN_ORIENTATION_PRECISION = 0.05  # deg
FALLBACK_PRECISION = (0.003, 0.5)  # m, deg: when no object was placed twice


def estimate_precision(
    relative: dict[tuple[str, Kind, str | None], np.ndarray],
    settings: StateGenerationSettings,
) -> Precision:
    """The placement precision of the demonstrations (docs/learning.md), unless set.

    For every object placed at least twice, the RMS spread of its placements
    relative to the candidate that explains them best as one cluster (the
    lowest trace of the sample covariance over absolute, the landmarks and
    the objects placed before it in every demonstration — ``relative`` holds
    just those: the best of many candidates that were never available would
    be low by chance); the precision is the median of these over the
    objects (the lower one of an even count: with two objects, the more
    precise). An object placed where it is meant to go, relative to what it is
    meant to go with, scatters by the teacher's precision; the median keeps
    objects with several places (whose best single cluster is wide) from
    inflating it. A virtual environment gives well under a millimetre,
    people teleoperating a robot centimetres. Without any object placed
    twice, :data:`FALLBACK_PRECISION`.
    """
    return _precision({kind: _tightest(relative, kind, settings) for kind in KINDS}, settings)


def _precision(
    tightest: dict[Kind, dict[str, _Spread]], settings: StateGenerationSettings
) -> Precision:
    """:func:`estimate_precision` from each object's tightest spread, per kind; with
    the degrees of freedom of the median one (an estimate from that object's
    placements, not the truth)."""
    found: dict[Kind, _Spread] = {}
    for kind, best in tightest.items():
        fallback = FALLBACK_PRECISION[0 if kind == "position" else 1]
        ranked = sorted(best.values())
        found[kind] = ranked[(len(ranked) - 1) // 2] if ranked else _Spread(fallback, UNBOUNDED_DF)
    position = _floored(found["position"], MIN_POSITION_PRECISION)
    orientation = _floored(found["orientation"], MIN_ORIENTATION_PRECISION)
    set_position, set_orientation = settings.position_noise, settings.orientation_noise
    return Precision(
        position=position.rms if set_position is None else set_position,
        orientation=orientation.rms if set_orientation is None else set_orientation,
        position_estimated=set_position is None,
        orientation_estimated=set_orientation is None,
        position_df=position.df if set_position is None else UNBOUNDED_DF,
        orientation_df=orientation.df if set_orientation is None else UNBOUNDED_DF,
    )


def _own_precisions(
    tightest: dict[str, _Spread], median: float, median_df: float
) -> dict[str, _Spread]:
    """The precision each object's decisions are judged by.

    The median object's (:func:`estimate_precision`), or the object's own
    tightest spread where that is lower — red stands on wood to 0.6 mm while
    wood and green scatter by centimetres (the shipped blocks) — or where the
    object's own is measured (:data:`OWN_PRECISION_DF`) and another object is
    placed about as precisely (:data:`SIMILAR_PRECISION`): a task may mix
    objects put down to 2 mm relative to others with objects put on spots to
    2 cm, and one median precision would judge half of them wrongly. An
    object alone at its precision is judged by the median: a can put
    anywhere on the table that happened to land in two regions 80 cm apart
    is not two places of 8 cm while everything else is placed to 2 mm.
    """
    common = _Spread(median, median_df)
    own: dict[str, _Spread] = {}
    for obj, spread in tightest.items():
        confirmed = spread.df >= OWN_PRECISION_DF and any(
            spread.rms / SIMILAR_PRECISION <= other.rms <= spread.rms * SIMILAR_PRECISION
            for name, other in tightest.items()
            if name != obj
        )
        own[obj] = spread if confirmed else min(spread, common)
    return own


def _floored(spread: _Spread, least: float) -> _Spread:
    """``spread`` raised to at least ``least`` — noise-free data still have a scale
    for ties — and then known exactly (no degrees of freedom to doubt it by)."""
    return spread if spread.rms >= least else _Spread(least, UNBOUNDED_DF)


def _tightest(
    relative: dict[tuple[str, Kind, str | None], np.ndarray],
    kind: Kind,
    settings: StateGenerationSettings,
) -> dict[str, _Spread]:
    """Per object placed at least twice: its RMS spread relative to the candidate
    that explains it best (``relative`` holds the candidates), and its degrees
    of freedom, (placements − 1) × the axes they vary along. For positions a
    few well-separated places count too (:func:`_grouped_spreads`): an object
    put in one of two slots 15 cm apart scatters by its teacher's precision
    within each slot, not by 75 mm — which, as the median of three objects,
    was once the precision and merged the slots."""
    by_object: dict[str, list[np.ndarray]] = {}
    for (obj, what, _), values in relative.items():
        if what == kind and len(values) >= 2:
            by_object.setdefault(obj, []).append(values)
    best: dict[str, _Spread] = {}
    for obj, candidates in by_object.items():
        for values in candidates:
            space: Space = PositionSpace(values) if kind == "position" else RotationSpace(values)
            _, spread = space.stats(np.arange(len(values)))
            found = _Spread(math.sqrt(spread), (len(values) - 1) * space.dims)
            if obj not in best or found < best[obj]:
                best[obj] = found
        if kind == "position":
            grouped = _grouped_spreads(np.stack(candidates), settings)
            if grouped is not None and grouped < best[obj]:
                best[obj] = grouped
    return best


GROUP_GAP = 4.0
"""Groups of placements count as separate places in the precision estimate only
where every two centres lie at least this many pooled RMS spreads apart (and at
least ``position_separation``): two slots 11 cm apart, each scattered by 2 cm,
do; a continuum cut by K-means does not (neighbouring pieces of a uniform
stretch lie about 3.5 RMS apart)."""
GROUP_MAX_PLACES = 3
"""At most this many places per object in the precision estimate."""


def _grouped_spreads(candidates: np.ndarray, settings: StateGenerationSettings) -> _Spread | None:
    """The lowest pooled within-group RMS spread of one object's positions ``(B, n,
    3)`` (relative to B candidates) split into 2..:data:`GROUP_MAX_PLACES`
    groups of at least two placements whose centres lie :data:`GROUP_GAP`
    spreads apart and that one cluster explains far worse (an F test at
    ``CONSISTENCY_LEVEL``); ``None`` where no split qualifies. Degrees of freedom:
    (placements − groups) × varying axes. One batched K-means per group count."""
    _, n, _ = candidates.shape
    best: _Spread | None = None
    generator = np.random.default_rng(settings.seed)
    for c in range(2, min(GROUP_MAX_PLACES, n // 2) + 1):
        labels = kmeans_batch(candidates, c, settings.n_init, 100, generator)
        for values, label in zip(candidates, labels, strict=True):
            sizes = np.bincount(label, minlength=c)
            if sizes.min() < 2:
                continue
            space = PositionSpace(values)
            centres, spreads = cluster_stats(space, label, c)
            pooled = sum((k - 1) * v for k, v in zip(sizes, spreads, strict=True)) / (n - c)
            gap = max(settings.position_separation, GROUP_GAP * math.sqrt(pooled))
            if closest_pair(space.distance, centres) < gap:
                continue
            # ... and only where the groups explain the placements far better than
            # one cluster does (an F test at 0.1 %): four or six placements of one
            # spot fall into two tight-looking groups often enough by chance.
            df_one, df_groups = (n - 1) * space.dims, (n - c) * space.dims
            if spread_of(values) < f_critical(CONSISTENCY_LEVEL, df_one, df_groups) * pooled:
                continue
            found = _Spread(math.sqrt(pooled), df_groups)
            if best is None or found < best:
                best = found
    return best
