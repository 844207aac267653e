"""GRASP / PUT_DOWN on names: the operators of docs/formats.md and the order rule of
docs/planning.md, written as plainly as a STRIPS interpreter (pyperplan's
``applicable`` / ``apply``).

The searches run on a compiled, bitmask form of the same rules
(:mod:`demoplan.planning.compiled`); this module is the readable one. The
validator (:func:`validate`) and the executor's bookkeeping of reached
subgoals use it, so a plan, the executor and the tests agree on one reading:

- one object per location, the hand holds at most one object;
- ``GRASP o la g``: hand empty, o at la, g allowed for o, no *other* object at
  any lb with a collision fact ``(la, lb, g)``, nothing standing on la;
- ``PUT_DOWN o lb g``: holding o with g; lb is not where o was grasped from
  (no move ends where it started); lb free; no other object at any lc with a
  fact ``(lb, lc, g)``; every location lb stands on occupied; lb's exclusive
  partners free; lb accepts o; and **the order rule**: if o has a subgoal X at
  lb not yet reached, X's predecessors are all reached — o is never put down
  on X's place before them (it is parked elsewhere instead). Such a put-down
  reaches X;
- at the start, a subgoal counts as reached when its object already stands at
  its place and the object's own earlier subgoals (predecessors that are
  subgoals of the same object) are reached. Other objects' predecessors are
  not required: the constraints order the robot's put-downs, and an object
  the robot finds in place was not put down by it. Lifting it and putting it
  back would cost two moves and a chance of failure and add nothing that the
  geometry does not already demand — where the order is physical (one object
  on another, one blocking another's grasp), the support and collision facts
  force the moves anyway;
- the goal holds when the hand is empty, every goal object is at its goal
  location and every subgoal is reached.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

from demoplan.errors import DemoplanError
from demoplan.planning.problem import Action, Problem, Subgoal

__all__ = ["InvalidPlanError", "Rules", "World", "validate"]


class InvalidPlanError(DemoplanError):
    """A plan that is not applicable in turn, or does not reach the goal."""


@dataclass(frozen=True, slots=True)
class World:
    """Where each placed object is, what the hand holds — (object, grasp,
    location it was taken from) — and the subgoals reached."""

    at: Mapping[str, str]
    held: tuple[str, str, str] | None
    reached: frozenset[str]


class Rules:
    """The operators of one problem, indexed by name once."""

    def __init__(self, problem: Problem):
        self.problem = problem
        self.blockers: dict[tuple[str, str], set[str]] = defaultdict(set)
        for la, lb, grasp in problem.collisions:
            if la != lb:
                self.blockers[la, grasp].add(lb)
        self.below: dict[str, set[str]] = defaultdict(set)
        self.above: dict[str, set[str]] = defaultdict(set)
        for upper, lower in problem.supports:
            self.below[upper].add(lower)
            self.above[lower].add(upper)
        self.exclusive: dict[str, set[str]] = defaultdict(set)
        for a, b in problem.exclusions:
            self.exclusive[a].add(b)
            self.exclusive[b].add(a)
        self.takes: dict[str, set[str]] = defaultdict(set)
        for location, obj in problem.accepts:
            self.takes[location].add(obj)
        self.before: dict[str, set[str]] = defaultdict(set)
        for first, then in problem.precedences:
            self.before[then].add(first)
        self.subgoals_of: dict[str, list[Subgoal]] = defaultdict(list)
        for subgoal in problem.subgoals:
            self.subgoals_of[subgoal.object].append(subgoal)

    def start(self) -> World:
        """The initial world, with the subgoals that count as reached at the start."""
        at = dict(self.problem.initial)
        return World(at, None, self.reached_where_they_stand(at, frozenset(self.problem.reached)))

    def reached_where_they_stand(
        self, at: Mapping[str, str], reached: Iterable[str]
    ) -> frozenset[str]:
        """``reached`` plus, per object, the first unreached subgoal at the place it
        stands whose predecessors among the object's own subgoals are reached."""
        done = set(reached)
        for obj, location in at.items():
            own = {s.id for s in self.subgoals_of[obj]}
            for subgoal in self.subgoals_of[obj]:
                if subgoal.location != location or subgoal.id in done:
                    continue
                if self.before[subgoal.id] & own <= done:
                    done.add(subgoal.id)
                break
        return frozenset(done)

    def next_subgoal(self, obj: str, location: str, reached: frozenset[str]) -> Subgoal | None:
        """The first subgoal of ``obj`` at ``location`` not yet reached."""
        return next(
            (s for s in self.subgoals_of[obj] if s.location == location and s.id not in reached),
            None,
        )

    def why_not(self, world: World, action: Action) -> str | None:
        """Why ``action`` is not applicable in ``world``; None if it is."""
        o, location, grasp = action.object, action.location, action.grasp
        if (o, grasp) not in self.problem.allowed:
            return f"grasp {grasp} is not allowed for {o}"

        def occupant(place: str) -> str | None:
            return next((obj for obj, at in world.at.items() if at == place), None)

        if action.kind == "GRASP":
            if world.held is not None:
                return "the hand is not empty"
            if world.at.get(o) != location:
                return f"{o} is not at {location}"
            for other_place in self.blockers[location, grasp]:
                other = occupant(other_place)
                if other is not None and other != o:
                    return f"{other} at {other_place} is in the way of grasp {grasp}"
            for upper in self.above[location]:
                if occupant(upper) is not None:
                    return f"{occupant(upper)} stands on it"
            return None
        if action.kind != "PUT_DOWN":
            return f"unknown action {action.kind!r}"
        if world.held is None or world.held[:2] != (o, grasp):
            return f"the hand does not hold {o} with {grasp}"
        if world.held[2] == location:
            return f"{o} was taken from {location}: a move must end elsewhere"
        if occupant(location) is not None:
            return f"{location} is occupied by {occupant(location)}"
        for other_place in self.blockers[location, grasp]:
            if occupant(other_place) is not None:
                return f"{occupant(other_place)} at {other_place} is in the way of grasp {grasp}"
        for lower in self.below[location]:
            if occupant(lower) is None:
                return f"nothing stands under it at {lower}"
        for partner in self.exclusive[location]:
            if occupant(partner) is not None:
                return f"it overlaps {occupant(partner)} at {partner}"
        if self.takes[location] and o not in self.takes[location]:
            return f"{location} does not take {o}"
        subgoal = self.next_subgoal(o, location, world.reached)
        if subgoal is not None:
            missing = sorted(self.before[subgoal.id] - world.reached)
            if missing:
                return (
                    f"{location} is the place of subgoal {subgoal.id}, which must wait for "
                    f"{', '.join(missing)}"
                )
        return None

    def reached_by_put_down(
        self, obj: str, location: str, reached: frozenset[str]
    ) -> frozenset[str]:
        """``reached`` after ``obj`` is put down at ``location``: with the subgoal
        it reaches there, if any (the first one not yet reached, its
        predecessors reached)."""
        subgoal = self.next_subgoal(obj, location, reached)
        if subgoal is None or not self.before[subgoal.id] <= reached:
            return reached
        return reached | {subgoal.id}

    def apply(self, world: World, action: Action) -> World:
        """The world after ``action`` (assumed applicable: see :meth:`why_not`)."""
        at = dict(world.at)
        if action.kind == "GRASP":
            del at[action.object]
            return World(at, (action.object, action.grasp, action.location), world.reached)
        at[action.object] = action.location
        reached = self.reached_by_put_down(action.object, action.location, world.reached)
        return World(at, None, reached)

    def unmet(self, world: World) -> str | None:
        """What of the goal does not hold in ``world``; None if it all does."""
        if world.held is not None:
            return f"the hand still holds {world.held[0]}"
        for obj, location in self.problem.goal:
            if world.at.get(obj) != location:
                return f"{obj} is at {world.at.get(obj)}, not at its goal {location}"
        missing = sorted({s.id for s in self.problem.subgoals} - world.reached)
        if missing:
            return f"subgoals never reached: {', '.join(missing)}"
        return None


def validate(problem: Problem, actions: Iterable[Action]) -> World:
    """The final world of ``actions`` applied in turn; raises
    :class:`InvalidPlanError` naming the first step that is not applicable,
    or what of the goal does not hold at the end."""
    rules = Rules(problem)
    world = rules.start()
    for step, action in enumerate(actions, start=1):
        why = rules.why_not(world, action)
        if why is not None:
            raise InvalidPlanError(f"step {step} ({action}): {why}")
        world = rules.apply(world, action)
    unmet = rules.unmet(world)
    if unmet is not None:
        raise InvalidPlanError(f"goal: {unmet}")
    return world
