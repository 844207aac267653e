"""The block sizes among the sides of squares: a table of cubes holds few sizes.

The squares the detector accepts are grouped by side — a group is the sides
within :data:`SIDE_TOLERANCE` (15 %, as for a given ``--side``) of the side with
the most others that near it —
and a group of two or more squares, or the largest group, is a block size. Used
by the detector itself (:mod:`demoplan.perception.blocks`: a second look at the
regions with no square, at the sizes found) and after it
(:mod:`demoplan.perception.sizes`: squares of no block size rejected).
"""

from __future__ import annotations

from collections.abc import Sequence

__all__ = ["SIDE_TOLERANCE", "block_sizes", "within_sizes"]

SIDE_TOLERANCE = 0.15
"""Sides this far off a block size (relative) are not of that size."""


def block_sizes(
    sides: Sequence[float], tolerance: float = SIDE_TOLERANCE
) -> tuple[tuple[float, float, float], ...]:
    """The block sizes among ``sides``, most squares first, each as (median,
    smallest, largest side of its group): greedily, the side with the most
    others within ``tolerance`` of it (ties: the smaller side) makes a group of
    those; a group of two or more, or the first, counts."""
    left = sorted(sides)
    sizes: list[tuple[float, float, float]] = []
    while left:
        counts = [sum(_within(s, other, tolerance) for other in left) for s in left]
        best = max(range(len(left)), key=lambda i: (counts[i], -left[i]))
        group = [s for s in left if _within(left[best], s, tolerance)]
        if sizes and len(group) < 2:
            break
        middle = len(group) // 2
        median = group[middle] if len(group) % 2 else (group[middle - 1] + group[middle]) / 2
        sizes.append((median, group[0], group[-1]))
        left = [s for s in left if not _within(left[best], s, tolerance)]
    return tuple(sizes)


def _within(size: float, side: float, tolerance: float) -> bool:
    return abs(side - size) <= tolerance * size


def within_sizes(
    sizes: Sequence[tuple[float, float, float]], tolerance: float = SIDE_TOLERANCE
) -> tuple[float, float]:
    """The sides a block of one of ``sizes`` may show: from the smallest side of a
    size's group less ``tolerance`` to the largest side of one plus it."""
    return (
        min(size[1] for size in sizes) * (1 - tolerance),
        max(size[2] for size in sizes) * (1 + tolerance),
    )
