"""Pose streams: what a motion-capture system or an object tracker records.

A :class:`PoseStream` holds one :class:`ObjectTrack` per object: sample times
(seconds, strictly increasing), positions (metres, world frame, z up) and,
when the source has them, orientations as unit quaternions ``(x, y, z, w)``.
Tracks are sampled independently: rates may differ between objects, vary over
time, and samples may be missing.

The readers (:mod:`demoplan.segmentation.readers`) turn flat samples into a
stream with :func:`stream_from_samples`; the writers are in
:mod:`demoplan.segmentation.writers`.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from fnmatch import fnmatchcase

import numpy as np
from numpy.typing import NDArray

from demoplan.errors import InputError
from demoplan.rotations import UNIT_TOLERANCE, unit_length_expected

FloatArray = NDArray[np.float64]

__all__ = [
    "MAX_OBJECTS",
    "MAX_SPAN_S",
    "FloatArray",
    "ObjectTrack",
    "PoseStream",
    "check_object_count",
    "check_stream_limits",
    "normalise_quats",
    "parse_object_patterns",
    "select_objects",
    "stream_from_samples",
]


@dataclass(frozen=True, slots=True, eq=False)
class ObjectTrack:
    """The samples of one object.

    Parameters
    ----------
    name : str
        The object's name (CSV ``object`` column, TF child frame, topic).
    times : ndarray, shape (n,)
        Sample times in seconds, strictly increasing.
    positions : ndarray, shape (n, 3)
        Positions in metres (world frame, z up).
    orientations : ndarray, shape (n, 4), or None
        Unit quaternions ``(x, y, z, w)``; ``None`` when the source has none.
    """

    name: str
    times: FloatArray
    positions: FloatArray
    orientations: FloatArray | None = None

    def __post_init__(self) -> None:
        n = self.times.shape[0]
        if self.times.ndim != 1 or self.positions.shape != (n, 3):
            raise ValueError(
                f"track {self.name!r}: times (n,) and positions (n, 3) expected, got "
                f"{self.times.shape} and {self.positions.shape}"
            )
        if self.orientations is not None and self.orientations.shape != (n, 4):
            raise ValueError(
                f"track {self.name!r}: orientations (n, 4) expected, got {self.orientations.shape}"
            )
        if n > 1 and not bool(np.all(np.diff(self.times) > 0)):
            raise ValueError(f"track {self.name!r}: times must be strictly increasing")

    def __len__(self) -> int:
        return int(self.times.shape[0])

    @property
    def duration(self) -> float:
        """Time from the first to the last sample (s)."""
        return float(self.times[-1] - self.times[0]) if len(self) else 0.0


@dataclass(frozen=True, slots=True, eq=False)
class PoseStream:
    """Object poses over time: one :class:`ObjectTrack` per object, in order of appearance."""

    tracks: tuple[ObjectTrack, ...]
    source: str | None = None

    @property
    def objects(self) -> tuple[str, ...]:
        """The objects' names, in the stream's order."""
        return tuple(track.name for track in self.tracks)

    @property
    def n_samples(self) -> int:
        """Number of samples over all objects."""
        return sum(len(track) for track in self.tracks)

    @property
    def start_time(self) -> float:
        return min(float(track.times[0]) for track in self.tracks if len(track))

    @property
    def end_time(self) -> float:
        return max(float(track.times[-1]) for track in self.tracks if len(track))

    def track(self, name: str) -> ObjectTrack:
        """The track of object ``name`` (``KeyError`` if absent)."""
        for track in self.tracks:
            if track.name == name:
                return track
        raise KeyError(name)

    def __iter__(self) -> Iterator[ObjectTrack]:
        return iter(self.tracks)


def stream_from_samples(
    names: Sequence[str],
    times: FloatArray,
    positions: FloatArray,
    orientations: FloatArray | None = None,
    *,
    source: str | None = None,
    where: Sequence[str] | None = None,
) -> PoseStream:
    """Group flat samples (one per row, any order) into a :class:`PoseStream`.

    ``orientations`` may hold NaN rows for samples without an orientation; an
    object must then have orientations on all of its samples or on none.
    ``where[i]`` names sample i in error messages (e.g. ``"row 12"``). Two
    samples of one object at the same time are refused.
    """
    codes, order_names = _codes(names)
    check_object_count(len(order_names), "objects", source, None)
    label = (lambda i: where[i]) if where is not None else (lambda i: f"sample {i}")
    has_q: NDArray[np.bool_] | None = None
    if orientations is not None:
        has_q = np.asarray(~np.isnan(orientations).any(axis=1), dtype=bool)
    tracks = []
    # One stable sort groups the samples by object, in time order within each.
    order = np.lexsort((times, codes))
    bounds = np.searchsorted(codes[order], np.arange(len(order_names) + 1))
    for k, name in enumerate(order_names):
        index = order[bounds[k] : bounds[k + 1]]
        t = times[index]
        repeated = np.flatnonzero(np.diff(t) <= 0)
        if repeated.size:
            first = int(index[repeated[0] + 1])
            raise InputError(
                f"object {name!r} has two samples at t = {float(t[repeated[0]]):g}; "
                "one sample per object per time expected",
                source=source,
                field=label(first),
            )
        quats = None
        if orientations is not None and has_q is not None:
            present = has_q[index]
            if present.any() and not present.all():
                missing = int(index[int(np.argmin(present))])
                raise InputError(
                    f"object {name!r} has orientations on some samples only; "
                    "every sample of an object needs one, or none",
                    source=source,
                    field=label(missing),
                )
            if present.all():
                quats = orientations[index]
        tracks.append(
            ObjectTrack(
                name,
                np.ascontiguousarray(t, dtype=float),
                np.ascontiguousarray(positions[index], dtype=float),
                None if quats is None else np.ascontiguousarray(quats, dtype=float),
            )
        )
    return PoseStream(tuple(tracks), source)


def _codes(names: Sequence[str]) -> tuple[NDArray[np.intp], list[str]]:
    """Integer code per sample, codes numbered in order of first appearance."""
    table: dict[str, int] = {}
    codes = np.fromiter((table.setdefault(name, len(table)) for name in names), np.intp, len(names))
    return codes, list(table)


MAX_OBJECTS = 1000
"""The most objects a stream may follow — tracks of a CSV file or a bag, frames
of a TF tree, free-jointed bodies of a recording's model (docs/limits.md).
Segmenting costs a few milliseconds an object: a model of 20,000 free bodies
took a minute and 800 MB to import, a TF tree of 5,000 frames two minutes to
read; robot tasks follow tens, and a robot's TF tree holds hundreds."""


def check_object_count(count: int, what: str, source: str | None, field: str | None) -> None:
    """Refuse ``count`` objects (``what`` they are, e.g. "TF frames") beyond
    :data:`MAX_OBJECTS`, in one InputError: checked as early as the count is
    known, before the work that grows with it."""
    if count > MAX_OBJECTS:
        raise InputError(
            f"{count:,} {what}; at most {MAX_OBJECTS:,} objects followed in one stream "
            "(a documented limit: docs/limits.md)",
            source=source,
            field=field,
        )


MAX_SPAN_S = 7 * 24 * 3600.0
"""Seconds from a stream's first sample to its last, at most: a week. A
demonstration is minutes long and a day's recording holds hundreds; a span of
years or of 1e300 s is a time in another unit, or one absurd time — which,
read as it is, made a lone sample an object's last pose (a step that never
happened: 8 steps for 7)."""


def check_stream_limits(stream: PoseStream) -> None:
    """Every position of ``stream`` finite and within 1 km of the origin on
    each axis (docs/limits.md, as a demonstration file's); one InputError
    naming the object and the time. At most :data:`MAX_OBJECTS` objects, each
    named as a demonstration file's (:mod:`demoplan.documents.names`: what is
    segmented becomes one, and a name a plan cannot show is refused here, where
    it is read, rather than by ``learn`` of the file ``segment`` wrote)."""
    from demoplan.documents.names import check_object_name
    from demoplan.documents.poses import MAX_DISTANCE_M

    check_object_count(len(stream.tracks), "objects", stream.source, None)
    for track in stream:
        check_object_name(track.name, stream.source, f"object {track.name!r}")
    _check_span(stream)
    for track in stream:
        far = np.flatnonzero(~(np.abs(track.positions) <= MAX_DISTANCE_M).all(axis=1))
        if far.size:
            x, y, z = (float(v) for v in track.positions[far[0]])
            raise InputError(
                f"{track.name!r} at t = {float(track.times[far[0]]):g} s is at ({x:g}, {y:g}, "
                f"{z:g}) m, more than 1 km from the origin; a position on a table expected (a "
                "documented limit: docs/limits.md)",
                source=stream.source,
                field=f"object {track.name!r}",
            )


def _check_span(stream: PoseStream) -> None:
    """The stream's times within :data:`MAX_SPAN_S` of one another, or one
    InputError naming the earliest and the latest sample (object and time)."""
    ends = [
        (float(track.times[k]), track.name) for track in stream if track.times.size for k in (0, -1)
    ]
    if not ends:
        return
    (first, early), (last, late) = min(ends), max(ends)
    if last - first > MAX_SPAN_S:
        raise InputError(
            f"its times span {last - first:.4g} s, from t = {first:.6g} s ({early!r}) to "
            f"t = {last:.6g} s ({late!r}); a recording of at most {MAX_SPAN_S / 86400:g} days "
            "expected, times in seconds (a documented limit: docs/limits.md)",
            source=stream.source,
            field="t",
        )


def normalise_quats(
    quats: FloatArray, source: str | None, where: Sequence[str] | None
) -> FloatArray:
    """``(n, 4)`` quaternions scaled to unit length; NaN rows (no orientation) stay NaN.

    A quaternion farther than :data:`~demoplan.rotations.UNIT_TOLERANCE` from
    unit length (zero, scaled, components of 1e200) is an
    :class:`~demoplan.errors.InputError` naming ``where[i]`` (or ``sample i``).
    """
    with np.errstate(over="ignore"):
        norms = np.linalg.norm(quats, axis=1)
    bad = np.flatnonzero(~(np.abs(norms - 1.0) <= UNIT_TOLERANCE) & ~np.isnan(norms))
    if bad.size:
        i = int(bad[0])
        raise InputError(
            f"quaternion (qx, qy, qz, qw): {unit_length_expected(float(norms[i]))}",
            source=source,
            field=where[i] if where is not None else f"sample {i}",
        )
    with np.errstate(invalid="ignore"):
        unit = quats / norms[:, None]
    return np.asarray(unit, dtype=float)


def parse_object_patterns(text: str | None) -> list[str] | None:
    """``"cup, plate,obj_*"`` → ``["cup", "plate", "obj_*"]``; ``None`` or blank → ``None``."""
    if text is None:
        return None
    patterns = [part.strip() for part in text.split(",") if part.strip()]
    return patterns or None


def select_objects(
    patterns: Sequence[str] | None,
    available: Sequence[str],
    default: Sequence[str],
    *,
    source: str | None = None,
    field: str = "objects",
) -> list[str]:
    """The objects chosen by ``patterns`` (names or :mod:`fnmatch` globs) among ``available``.

    ``None`` chooses ``default``. The result keeps the order of ``available``.
    A pattern that matches nothing is an :class:`~demoplan.errors.InputError`
    naming every such pattern and listing what is available (``field``: the
    option the patterns came from).
    """
    if patterns is None:
        return list(default)
    missing = [p for p in patterns if not any(fnmatchcase(name, p) for name in available)]
    if missing:
        listed = ", ".join(repr(p) for p in missing)
        raise InputError(
            f"no object {'matches' if len(missing) == 1 else 'match'} {listed}; "
            f"available: {', '.join(available) or 'none'}",
            source=source,
            field=field,
        )
    return [name for name in available if any(fnmatchcase(name, p) for p in patterns)]
