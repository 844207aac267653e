"""Synthetic pose streams from known demonstrations, and scoring segmentations against them.

:func:`stream_from_demonstration` plays a :class:`~demoplan.model.Demonstration`
back as a tracker would record it. Each step is a hand carry of its object
from where it rests to the step's pose, of duration
``0.6 s + horizontal distance / speed_m_s``:

* **lift and place** — the height gains a bump of ``lift_m`` that rises over
  the first quarter of the move and falls over the last quarter (minimum-jerk
  profiles), so the object leaves and meets the table vertically;
* **carry** — position and orientation progress along a minimum-jerk profile
  over the middle 60 % of the move (orientation: normalised linear
  interpolation of the quaternions);
* **rest** — ``rest_s`` between moves, ``1.5 s`` before the first and after the last.

With ``overlap > 0`` the next move (of another object: a second hand) starts
when ``1 − overlap`` of the previous one is done; moves still come to rest in
step order, at least ``MIN_END_GAP_S`` apart. A **nudge** pushes a resting
object by ``nudge_m`` (horizontally, random direction) within 0.25 s, 1.5 s
after a step ended. Samples are taken at ``rate_hz`` with Gaussian noise of
``noise_m`` per axis (and ``noise_deg`` of rotation), optionally on uneven
clocks (``rate_jitter``) and with bursts of dropped samples (``drop_fraction``).

Objects are those of ``demo.initial``, its moved objects and its landmarks
(static). A moved object without an initial pose starts 0.25 m in −y of its
first placement. Objects with an orientation anywhere are tracked with
orientations.

:func:`compare_steps` scores found steps against the expected ones.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from demoplan.model import Demonstration, Pose, Step
from demoplan.segmentation.types import ObjectTrack, PoseStream

FloatArray = NDArray[np.float64]

__all__ = ["StepComparison", "compare_steps", "stream_from_demonstration"]

MIN_END_GAP_S = 0.5  # s between the ends of two consecutive moves
EDGE_REST_S = 1.5  # s of rest at the start and the end of a stream
NUDGE_DELAY_S = 1.5  # s after a step ends
NUDGE_DURATION_S = 0.25
BASE_DURATION_S = 0.6
UNPLACED_OFFSET = (0.0, -0.25, 0.0)  # m: start of a moved object without an initial pose
LIFT_FRACTION = 0.25  # of a move's duration for lifting, and for placing
CARRY = (0.2, 0.8)  # the part of a move's duration the carry takes


@dataclass(frozen=True, slots=True)
class _Event:
    object: str
    start: float
    duration: float
    begin: Pose
    end: Pose
    lift: float
    carry: bool  # False: a nudge (straight, no lift)


def _min_jerk(s: FloatArray) -> FloatArray:
    s = np.clip(s, 0.0, 1.0)
    return np.asarray(s**3 * (10.0 - 15.0 * s + 6.0 * s * s), dtype=float)


def _rng(rng: np.random.Generator | int | None) -> np.random.Generator:
    return rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)


def stream_from_demonstration(
    demo: Demonstration,
    *,
    rate_hz: float = 60.0,
    noise_m: float = 0.002,
    noise_deg: float = 0.5,
    rng: np.random.Generator | int | None = None,
    rate_jitter: float = 0.0,
    drop_fraction: float = 0.0,
    overlap: float = 0.0,
    nudges: int = 0,
    nudge_m: float = 0.01,
    lift_m: float = 0.08,
    speed_m_s: float = 0.4,
    rest_s: float = 1.0,
    start_time: float = 0.0,
    hover_s: float = 0.0,
    hover_m: float = 0.1,
    end_rest_s: float = EDGE_REST_S,
) -> PoseStream:
    """A realistic pose stream of ``demo`` (module docstring).

    Parameters
    ----------
    rate_hz : float
        Mean sampling rate per object (Hz).
    noise_m, noise_deg : float
        Standard deviation of the position noise per axis (m) and of the
        orientation noise (degrees, rotation vector per axis).
    rng : numpy Generator, int or None
        Source of all randomness (a seed, or a generator to draw from).
    rate_jitter : float
        In [0, 1): each sample interval is ``(1 ± U(rate_jitter)) / rate_hz``;
        each object then has its own clock. 0: all objects share one clock.
    drop_fraction : float
        In [0, 1): about this fraction of samples is lost, in bursts of 1 to
        ``0.2 s · rate_hz`` samples.
    overlap : float
        In [0, 1): how much of a move the next move (of another object) overlaps.
    nudges, nudge_m : int, float
        Number of nudges and their size (m).
    lift_m, speed_m_s, rest_s : float
        Lift height (m), mean horizontal carry speed (m/s), rest between moves (s).
    start_time : float
        Time of the first sample (s).
    hover_s, hover_m : float
        With ``hover_s > 0`` every carry stops ``hover_m`` above its target
        and is held still there for ``hover_s`` before the final lowering (a
        teleoperator lining an object up).
    end_rest_s : float
        Rest after the last move (s): ``EDGE_REST_S`` by default; a few
        hundredths for a recording stopped right after the last release.
    """
    if not (rate_hz > 0 and 0 <= rate_jitter < 1 and 0 <= drop_fraction < 1 and 0 <= overlap < 1):
        raise ValueError("rate_hz > 0 and rate_jitter, drop_fraction, overlap in [0, 1) expected")
    generator = _rng(rng)
    landmarks = dict(demo.landmarks)
    current: dict[str, Pose] = {}
    for name, pose in demo.initial:
        current[name] = pose
    for step in demo.steps:
        if step.object not in current:
            x, y, _ = (p + o for p, o in zip(step.pose.position, UNPLACED_OFFSET, strict=True))
            current[step.object] = Pose((x, y, 0.0), step.pose.orientation)
    names = [*current, *(n for n in landmarks if n not in current)]
    oriented = {step.object for step in demo.steps if step.pose.orientation is not None} | {
        n for n, p in [*demo.initial, *demo.landmarks] if p.orientation is not None
    }
    first_pose = {**landmarks, **current}

    events = _schedule(
        demo.steps,
        dict(current),
        generator,
        overlap,
        nudges,
        nudge_m,
        lift_m,
        speed_m_s,
        rest_s,
        start_time + EDGE_REST_S,
        set(landmarks),
        (hover_s, hover_m),
    )
    end_time = max((e.start + e.duration for e in events), default=start_time) + end_rest_s

    tracks = []
    for name in names:
        times = _sample_times(start_time, end_time, rate_hz, rate_jitter, generator)
        times = _drop(times, drop_fraction, rate_hz, generator)
        positions, quats = _evaluate(
            times, first_pose[name], [e for e in events if e.object == name]
        )
        positions = positions + generator.normal(0.0, noise_m, positions.shape)
        orientations = None
        if name in oriented:
            orientations = _add_rotation_noise(quats, noise_deg, generator)
        tracks.append(ObjectTrack(name, times, positions, orientations))
    return PoseStream(tuple(tracks), source=f"synthetic:{demo.name}")


def _schedule(
    steps: Sequence[Step],
    current: dict[str, Pose],
    rng: np.random.Generator,
    overlap: float,
    nudges: int,
    nudge_m: float,
    lift_m: float,
    speed_m_s: float,
    rest_s: float,
    t0: float,
    landmarks: set[str],
    hover: tuple[float, float] = (0.0, 0.0),
) -> list[_Event]:
    nudge_after = set(
        rng.choice(len(steps), size=min(nudges, len(steps)), replace=False).tolist()
        if steps
        else []
    )
    movable = [n for n in current if n not in landmarks]
    free_at = dict.fromkeys(current, t0)  # when each object may start its next move
    events: list[_Event] = []
    previous: _Event | None = None
    barrier = t0  # nothing starts before this (after a nudge)
    for k, step in enumerate(steps):
        begin = current[step.object]
        distance = math.dist(begin.position[:2], step.pose.position[:2])
        duration = BASE_DURATION_S + distance / speed_m_s
        if previous is None:
            start = t0
        else:
            previous_end = previous.start + previous.duration
            if overlap > 0 and previous.object != step.object:
                start = previous.start + (1.0 - overlap) * previous.duration
            else:
                start = previous_end + rest_s
            start = max(start, previous_end + MIN_END_GAP_S - duration)
        start = max(start, free_at[step.object], barrier)
        hover_s, hover_m = hover
        if hover_s > 0:  # carry to above the target, hold still, then lower straight down
            x, y, z = step.pose.position
            above = Pose((x, y, z + hover_m), step.pose.orientation)
            events.append(_Event(step.object, start, duration, begin, above, lift_m, True))
            lower = BASE_DURATION_S + hover_m / speed_m_s
            settle = start + duration + hover_s
            event = _Event(step.object, settle, lower, above, step.pose, 0.0, True)
            duration += hover_s + lower
        else:
            event = _Event(step.object, start, duration, begin, step.pose, lift_m, True)
        events.append(event)
        current[step.object] = step.pose
        free_at[step.object] = start + duration + rest_s
        previous = event
        if k in nudge_after:
            when = start + duration + NUDGE_DELAY_S
            candidates = [n for n in movable if free_at[n] <= when]
            name = candidates[int(rng.integers(len(candidates)))]
            angle = float(rng.uniform(0, 2 * math.pi))
            x, y, z = current[name].position
            pushed = Pose(
                (x + nudge_m * math.cos(angle), y + nudge_m * math.sin(angle), z),
                current[name].orientation,
            )
            events.append(_Event(name, when, NUDGE_DURATION_S, current[name], pushed, 0.0, False))
            current[name] = pushed
            barrier = when + NUDGE_DURATION_S + rest_s
            free_at[name] = barrier
    return events


def _sample_times(
    start: float, end: float, rate_hz: float, jitter: float, rng: np.random.Generator
) -> FloatArray:
    period = 1.0 / rate_hz
    count = math.ceil((end - start) * rate_hz * (1 + jitter)) + 2
    if jitter == 0:
        return np.asarray(start + period * np.arange(int((end - start) * rate_hz) + 1), dtype=float)
    steps = period * (1.0 + rng.uniform(-jitter, jitter, count))
    times = start + rng.uniform(0, period) + np.cumsum(steps)
    return np.asarray(times[times <= end], dtype=float)


def _drop(
    times: FloatArray, fraction: float, rate_hz: float, rng: np.random.Generator
) -> FloatArray:
    if fraction <= 0 or times.size == 0:
        return times
    longest = max(1, int(0.2 * rate_hz))
    keep = np.ones(times.size, dtype=bool)
    target = int(fraction * times.size)
    while (~keep).sum() < target:
        length = int(rng.integers(1, longest + 1))
        first = int(rng.integers(0, times.size))
        keep[first : first + length] = False
    return times[keep]


def _quats(pose: Pose) -> FloatArray:
    return np.asarray(pose.orientation if pose.orientation is not None else (0.0, 0.0, 0.0, 1.0))


def _evaluate(
    times: FloatArray, initial: Pose, events: Sequence[_Event]
) -> tuple[FloatArray, FloatArray]:
    """Positions (n, 3) and quaternions (n, 4) of one object at ``times``."""
    positions = np.tile(np.asarray(initial.position, dtype=float), (times.size, 1))
    quats = np.tile(_quats(initial), (times.size, 1))
    for event in sorted(events, key=lambda e: e.start):
        a = np.asarray(event.begin.position, dtype=float)
        b = np.asarray(event.end.position, dtype=float)
        qa, qb = _quats(event.begin), _quats(event.end)
        if float(qa @ qb) < 0:
            qb = -qb
        after = times >= event.start + event.duration
        positions[after] = b
        quats[after] = qb
        during = (times >= event.start) & ~after
        s = (times[during] - event.start) / event.duration
        if event.carry:
            u = _min_jerk((s - CARRY[0]) / (CARRY[1] - CARRY[0]))
            bump = _min_jerk(s / LIFT_FRACTION) * _min_jerk((1.0 - s) / LIFT_FRACTION)
        else:
            u, bump = _min_jerk(s), np.zeros_like(s)
        path = a + (b - a) * u[:, None]
        path[:, 2] += event.lift * bump
        positions[during] = path
        q = qa + (qb - qa) * u[:, None]
        quats[during] = q / np.linalg.norm(q, axis=1, keepdims=True)
    return positions, quats


def _add_rotation_noise(
    quats: FloatArray, noise_deg: float, rng: np.random.Generator
) -> FloatArray:
    rotvec = np.radians(rng.normal(0.0, noise_deg, (quats.shape[0], 3)))
    angle = np.linalg.norm(rotvec, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        axis = np.where(angle[:, None] > 0, rotvec / angle[:, None], 0.0)
    noise = np.concatenate([axis * np.sin(angle / 2)[:, None], np.cos(angle / 2)[:, None]], axis=1)
    x1, y1, z1, w1 = noise.T
    x2, y2, z2, w2 = quats.T
    product = np.stack(
        [
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
        ],
        axis=1,
    )
    return np.asarray(product, dtype=float)


# --------------------------------------------------------------------------- scoring


@dataclass(frozen=True, slots=True)
class StepComparison:
    """Found steps against expected ones.

    Steps are aligned in order (longest common subsequence): a found step
    matches an expected one when the object is the same and the positions
    are within the tolerance. ``errors`` are the matched steps' position errors (m).
    """

    expected: int
    found: int
    matched: int
    errors: tuple[float, ...]

    @property
    def precision(self) -> float:
        return self.matched / self.found if self.found else 1.0

    @property
    def recall(self) -> float:
        return self.matched / self.expected if self.expected else 1.0

    @property
    def exact(self) -> bool:
        """Every expected step found, in order, and nothing else."""
        return self.matched == self.expected == self.found


def compare_steps(
    expected: Sequence[Step], found: Sequence[Step], tolerance_m: float = 0.02
) -> StepComparison:
    """Align ``found`` with ``expected`` in order and score them (:class:`StepComparison`)."""
    m, n = len(expected), len(found)
    distance = [
        [
            math.dist(e.pose.position, f.pose.position) if e.object == f.object else math.inf
            for f in found
        ]
        for e in expected
    ]
    table = np.zeros((m + 1, n + 1), dtype=int)
    for i in range(m - 1, -1, -1):
        for j in range(n - 1, -1, -1):
            best = max(table[i + 1, j], table[i, j + 1])
            if distance[i][j] <= tolerance_m:
                best = max(best, table[i + 1, j + 1] + 1)
            table[i, j] = best
    errors = []
    i = j = 0
    while i < m and j < n:
        if distance[i][j] <= tolerance_m and table[i, j] == table[i + 1, j + 1] + 1:
            errors.append(distance[i][j])
            i, j = i + 1, j + 1
        elif table[i + 1, j] >= table[i, j + 1]:
            i += 1
        else:
            j += 1
    return StepComparison(m, n, len(errors), tuple(errors))
