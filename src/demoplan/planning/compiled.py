"""A problem compiled to integers and bitmasks for fast search.

Locations, objects and grasps become indices; a set of locations is an int
bitmask, so an operator's collision test is one ``&``. Shared by every search.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from demoplan.planning.problem import Action, Problem

if TYPE_CHECKING:
    from demoplan.budget import Clock

__all__ = ["Compiled", "compile_problem"]


@dataclass(frozen=True, slots=True)
class Compiled:
    """Indices and masks of a :class:`Problem` (see the module docstring)."""

    problem: Problem
    objects: tuple[str, ...]
    locations: tuple[str, ...]
    grasps: tuple[str, ...]  # per allowed (object, grasp) pair: the grasp's name
    grasp_object: tuple[int, ...]  # per allowed pair: its object
    grasps_of: tuple[tuple[int, ...], ...]  # object -> its allowed pairs
    block: tuple[tuple[int, ...], ...]  # [location][pair] -> locations that block it (mask)
    below: tuple[int, ...]  # location -> mask of the locations it stands on (all needed)
    above: tuple[int, ...]  # location -> mask of locations standing on it
    exclusive: tuple[int, ...]  # location -> mask of locations that exclude it
    accepts: tuple[int, ...]  # location -> mask of the objects it takes
    start: tuple[int, ...]  # object -> start location
    goal: tuple[int, ...]  # object -> final location, or -1
    subgoal_object: tuple[int, ...]
    subgoal_location: tuple[int, ...]
    subgoal_before: tuple[int, ...]  # subgoal -> mask of subgoals that must be reached first
    subgoals_of: tuple[tuple[int, ...], ...]  # object -> its subgoals in order
    all_subgoals: int
    start_reached: int
    plain: int  # mask of interchangeable free-space locations (no fact mentions them)

    def is_goal(self, positions: tuple[int, ...], reached: int) -> bool:
        """Every subgoal reached and every goal object at its goal (hand empty)."""
        if reached != self.all_subgoals:
            return False
        return all(goal < 0 or goal == at for goal, at in zip(self.goal, positions, strict=True))

    def must_move(self, obj: int) -> bool:
        """Whether ``obj`` must move from the start: it stands off its goal or
        has a subgoal to reach."""
        if 0 <= self.goal[obj] != self.start[obj]:
            return True
        return any(not self.start_reached >> s & 1 for s in self.subgoals_of[obj])

    def grasp_ok(self, occupied: int, location: int, grasp: int) -> bool:
        """GRASP at ``location`` with ``grasp`` while ``occupied`` (it included)."""
        others = occupied & ~(1 << location)
        return not (others & self.block[location][grasp]) and not (occupied & self.above[location])

    def put_ok(self, others: int, location: int, grasp: int) -> bool:
        """PUT_DOWN at ``location`` with ``grasp`` (an allowed pair, so it names
        the object) while ``others`` are occupied."""
        bit = 1 << location
        if (
            others & bit
            or others & self.block[location][grasp]
            or others & self.exclusive[location]
            or not self.accepts[location] >> self.grasp_object[grasp] & 1
        ):
            return False
        support = self.below[location]
        return others & support == support

    def frozen(self, positions: tuple[int, ...]) -> int:
        """Mask of the places whose objects can never be picked up again.

        Start from every occupied place and drop an object whenever one of its
        grasps is clear of the remaining ones (and nothing remaining stands on
        it): what is left blocks itself for good — each of its objects has
        every grasp blocked by another of them, which cannot move either.
        """
        where = [(obj, location) for obj, location in enumerate(positions) if location >= 0]
        stuck = 0
        for _, location in where:
            stuck |= 1 << location
        changed = True
        while changed:
            changed = False
            for obj, location in where:
                bit = 1 << location
                if not stuck & bit:
                    continue
                others = stuck & ~bit
                if not others & self.above[location] and any(
                    not others & self.block[location][g] for g in self.grasps_of[obj]
                ):
                    stuck &= ~bit
                    changed = True
        return stuck

    def peel(self, objects: list[int], fixed: int = 0) -> tuple[list[int], list[int]]:
        """Peel off, one at a time, objects of ``objects`` that could be put down
        at their goals last: with a grasp there clear of the goals of those
        still left and of the places ``fixed`` (objects that stay). Returns
        the objects peeled, in order (the last put down first), and those left
        — every grasp of each blocked by the others' goals or ``fixed``."""
        goals = fixed
        for obj in objects:
            goals |= 1 << self.goal[obj]
        peeled: list[int] = []
        remaining = objects
        while remaining:
            kept = []
            for obj in remaining:
                target = self.goal[obj]
                others = goals & ~(1 << target)
                if any(not self.block[target][g] & others for g in self.grasps_of[obj]):
                    goals &= ~(1 << target)
                    peeled.append(obj)
                else:
                    kept.append(obj)
            if len(kept) == len(remaining):
                break
            remaining = kept
        return peeled, remaining

    def never_placed(self) -> int:
        """Mask of the goal objects that no plan can ever move.

        Every object with a goal ends there, and an object's last put-down
        puts it at its goal. Among the goal objects of a set R that move, the
        one put down last finds every other one of R at its goal (moved ones
        have finished; one that must not move is there already), so one of
        its grasps at its goal must be clear of the other goals of R. Peel off
        objects with a grasp at their goal clear of the goals still left (any
        of them could be that last one); the objects left over, if any, have
        every grasp at their goal blocked by the others' goals, so none of them
        may move — from any state, since one of them away from its goal would
        have to move and then be last or find the last one blocked. Objects
        without a grasp never peel off (they cannot move either way).
        """
        _, remaining = self.peel([obj for obj, goal in enumerate(self.goal) if goal >= 0])
        stuck = 0
        for obj in remaining:
            stuck |= 1 << obj
        return stuck

    def put_down(self, obj: int, location: int, reached: int) -> int:
        """The subgoals reached after putting ``obj`` down at ``location``, or -1
        if the order rule forbids it (docs/planning.md; :mod:`demoplan.planning.strips`):
        the first unreached subgoal of ``obj`` there must have every predecessor
        reached, and is reached by the put-down."""
        for s in self.subgoals_of[obj]:
            if self.subgoal_location[s] == location and not reached >> s & 1:
                if self.subgoal_before[s] & ~reached:
                    return -1
                return reached | 1 << s
        return reached

    def move_actions(self, obj: int, source: int, target: int, grasp: int) -> tuple[Action, Action]:
        o, g = self.objects[obj], self.grasps[grasp]
        return (
            Action("GRASP", o, self.locations[source], g),
            Action("PUT_DOWN", o, self.locations[target], g),
        )


_CHECK_EVERY = 4096
"""Facts compiled between two readings of the clock."""


def compile_problem(problem: Problem, clock: Clock | None = None) -> Compiled:
    """Index a problem; the masks are what :mod:`demoplan.planning.search` tests.
    ``clock``: read as it goes (LimitReachedError, exit 4, once the time is
    up: a thousand objects take a large part of a second)."""

    def check() -> None:
        if clock is not None:
            clock.check(
                f"compiling the problem ({len(objects)} objects, {len(locations)} locations), "
                "before any search"
            )

    objects, locations = problem.objects, problem.locations
    loc_index = {name: i for i, name in enumerate(locations)}
    obj_index = {name: i for i, name in enumerate(objects)}
    grasp_order = {name: i for i, name in enumerate(problem.grasps)}
    # A grasp is compiled per object that allows it: masks per (object, grasp) pair.
    pairs = sorted(problem.allowed, key=lambda p: (obj_index[p[0]], grasp_order[p[1]]))
    grasps = tuple(g for _, g in pairs)
    grasp_object = tuple(obj_index[o] for o, _ in pairs)
    pairs_named: dict[str, list[int]] = {}
    for index, (_, g) in enumerate(pairs):
        pairs_named.setdefault(g, []).append(index)
    pairs_of: list[list[int]] = [[] for _ in objects]
    for index, owner in enumerate(grasp_object):
        pairs_of[owner].append(index)
    grasps_of = tuple(tuple(indices) for indices in pairs_of)
    check()
    block = [[0] * len(pairs) for _ in locations]
    for count, (la, lb, g) in enumerate(problem.collisions):
        if not count % _CHECK_EVERY:
            check()
        if la != lb:  # "no *other* object at lb": the grasped object itself stands at la
            for pair_index in pairs_named.get(g, ()):
                block[loc_index[la]][pair_index] |= 1 << loc_index[lb]
    accepts, below, above, exclusive = _location_masks(problem, loc_index, obj_index)
    start = [0] * len(objects)
    for obj, loc in problem.initial:
        start[obj_index[obj]] = loc_index[loc]
    goal = [-1] * len(objects)
    for obj, loc in problem.goal:
        goal[obj_index[obj]] = loc_index[loc]
    sub_index = {s.id: i for i, s in enumerate(problem.subgoals)}
    before = [0] * len(problem.subgoals)
    for a, b in problem.precedences:
        before[sub_index[b]] |= 1 << sub_index[a]
    subgoals_of: list[list[int]] = [[] for _ in objects]
    for i, s in enumerate(problem.subgoals):
        subgoals_of[obj_index[s.object]].append(i)
    check()
    compiled = Compiled(
        problem=problem,
        objects=objects,
        locations=locations,
        grasps=grasps,
        grasp_object=grasp_object,
        grasps_of=grasps_of,
        block=tuple(tuple(row) for row in block),
        below=tuple(below),
        above=tuple(above),
        exclusive=tuple(exclusive),
        accepts=tuple(accepts),
        start=tuple(start),
        goal=tuple(goal),
        subgoal_object=tuple(obj_index[s.object] for s in problem.subgoals),
        subgoal_location=tuple(loc_index[s.location] for s in problem.subgoals),
        subgoal_before=tuple(before),
        subgoals_of=tuple(tuple(s) for s in subgoals_of),
        all_subgoals=(1 << len(problem.subgoals)) - 1,
        start_reached=0,
        plain=_plain_locations(problem, loc_index),
    )
    return replace(compiled, start_reached=_reached_at_start(compiled, sub_index))


def _location_masks(
    problem: Problem, loc_index: dict[str, int], obj_index: dict[str, int]
) -> tuple[list[int], list[int], list[int], list[int]]:
    """Per location: the objects it takes, the locations it stands on, those
    standing on it, and those it excludes (masks)."""
    restricted: dict[int, int] = {}
    for loc, obj in problem.accepts:
        restricted[loc_index[loc]] = restricted.get(loc_index[loc], 0) | 1 << obj_index[obj]
    everything_objects = (1 << len(problem.objects)) - 1
    accepts = [restricted.get(li, everything_objects) for li in range(len(problem.locations))]
    below = [0] * len(problem.locations)
    above = [0] * len(problem.locations)
    for upper, lower in problem.supports:
        below[loc_index[upper]] |= 1 << loc_index[lower]
        above[loc_index[lower]] |= 1 << loc_index[upper]
    exclusive = [0] * len(problem.locations)
    for a, b in problem.exclusions:
        exclusive[loc_index[a]] |= 1 << loc_index[b]
        exclusive[loc_index[b]] |= 1 << loc_index[a]
    return accepts, below, above, exclusive


def _plain_locations(problem: Problem, loc_index: dict[str, int]) -> int:
    """The mask of the free-space locations no fact mentions: no collision,
    support, exclusion, accepts, goal or subgoal."""
    mentioned = set()
    for la, lb, _ in problem.collisions:
        mentioned |= {la, lb}
    for pair in problem.supports | problem.exclusions:
        mentioned |= set(pair)
    mentioned |= {loc for loc, _ in problem.accepts}
    mentioned |= {loc for _, loc in problem.goal} | {s.location for s in problem.subgoals}
    plain = 0
    for name in problem.freespace - mentioned:
        plain |= 1 << loc_index[name]
    return plain


def _reached_at_start(compiled: Compiled, sub_index: dict[str, int]) -> int:
    """The mask of the subgoals reached at the start: those the problem says,
    and where an object stands at one of its subgoals."""
    reached = 0
    for sid in compiled.problem.reached:
        reached |= 1 << sub_index[sid]
    # At the start a subgoal counts where its object stands, once its own earlier
    # subgoals are reached (other objects' predecessors are not required; see
    # demoplan.planning.strips); at most one per object.
    for index, at in enumerate(compiled.start):
        own = 0
        for sub in compiled.subgoals_of[index]:
            own |= 1 << sub
        for sub in compiled.subgoals_of[index]:
            if compiled.subgoal_location[sub] == at and not reached >> sub & 1:
                if compiled.subgoal_before[sub] & own & ~reached == 0:
                    reached |= 1 << sub
                break
    return reached
