"""A* over moves (a GRASP and the PUT_DOWN after it) with the admissible
bounds of :mod:`demoplan.planning.bounds`: every plan alternates the two
actions, so a plan of k moves has 2k actions and shortest in moves is shortest
in actions. States are deduplicated on the tuple of object locations in which
interchangeable free-space locations — mentioned by no fact and no goal — are
one symmetric class.
"""

from __future__ import annotations

import heapq

from demoplan.planning.bounds import (
    DEAD_END,
    DIRECT_NODES,
    MAX_DIRECT_DEPTH,
    LowerBounds,
    OutOfNodesError,
)
from demoplan.planning.budget import Budget, Clock, SearchOutcome
from demoplan.planning.compiled import Compiled, compile_problem
from demoplan.planning.problem import Action, Problem

__all__ = ["AStar", "astar_search"]


def astar_search(
    problem: Problem, budget: Budget = Budget(), upper: int | None = None
) -> SearchOutcome:
    """A shortest plan by A* over moves. ``upper``: the length (in actions) of a
    plan already known — A* then only looks for a shorter one, and ends with
    ``actions`` None and ``bound == upper`` when it proves there is none."""
    c = compile_problem(problem)
    return AStar(c, LowerBounds(c), Clock(budget)).run(None if upper is None else upper // 2)


# A queue entry is (f, -g, h where known — else _DEFERRED —, place rank, -counter,
# key, h of the parent): the least f first; among equal f the deepest; then the
# least h, children queued with their parent's bound last; then moves from a place
# another object waits for, then the order that keeps the rest placeable.
_Entry = tuple[int, int, int, int, int, tuple[int, ...], int]
_EVALUATED = 0
_DEFERRED = 1 << 30  # an unproductive child, queued with a lower bound only
_NOT_WAITED_FOR = 1 << 20  # place rank: the source is no other object's goal
_NO_PEEL_RANK = 1 << 19  # place rank: the object is not in the peeling order


class AStar:
    """One A* run over the moves of a compiled problem (see :meth:`run`)."""

    def __init__(self, c: Compiled, bounds: LowerBounds, clock: Clock):
        self.c = c
        self.bounds = bounds
        self.clock = clock
        n_locations = len(c.locations)
        self.plain_locations = [loc for loc in range(n_locations) if c.plain >> loc & 1]
        self.parent: dict[
            tuple[int, ...], tuple[tuple[int, ...], tuple[int, int, int, int]] | None
        ] = {}

    def key(self, positions: tuple[int, ...], reached: int) -> tuple[int, ...]:
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
        it is popped; if its f then turns out larger it is queued again. Among
        equal f the deepest node comes first, and among equal depth a move of a
        needy object onto its goal (or a subgoal) before other moves, so that
        where the heuristic is exact the search walks straight to a plan whose
        length equals the root's lower bound — which proves it shortest.
        Where h is just the objects' needs, a bounded depth-first search for a
        finish with one straight move per object
        (:meth:`~demoplan.planning.bounds.LowerBounds.direct_plan`) ends the
        search at once, or proves h one too low for that state. Nodes whose f
        reaches ``upper`` are dropped: when none is left, no shorter plan exists.
        """
        c, bounds = self.c, self.bounds
        limit_f = 1 << 60 if upper is None else upper
        start = (c.start, c.start_reached)
        start_key = self.key(*start)
        best_g = {start_key: 0}
        known_h: dict[tuple[int, ...], int] = {}
        parent = self.parent
        parent[start_key] = None
        concrete = {start_key: start}
        heap: list[_Entry] = [(0, 0, _EVALUATED, 0, 0, start_key, 0)]
        counter = 0
        expanded = 0
        bound = 0
        n_locations = len(c.locations)
        grasps_of, block, above, exclusive, below = (
            c.grasps_of,
            c.block,
            c.above,
            c.exclusive,
            c.below,
        )
        plain, goal_of, unmovable, accepts = c.plain, c.goal, bounds.unmovable, c.accepts

        def outcome(
            actions: tuple[Action, ...] | None, exhausted: bool = False, limit: str | None = None
        ) -> SearchOutcome:
            lower = limit_f if exhausted and upper is not None else bound
            return SearchOutcome(
                actions,
                expanded,
                len(best_g),
                exhausted,
                limit,
                bound=2 * lower,
                optimal=limit is None,
            )

        while heap:
            f, negative_g, _, _, _, key, parent_h = heapq.heappop(heap)
            if f >= limit_f:
                break  # every node left needs at least ``upper`` moves
            g = best_g[key]
            if -negative_g != g:  # stale: the state was reached more cheaply since
                continue
            h = known_h.get(key)
            if h is None:
                h = known_h[key] = bounds.estimate(*concrete[key])
                if not len(known_h) & 15 and self.clock.expired():  # bounds take time
                    return outcome(None, limit=self.clock.stop(expanded, len(best_g)))
            if h >= DEAD_END:
                continue
            h = max(h, parent_h - 1)  # pathmax
            if g + h > f:
                counter += 1
                heapq.heappush(heap, (g + h, negative_g, _EVALUATED, 0, -counter, key, parent_h))
                continue
            positions, reached = concrete[key]
            bound = max(bound, f)
            if h == 0 and c.is_goal(positions, reached):
                return outcome(self.unwind(key))
            if (
                reached == c.all_subgoals
                and h == bounds.needs(positions, reached)
                and positions not in bounds.no_direct
                and len(positions) < MAX_DIRECT_DEPTH
            ):
                # Where h is just the needs, try to finish with one move per
                # object: found, it is a plan of length g + h <= f, and no plan
                # is shorter than the smallest f in the queue (A*), so it is
                # shortest; shown impossible, h grows by one (see direct_plan).
                try:
                    direct = bounds.direct_plan(positions, DIRECT_NODES)
                except OutOfNodesError:
                    direct = []
                if direct:
                    actions = list(self.unwind(key))
                    for move in direct:
                        actions += self.c.move_actions(*move)
                    return outcome(tuple(actions))
                if direct is None:
                    h = known_h[key] = h + 1
                    if g + h > f:
                        counter += 1
                        heapq.heappush(
                            heap, (g + h, negative_g, _EVALUATED, 0, -counter, key, parent_h)
                        )
                        continue
            limit = self.clock.stop(expanded, len(best_g))
            if limit:
                return outcome(None, limit=limit)
            expanded += 1
            # A move that reaches no goal and no subgoal leaves every object's
            # need as it was or raises it (an object taken off its goal needs one
            # more), and h is at least the sum of the needs: such a child's f is
            # at least g + 1 + needs — one more than f when h is just the needs.
            unproductive_f = max(f, g + 1 + bounds.needs(positions, reached))
            # Put objects down in an order that keeps the rest placeable: the
            # reverse of the peeling order goes first among equals.
            order = bounds.peel_order(positions) or []
            first = {obj: len(order) - index for index, obj in enumerate(order)}
            # ... and before that, moves that free another object's goal (they
            # unblock a chain of objects waiting for their places).
            waited_for = 0
            for other, at in enumerate(positions):
                if goal_of[other] >= 0 and goal_of[other] != at:
                    waited_for |= 1 << goal_of[other]
            occupied = 0
            for location in positions:
                occupied |= 1 << location
            free_plain = -1  # one free interchangeable location stands for all of them
            for location in self.plain_locations:
                if not occupied >> location & 1:
                    free_plain = location
                    break
            for obj, source in enumerate(positions):
                others = occupied & ~(1 << source)
                if occupied & above[source] or unmovable >> obj & 1:
                    continue
                goal = goal_of[obj]
                has_subgoals = bool(c.subgoals_of[obj])
                for grasp in grasps_of[obj]:
                    if others & block[source][grasp]:
                        continue
                    for target in range(n_locations):
                        if target == source:
                            continue  # no move ends where it started (SPEC §5)
                        if plain >> target & 1 and (target != free_plain or plain >> source & 1):
                            continue
                        if (
                            others >> target & 1
                            or others & block[target][grasp]
                            or others & exclusive[target]
                            or not accepts[target] >> obj & 1
                        ):
                            continue
                        support = below[target]
                        if others & support != support:
                            continue
                        now_reached = c.put_down(obj, target, reached) if has_subgoals else reached
                        if now_reached < 0:
                            continue  # the order rule: parked elsewhere instead
                        moved = positions[:obj] + (target,) + positions[obj + 1 :]
                        # The key differs from the parent's in one place (and reached).
                        child = (
                            *key[:obj],
                            -1 if plain >> target & 1 else target,
                            *key[obj + 1 : -1],
                            now_reached,
                        )
                        if best_g.get(child, 1 << 60) <= g + 1:
                            continue
                        if not len(best_g) & 1023 and self.clock.expired():
                            # An expansion can take long: the clock is read as it goes.
                            return outcome(None, limit=self.clock.stop(expanded, len(best_g)))
                        best_g[child] = g + 1
                        parent[child] = (key, (obj, source, target, grasp))
                        concrete[child] = (moved, now_reached)
                        counter += 1
                        if target == goal or now_reached != reached:
                            # Productive: evaluate now, so the best of them comes first.
                            child_h = known_h.get(child)
                            if child_h is None:
                                child_h = known_h[child] = bounds.estimate(moved, now_reached)
                                if not len(known_h) & 15 and self.clock.expired():
                                    return outcome(
                                        None, limit=self.clock.stop(expanded, len(best_g))
                                    )
                            if child_h >= DEAD_END:
                                continue
                            child_h = max(child_h, h - 1)
                            if g + 1 + child_h >= limit_f:
                                continue
                            heapq.heappush(
                                heap,
                                (
                                    g + 1 + child_h,
                                    -(g + 1),
                                    child_h,
                                    (0 if waited_for >> source & 1 else _NOT_WAITED_FOR)
                                    + first.get(obj, _NO_PEEL_RANK),
                                    -counter,
                                    child,
                                    h,
                                ),
                            )
                        elif unproductive_f < limit_f:  # deferred, with the bound above
                            heapq.heappush(
                                heap, (unproductive_f, -(g + 1), _DEFERRED, 0, -counter, child, h)
                            )
        return outcome(None, exhausted=True)

    def unwind(self, key: tuple[int, ...]) -> tuple[Action, ...]:
        actions: list[Action] = []
        link = self.parent[key]
        while link is not None:
            key, (obj, source, target, grasp) = link
            actions[:0] = self.c.move_actions(obj, source, target, grasp)
            link = self.parent[key]
        return tuple(actions)
