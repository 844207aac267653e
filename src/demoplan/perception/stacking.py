"""Stacking from occlusion (paper §V.B): "If a block that was visible change to
fully or partly occluded, it is concluded that the last block moved was placed
upon that block."

A top camera cannot measure heights, so they are tracked from one picture to
the next: :class:`BlockTracker` keeps every block's last known pose. In a new
picture, a block that moved (by more than ``still`` in the image) and now
covers part of the outline another block had before stands on it — its z is
the top of the highest block it covers — and a block that is now covered keeps
its last pose (its visible remains are not a whole square and say nothing
reliable about it). The first picture's heights come from what is known of the
start (a scene), or are 0.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, replace

import shapely

from demoplan.perception.blocks import DetectedBlock

__all__ = ["BlockTracker", "TrackedBlock", "covered_by", "scene_document"]


@dataclass(frozen=True, slots=True)
class TrackedBlock:
    """A block's last known pose: centre (m), bottom height z (m), yaw (deg), side (m)."""

    name: str
    x: float
    y: float
    z: float
    yaw: float
    side: float

    def outline(self) -> shapely.Polygon:
        h = self.side / 2
        c, s = math.cos(math.radians(self.yaw)), math.sin(math.radians(self.yaw))
        return shapely.Polygon(
            [
                (self.x + c * a - s * b, self.y + s * a + c * b)
                for a, b in ((-h, -h), (h, -h), (h, h), (-h, h))
            ]
        )


def covered_by(upper: TrackedBlock, lower: TrackedBlock, share: float = 0.05) -> bool:
    """Does ``upper`` (seen now) cover at least ``share`` of ``lower``'s outline?"""
    below = lower.outline()
    return bool(upper.outline().intersection(below).area > share * below.area)


class BlockTracker:
    """Block poses from successive top-view detections (see the module docstring)."""

    def __init__(self, known: Iterable[TrackedBlock] = (), still: float = 0.005):
        self.blocks: dict[str, TrackedBlock] = {b.name: b for b in known}
        self.still = still

    def update(
        self, detected: Iterable[DetectedBlock], held: str | None = None
    ) -> dict[str, TrackedBlock]:
        """Blocks standing now (the one in the hand, ``held``, is left out)."""
        seen = {d.name: d for d in detected if d.name != held}
        previous = {n: b for n, b in self.blocks.items() if n != held}
        moved: dict[str, TrackedBlock] = {}
        steady: dict[str, TrackedBlock] = {}
        for name, d in seen.items():
            before = previous.get(name)
            now = TrackedBlock(name, d.x, d.y, 0.0, d.yaw, d.side)
            if before is not None and math.dist((d.x, d.y), (before.x, before.y)) <= self.still:
                steady[name] = replace(now, z=before.z)
            else:
                moved[name] = now

        # A moved block stands on the blocks whose outline it now covers. The one that
        # moved farthest is taken first: a block it now covers may look "moved" only
        # because what is left of it in view is not a whole square.
        def displacement(name: str) -> float:
            before = previous.get(name)
            block = moved[name]
            return (
                math.inf if before is None else math.dist((block.x, block.y), (before.x, before.y))
            )

        resolved: dict[str, TrackedBlock] = {}
        known = sorted((n for n in moved if n in previous), key=displacement, reverse=True)
        new = [n for n in moved if n not in previous]
        for name in known + new:  # new names last: they may be pieces of a covered block
            block, before = moved[name], previous.get(name)
            if before is None and any(
                r.z > 1e-3
                and covered_by(r, b)
                and b.outline().contains(shapely.Point(block.x, block.y))
                for r in resolved.values()
                for b in previous.values()
            ):
                continue  # what is left in view of a block now covered, not a new block
            if before is not None and any(
                r.z > before.z + 1e-3 and covered_by(r, before) for r in resolved.values()
            ):
                steady[name] = before  # covered now: keep what was known
                continue
            under = [b for n, b in previous.items() if n != name and covered_by(block, b)]
            resolved[name] = replace(block, z=max((b.z + b.side for b in under), default=0.0))
        moved = resolved
        current = {**steady, **moved}
        # A block not seen whole any more but covered by one standing higher keeps its pose.
        for name, before in previous.items():
            if name in steady:
                continue
            cover = [
                b
                for n, b in current.items()
                if n != name and b.z > before.z + 1e-3 and covered_by(b, before)
            ]
            if cover:
                current[name] = before
        self.blocks = dict(current)
        if held is not None and held in previous:
            self.blocks[held] = previous[held]
        return {n: b for n, b in current.items()}

    @staticmethod
    def from_poses(poses: Mapping[str, tuple[float, float, float, float, float]]) -> BlockTracker:
        """A tracker that knows ``name → (x, y, z, yaw, side)``."""
        return BlockTracker(TrackedBlock(n, *p) for n, p in poses.items())


def scene_document(blocks: Mapping[str, TrackedBlock]) -> dict[str, object]:
    """The blocks as a ``demoplan/scene-1`` document (cubes of the measured side)."""
    objects = {
        name: {
            "position": [round(b.x, 6), round(b.y, 6), round(b.z, 6)],
            "yaw": round(b.yaw, 3),
            "shape": "box",
            "size": [round(b.side, 6)] * 3,
        }
        for name, b in blocks.items()
    }
    return {"format": "demoplan/scene-1", "objects": objects}
