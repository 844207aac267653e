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

Blocks of one colour look alike (instances of one type, docs/perception.md):
a detection's name says nothing about which of them it is, so the tracker
gives each detection the identity of a block of its colour by proximity — the
assignment (Hungarian method) that leaves as many blocks as it can where they
are expected (where last seen or, for a block just put down, where it was put;
one block moves at a time) and otherwise has the least total distance. The
last block moved stands on top and is in view (§V.B's premise), so it is
matched first: a red put squarely onto another red hides it, and the one red
seen there is the one moved, the other is under it. Where the caller does not
say which block was put down, a block whose spot is now empty — no detection
of any colour overlaps it — is the one that moved.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, replace

import numpy as np
import shapely

from demoplan.perception.blocks import DetectedBlock

__all__ = [
    "UNNAMED_COLOUR",
    "BlockTracker",
    "TrackedBlock",
    "colour_of_name",
    "covered_by",
    "scene_document",
]


@dataclass(frozen=True, slots=True)
class TrackedBlock:
    """A block's last known pose: centre (m), bottom height z (m), yaw (deg), side (m);
    ``colour``: what the camera sees it as (``None``: its name's, ``red2`` → ``red``)."""

    name: str
    x: float
    y: float
    z: float
    yaw: float
    side: float
    colour: str | None = None

    @property
    def seen_as(self) -> str:
        """The colour the camera sees: ``colour``, else the name without its number."""
        return self.colour or colour_of_name(self.name)

    def outline(self) -> shapely.Polygon:
        h = self.side / 2
        c, s = math.cos(math.radians(self.yaw)), math.sin(math.radians(self.yaw))
        return shapely.Polygon(
            [
                (self.x + c * a - s * b, self.y + s * a + c * b)
                for a, b in ((-h, -h), (h, -h), (h, h), (-h, h))
            ]
        )


_FIRST = 1e6
"""Metres taken off the cost of matching the block moved last: it is matched first."""
_AWAY = 1.0
"""Metres added to the cost of matching a block away from where it is expected: as
many blocks as can stay where they were (one block moves at a time), then the least
total distance."""


def _detected_block(d: DetectedBlock) -> TrackedBlock:
    return TrackedBlock(d.name, d.x, d.y, 0.0, d.yaw, d.side, d.colour)


def colour_of_name(name: str) -> str:
    """The colour a detected block's name says: ``red2`` → ``red``, ``block1`` → ``block``."""
    return re.sub(r"\d+$", "", name) or name


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
        self,
        detected: Iterable[DetectedBlock],
        held: str | None = None,
        placed: Mapping[str, tuple[float, float]] | None = None,
    ) -> dict[str, TrackedBlock]:
        """Blocks standing now (the one in the hand, ``held``, is left out);
        ``placed``: the blocks just put down and where (x, y) they were put
        (``None``: not known — a block whose spot is empty now is taken to be the
        one moved)."""
        detections = self.identify(list(detected), held, placed)
        seen = {d.name: d for d in detections if d.name != held}
        previous = {n: b for n, b in self.blocks.items() if n != held}
        moved: dict[str, TrackedBlock] = {}
        steady: dict[str, TrackedBlock] = {}
        for name, d in seen.items():
            before = previous.get(name)
            now = TrackedBlock(name, d.x, d.y, 0.0, d.yaw, d.side, d.colour)
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
        in_hand = self.blocks.get(held) if held is not None else None
        self.blocks = dict(current)
        if in_hand is not None:  # remembered where it was until it is seen again
            self.blocks[in_hand.name] = in_hand
        return {n: b for n, b in current.items()}

    def identify(
        self,
        detected: list[DetectedBlock],
        held: str | None = None,
        placed: Mapping[str, tuple[float, float]] | None = None,
    ) -> list[DetectedBlock]:
        """The detections named after the blocks they are (see the module
        docstring): per colour, the assignment of detections to the known blocks
        of that colour (the held one aside) that matches the block moved last
        first, leaves as many blocks as it can where they are expected (within
        ``still``) — where it was put, for a block just put down, else where it
        was last seen — and then has the least total distance.
        A detection left over (a block not known before, or a piece of one now
        covered) keeps its detected name unless a known block has it; then it
        gets the colour's next free number."""
        known = [b for n, b in self.blocks.items() if n != held]
        expected = dict(placed or {})
        if placed is None:  # not told: a block whose spot is empty now has moved
            outlines = [_detected_block(d) for d in detected]
            moved_last = {b.name for b in known if not any(covered_by(d, b) for d in outlines)}
        else:
            moved_last = set(placed)
        taken = set(self.blocks)
        detector_names = {d.name for d in detected}
        named: list[DetectedBlock] = []
        for colour in dict.fromkeys(d.colour for d in detected):
            found = [d for d in detected if d.colour == colour]
            blocks = [b for b in known if b.seen_as == colour]
            names: list[str | None] = [None] * len(found)
            if blocks:
                distance = np.array(
                    [
                        [math.dist(expected.get(b.name, (b.x, b.y)), (d.x, d.y)) for d in found]
                        for b in blocks
                    ]
                )
                cost = distance + _AWAY * (distance > self.still)
                cost -= _FIRST * np.array([[b.name in moved_last] for b in blocks], dtype=float)
                # SciPy's optimiser, imported here: a picture's first perception (one
                # `demoplan perceive`) has no blocks known yet and never gets here
                from scipy.optimize import linear_sum_assignment

                for row, column in zip(*linear_sum_assignment(cost), strict=True):
                    names[column] = blocks[row].name
            for d, name in zip(found, names, strict=True):
                if name is None:
                    name = d.name
                    if name in taken:
                        number = 2
                        while (name := f"{colour}{number}") in taken | detector_names:
                            number += 1
                    taken.add(name)
                named.append(replace(d, name=name))
        return named

    @staticmethod
    def from_poses(poses: Mapping[str, tuple[float, float, float, float, float]]) -> BlockTracker:
        """A tracker that knows ``name → (x, y, z, yaw, side)``."""
        return BlockTracker(TrackedBlock(n, *p) for n, p in poses.items())


UNNAMED_COLOUR = "block"
"""What the detector calls a block whose colour has no name (``block1``, ``block2``):
two of them may differ in colour, so they are not taken for one type."""


def scene_document(blocks: Mapping[str, TrackedBlock]) -> dict[str, object]:
    """The blocks as a ``demoplan/scene-1`` document (cubes of the measured side).
    Where two or more blocks have one (named) colour, each of them says
    ``"type": colour``: instances of one type, interchangeable to the planner."""
    counts: dict[str, int] = {}
    for b in blocks.values():
        counts[b.seen_as] = counts.get(b.seen_as, 0) + 1
    objects: dict[str, dict[str, object]] = {}
    for name, b in blocks.items():
        entry: dict[str, object] = {
            "position": [round(b.x, 6), round(b.y, 6), round(b.z, 6)],
            "yaw": round(b.yaw, 3),
            "shape": "box",
            "size": [round(b.side, 6)] * 3,
        }
        if counts[b.seen_as] > 1 and b.seen_as != UNNAMED_COLOUR:
            entry["type"] = b.seen_as
        objects[name] = entry
    return {"format": "demoplan/scene-1", "objects": objects}
