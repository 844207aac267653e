"""Settings values the commands build from what the user asked for."""

from __future__ import annotations

from demoplan.scenes.geometry import GeometrySettings

__all__ = ["geometry_settings"]


def geometry_settings(freespace: int | None = None, collisions: str = "rule") -> GeometrySettings:
    """The scene geometry's settings: ``freespace`` spots to generate where the
    scene gives none (None: the default), and where collision facts come from
    — ``rule`` (the finger discs, §V.B) or ``simulation`` (the arm posed in
    MuJoCo along each grasp's approach, §IV.C's path planner), whose
    simulator is execution's and is handed down here."""
    simulator = None
    if collisions == "simulation":
        from demoplan.execution.collision_simulation import simulated_collision_facts

        simulator = simulated_collision_facts
    if freespace is None:
        return GeometrySettings(collisions=collisions, simulator=simulator)
    return GeometrySettings(n_freespace=freespace, collisions=collisions, simulator=simulator)
