"""Steps released where nothing holds the object up (docs/formats.md
"Demonstration", docs/limits.md "Warnings about a file's contents").

A step is the pose where an object is released (paper §IV: the demonstration is
segmented into pick-and-place subtasks). An object let go 2 cm above the table
with nothing under it would fall: the file is wrong — a height in the wrong
unit, a step out of order (the bowl released on the plate before the plate is
put there). Learning would take the pose at its word and, since a position is
learned only relative to objects already placed (§IV.A), lose the relation to
the object that comes later. :func:`unsupported_releases` finds such steps and
:func:`warn_unsupported_releases` reports each in one warning.

What holds an object up is judged as the scene geometry judges support
(:mod:`demoplan.scenes.geometry`: footprints on the table, an upper footprint
resting on a lower one that covers ``support_fraction`` of it) and as the
segmentation judges a rest (``support_tolerance``: within 1 cm of the table
or of a top). An object (or landmark) of unknown size within
:data:`UNKNOWN_REACH_M` beneath may be the support; one whose body reaches up
to the released object's height holds it too (a cup inside a bin). Only
releases are checked: a step followed by another step of the same object is a
point it was carried through (a knife going down and up), not let go of.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import shapely

from demoplan.model import (
    LEVEL_TOLERANCE,
    REST_TOLERANCE,
    SUPPORT_FRACTION,
    Demonstration,
    ObjectGeometry,
    Pose,
    demonstrated_shapes,
    footprint,
    lowest_point,
)
from demoplan.rotations import rpy_from_quat

__all__ = [
    "UNKNOWN_REACH_M",
    "UnsupportedRelease",
    "unsupported_releases",
    "warn_unsupported_releases",
]

logger = logging.getLogger(__name__)

RELEASE_TOLERANCE_M = REST_TOLERANCE
"""A release this close above the table or a top rests on it (as a segmented rest)."""
UNKNOWN_REACH_M = 0.1
"""An object of unknown size this close beneath (horizontally) may be the support."""
TILT_LIMIT_DEG = 10.0
"""An object tilted more than this (roll or pitch) has no footprint known here."""


@dataclass(frozen=True, slots=True)
class UnsupportedRelease:
    """Step ``step`` (1-based, as the command line prints steps) of
    ``demonstration`` releases ``object`` at ``height`` above ``above`` (the
    table, or the top of the object under it) with nothing holding it up;
    ``arrives``: the object that stands under it later, and at which step."""

    demonstration: str
    step: int
    object: str
    height: float
    above: str | None
    arrives: tuple[str, int] | None

    def describe(self) -> str:
        """One line, e.g. ``demonstration 'd2' step 4: bowl released 2 cm above the
        table with nothing under it (the plate arrives at step 6)``."""
        where = (
            f"{_length(self.height)} above the table with nothing under it"
            if self.above is None
            else f"{_length(self.height)} above the top of the {self.above}, resting on nothing"
        )
        later = (
            ""
            if self.arrives is None
            else f" (the {self.arrives[0]} arrives at step {self.arrives[1]})"
        )
        step = f"demonstration {self.demonstration!r} step {self.step}"
        return f"{step}: {self.object} released {where}{later}"


def warn_unsupported_releases(demos: Sequence[Demonstration]) -> None:
    """Log one warning per release with nothing under it, naming the
    demonstration's file; sizes from any of the demonstrations."""
    shapes = demonstrated_shapes(demos)
    for demo in demos:
        for release in unsupported_releases(demo, shapes):
            logger.warning("%s: %s", demo.source or demo.name, release.describe())


def unsupported_releases(
    demo: Demonstration, shapes: Mapping[str, ObjectGeometry] | None = None
) -> list[UnsupportedRelease]:
    """The releases of ``demo`` that nothing holds up (module docstring);
    ``shapes``: object and landmark geometry beyond the demonstration's own."""
    known = {**(shapes or {}), **dict(demo.objects)}
    standing: dict[str, Pose] = dict(demo.initial)
    landmarks = dict(demo.landmarks)
    found = []
    steps = demo.steps
    for index, step in enumerate(steps):
        released = index + 1 == len(steps) or steps[index + 1].object != step.object
        height = _lowest(known, step.object, step.pose)
        if released and height > RELEASE_TOLERANCE_M:
            others = {**landmarks, **{n: p for n, p in standing.items() if n != step.object}}
            holds = [_holds(known, n, p, step.object, step.pose, height) for n, p in others.items()]
            if not any(h is not False for h in holds):
                tops = [
                    (p.position[2] + known[n].size[2], n)
                    for n, p in others.items()
                    if _under(known, n, p, step.object, step.pose, height)
                ]
                top, name = max(((t, n) for t, n in tops if t < height), default=(0.0, None))
                arrives = None
                for later in range(index + 1, len(steps)):
                    other = steps[later]
                    if other.object == step.object:
                        break
                    if _holds(known, other.object, other.pose, step.object, step.pose, height):
                        arrives = (other.object, later + 1)
                        break
                found.append(
                    UnsupportedRelease(
                        demo.name, index + 1, step.object, height - top, name, arrives
                    )
                )
        standing[step.object] = step.pose
    return found


def _holds(
    known: Mapping[str, ObjectGeometry], lower: str, at: Pose, upper: str, pose: Pose, z: float
) -> bool | None:
    """Whether ``lower`` at ``at`` holds ``upper`` released at ``pose`` (its lowest
    point at height ``z``) up: True (its footprint under it, its body reaching up
    to it), False, or None (its size unknown and it is near enough beneath that
    it may)."""
    if lower not in known or _tilted(at):
        near = math.dist(at.position[:2], pose.position[:2]) < UNKNOWN_REACH_M
        return None if near and at.position[2] < z else False
    if not _under(known, lower, at, upper, pose, z):
        return False
    bottom = at.position[2]
    top = bottom + known[lower].size[2]
    return bottom + LEVEL_TOLERANCE < z <= top + RELEASE_TOLERANCE_M


def _under(
    known: Mapping[str, ObjectGeometry], lower: str, at: Pose, upper: str, pose: Pose, z: float
) -> bool:
    """``lower`` (of known size) at ``at`` stands beneath ``upper`` at ``pose``, its
    bottom below ``z``: their footprints overlap as a support's must."""
    if lower not in known or _tilted(at) or at.position[2] >= z:
        return False
    below = footprint(known[lower], at.position, _yaw(at))
    if upper in known and not _tilted(pose):
        above = footprint(known[upper], pose.position, _yaw(pose))
        overlap = below.intersection(above).area
        return bool(overlap >= SUPPORT_FRACTION * above.area)
    return bool(below.covers(shapely.Point(pose.position[0], pose.position[1])))


def _lowest(known: Mapping[str, ObjectGeometry], name: str, pose: Pose) -> float:
    """The height of the lowest corner of ``name``'s box at ``pose``
    (:func:`~demoplan.model.lowest_point`)."""
    return lowest_point(known.get(name), pose)


def _yaw(pose: Pose) -> float:
    return 0.0 if pose.orientation is None else rpy_from_quat(pose.orientation)[2]


def _tilted(pose: Pose) -> bool:
    if pose.orientation is None:
        return False
    roll, pitch, _ = rpy_from_quat(pose.orientation)
    return abs(roll) > TILT_LIMIT_DEG or abs(pitch) > TILT_LIMIT_DEG


def _length(metres: float) -> str:
    return f"{metres * 100:.2g} cm" if metres < 1 else f"{metres:.3g} m"
