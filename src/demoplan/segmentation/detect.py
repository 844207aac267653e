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
   mid-air is not a placement). The last move needs ``min_rest_s`` of rest
   after it, or — at the very end of the stream — at least three samples.
4. **Rest poses.** The pose of a rest is the robust mean of the samples in its
   first :attr:`~SegmentationSettings.pose_window_s` (the pose right after
   placing, so a later unnoticed nudge does not shift it): the per-axis
   median, then the mean of the samples closer to it than 3 × the median
   distance (≈ 4.6 σ for normal noise: a tracker's outliers are dropped, its
   noise is averaged); orientations are the chordal mean of those samples'
   quaternions.
5. **Steps.** A move is a step when the new rest pose is at least
   :attr:`~SegmentationSettings.min_distance` away from the object's last
   *accepted* rest pose, or turned by at least
   :attr:`~SegmentationSettings.min_angle_deg`. Anything smaller is a nudge:
   it is kept in :attr:`Segmentation.nudges` and is not a step (so is a
   tracker glitch that jumps and comes back). Steps are ordered by the time
   their object comes to rest.

Limits: the parent frame of TF transforms is taken as the world; detection
uses translation speed only, so an object turned in place without its
reference point moving faster than ``start_speed`` is not seen to move; an
object carried on another (a napkin on a moved plate) counts as moved.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from demoplan.demonstrations import demonstration_to_dict
from demoplan.errors import InputError
from demoplan.fileio import dump_json, write_atomic
from demoplan.model import Demonstration, ObjectGeometry, Pose, Step
from demoplan.rotations import angle_between, mean_quat
from demoplan.segmentation.types import ObjectTrack, PoseStream

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
INLIER_FACTOR = 3.0  # inliers lie within this many median distances of the median
MIN_INLIER_RADIUS = 1e-4  # m: noise-free streams have a MAD of 0


@dataclass(frozen=True, slots=True)
class SegmentationSettings:
    """Thresholds of the move detection (module docstring); the defaults suit
    hand-carried table-top objects tracked at 30–120 Hz with up to ~3 mm noise.

    Attributes
    ----------
    speed_window_s : float
        Width of the speed estimate's window (s), default 0.4. Wider is less
        noisy but blurs the start and end of a move by about half of it.
    start_speed : float
        A move starts when the speed exceeds this (m/s), default 0.10. Hand
        carries peak at 0.3–1 m/s; sensor noise stays far below it.
    stop_speed : float
        A move ends when the speed falls below this (m/s), default 0.04; must be
        below ``start_speed`` (the hysteresis).
    min_rest_s : float
        Rest needed to end a move (s), default 0.5; shorter pauses are part of
        the move.
    min_distance : float
        Smallest displacement that makes a move a step (m), default 0.02 (2 cm).
        Smaller moves are nudges and not steps.
    min_angle_deg : float
        Smallest rotation that makes a move a step (degrees), default 20, for
        streams with orientations.
    pose_window_s : float
        Length of the start of a rest averaged into its pose (s), default 1.0.
    max_gap_s : float
        Gaps between samples longer than this (s), default 0.25, are checked for
        a move the tracker did not see.
    """

    speed_window_s: float = 0.4
    start_speed: float = 0.10
    stop_speed: float = 0.04
    min_rest_s: float = 0.5
    min_distance: float = 0.02
    min_angle_deg: float = 20.0
    pose_window_s: float = 1.0
    max_gap_s: float = 0.25

    def __post_init__(self) -> None:
        for item in fields(self):
            value = getattr(self, item.name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise InputError(
                    f"must be a positive number, got {value!r}", field=f"settings.{item.name}"
                )
        if self.stop_speed >= self.start_speed:
            raise InputError(
                f"must be below start_speed ({self.start_speed} m/s) for hysteresis, "
                f"got {self.stop_speed}",
                field="settings.stop_speed",
            )


@dataclass(frozen=True, slots=True)
class Move:
    """One detected move of one object.

    ``start`` and ``end`` are stream times (s): the object is moving from
    ``start`` and at rest again after ``end``. ``pose`` is the robust mean of
    the rest that follows; ``before`` the pose of the rest that precedes it
    (``None`` when the object was moving when its track began).
    """

    object: str
    start: float
    end: float
    pose: Pose
    before: Pose | None

    @property
    def distance(self) -> float:
        """Displacement from ``before`` to ``pose`` (m); NaN without ``before``."""
        if self.before is None:
            return math.nan
        return math.dist(self.before.position, self.pose.position)


@dataclass(frozen=True, slots=True, eq=False)
class SpeedTrace:
    """An object's estimated speed (m/s) at its sample times (s), for plots and checks."""

    object: str
    times: FloatArray
    speed: FloatArray


@dataclass(frozen=True, slots=True, eq=False)
class Segmentation:
    """What :func:`segment` found in a stream.

    ``moves`` are the steps, ordered by the time their object comes to rest
    (``end``); ``nudges`` the moves too small to be steps; ``initial`` each
    object's pose in its first rest (objects already moving when their track
    begins have none); ``traces`` the speed signals.
    """

    moves: tuple[Move, ...]
    nudges: tuple[Move, ...]
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
        """The segmented demonstration (SPEC §3 ``demoplan/demonstration-1``).

        Steps in the order objects come to rest; initial poses from each
        object's first rest. ``name`` defaults to the stream file's stem.
        ``objects`` adds geometry (only for objects in the stream);
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
        return Demonstration(
            name=name,
            steps=self.steps,
            objects=tuple((n, geometry[n]) for n in self.objects if n in geometry),
            landmarks=tuple((n, initial[n]) for n in landmark_names),
            initial=tuple((n, p) for n, p in self.initial if n not in landmark_names),
            source=self.source,
        )


def write_demonstration(demonstration: Demonstration, path: str | Path) -> None:
    """Write ``demonstration`` as a ``demoplan/demonstration-1`` file, atomically."""
    write_atomic(Path(path), dump_json(demonstration_to_dict(demonstration)))


# --------------------------------------------------------------------------- detection


def segment(stream: PoseStream, settings: SegmentationSettings | None = None) -> Segmentation:
    """Detect every object's moves in ``stream`` (module docstring) and order them."""
    settings = settings or SegmentationSettings()
    moves: list[Move] = []
    nudges: list[Move] = []
    initial: list[tuple[str, Pose]] = []
    traces: list[SpeedTrace] = []
    for track in stream.tracks:
        result = _segment_track(track, settings)
        moves += result.moves
        nudges += result.nudges
        traces.append(SpeedTrace(track.name, track.times, result.speed))
        if result.initial is not None:
            initial.append((track.name, result.initial))
        else:
            logger.info("%s: moving when its track begins; no initial pose", track.name)
    moves.sort(key=lambda m: (m.end, m.start, m.object))
    nudges.sort(key=lambda m: (m.end, m.start, m.object))
    return Segmentation(
        moves=tuple(moves),
        nudges=tuple(nudges),
        initial=tuple(initial),
        traces=tuple(traces),
        settings=settings,
        objects=stream.objects,
        source=stream.source,
    )


@dataclass(frozen=True, slots=True)
class _TrackResult:
    moves: list[Move]
    nudges: list[Move]
    initial: Pose | None
    speed: FloatArray


def _cumsum0(values: FloatArray) -> FloatArray:
    """Cumulative sum along axis 0 with a leading zero row (window sums by differences)."""
    out = np.zeros((values.shape[0] + 1, *values.shape[1:]))
    np.cumsum(values, axis=0, out=out[1:])
    return out


def _window_means(
    t: FloatArray, ct: FloatArray, cp: FloatArray, lo: IntArray, hi: IntArray
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
    left_n, left_t, left_p = _window_means(t, ct, cp, lo, mid)
    right_n, right_t, right_p = _window_means(t, ct, cp, mid, hi)
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
    _, _, before = _window_means(t, ct, cp, before_lo, gap + 1)
    _, _, after = _window_means(t, ct, cp, gap + 1, after_hi)
    return np.asarray(np.linalg.norm(after - before, axis=1), dtype=float)


def _runs(mask: NDArray[np.bool_]) -> tuple[IntArray, IntArray]:
    """First and last index (inclusive) of each run of True in ``mask``."""
    edges = np.diff(np.concatenate(([0], mask.astype(np.int8), [0])))
    return np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1


def _segment_track(track: ObjectTrack, settings: SegmentationSettings) -> _TrackResult:
    n = len(track)
    times, positions = track.times, track.positions
    if n == 0:
        return _TrackResult([], [], None, np.zeros(0))
    speed = track_speed(times, positions, settings.speed_window_s)
    forced = np.zeros(n, dtype=bool)
    # Step 2: moves hidden in tracking gaps.
    gap = np.flatnonzero(np.diff(times) > settings.max_gap_s)
    if gap.size:
        jump = _gap_jumps(times, positions, gap, settings.speed_window_s / 2.0)
        moved = gap[jump > settings.min_distance / 2.0]
        forced[moved] = True
        forced[moved + 1] = True
        gap_speed = jump / (times[gap + 1] - times[gap])
        speed[gap] = np.maximum(speed[gap], gap_speed)
        speed[gap + 1] = np.maximum(speed[gap + 1], gap_speed)
    # Step 3: hysteresis.
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
    if ends.size and (
        ends[-1] == n - 1
        or (
            times[-1] - times[ends[-1]] < settings.min_rest_s
            and n - 1 - ends[-1] < MIN_FINAL_REST_SAMPLES
        )
    ):
        logger.warning(
            "%s: still moving at the end of the stream (t = %.3f s); its last move is not a step",
            track.name,
            times[-1],
        )
        starts, ends = starts[:-1], ends[:-1]

    # Rests: before the first move, between moves, after the last one (index ranges, end excl.).
    rest_starts = np.concatenate(([0], ends + 1))
    rest_ends = np.concatenate((starts, [n]))
    orientations = track.orientations

    def rest_pose(k: int, *, last: bool = False) -> Pose | None:
        a, b = int(rest_starts[k]), int(rest_ends[k])
        if b <= a:
            return None
        if last:
            a = int(np.searchsorted(times, times[b - 1] - settings.pose_window_s, side="left"))
        else:
            b = int(np.searchsorted(times, times[a] + settings.pose_window_s, side="right"))
        return _robust_pose(positions[a:b], None if orientations is None else orientations[a:b])

    # Step 5: steps and nudges, measured from the last accepted rest pose.
    initial = rest_pose(0)
    reference = initial
    if reference is None:
        # Moving when the track begins: measure the first move from where the track starts.
        b = int(np.searchsorted(times, times[0] + settings.pose_window_s, side="right"))
        reference = _robust_pose(positions[:b], None if orientations is None else orientations[:b])
    moves: list[Move] = []
    nudges: list[Move] = []
    for k in range(starts.size):
        after = rest_pose(k + 1)
        if after is None:  # pragma: no cover - every kept move has a rest after it
            continue
        move = Move(
            track.name,
            float(times[starts[k]]),
            float(times[ends[k]]),
            after,
            rest_pose(k, last=True),
        )
        if _is_step(reference, after, settings):
            moves.append(move)
            reference = after
        else:
            nudges.append(move)
            logger.info(
                "%s: move at t = %.3f–%.3f s is a nudge (%.1f mm), not a step",
                track.name,
                move.start,
                move.end,
                math.dist(reference.position, after.position) * 1000,
            )
    return _TrackResult(moves, nudges, initial, speed)


def _is_step(before: Pose, after: Pose, settings: SegmentationSettings) -> bool:
    if math.dist(before.position, after.position) >= settings.min_distance:
        return True
    if before.orientation is not None and after.orientation is not None:
        return angle_between(before.orientation, after.orientation) >= settings.min_angle_deg
    return False


def _robust_pose(positions: FloatArray, orientations: FloatArray | None) -> Pose:
    """Step 4: median, then the mean of the samples within 3 median distances of it."""
    median = np.median(positions, axis=0)
    distance = np.linalg.norm(positions - median, axis=1)
    radius = max(INLIER_FACTOR * float(np.median(distance)), MIN_INLIER_RADIUS)
    inliers = distance <= radius
    mean = positions[inliers].mean(axis=0)
    orientation = None if orientations is None else mean_quat(orientations[inliers])
    x, y, z = (float(v) for v in mean)
    return Pose((x, y, z), orientation)
