"""Collision facts from a simulation (``--collisions simulation``) beside the
geometric finger rule's: which (location, grasp) pairs are checked, and how
the two sets of facts compare. The simulation itself — the arm posed in
MuJoCo along each grasp's approach — is execution's
(:mod:`demoplan.execution.collision_simulation`): the planner is handed it as
``GeometrySettings.simulator`` by the command layer, so that scenes, a floor
below execution, never imports it.

A fact ``(a, b, g)`` says grasp ``g`` at location ``a`` hits whatever stands at
``b``. The two need not agree, and the difference is the point: the finger rule
blocks a grasp whose finger discs reach a neighbour's outline; the suction cup
comes from above and is blocked only where a neighbour reaches up into the
arm's way. :class:`CollisionComparison` keeps both sets of facts.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from demoplan.model import ObjectGeometry
from demoplan.scenes.geometry import GeometrySettings, Location, accepted_objects

__all__ = ["CollisionComparison", "Fact", "checked_pairs"]

Fact = tuple[str, str, str]


@dataclass(frozen=True, slots=True)
class CollisionComparison:
    """The collision facts of the geometric rule and of the arm in simulation,
    and the grasps (location, grasp) the arm could not reach to check."""

    rule: tuple[Fact, ...]
    simulation: tuple[Fact, ...]
    unreachable: tuple[tuple[str, str], ...] = ()

    @property
    def only_rule(self) -> tuple[Fact, ...]:
        simulated = set(self.simulation)
        return tuple(f for f in self.rule if f not in simulated)

    @property
    def only_simulation(self) -> tuple[Fact, ...]:
        ruled = set(self.rule)
        return tuple(f for f in self.simulation if f not in ruled)

    def summary(self) -> str:
        """One line: how many facts each gives, and where they disagree."""
        line = (
            f"collision facts from the arm in simulation: {len(self.simulation)} "
            f"(the geometric rule: {len(self.rule)}); only the rule: "
            f"{_facts(self.only_rule)}; only the simulation: {_facts(self.only_simulation)}"
        )
        if self.unreachable:
            line += f"; {len(self.unreachable)} grasp poses out of the arm's reach, unchecked"
        return line

    def to_json(self) -> dict[str, Any]:
        return {
            "source": "simulation",
            "simulation": len(self.simulation),
            "rule": len(self.rule),
            "only_rule": [list(f) for f in self.only_rule],
            "only_simulation": [list(f) for f in self.only_simulation],
            "unreachable": [list(u) for u in self.unreachable],
        }


def _facts(facts: Sequence[Fact], shown: int = 4) -> str:
    if not facts:
        return "none"
    listed = ", ".join(f"({a}, {b}, {g})" for a, b, g in facts[:shown])
    more = f" and {len(facts) - shown} more" if len(facts) > shown else ""
    return f"{len(facts)} — {listed}{more}"


def checked_pairs(
    locations: Sequence[Location],
    grasps: Sequence[tuple[str, str, ObjectGeometry, float]],
    shapes: dict[str, ObjectGeometry],
    settings: GeometrySettings = GeometrySettings(),
) -> set[tuple[str, str]]:
    """The (location, grasp) pairs whose facts matter: the grasp's object may
    stand at the location."""
    return {
        (loc.name, grasp)
        for grasp, obj, _shape, _axis in grasps
        for loc in locations
        if obj in accepted_objects(loc, shapes, settings)
    }
