"""What the executor needs of a world: observe it, grasp, put down.

A world reports what its sensors would: the pose of every object standing in
it (a held object is not standing anywhere) and what the hand holds. Actions
are commands; whether they worked is for the executor to find out by
observing (paper: "observe and compare with the expected effect").
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

from demoplan.model import ObjectGeometry, Pose

__all__ = ["Observation", "World"]


@dataclass(frozen=True, slots=True)
class Observation:
    """Poses of the objects standing in the world, and the object in the hand."""

    poses: dict[str, Pose]
    held: str | None
    geometry: dict[str, ObjectGeometry]


class World(Protocol):
    """A world the executor can act in (kinematic, MuJoCo, a robot)."""

    name: str

    def observe(self) -> Observation:
        """What the sensors see now."""
        ...

    def grasp(self, obj: str, axis: float, where: Pose | None = None) -> None:
        """Close the hand on ``obj``, fingers along ``axis`` (deg, object frame), and
        lift it; ``where``: the pose the executor believes it has (a world that
        knows better may use its own)."""
        ...

    def put_down(self, obj: str, pose: Pose) -> None:
        """Carry the held ``obj`` to ``pose`` and release it there."""
        ...

    def between_actions(self, upcoming: Sequence[Pose] = ()) -> None:
        """Let the world go on between two actions (people may move things);
        ``upcoming``: the targets of the plan's next put-downs (simulated faults
        use them; a real world ignores them)."""
        ...
