"""The demonstrations as the state generation reads them: every object's
placements (demonstration, step, pose) and where every object was at each step."""

from __future__ import annotations

from bisect import bisect_left
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from demoplan import rotations
from demoplan.model import (
    Demonstration,
    Pose,
    demonstrated_shapes,
    yaw_period,
)

__all__ = ["DemonstrationWorld"]


@dataclass(frozen=True, slots=True)
class _Placement:
    demo: int
    step: int
    pose: Pose


class DemonstrationWorld:
    """Per-demonstration lookup of where every object and landmark was."""

    def __init__(self, demonstrations: Sequence[Demonstration]):
        # Per demonstration and object: the step indices of its moves, and its poses.
        self.moves: list[dict[str, tuple[list[int], list[Pose]]]] = []
        self.landmarks = [d.landmark_poses() for d in demonstrations]
        self.initial = [d.initial_poses() for d in demonstrations]
        self.geometry = demonstrated_shapes(demonstrations)
        for demo in demonstrations:
            moves: dict[str, tuple[list[int], list[Pose]]] = {}
            for index, step in enumerate(demo.steps):
                steps, poses = moves.setdefault(step.object, ([], []))
                steps.append(index)
                poses.append(step.pose)
            self.moves.append(moves)

    def pose(self, demo: int, name: str, step: int) -> Pose | None:
        """``name``'s placement when ``step`` happens (docs/learning.md).

        The placement current at the step; for an object placed only after the
        step, its first placement; for one never moved, its initial pose.
        """
        if name in self.landmarks[demo]:
            return self.landmarks[demo][name]
        history = self.moves[demo].get(name)
        if history:
            steps, poses = history
            moved_before = bisect_left(steps, step)
            return poses[moved_before - 1] if moved_before else poses[0]
        return self.initial[demo].get(name)

    def yaw_period(self, name: str | None) -> float:
        """``name``'s symmetry about its own z axis (deg; 0: any turn); 360° (none)
        where its geometry is unknown, and for a landmark: its yaw is given, not
        tracked, so its frame is the one given (a tray has a front, whatever
        its shape's symmetry)."""
        if name is None or any(name in landmarks for landmarks in self.landmarks):
            return 360.0
        return yaw_period(self.geometry.get(name))

    def own_symmetry(self, name: str, quats: np.ndarray) -> np.ndarray:
        """``name``'s orientations (absolute or relative to a reference) compared
        modulo its shape's symmetry: a box's half turns about its axes (and quarter
        turns where two extents agree), a cylinder's turns about its axis and
        flip, a sphere's every turn; none for other or unknown shapes."""
        shape = self.geometry.get(name)
        if shape is None or shape.shape not in {"box", "cylinder", "sphere"}:
            return quats
        if shape.shape == "sphere":
            return np.tile([0.0, 0.0, 0.0, 1.0], (len(quats), 1))
        if shape.shape == "cylinder":
            return rotations.axis_modulo_flip(quats)
        return rotations.modulo_group(quats, rotations.box_symmetries(shape.size))

    def available(self, demo: int, name: str, step: int) -> bool:
        """Whether ``name`` may serve as a reference at ``step`` of ``demo``."""
        if name in self.landmarks[demo]:
            return True
        history = self.moves[demo].get(name)
        if history:
            return history[0][0] < step
        return name in self.initial[demo]
