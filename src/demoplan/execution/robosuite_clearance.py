"""How low the Panda's hand may go over a bin without striking its walls.

The Panda's hand is long along its fingers and narrow across them (robosuite
1.5.2's collision box: 20.8 cm by 6.4 cm, from 2.6 cm above the grip site
up). PickPlace's compartments are 18 cm by 23 cm inside their walls and 8 cm
deep: lowered into one with the fingers along its short side, the hand's ends
come down on the walls, the move stalls, and robosuite's controller, pushing
on, straightens the elbow to its limit, from where no later move comes back
(measured, docs/execution.md "robosuite": 0.735 m out at bearing 19.5°, the
grip lowered to 2.6 cm above the floor; with the fingers within 30° of the
bearing's line the elbow locked, across it the hand went down and back).

So a put-down chooses the finger direction whose hand clears the walls, and
where none does, releases its object from the lowest height at which the
hand stays above them (:func:`lowest_grip`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely
from shapely import affinity

__all__ = ["HAND_MARGIN", "HandShape", "Wall", "hand_footprint", "lowest_grip"]

HAND_MARGIN = 0.008
"""m: how far the hand keeps from a wall, sideways and above its top."""


@dataclass(frozen=True, slots=True)
class HandShape:
    """The hand's box in the grip site's frame: half its length along the
    fingers, half its width across them, and how far its lowest point lies
    above the grip site (m)."""

    half_length: float
    half_width: float
    bottom: float


@dataclass(frozen=True, slots=True)
class Wall:
    """A wall or divider of a bin: the centre of its footprint (world x, y),
    half its sizes along its own axes, its yaw (deg) and its top (world z)."""

    centre: tuple[float, float]
    half_size: tuple[float, float]
    yaw: float
    top: float


def _rectangle(
    centre: Sequence[float] | np.ndarray, half: tuple[float, float], yaw: float
) -> shapely.Polygon:
    box = shapely.box(-half[0], -half[1], half[0], half[1])
    turned = affinity.rotate(box, yaw, origin=(0.0, 0.0))
    moved: shapely.Polygon = affinity.translate(turned, float(centre[0]), float(centre[1]))
    return moved


def hand_footprint(
    hand: HandShape, grip: Sequence[float] | np.ndarray, finger_yaw: float
) -> shapely.Polygon:
    """The hand's footprint (world x, y) with the grip site over ``grip`` and
    the fingers closing along ``finger_yaw`` (deg), :data:`HAND_MARGIN` wider
    all round."""
    half = (hand.half_length + HAND_MARGIN, hand.half_width + HAND_MARGIN)
    return _rectangle(grip, half, finger_yaw)


def lowest_grip(
    hand: HandShape,
    grip: Sequence[float] | np.ndarray,
    finger_yaw: float,
    walls: Sequence[Wall],
) -> float:
    """World z below which the grip site may not go at ``grip`` (x, y) with
    the fingers along ``finger_yaw`` (deg): the hand's bottom
    :data:`HAND_MARGIN` above the top of every wall its footprint overlaps;
    −∞ where it overlaps none."""
    footprint = hand_footprint(hand, grip, finger_yaw)
    lowest = -math.inf
    for wall in walls:
        if footprint.intersects(_rectangle(wall.centre, wall.half_size, wall.yaw)):
            lowest = max(lowest, wall.top + HAND_MARGIN - hand.bottom)
    return lowest
