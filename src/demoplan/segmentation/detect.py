"""Move detection: a pose stream → the pick-and-place steps it shows.

The method, per object (objects are independent, so two hands moving two
objects at once give two moves):

1. **Speed.** At every sample ``i`` the object's speed is estimated from the
   mean position over the half window ``[t_i − w/2, t_i]`` and the one over
   ``(t_i, t_i + w/2]`` (``w`` = :attr:`SegmentationSettings.speed_window_s`),
   divided by the difference of the two windows' mean times. Windows are in
   time, not samples, so uneven sampling and dropped samples only change how
   many samples are averaged (a half window holding fewer than 4 samples —
   low rates, dropped samples — is widened to 4); with σ of sensor noise and ``k`` samples per
   half window the speed noise is about ``σ·√(2/k) / (w/2)`` per axis
   (3 mm at 30 Hz with w = 0.4 s: ≈ 8 mm/s). Everything is computed with
   cumulative sums and ``searchsorted`` — O(n log n), no Python loop per sample.
2. **Gaps.** Where the tracker lost the object for longer than
   :attr:`~SegmentationSettings.max_gap_s` and the mean positions on either
   side differ by more than half of :attr:`~SegmentationSettings.min_distance`,
   the object moved unseen: both samples around the gap count as moving.
3. **Hysteresis.** A move is a maximal run of samples faster than
   :attr:`~SegmentationSettings.stop_speed` that contains at least one sample
   faster than :attr:`~SegmentationSettings.start_speed`. Noise above the low
   threshold alone never starts a move; a move lasts until the object is
   slower than the low threshold. Moves separated by less than
   :attr:`~SegmentationSettings.min_rest_s` of rest are one move (a pause in
   mid-air is not a placement); the last move needs ``min_rest_s`` of rest
   after it, or the end of the stream (6.).
4. **Rest poses.** The pose of a rest is read where the object first lies as
   low as it gets in that rest after the last time it was held higher (so a
   teleoperator's slow final lowering, or a lift-and-set-down too slow for
   the thresholds, ends before it), over :attr:`~SegmentationSettings.pose_window_s`:
   the per-axis median, then the mean of the samples closer to it than 3 ×
   the median distance (≈ 4.6 σ for normal noise: a tracker's outliers are
   dropped, its noise is averaged); orientations are the chordal mean of
   those samples' quaternions.
5. **Pauses in the air.** A rest is not a placement — the move goes on
   through it — when the next move only lowers the object (it never rises
   :attr:`~SegmentationSettings.min_lift` above the rest and ends at least
   that much lower: an object standing on a support must be lifted before
   it can go down), or when it is above the table (z = 0, docs/formats.md) and
   above no object or landmark whose top it could stand on (from
   ``geometry``; an object of unknown size within 10 cm beneath may be the
   support). The objects beneath are read over the times the rest's pose was
   read (at least the last ``pose_window_s`` of them), robustly as in 4., not
   from one sample.
6. **The end of the stream.** A recording that stops right after the last
   release still gives that placement: the samples at the end within
   :attr:`~SegmentationSettings.settle_radius` of the last ones (or 4 × the
   noise) are the final rest when they lie on a support, or on an object of
   unknown size with at least two samples there, the last two no faster than ``start_speed``.
   An object still carried when the stream ends gives no step (a warning).
7. **Steps, nudges and pushes.** A move is a nudge when the new rest pose is
   less than :attr:`~SegmentationSettings.min_distance` from the object's
   last *accepted* rest pose and turned by less than
   :attr:`~SegmentationSettings.min_angle_deg` (so is a tracker glitch that
   jumps and comes back); a push when it is longer but the object was never
   lifted ``min_lift`` above where it rested and ends at the same height
   (slid along its support; kept in :attr:`Segmentation.pushes`, and the
   object's new place is where later moves are measured from); otherwise a
   step. An object moving when its track begins that only comes down, in
   place, is settling (robosuite drops its objects onto the table at the
   start), not a move. Steps are ordered by the time their object comes to
   rest.

Limits: detection uses translation speed only, so an object turned in place
without its reference point moving faster than ``start_speed`` is not seen
to move; an object carried on another (a napkin on a moved plate) counts as
moved; a pause in the air followed by a lift higher is a placement unless
geometry shows nothing to stand on.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, fields
from operator import attrgetter
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from demoplan.documents.demonstrations import demonstration_to_dict
from demoplan.errors import InputError
from demoplan.fileio import dump_json, write_atomic
from demoplan.model import Demonstration, ObjectGeometry, Pose, Step
from demoplan.rotations import angle_between
from demoplan.segmentation.rests import Supports, robust_pose
from demoplan.segmentation.settings import SegmentationSettings
from demoplan.segmentation.types import ObjectTrack, PoseStream, check_object_count

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]

__all__ = [
    "Move",
    "Segmentation",
    "SegmentationSettings",
    "SpeedTrace",
    "segment",
    "track_speed",
    "write_demonstration",
]

logger = logging.getLogger(__name__)

MIN_FINAL_REST_SAMPLES = 3
MIN_HALF_WINDOW_SAMPLES = 4  # a half window shorter than this is widened (sparse samples)
MIN_SAMPLE_STEP = 1e-5
"""Seconds between samples, at least (median of a track): 100,000 samples a
second, fifty times a fast motion-capture system. The windows of the
segmentation are seconds long, so samples nanoseconds apart (times written
in ns, or in s but scaled) made windows of billions of samples: segment ran
for minutes or asked for 400 GB."""


@dataclass(frozen=True, slots=True)
class Move:
    """One detected move of one object.

    ``start`` and ``end`` are stream times (s): the object is moving from
    ``start`` and at rest again after ``end``. ``pose`` is the robust mean of
    the rest that follows; ``before`` the pose of the rest that precedes it
    (``None`` when the object was moving when its track began); ``lift`` how
    far (m) it rose above where it rested before.
    """

    object: str
    start: float
    end: float
    pose: Pose
    before: Pose | None
    lift: float = math.nan

    @property
    def distance(self) -> float:
        """Displacement from ``before`` to ``pose`` (m); NaN without ``before``."""
        if self.before is None:
            return math.nan
        return math.dist(self.before.position, self.pose.position)


@dataclass(frozen=True, slots=True, eq=False)
class SpeedTrace:
    """An object's estimated speed (m/s) and its height z (m; ``None`` when not
    kept) at its sample times (s), for plots and checks."""

    object: str
    times: FloatArray
    speed: FloatArray
    height: FloatArray | None = None


@dataclass(frozen=True, slots=True, eq=False)
class Segmentation:
    """What :func:`segment` found in a stream.

    ``moves`` are the steps, ordered by the time their object comes to rest
    (``end``); ``nudges`` the moves too small to be steps; ``pushes`` the
    moves along the support without a lift (not steps); ``initial`` each
    object's pose in its first rest (objects already moving when their track
    begins have none); ``traces`` the speed signals.
    """

    moves: tuple[Move, ...]
    nudges: tuple[Move, ...]
    pushes: tuple[Move, ...]
    initial: tuple[tuple[str, Pose], ...]
    traces: tuple[SpeedTrace, ...]
    settings: SegmentationSettings
    objects: tuple[str, ...]
    source: str | None = None

    @property
    def steps(self) -> tuple[Step, ...]:
        """The moves as demonstration steps (object, pose after the move)."""
        return tuple(Step(move.object, move.pose) for move in self.moves)

    def to_demonstration(
        self,
        name: str | None = None,
        *,
        objects: Mapping[str, ObjectGeometry] | Iterable[tuple[str, ObjectGeometry]] = (),
        landmarks: Iterable[str] = (),
    ) -> Demonstration:
        """The segmented demonstration (docs/formats.md ``demoplan/demonstration-1``).

        Steps in the order objects come to rest; initial poses from each
        object's first rest. ``name`` defaults to the stream file's stem.
        ``objects`` adds geometry (only for objects in the stream);
        the provenance records the stream, the pushes and nudges left out,
        and every threshold used (``segment.min_lift``, …);
        ``landmarks`` names stream objects that are static references: they
        become landmarks (at their first rest pose) instead of initial poses,
        and must not have moved.

        Raises :class:`InputError` when no step was found (a demonstration has
        at least one step) or a landmark moved or is not in the stream.
        """
        source = self.source or "pose stream"
        if not self.moves:
            raise InputError(
                f"no pick-and-place step found: no object moved at least "
                f"{self.settings.min_distance * 100:g} cm and came to rest; at least one expected",
                source=source,
            )
        if name is None:
            name = Path(self.source).stem if self.source else "segmented"
        initial = dict(self.initial)
        landmark_names = list(dict.fromkeys(landmarks))
        for landmark in landmark_names:
            if landmark not in self.objects:
                raise InputError(
                    f"landmark {landmark!r} is not in the stream; expected one of "
                    f"{sorted(self.objects)}",
                    source=source,
                    field="landmarks",
                )
            if any(move.object == landmark for move in self.moves):
                raise InputError(
                    f"landmark {landmark!r} moved; landmarks must stay in place",
                    source=source,
                    field="landmarks",
                )
            if landmark not in initial:
                raise InputError(
                    f"landmark {landmark!r} never came to rest", source=source, field="landmarks"
                )
        geometry = dict(objects)
        provenance: list[tuple[str, str | int | float]] = []
        if self.source is not None:
            provenance.append(("source", self.source))
        provenance += [("pushes", len(self.pushes)), ("nudges", len(self.nudges))]
        provenance += [
            (f"segment.{f.name}", getattr(self.settings, f.name)) for f in fields(self.settings)
        ]
        return Demonstration(
            name=name,
            steps=self.steps,
            objects=tuple((n, geometry[n]) for n in self.objects if n in geometry),
            landmarks=tuple((n, initial[n]) for n in landmark_names),
            initial=tuple((n, p) for n, p in self.initial if n not in landmark_names),
            source=self.source,
            provenance=tuple(provenance),
        )


def write_demonstration(demonstration: Demonstration, path: str | Path) -> None:
    """Write ``demonstration`` as a ``demoplan/demonstration-1`` file, atomically."""
    write_atomic(Path(path), dump_json(demonstration_to_dict(demonstration)))


# --------------------------------------------------------------------------- detection


def segment(
    stream: PoseStream,
    settings: SegmentationSettings | None = None,
    *,
    geometry: Mapping[str, ObjectGeometry] | None = None,
    landmarks: Mapping[str, Pose] | None = None,
) -> Segmentation:
    """Detect every object's moves in ``stream`` (module docstring) and order them.

    ``geometry`` (object and landmark sizes) and ``landmarks`` (static
    references not in the stream) let a rest be checked against the supports
    beneath it (:attr:`SegmentationSettings.support_tolerance`); without
    geometry only the motion tells a pause in the air from a placement.
    """
    settings = settings or SegmentationSettings()
    check_object_count(len(stream.tracks), "objects", stream.source, None)
    _check_sample_steps(stream)
    supports = Supports(stream, geometry or {}, landmarks or {}, settings)
    moves: list[Move] = []
    nudges: list[Move] = []
    pushes: list[Move] = []
    initial: list[tuple[str, Pose]] = []
    traces: list[SpeedTrace] = []
    for track in stream.tracks:
        result = _segment_track(track, settings, supports)
        moves += result.moves
        nudges += result.nudges
        pushes += result.pushes
        traces.append(SpeedTrace(track.name, track.times, result.speed, track.positions[:, 2]))
        if result.initial is not None:
            initial.append((track.name, result.initial))
        else:
            logger.info("%s: moving when its track begins; no initial pose", track.name)
    order = attrgetter("end", "start", "object")
    return Segmentation(
        moves=tuple(sorted(moves, key=order)),
        nudges=tuple(sorted(nudges, key=order)),
        pushes=tuple(sorted(pushes, key=order)),
        initial=tuple(initial),
        traces=tuple(traces),
        settings=settings,
        objects=stream.objects,
        source=stream.source,
    )


def _check_sample_steps(stream: PoseStream) -> None:
    """Refuse a track whose samples come more than 1 / :data:`MIN_SAMPLE_STEP` a second."""
    for track in stream.tracks:
        if len(track.times) < 2:
            continue
        step = float(np.median(np.diff(track.times)))
        if step < MIN_SAMPLE_STEP:
            raise InputError(
                f"{track.name}: samples {step:.3g} s apart (the median), more than "
                f"{1 / MIN_SAMPLE_STEP:,.0f} a second; sample times in seconds expected "
                "(convert times written in ms, µs or ns)",
                source=stream.source,
            )


@dataclass(frozen=True, slots=True)
class _TrackResult:
    moves: list[Move]
    nudges: list[Move]
    pushes: list[Move]
    initial: Pose | None
    speed: FloatArray


def _cumsum0(values: FloatArray) -> FloatArray:
    """Cumulative sum along axis 0 with a leading zero row (window sums by differences)."""
    out = np.zeros((values.shape[0] + 1, *values.shape[1:]))
    np.cumsum(values, axis=0, out=out[1:])
    return out


def _window_means(
    ct: FloatArray, cp: FloatArray, lo: IntArray, hi: IntArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Sample count, mean time and mean position of samples ``lo … hi − 1`` (vectorised)."""
    count = (hi - lo).astype(float)
    with np.errstate(divide="ignore", invalid="ignore"):
        mean_t = (ct[hi] - ct[lo]) / count
        mean_p = (cp[hi] - cp[lo]) / count[:, None]
    return count, mean_t, mean_p


def track_speed(times: FloatArray, positions: FloatArray, window_s: float) -> FloatArray:
    """Speed (m/s) at each sample: difference of the half-window mean positions over
    the difference of their mean times (step 1 of the module docstring).

    Within ``window_s / 2`` of either end of the track the window is not
    shrunk but held at the first (last) full window, so the ends are no
    noisier than the middle.

    Parameters
    ----------
    times : ndarray, shape (n,)
        Strictly increasing sample times (s).
    positions : ndarray, shape (n, 3)
        Positions (m).
    window_s : float
        Full window width (s).
    """
    n = times.shape[0]
    if n < 2:
        return np.zeros(n)
    t = times - times[0]
    half = window_s / 2.0
    # Hold the window inside the track near its ends.
    centre = np.clip(t, half, t[-1] - half) if t[-1] > window_s else np.full(n, t[-1] / 2.0)
    ct, cp = _cumsum0(t), _cumsum0(positions)
    mid = np.searchsorted(t, centre, side="right")
    # Each half window spans w/2, widened to MIN_HALF_WINDOW_SAMPLES where samples are sparse.
    lo = np.minimum(np.searchsorted(t, centre - half, side="left"), mid - MIN_HALF_WINDOW_SAMPLES)
    hi = np.maximum(np.searchsorted(t, centre + half, side="right"), mid + MIN_HALF_WINDOW_SAMPLES)
    lo, hi = np.maximum(lo, 0), np.minimum(hi, n)
    left_n, left_t, left_p = _window_means(ct, cp, lo, mid)
    right_n, right_t, right_p = _window_means(ct, cp, mid, hi)
    dt = right_t - left_t
    valid = (left_n > 0) & (right_n > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        speed = np.linalg.norm(right_p - left_p, axis=1) / dt
    # A half window without samples (a gap) gives no speed; gaps are checked apart.
    return np.asarray(np.where(valid, speed, 0.0), dtype=float)


def _gap_jumps(times: FloatArray, positions: FloatArray, gap: IntArray, half: float) -> FloatArray:
    """Distance (m) between the mean positions over ``half`` before and after each gap
    (the gap lies between samples ``gap`` and ``gap + 1``)."""
    t = times - times[0]
    ct, cp = _cumsum0(t), _cumsum0(positions)
    before_lo = np.searchsorted(t, t[gap] - half, side="left")
    after_hi = np.searchsorted(t, t[gap + 1] + half, side="right")
    _, _, before = _window_means(ct, cp, before_lo, gap + 1)
    _, _, after = _window_means(ct, cp, gap + 1, after_hi)
    return np.asarray(np.linalg.norm(after - before, axis=1), dtype=float)


def _runs(mask: NDArray[np.bool_]) -> tuple[IntArray, IntArray]:
    """First and last index (inclusive) of each run of True in ``mask``."""
    edges = np.diff(np.concatenate(([0], mask.astype(np.int8), [0])))
    return np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1


def _segment_track(
    track: ObjectTrack, settings: SegmentationSettings, supports: Supports
) -> _TrackResult:
    """One object's track → its moves, nudges and pushes (steps 1–7 of the module docstring)."""
    n = len(track)
    times, positions = track.times, track.positions
    if n == 0:
        return _TrackResult([], [], [], None, np.zeros(0))
    speed = track_speed(times, positions, settings.speed_window_s)
    forced = _moves_in_gaps(times, positions, speed, settings)
    starts, ends = _hysteresis(times, speed, forced, settings)
    starts, ends, last_rest_end = _settle_at_the_end(track, starts, ends, settings, supports)
    # Rests: before the first move, between moves, after the last one (index ranges, end excl.).
    rest_ends = np.concatenate((starts, [last_rest_end]))
    noise = _noise_sigma(positions[:, 2])
    poses, spans = _rest_poses(track, np.concatenate(([0], ends + 1)), rest_ends, settings, noise)
    hover = _pauses_in_the_air(track, starts, ends, poses, spans, settings, supports)
    moves, nudges, pushes, initial = _steps_nudges_and_pushes(
        track, starts, ends, poses, hover, forced, settings
    )
    if starts.size and hover[starts.size]:
        last, (first, _) = poses[-1], spans[-1]
        assert last is not None
        logger.warning(
            "%s: at rest from t = %.2f s to the end of the stream (t = %.2f s), %s: "
            "taken as held in the air, so its last move (from t = %.2f s) is not a step",
            track.name,
            first,
            times[-1],
            _off_support(supports, track.name, last, *spans[-1]),
            times[starts[-1]],
        )
    return _TrackResult(moves, nudges, pushes, initial, speed)


def _moves_in_gaps(
    times: FloatArray, positions: FloatArray, speed: FloatArray, settings: SegmentationSettings
) -> NDArray[np.bool_]:
    """Step 2 of the module docstring: the samples around a tracking gap the
    object moved in count as moving (returned), and ``speed`` there is raised
    to at least the jump over the gap's duration."""
    forced = np.zeros(len(times), dtype=bool)
    gap = np.flatnonzero(np.diff(times) > settings.max_gap_s)
    if gap.size:
        jump = _gap_jumps(times, positions, gap, settings.speed_window_s / 2.0)
        moved = gap[jump > settings.min_distance / 2.0]
        forced[moved] = True
        forced[moved + 1] = True
        gap_speed = jump / (times[gap + 1] - times[gap])
        speed[gap] = np.maximum(speed[gap], gap_speed)
        speed[gap + 1] = np.maximum(speed[gap + 1], gap_speed)
    return forced


def _hysteresis(
    times: FloatArray,
    speed: FloatArray,
    forced: NDArray[np.bool_],
    settings: SegmentationSettings,
) -> tuple[IntArray, IntArray]:
    """Step 3 of the module docstring: the first and last sample of each move —
    a run above ``stop_speed`` reaching ``start_speed``; moves less than
    ``min_rest_s`` apart are one."""
    starts, ends = _runs((speed > settings.stop_speed) | forced)
    high = _cumsum0(((speed > settings.start_speed) | forced).astype(float))
    keep = high[ends + 1] - high[starts] > 0
    starts, ends = starts[keep], ends[keep]
    if starts.size > 1:
        separate = np.concatenate(
            ([True], times[starts[1:]] - times[ends[:-1]] >= settings.min_rest_s)
        )
        starts = starts[separate]
        ends = ends[np.concatenate((separate[1:], [True]))]
    return starts, ends


def _rest_poses(
    track: ObjectTrack,
    rest_starts: IntArray,
    rest_ends: IntArray,
    settings: SegmentationSettings,
    noise: float,
) -> tuple[list[Pose | None], list[tuple[float, float]]]:
    """Step 4 of the module docstring: the pose of each rest (samples
    ``rest_starts[k] … rest_ends[k] − 1``), None for a rest without samples,
    and the times (first, last sample) it was read over; ``noise`` is the
    track's height noise σ (m, :func:`_settled_start`)."""
    times, positions, orientations = track.times, track.positions, track.orientations
    poses: list[Pose | None] = []
    spans: list[tuple[float, float]] = []
    for a, b in zip(rest_starts.tolist(), rest_ends.tolist(), strict=True):
        if b <= a:
            poses.append(None)
            spans.append((math.nan, math.nan))
            continue
        a = _settled_start(times, positions, a, b, settings, noise)
        b = min(b, int(np.searchsorted(times, times[a] + settings.pose_window_s, side="right")))
        poses.append(
            robust_pose(positions[a:b], None if orientations is None else orientations[a:b])
        )
        spans.append((float(times[a]), float(times[b - 1])))
    return poses, spans


def _pauses_in_the_air(
    track: ObjectTrack,
    starts: IntArray,
    ends: IntArray,
    poses: list[Pose | None],
    spans: list[tuple[float, float]],
    settings: SegmentationSettings,
    supports: Supports,
) -> list[bool]:
    """Step 5 of the module docstring: whether each rest is in the air (not a
    placement: the move through it continues); the objects beneath are read
    over the times the rest's pose was read (``spans``)."""
    positions = track.positions
    hover = [False] * (starts.size + 1)
    for k in range(1, starts.size + 1):
        pose = poses[k]
        if pose is None:  # pragma: no cover - every kept move has a rest after it
            continue
        if k < starts.size:  # the next move only lowers the object: it was held up
            rise = float(positions[starts[k] : ends[k] + 1, 2].max()) - pose.position[2]
            after = poses[k + 1]
            drop = pose.position[2] - (after.position[2] if after else pose.position[2])
            hover[k] = rise < settings.min_lift and drop >= settings.min_lift
        if not hover[k]:
            hover[k] = supports.supported(track.name, pose, *spans[k]) is False
    return hover


def _steps_nudges_and_pushes(
    track: ObjectTrack,
    starts: IntArray,
    ends: IntArray,
    poses: list[Pose | None],
    hover: list[bool],
    forced: NDArray[np.bool_],
    settings: SegmentationSettings,
) -> tuple[list[Move], list[Move], list[Move], Pose | None]:
    """Step 7 of the module docstring: each move (from rest to rest, through
    pauses in the air) as a step, a nudge or a push; settling when the track
    begins is none. Returns the steps, nudges, pushes and the initial pose."""
    times, positions, orientations = track.times, track.positions, track.orientations
    moves: list[Move] = []
    nudges: list[Move] = []
    pushes: list[Move] = []
    initial = poses[0]
    reference = initial
    if reference is None:
        # Moving when the track begins: measure the first move from where the track starts.
        b = int(np.searchsorted(times, times[0] + settings.pose_window_s, side="right"))
        reference = robust_pose(positions[:b], None if orientations is None else orientations[:b])
    previous = 0  # the rest the current move started from
    first = 0  # the first hysteresis move of the current move
    for k in range(starts.size):
        if hover[k + 1]:
            continue
        a, b = int(starts[first]), int(ends[k])
        after, before = poses[k + 1], poses[previous]
        assert after is not None
        first, previous = k + 1, k + 1
        start_z = before.position[2] if before is not None else float(positions[a, 2])
        lift = float(positions[a : b + 1, 2].max()) - start_z
        move = Move(track.name, float(times[a]), float(times[b]), after, before, lift)
        if (
            before is None
            and initial is None
            and not moves
            and lift < settings.min_lift
            and math.dist(positions[a, :2], after.position[:2]) < settings.min_distance
        ):
            initial = reference = after  # settling when the track begins: not a move
            continue
        if not _is_step(reference, after, settings):
            nudges.append(move)
            logger.info(
                "%s: move at t = %.3f–%.3f s is a nudge (%.1f mm), not a step",
                track.name,
                move.start,
                move.end,
                math.dist(reference.position, after.position) * 1000,
            )
            continue
        unseen = bool(forced[a : b + 1].any())  # a lift may have happened in a tracking gap
        if (
            not unseen
            and lift < settings.min_lift
            and abs(after.position[2] - start_z) < settings.min_lift
        ):
            logger.info(
                "%s: moved %.1f cm at t = %.3f–%.3f s without being lifted: a push, not a step",
                track.name,
                math.dist(reference.position, after.position) * 100,
                move.start,
                move.end,
            )
            pushes.append(move)
            reference = after
            continue
        moves.append(move)
        reference = after
    return moves, nudges, pushes, initial


def _settle_at_the_end(
    track: ObjectTrack,
    starts: IntArray,
    ends: IntArray,
    settings: SegmentationSettings,
    supports: Supports,
) -> tuple[IntArray, IntArray, int]:
    """Cut the last move short where the object already lies still at the end of the stream.

    A recording often stops a few samples after the last release (robosuite's
    stop 0.05 s after it), too soon for the windowed speed to fall: the
    samples at the end within :attr:`~SegmentationSettings.settle_radius` of
    the last ones are the final rest when the object lies there (its pose read
    from where it is as low as it gets, as step 4 reads it) on a support
    (the table, or a known support beneath it; one sample is enough) or, on
    an object of unknown size, when there are at least two of them and the
    last two are no faster than ``start_speed``. Otherwise the object is still
    moving (or held) and its last move is dropped. Returns the moves and the
    end (exclusive) of the last rest.
    """
    n = len(track)
    times, positions = track.times, track.positions
    if not ends.size:
        return starts, ends, n
    rest_after = n - 1 - int(ends[-1])
    if rest_after >= MIN_FINAL_REST_SAMPLES and times[-1] - times[ends[-1]] >= min(
        settings.min_rest_s, 0.1
    ):
        return starts, ends, n
    window = int(np.searchsorted(times, times[-1] - settings.pose_window_s, side="left"))
    first_still = max(_settled_from(positions, window, n, settings), int(starts[-1]) + 1)
    if first_still < n:
        # Read as step 4 reads the rest (so the two checks of it agree): from
        # where it is as low as it gets, not from where the last lowering began.
        a = _settled_start(
            times, positions, first_still, n, settings, _noise_sigma(positions[:, 2])
        )
        pose = robust_pose(positions[a:], None)
        on = abs(pose.position[2]) <= settings.support_tolerance
        span = float(times[a]), float(times[-1])
        below = supports.supported(track.name, pose, *span)
        # Coming to a stop: at least two samples there, the last two slower than
        # start_speed (a min-jerk set-down ends at rest even when the samples
        # before it, at 20 Hz, are still on the way down).
        still = (
            n - first_still >= 2 and _speed_of(times[-2:], positions[-2:]) < settings.start_speed
        )
        if on or below is True or (still and below is None):
            ends = ends.copy()
            ends[-1] = first_still - 1
            return starts, ends, n
        if below is False and supports.nearest_top(track.name, pose, *span) is not None:
            logger.warning(
                "%s: its last samples (t = %.2f–%.2f s) lie %s: still carried, or set "
                "down where the sizes given say nothing is; its last move is not a step",
                track.name,
                times[first_still],
                times[-1],
                _off_support(supports, track.name, pose, *span),
            )
            return starts[:-1], ends[:-1], int(starts[-1])
    logger.warning(
        "%s: still moving at the end of the stream (t = %.3f s); its last move is not a step",
        track.name,
        times[-1],
    )
    return starts[:-1], ends[:-1], int(starts[-1])


def _off_support(supports: Supports, name: str, pose: Pose, start: float, end: float) -> str:
    """Why a rest at ``pose`` is on no support, for a warning: its height and the
    nearest top of known size beneath it."""
    z = pose.position[2]
    near = supports.nearest_top(name, pose, start, end)
    beneath = (
        "nothing of known size beneath"
        if near is None
        else f"{near[0]}'s top beneath at {near[1] * 1000:.1f} mm, {abs(z - near[1]) * 1000:.1f} "
        "mm away"
    )
    return (
        f"{z * 1000:.1f} mm high, on no support within support_tolerance "
        f"({supports.tolerance * 1000:g} mm; {beneath})"
    )


def _settled_from(positions: FloatArray, a: int, b: int, settings: SegmentationSettings) -> int:
    """The first index of the samples at the end of ``a:b`` that all lie near where the
    object is at ``b`` (the median of its last samples): within ``settle_radius``, or
    within 4 × the sensor noise where that is larger (noise from the median
    second difference of the samples, which smooth motion leaves at zero, so a
    noisy tracker is not cut short)."""
    window = positions[a:b]
    radius = settings.settle_radius
    if len(window) > 3:
        # Second differences: smooth motion cancels out, white noise has σ·√6.
        sigma = 1.4826 * np.median(np.abs(np.diff(window, n=2, axis=0)), axis=0) / math.sqrt(6.0)
        radius = max(radius, 4.0 * float(np.linalg.norm(sigma)))
    first = max(0, len(window) - MIN_FINAL_REST_SAMPLES)
    for _ in range(2):  # the median of the last samples, then of the still ones
        final = np.median(window[first:], axis=0)
        far = np.linalg.norm(window - final, axis=1) > radius
        first = int(np.flatnonzero(far)[-1]) + 1 if far.any() else 0
        if first >= len(window):
            return b
    return a + first


def _settled_start(
    times: FloatArray,
    positions: FloatArray,
    a: int,
    b: int,
    settings: SegmentationSettings,
    noise: float = 0.0,
) -> int:
    """Where the pose of the rest ``a:b`` is read (step 4): its first sample as low as
    the rest gets (within ``min_lift / 2`` of its lowest height, heights median-filtered
    over 0.1 s) after the last time it was ``min_lift`` higher. A placed
    object is at rest from there on; an object held still in the air before
    it is set down, or lifted a little and set down again (too slowly for the
    speed thresholds), reaches it last, and a later slide at the same height
    (an unnoticed nudge) does not shift the pose. ``noise``: the track's height
    noise σ (m), a floor under the rest's own estimate — a rest of a few samples
    (a recording stopped right after the release) tells too little of it, and
    its one low sample would be read as the rest."""
    z = positions[a:b, 2]
    if z.size < 3:
        return a
    rate = (z.size - 1) / max(float(times[b - 1] - times[a]), 1e-9)
    half = max(1, int(0.05 * rate))
    padded = np.pad(z, half, mode="edge")
    smooth = np.median(np.lib.stride_tricks.sliding_window_view(padded, 2 * half + 1), axis=1)
    # Margins above the sensor noise (σ from second differences, as _settled_from).
    sigma = max(_noise_sigma(z), noise)
    low = smooth <= smooth.min() + max(settings.min_lift / 2.0, 4.0 * sigma)
    raised = np.flatnonzero(smooth >= smooth.min() + max(settings.min_lift, 8.0 * sigma))
    if raised.size:  # set down again after being held up: read it after that
        low[: raised[-1]] = False
    return a + int(np.argmax(low))


def _noise_sigma(z: FloatArray) -> float:
    """Sensor noise σ of heights ``z`` from their second differences (white noise
    gives σ·√6, smooth motion next to nothing); 0 for fewer than 3."""
    if z.size < 3:
        return 0.0
    return 1.4826 * float(np.median(np.abs(np.diff(z, n=2)))) / math.sqrt(6.0)


def _speed_of(times: FloatArray, positions: FloatArray) -> float:
    """Speed (m/s) of the least-squares line through the samples."""
    t = times - times.mean()
    span = float((t * t).sum())
    if span <= 0:
        return 0.0
    slope = (t[:, None] * (positions - positions.mean(axis=0))).sum(axis=0) / span
    return float(np.linalg.norm(slope))


def _is_step(before: Pose, after: Pose, settings: SegmentationSettings) -> bool:
    if math.dist(before.position, after.position) >= settings.min_distance:
        return True
    if before.orientation is not None and after.orientation is not None:
        return angle_between(before.orientation, after.orientation) >= settings.min_angle_deg
    return False
