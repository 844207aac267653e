"""How far goal objects are turned from their targets, where that matters.

A target's orientation matters where it was learned (its subtask is not
turnable: the object was put down turned alike in every demonstration, in the
frame of what it stands on or beside); a turn is read given the object's
symmetry (:func:`demoplan.scenes.geometry.yaw_difference`) — none for a shape
every turn leaves looking the same (a cylinder).
"""

from __future__ import annotations

from demoplan.execution.world import Observation
from demoplan.scenes.geometry import symmetry, yaw_difference
from demoplan.scenes.problems import SceneProblem

__all__ = ["oriented_locations", "turn_errors", "turned_beyond"]


def oriented_locations(problem: SceneProblem) -> set[str]:
    """Locations of targets whose orientation was learned (yaw matters there)."""
    turnable = {s.label: s.turnable for s in problem.candidate.subtasks}
    return {s.location for s in problem.problem.subgoals if not turnable.get(s.id, True)}


def turn_errors(problem: SceneProblem, observation: Observation) -> dict[str, float]:
    """How far (deg) each goal object whose target's orientation was learned is
    turned from it in ``observation``, given its symmetry (none for the others, nor
    for a shape every turn leaves looking the same: a cylinder)."""
    oriented = oriented_locations(problem)
    return {
        obj: yaw_difference(shape, observation.poses[obj].yaw, problem.location(loc).yaw)
        for obj, loc in problem.problem.goal
        if loc in oriented
        and obj in observation.poses
        and (shape := observation.geometry.get(obj)) is not None
        and symmetry(shape) > 0.0
    }


def turned_beyond(
    problem: SceneProblem, observation: Observation, obj: str, location: str, tolerance: float
) -> float | None:
    """How far (deg) ``obj`` is turned from ``location``'s yaw, where that matters
    and it is more than ``tolerance``; else None."""
    shape = observation.geometry.get(obj)
    pose = observation.poses.get(obj)
    if shape is None or pose is None or location not in oriented_locations(problem):
        return None
    turn = yaw_difference(shape, pose.yaw, problem.location(location).yaw)
    return turn if turn > tolerance else None
