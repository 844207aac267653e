"""A* over moves (a GRASP and the PUT_DOWN after it) with the admissible
bounds of :mod:`demoplan.planning.bounds`: every plan alternates the two
actions, so a plan of k moves has 2k actions and shortest in moves is shortest
in actions. States are deduplicated on the tuple of object locations in which
interchangeable free-space locations — mentioned by no fact and no goal — are
one symmetric class.
"""

from __future__ import annotations

import heapq
from collections.abc import Iterator
from typing import NamedTuple

from demoplan.planning.bounds import (
    DEAD_END,
    DIRECT_NODES,
    MAX_DIRECT_DEPTH,
    LowerBounds,
    Move,
    OutOfNodesError,
)
from demoplan.planning.budget import Budget, Clock, SearchOutcome
from demoplan.planning.compiled import Compiled, compile_problem
from demoplan.planning.problem import Action, Problem

__all__ = ["AStar", "astar_search"]

State = tuple[tuple[int, ...], int]  # object locations, reached subgoals (mask)
Key = tuple[int, ...]  # a state with interchangeable locations merged (AStar.key)


def astar_search(
    problem: Problem, budget: Budget = Budget(), upper: int | None = None
) -> SearchOutcome:
    """A shortest plan by A* over moves. ``upper``: the length (in actions) of a
    plan already known — A* then only looks for a shorter one, and ends with
    ``actions`` None and ``bound == upper`` when it proves there is none."""
    c = compile_problem(problem)
    return AStar(c, LowerBounds(c), Clock(budget)).run(None if upper is None else upper // 2)


class Priority(NamedTuple):
    """A queue entry; entries compare field by field, the least popped first."""

    f: int  # g + h: the least first (A*)
    negative_g: int  # among equal f, the deepest first
    h: int  # then the least bound; DEFERRED for a child queued with its parent's f
    place_rank: int  # then moves that free a place another object waits for, in peel order
    negative_order: int  # then the latest queued
    key: Key
    parent_h: int  # the parent's bound, for pathmax


EVALUATED = 0  # the h of an entry whose bound is known (its f is exact)
DEFERRED = 1 << 30  # the h of an unproductive child, queued with a lower bound only
NOT_WAITED_FOR = 1 << 20  # place rank: the source is no other object's goal
NOT_PEELED = 1 << 19  # place rank: the object is not in the peeling order


class _BudgetSpentError(Exception):
    """A limit of the budget is reached (the message names it)."""


class AStar:
    """One A* run over the moves of a compiled problem (see :meth:`run`)."""

    def __init__(self, c: Compiled, bounds: LowerBounds, clock: Clock):
        self.c = c
        self.bounds = bounds
        self.clock = clock
        self.plain_locations = [loc for loc in range(len(c.locations)) if c.plain >> loc & 1]
        self.parent: dict[Key, tuple[Key, Move] | None] = {}
        self.best_g: dict[Key, int] = {}
        self.known_h: dict[Key, int] = {}
        self.concrete: dict[Key, State] = {}
        self.queue: list[Priority] = []
        self.queued = 0
        self.expanded = 0
        self.bound = 0  # the largest f popped: no plan is shorter (in moves)
        self.limit_f = 1 << 60

    def key(self, positions: tuple[int, ...], reached: int) -> Key:
        plain = self.c.plain
        if not plain:
            return (*positions, reached)
        return (*(-1 if plain >> p & 1 else p for p in positions), reached)

    def run(self, upper: int | None = None) -> SearchOutcome:
        """A* with deferred heuristic evaluation and pathmax; ``upper``: only
        plans of fewer moves are of interest (a plan of that many is known).

        A child is queued with its parent's f — a lower bound of its own, since
        a move lowers the true distance by at most one (pathmax:
        ``h(child) ≥ h(parent) − 1``) — and its heuristic is computed only when
        it is popped; if its f then turns out larger it is queued again. The
        :class:`Priority` walks, where the heuristic is exact, straight to a
        plan whose length equals the root's lower bound — which proves it
        shortest. Where h is just the objects' needs, a bounded search for a
        finish with one straight move per object (:meth:`finish_straight`)
        ends the search at once, or proves h one too low for that state. Nodes
        whose f reaches ``upper`` are dropped: when none is left, no shorter
        plan exists.
        """
        if upper is not None:
            self.limit_f = upper
        start_key = self.key(self.c.start, self.c.start_reached)
        self.best_g[start_key] = 0
        self.parent[start_key] = None
        self.concrete[start_key] = (self.c.start, self.c.start_reached)
        self.queue.append(Priority(0, 0, EVALUATED, 0, 0, start_key, 0))
        try:
            while self.queue:
                entry = heapq.heappop(self.queue)
                if entry.f >= self.limit_f:
                    break  # every node left needs at least ``upper`` moves
                h = self.settled_bound(entry)
                if h is None:
                    continue
                self.bound = max(self.bound, entry.f)
                positions, reached = self.concrete[entry.key]
                if h == 0 and self.c.is_goal(positions, reached):
                    return self.outcome(self.unwind(entry.key))
                finish = self.finish_straight(entry, h)
                if isinstance(finish, tuple):
                    return self.outcome(finish)
                if finish > h:  # shown one too low: queued again if f grows
                    h = finish
                    if -entry.negative_g + h > entry.f:
                        self.requeue(entry, -entry.negative_g + h)
                        continue
                self.check_budget(always=True)
                self.expanded += 1
                self.expand(entry, h)
        except _BudgetSpentError as stop:
            return self.outcome(None, limit=str(stop))
        return self.outcome(None, exhausted=True)

    def settled_bound(self, entry: Priority) -> int | None:
        """The popped entry's bound (with pathmax), or None when the entry is
        stale, a dead end, or queued again with a larger f."""
        g = self.best_g[entry.key]
        if -entry.negative_g != g:
            return None  # stale: the state was reached more cheaply since
        h = self.known_h.get(entry.key)
        if h is None:
            h = self.evaluate(entry.key)
        if h >= DEAD_END:
            return None
        h = max(h, entry.parent_h - 1)  # pathmax
        if g + h > entry.f:
            self.requeue(entry, g + h)
            return None
        return h

    def evaluate(self, key: Key) -> int:
        """The admissible bound of a state, computed once (the clock is read
        every 16 evaluations: bounds take time)."""
        h = self.known_h[key] = self.bounds.estimate(*self.concrete[key])
        if not len(self.known_h) & 15:
            self.check_budget()
        return h

    def finish_straight(self, entry: Priority, h: int) -> tuple[Action, ...] | int:
        """Where h is just the needs, a plan that finishes with one straight
        move per object: found, it has length g + h ≤ f and no plan is shorter
        than the smallest f in the queue (A*), so it is shortest; shown
        impossible, h grows by one (see ``LowerBounds.direct_plan``). Returns
        the plan, or the node's bound."""
        bounds = self.bounds
        positions, reached = self.concrete[entry.key]
        if (
            reached != self.c.all_subgoals
            or h != bounds.needs(positions, reached)
            or positions in bounds.no_direct
            or len(positions) >= MAX_DIRECT_DEPTH
        ):
            return h
        try:
            direct = bounds.direct_plan(positions, DIRECT_NODES)
        except OutOfNodesError:
            return h
        if direct is None:
            self.known_h[entry.key] = h + 1
            return h + 1
        actions = list(self.unwind(entry.key))
        for move in direct:
            actions += self.c.move_actions(*move)
        return tuple(actions)

    def expand(self, entry: Priority, h: int) -> None:
        """Queue the children of a node: productive ones (a move onto the
        object's goal or a subgoal) evaluated at once, the others deferred.

        A move that reaches no goal and no subgoal leaves every object's need
        as it was or raises it (an object taken off its goal needs one more),
        and h is at least the sum of the needs: such a child's f is at least
        g + 1 + needs — one more than f when h is just the needs.
        """
        positions, reached = self.concrete[entry.key]
        g = -entry.negative_g
        unproductive_f = max(entry.f, g + 1 + self.bounds.needs(positions, reached))
        ranks = self.place_ranks(positions)
        for move, now_reached in self.moves(positions, reached):
            obj, source, target, _ = move
            child = self.child_key(entry.key, obj, target, now_reached)
            if self.best_g.get(child, 1 << 60) <= g + 1:
                continue
            if not len(self.best_g) & 1023:
                self.check_budget()  # an expansion can take long: the clock is read as it goes
            self.best_g[child] = g + 1
            self.parent[child] = (entry.key, move)
            moved = positions[:obj] + (target,) + positions[obj + 1 :]
            self.concrete[child] = (moved, now_reached)
            if target == self.c.goal[obj] or now_reached != reached:
                child_h = self.known_h.get(child)
                if child_h is None:
                    child_h = self.evaluate(child)
                if child_h >= DEAD_END:
                    continue
                child_f = g + 1 + max(child_h, h - 1)
                if child_f < self.limit_f:
                    rank = ranks[obj] + (0 if ranks[-1] >> source & 1 else NOT_WAITED_FOR)
                    self.push(Priority(child_f, -(g + 1), child_f - g - 1, rank, 0, child, h))
            elif unproductive_f < self.limit_f:
                self.push(Priority(unproductive_f, -(g + 1), DEFERRED, 0, 0, child, h))

    def place_ranks(self, positions: tuple[int, ...]) -> list[int]:
        """Per object, the rank of its productive moves among equals: the
        reverse of the peeling order first (it keeps the rest placeable); the
        last item is the mask of the places another object waits for (moves
        from there unblock a chain of objects), which rank before others."""
        order = self.bounds.peel_order(positions) or []
        ranks = [NOT_PEELED] * len(positions)
        for index, obj in enumerate(order):
            ranks[obj] = len(order) - index
        waited_for = 0
        for other, at in enumerate(positions):
            goal = self.c.goal[other]
            if goal >= 0 and goal != at:
                waited_for |= 1 << goal
        return [*ranks, waited_for]

    def moves(self, positions: tuple[int, ...], reached: int) -> Iterator[tuple[Move, int]]:
        """Every legal move from a state with the subgoals reached after it:
        the GRASP and PUT_DOWN tests of :class:`Compiled` (``grasp_ok``,
        ``put_ok``, ``put_down``) inlined, since they run for every candidate;
        of the free interchangeable locations only one is tried, and no move
        ends where it started (docs/planning.md). The BFS-versus-A* property test guards
        that these tests stay the rules of :mod:`demoplan.planning.strips`."""
        c = self.c
        block, above, exclusive, below, accepts, plain = (
            c.block,
            c.above,
            c.exclusive,
            c.below,
            c.accepts,
            c.plain,
        )
        occupied = 0
        for location in positions:
            occupied |= 1 << location
        free_plain = next((p for p in self.plain_locations if not occupied >> p & 1), -1)
        unmovable = self.bounds.unmovable
        for obj, source in enumerate(positions):
            if occupied & above[source] or unmovable >> obj & 1:
                continue
            others = occupied & ~(1 << source)
            for grasp in c.grasps_of[obj]:
                if others & block[source][grasp]:
                    continue
                for target in range(len(c.locations)):
                    if target == source:
                        continue
                    if plain >> target & 1 and (target != free_plain or plain >> source & 1):
                        continue
                    if (
                        others >> target & 1
                        or others & (block[target][grasp] | exclusive[target])
                        or not accepts[target] >> obj & 1
                        or others & below[target] != below[target]
                    ):
                        continue
                    now_reached = reached
                    if c.subgoals_of[obj]:
                        now_reached = c.put_down(obj, target, reached)
                    if now_reached >= 0:  # else the order rule: parked elsewhere instead
                        yield (obj, source, target, grasp), now_reached

    def child_key(self, key: Key, obj: int, target: int, reached: int) -> Key:
        """The key of a child: it differs from its parent's in one place (and reached)."""
        where = -1 if self.c.plain >> target & 1 else target
        return (*key[:obj], where, *key[obj + 1 : -1], reached)

    def requeue(self, entry: Priority, f: int) -> None:
        """Queue a popped node again with the larger f its bound gives."""
        self.push(entry._replace(f=f, h=EVALUATED, place_rank=0))

    def push(self, entry: Priority) -> None:
        self.queued += 1
        heapq.heappush(self.queue, entry._replace(negative_order=-self.queued))

    def check_budget(self, always: bool = False) -> None:
        """Raise :class:`_BudgetSpentError` when a limit is reached: every limit
        when ``always``, else only the clock (read from inner loops)."""
        if always or self.clock.expired():
            limit = self.clock.stop(self.expanded, len(self.best_g))
            if limit:
                raise _BudgetSpentError(limit)

    def outcome(
        self, actions: tuple[Action, ...] | None, exhausted: bool = False, limit: str | None = None
    ) -> SearchOutcome:
        """The result, its bound in actions: ``upper`` itself when the search
        below it was exhausted."""
        upper_exhausted = exhausted and self.limit_f < 1 << 60
        lower = self.limit_f if upper_exhausted else self.bound
        return SearchOutcome(
            actions,
            self.expanded,
            len(self.best_g),
            exhausted,
            limit,
            bound=2 * lower,
            optimal=limit is None,
        )

    def unwind(self, key: Key) -> tuple[Action, ...]:
        actions: list[Action] = []
        link = self.parent[key]
        while link is not None:
            key, (obj, source, target, grasp) = link
            actions[:0] = self.c.move_actions(obj, source, target, grasp)
            link = self.parent[key]
        return tuple(actions)
