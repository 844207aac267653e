"""An object at rest: its pose read robustly from noisy samples, and what it
stands on (:mod:`demoplan.segmentation.detect`, steps 4 and 5)."""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator, Mapping

import numpy as np
from numpy.typing import NDArray

from demoplan.model import ObjectGeometry, Pose
from demoplan.rotations import mean_quat, rpy_from_quat
from demoplan.segmentation.settings import SegmentationSettings
from demoplan.segmentation.types import ObjectTrack, PoseStream

FloatArray = NDArray[np.float64]

__all__ = ["Supports", "robust_pose"]

INLIER_FACTOR = 3.0  # inliers lie within this many median distances of the median
MIN_INLIER_RADIUS = 1e-4  # m: noise-free streams have a MAD of 0
UNKNOWN_FOOTPRINT_M = 0.1  # an object of unknown size this close beneath may be a support
NEAR_MARGIN_M = 0.05  # m beyond its reach at a rest's end: an object read as a support


def robust_pose(positions: FloatArray, orientations: FloatArray | None) -> Pose:
    """A rest's pose (step 4 of :mod:`~demoplan.segmentation.detect`): the
    per-axis median, then the mean of the samples within 3 median distances of
    it; orientations the chordal mean of those samples'."""
    median = np.median(positions, axis=0)
    distance = np.linalg.norm(positions - median, axis=1)
    radius = max(INLIER_FACTOR * float(np.median(distance)), MIN_INLIER_RADIUS)
    inliers = distance <= radius
    mean = positions[inliers].mean(axis=0)
    orientation = None if orientations is None else mean_quat(orientations[inliers])
    x, y, z = (float(v) for v in mean)
    return Pose((x, y, z), orientation)


class Supports:
    """What an object at rest stands on: the table (z = 0), or the top of an object
    (at that time) or landmark beneath it, from their geometry."""

    def __init__(
        self,
        stream: PoseStream,
        geometry: Mapping[str, ObjectGeometry],
        landmarks: Mapping[str, Pose],
        settings: SegmentationSettings,
    ):
        self.stream = stream
        self.geometry = geometry
        self.landmarks = landmarks
        self.tolerance = settings.support_tolerance
        self.window = settings.pose_window_s

    def supported(self, name: str, pose: Pose, start: float, end: float) -> bool | None:
        """True on a support, False above known supports only, None where an
        object of unknown size lies beneath (it may be the support).

        ``pose`` was read from the object's samples from ``start`` to ``end``
        (s); every other object is read over the same times (stretched back to
        ``pose_window_s`` before ``end`` when shorter: a rest cut short by the
        end of the recording), robustly as a rest pose (the median, then the
        mean of the samples near it), not from one sample: one sample's noise
        (3 σ is 6 mm with 2 mm noise) would use up most of ``support_tolerance``."""
        z = pose.position[2]
        if abs(z) <= self.tolerance:
            return True
        unknown = False
        for _, top in self._beneath(name, pose, start, end):
            if top is None:
                unknown = True
            elif abs(z - top) <= self.tolerance:
                return True
        return None if unknown else False

    def nearest_top(
        self, name: str, pose: Pose, start: float, end: float
    ) -> tuple[str, float] | None:
        """The object or landmark of known size beneath ``pose`` whose top (z, m)
        is nearest it, read as :meth:`supported` reads them; None without one."""
        tops = [(o, t) for o, t in self._beneath(name, pose, start, end) if t is not None]
        return min(tops, key=lambda item: abs(pose.position[2] - item[1]), default=None)

    def _beneath(
        self, name: str, pose: Pose, start: float, end: float
    ) -> Iterator[tuple[str, float | None]]:
        """Each object or landmark beneath ``pose`` and its top (z), or None for
        an object of unknown size within ``UNKNOWN_FOOTPRINT_M`` and lower."""
        x, y, z = pose.position
        others: Iterable[tuple[str, Pose]] = (
            *self.landmarks.items(),
            *(
                (track.name, self._pose_over(track, start, end))
                for track in self.stream.tracks
                if track.name != name and len(track) and self._near(track, x, y, end)
            ),
        )
        for other, where in others:
            size = self.geometry.get(other)
            dx, dy = x - where.position[0], y - where.position[1]
            if size is None:
                if math.hypot(dx, dy) < UNKNOWN_FOOTPRINT_M and where.position[2] < z:
                    yield other, None
                continue
            turned = where.orientation
            yaw = 0.0 if turned is None else math.radians(rpy_from_quat(turned)[2])
            u = math.cos(yaw) * dx + math.sin(yaw) * dy
            v = -math.sin(yaw) * dx + math.cos(yaw) * dy
            if abs(u) <= size.size[0] / 2 and abs(v) <= size.size[1] / 2:
                yield other, where.position[2] + size.size[2]

    def _near(self, track: ObjectTrack, x: float, y: float, end: float) -> bool:
        """Whether ``track``'s sample at ``end`` is within reach of (x, y): its
        footprint's half diagonal (``UNKNOWN_FOOTPRINT_M`` without a size) and
        ``NEAR_MARGIN_M`` more. Only these are read over the window: an object
        that far from the rest at its end is no support of it (and reading
        every object over every rest's window cost 6 × the segmentation of 200
        objects resting off the table)."""
        i = min(int(np.searchsorted(track.times, end)), len(track) - 1)
        size = self.geometry.get(track.name)
        reach = UNKNOWN_FOOTPRINT_M if size is None else math.hypot(*size.size[:2]) / 2
        px, py = (float(v) for v in track.positions[i, :2])
        return math.hypot(x - px, y - py) <= reach + NEAR_MARGIN_M

    def _pose_over(self, track: ObjectTrack, start: float, end: float) -> Pose:
        """``track``'s robust pose over its samples from ``start`` to ``end`` (s);
        its sample nearest ``end`` when it has none there."""
        a = int(np.searchsorted(track.times, min(start, end - self.window), side="left"))
        b = int(np.searchsorted(track.times, end, side="right"))
        if b <= a:
            a = min(int(np.searchsorted(track.times, end)), len(track) - 1)
            b = a + 1
        orientations = None if track.orientations is None else track.orientations[a:b]
        if self.geometry.get(track.name) is None:
            orientations = None  # only a known footprint is turned by its yaw
        return robust_pose(track.positions[a:b], orientations)
