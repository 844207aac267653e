"""Names of locations and grasps that stay the same across the planning
problems of one run: replanning builds a new problem from what is observed,
and a place the first plan called ``loc7`` is still ``loc7`` in the next one
(``GRASP red loc7 grasp5`` means the same spot and the same fingers in every
plan a run prints). A new place gets the next unused number.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field

from demoplan.model import Vector3

__all__ = ["StableNames"]


@dataclass
class StableNames:
    """The names handed out so far; ``tolerance`` (m): a place closer than this
    to a named one, at the same height, is that place."""

    tolerance: float = 0.01
    _places: list[tuple[str, Vector3]] = field(default_factory=list)
    _counts: dict[str, int] = field(default_factory=dict)
    _grasps: dict[tuple[str, float], str] = field(default_factory=dict)
    _cells: dict[tuple[int, int, int], list[int]] = field(default_factory=dict)
    """The places in each cube of side ``tolerance`` (indices into ``_places``):
    a place this close to a position is in its cube or a neighbouring one, so
    thousands of places are named without comparing every pair."""

    @classmethod
    def of(
        cls,
        places: Iterable[tuple[str, Vector3]],
        grasps: Iterable[tuple[str, str, float]],
        tolerance: float = 0.01,
    ) -> StableNames:
        """The names of an existing problem — ``(name, position)`` of its places,
        ``(name, object, axis)`` of its grasps — to keep in the next ones."""
        names = cls(tolerance)
        for name, position in places:
            names._add(name, position)
            prefix, number = _split(name)
            names._counts[prefix] = max(names._counts.get(prefix, 0), number)
        for name, obj, axis in grasps:
            names._grasps[(obj, axis)] = name
            prefix, number = _split(name)
            names._counts[prefix] = max(names._counts.get(prefix, 0), number)
        return names

    def place(
        self, prefix: str, position: Vector3, taken: set[str], any_prefix: bool = False
    ) -> str:
        """The name of a place (``prefix`` + number): the one already given to a
        place this close, unless this problem uses it already (``taken``).
        ``any_prefix``: an earlier name of another kind counts too (an object
        put down on ``freespace1`` stands at ``freespace1``)."""
        x, y, z = self._cell(position)
        near = sorted(
            index
            for dx in (-1, 0, 1)
            for dy in (-1, 0, 1)
            for dz in (-1, 0, 1)
            for index in self._cells.get((x + dx, y + dy, z + dz), ())
        )
        for index in near:  # the earliest named first
            name, known = self._places[index]
            if (
                (any_prefix or _split(name)[0] == prefix)
                and name not in taken
                and math.dist(known, position) < self.tolerance
            ):
                return name
        self._counts[prefix] = self._counts.get(prefix, 0) + 1
        name = f"{prefix}{self._counts[prefix]}"
        self._add(name, position)
        return name

    def _cell(self, position: Vector3) -> tuple[int, int, int]:
        size = self.tolerance if self.tolerance > 0 else 1.0
        x, y, z = (math.floor(v / size) for v in position)
        return x, y, z

    def _add(self, name: str, position: Vector3) -> None:
        self._cells.setdefault(self._cell(position), []).append(len(self._places))
        self._places.append((name, position))

    def grasp(self, obj: str, axis: float) -> str:
        """The name of grasp ``axis`` (deg) of ``obj``: ``grasp`` + number."""
        key = (obj, axis)
        if key not in self._grasps:
            self._counts["grasp"] = self._counts.get("grasp", 0) + 1
            self._grasps[key] = f"grasp{self._counts['grasp']}"
        return self._grasps[key]


def _split(name: str) -> tuple[str, int]:
    """``loc12`` → (``loc``, 12); a name without a number → (name, 0)."""
    digits = len(name) - len(name.rstrip("0123456789"))
    if digits == 0:
        return name, 0
    return name[:-digits], int(name[-digits:])
