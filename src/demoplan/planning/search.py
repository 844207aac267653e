"""Optimal search for GRASP / PUT_DOWN plans (paper §IV.C).

Two strategies, each one function, chosen from :data:`SEARCHES`:

- :func:`breadth_first_search` — the paper's method and our reference: BFS
  over the primitive GRASP and PUT_DOWN actions, so the first plan found is
  shortest. Exponential; for small problems and for checking the other.
- :func:`astar_search` — the default: A* over *moves* (a GRASP and the
  PUT_DOWN that follows it). Every plan alternates the two actions (the hand
  holds one object and must end empty), so a plan of k moves has 2k actions
  and shortest in moves is shortest in actions. Its heuristic is admissible
  (see :func:`_heuristic`), so A* returns a shortest plan; states are
  deduplicated on a tuple of object locations in which interchangeable
  free-space locations — mentioned by no collision, support or exclusion
  fact and no goal — are one symmetric class.

Both return a :class:`SearchOutcome`; :func:`solve` turns it into a
:class:`~demoplan.planning.problem.Plan` or raises NoPlanError (exit 3) /
LimitReachedError (exit 4).
"""

from __future__ import annotations

import heapq
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

from demoplan.errors import LimitReachedError, NoPlanError
from demoplan.graphs import find_cycle
from demoplan.planning.compiled import Compiled, compile_problem
from demoplan.planning.problem import Action, Plan, Problem

__all__ = [
    "SEARCHES",
    "Budget",
    "SearchOutcome",
    "astar_search",
    "breadth_first_search",
    "explain_unsolvable",
    "solve",
]


@dataclass(frozen=True, slots=True)
class Budget:
    """Limits of one search: expanded states and wall-clock seconds (None: no limit)."""

    max_nodes: int | None = None
    timeout: float | None = None


@dataclass(frozen=True, slots=True)
class SearchOutcome:
    """What a search found: ``actions`` (None when there is no plan or a limit hit)."""

    actions: tuple[Action, ...] | None
    expanded: int
    generated: int
    exhausted: bool  # the whole reachable space was searched without finding a plan
    limit: str | None = None  # which budget stopped the search
    bound: int = 0  # the f-bound (in actions) reached when a limit stopped A*


# BFS state: object locations (-1 for the held one), held (object, grasp, where it
# was taken from) or None, reached.
_BfsState = tuple[tuple[int, ...], tuple[int, int, int] | None, int]


DEAD_END = 1 << 40
"""Heuristic value of a state from which no plan exists."""

_Move = tuple[int, int, int, int]  # object, source, target, grasp
_DIRECT_NODES = 1000
"""States one search for a straight finish may visit (:meth:`_AStar._direct_plan`)."""
_MAX_DIRECT_DEPTH = 500  # objects; that search recurses once per move


class _OutOfNodesError(Exception):
    """The search for a straight finish ran out of states."""


class _Clock:
    def __init__(self, budget: Budget):
        self.budget = budget
        self.deadline = None if budget.timeout is None else time.monotonic() + budget.timeout

    def stop(self, expanded: int) -> str | None:
        if self.budget.max_nodes is not None and expanded >= self.budget.max_nodes:
            return f"--max-nodes {self.budget.max_nodes}"
        if self.deadline is not None and time.monotonic() > self.deadline:
            return f"--timeout {self.budget.timeout:g} s"
        return None


def breadth_first_search(problem: Problem, budget: Budget = Budget()) -> SearchOutcome:
    """The paper's breadth-first search over primitive GRASP / PUT_DOWN actions."""
    c = compile_problem(problem)
    clock = _Clock(budget)
    n_locations = len(c.locations)
    start: _BfsState = (c.start, None, c.start_reached)
    parents: dict[_BfsState, tuple[_BfsState, Action] | None] = {start: None}
    queue = deque([start])
    expanded = 0
    while queue:
        state = queue.popleft()
        positions, held, reached = state
        if held is None and _is_goal(c, positions, reached):
            return SearchOutcome(_unwind(parents, state), expanded, len(parents), False)
        limit = clock.stop(expanded)
        if limit:
            return SearchOutcome(None, expanded, len(parents), False, limit)
        expanded += 1
        occupied = 0
        for location in positions:
            if location >= 0:
                occupied |= 1 << location
        successors: list[tuple[_BfsState, Action]] = []
        if held is None:
            for obj, location in enumerate(positions):
                for grasp in c.grasps_of[obj]:
                    if c.grasp_ok(occupied, location, grasp):
                        moved = positions[:obj] + (-1,) + positions[obj + 1 :]
                        action = Action(
                            "GRASP", c.objects[obj], c.locations[location], c.grasps[grasp]
                        )
                        successors.append(((moved, (obj, grasp, location), reached), action))
        else:
            obj, grasp, source = held
            for location in range(n_locations):
                if location == source or not c.put_ok(occupied, location, grasp):
                    continue
                now_reached = c.put_down(obj, location, reached)
                if now_reached < 0:
                    continue
                placed = positions[:obj] + (location,) + positions[obj + 1 :]
                action = Action("PUT_DOWN", c.objects[obj], c.locations[location], c.grasps[grasp])
                successors.append(((placed, None, now_reached), action))
        for successor, action in successors:
            if successor not in parents:
                parents[successor] = (state, action)
                queue.append(successor)
    return SearchOutcome(None, expanded, len(parents), True)


def _is_goal(c: Compiled, positions: tuple[int, ...], reached: int) -> bool:
    if reached != c.all_subgoals:
        return False
    return all(goal < 0 or goal == at for goal, at in zip(c.goal, positions, strict=True))


def _unwind(
    parents: dict[_BfsState, tuple[_BfsState, Action] | None], state: _BfsState
) -> tuple[Action, ...]:
    actions: list[Action] = []
    link = parents[state]
    while link is not None:
        state, action = link
        actions.append(action)
        link = parents[state]
    return tuple(reversed(actions))


def astar_search(problem: Problem, budget: Budget = Budget()) -> SearchOutcome:
    """A* over moves with an admissible heuristic; returns a shortest plan."""
    return _AStar(compile_problem(problem), budget).run()


class _AStar:
    def __init__(self, c: Compiled, budget: Budget):
        self.c = c
        self.clock = _Clock(budget)
        n_locations = len(c.locations)
        self.plain_locations = [loc for loc in range(n_locations) if c.plain >> loc & 1]
        self._move_cache: dict[tuple[int, int, int], bool] = {}
        # Objects no plan can move (Compiled.never_placed): they are never moved,
        # and a state in which one of them still needs a move is a dead end.
        self.unmovable = c.never_placed()
        # States (object locations, every subgoal reached) from which the objects
        # away from their goals cannot each go straight there (see _direct_plan).
        self._no_direct: set[tuple[int, ...]] = set()
        self.parent: dict[
            tuple[int, ...], tuple[tuple[int, ...], tuple[int, int, int, int]] | None
        ] = {}

    def heuristic(self, positions: tuple[int, ...], reached: int) -> int:
        """Admissible lower bound on the moves still needed.

        Each move moves one object, so a sum of lower bounds on the moves of
        disjoint groups of objects is a lower bound. A *needy* object needs as
        many moves as it has unreached subgoals (each is reached by putting it
        down), and at least one if it is not at its final location. An *idle*
        object (needing none of its own) needs one when it is in the way: for
        each place a needy object must be grasped from or put down at, the
        idle objects that block a grasp there form a set U — when every grasp
        is blocked, some object of U must move. Pairwise disjoint sets U need
        distinct movers, so the number of such sets picked greedily (smallest
        first, disjoint from those picked) is added.
        """
        c = self.c
        total = 0
        idle = 0
        needy: list[tuple[int, int, int]] = []  # (object, location, target) pairs to check
        for obj, location in enumerate(positions):
            pending = 0
            for s in c.subgoals_of[obj]:
                if not reached >> s & 1:
                    pending += 1
                    needy.append((obj, location, c.subgoal_location[s]))
            goal = c.goal[obj]
            away = goal >= 0 and goal != location
            need = pending if pending > away else int(away)
            if need:
                if self.unmovable >> obj & 1:
                    return DEAD_END
                total += need
                if away:
                    needy.append((obj, location, goal))
            else:
                idle |= 1 << location
        if needy and self._dead_end(positions, needy):
            return DEAD_END
        extra = max(self._placement_deadlock(positions), self._pair_conflicts(positions, reached))
        total += extra
        if not idle or not needy:
            if not extra and needy:
                total += self._order_cycle(positions, reached, idle) or int(
                    reached == c.all_subgoals and positions in self._no_direct
                )
            return total
        block, above, exclusive, grasps_of = c.block, c.above, c.exclusive, c.grasps_of
        blocking_sets = []
        seen = set()
        for obj, location, target in needy:
            grasps = grasps_of[obj]
            if not grasps:
                continue
            if obj not in seen:  # grasping it where it stands
                seen.add(obj)
                union = _all_grasps_hit([block[location][g] for g in grasps], above[location], idle)
                if union:
                    blocking_sets.append(union)
            # putting it down at the target
            extra = exclusive[target] | 1 << target
            union = _all_grasps_hit([block[target][g] for g in grasps], extra, idle)
            if union:
                blocking_sets.append(union)
        if not blocking_sets:
            if not extra:
                total += self._order_cycle(positions, reached, idle) or int(
                    reached == c.all_subgoals and positions in self._no_direct
                )
            return total
        blocking_sets.sort(key=int.bit_count)
        taken = 0
        extra = 0
        for union in blocking_sets:
            if not union & taken:
                taken |= union
                extra += 1
        return total + extra

    def _direct_plan(self, positions: tuple[int, ...], nodes: int) -> list[_Move] | None:
        """Moves taking every object away from its goal straight there, one
        move each, in some order: the moves (a plan, if every subgoal is
        reached), or None if there is no such order; raises
        :class:`_OutOfNodesError` if ``nodes`` states did not settle it.

        A depth-first search over the orders with the real operator tests;
        a state shown to have no such completion is remembered in
        ``_no_direct``. The heuristic adds 1 for a remembered state when its
        other terms are just the needs (no blocking set, no extra move): a
        plan of that length would move each object away from its goal exactly
        once, straight to its goal, and no other object — such an order.
        """
        c = self.c
        goal_of, grasps_of, block, above = c.goal, c.grasps_of, c.block, c.above
        failed = self._no_direct
        left = [
            obj
            for obj, location in enumerate(positions)
            if goal_of[obj] >= 0 and goal_of[obj] != location
        ]
        occupied = 0
        for location in positions:
            occupied |= 1 << location
        budget = [nodes]

        def search(at: tuple[int, ...], occupied: int, left: list[int]) -> list[_Move] | None:
            if not left:
                return []
            if at in failed:
                return None
            if budget[0] <= 0:
                raise _OutOfNodesError
            budget[0] -= 1
            for i, obj in enumerate(left):
                source, target = at[obj], goal_of[obj]
                if occupied & above[source]:
                    continue
                others = occupied & ~(1 << source)
                for g in grasps_of[obj]:
                    if others & block[source][g] or not c.put_ok(others, target, g):
                        continue
                    moved = at[:obj] + (target,) + at[obj + 1 :]
                    rest = search(moved, others | 1 << target, left[:i] + left[i + 1 :])
                    if rest is not None:
                        return [(obj, source, target, g), *rest]
                    break  # another grasp leads to the same state
            failed.add(at)
            return None

        return search(positions, occupied, left)

    def needs(self, positions: tuple[int, ...], reached: int) -> int:
        """The sum of the objects' own needs, the first term of :meth:`heuristic`."""
        c = self.c
        total = 0
        for obj, location in enumerate(positions):
            pending = 0
            for s in c.subgoals_of[obj]:
                if not reached >> s & 1:
                    pending += 1
            goal = c.goal[obj]
            away = goal >= 0 and goal != location
            total += pending if pending > away else int(away)
        return total

    def _dead_end(self, positions: tuple[int, ...], needy: list[tuple[int, int, int]]) -> bool:
        """No plan from here: a needy object, or what stands on or around its
        target, can never be picked up again (:meth:`Compiled.frozen`)."""
        c = self.c
        frozen = c.frozen(positions)
        if not frozen:
            return False
        for obj, location, target in needy:
            if frozen >> location & 1 and location != target:
                return True
            if frozen >> target & 1 and positions[obj] != target:
                return True
            if frozen & c.exclusive[target] or all(
                frozen & c.block[target][g] for g in c.grasps_of[obj]
            ):
                return True
        return False

    def _pair_conflicts(self, positions: tuple[int, ...], reached: int) -> int:
        """Disjoint pairs of objects that cannot both reach their goals in one move each.

        For objects X and Y that each need exactly one move (source → final
        goal), X may go first only if X's move is possible with Y still at its
        source and Y's move with X already at its goal, and likewise the other
        way round; other objects can only get in the way more. When neither
        order works, X or Y moves twice: +1 per pair of a greedy matching
        (e.g. X on Y's goal and Y on X's). The second moves are those of the
        needy objects, so this bound and the deadlock bound share moves: the
        heuristic takes the larger of the two.
        """
        c = self.c
        single = [
            obj
            for obj, location in enumerate(positions)
            if c.goal[obj] >= 0
            and c.goal[obj] != location
            and c.grasps_of[obj]
            and all(reached >> s & 1 for s in c.subgoals_of[obj])
        ]
        if len(single) < 2:
            return 0
        ok = self._move_ok
        matched: set[int] = set()
        pairs = 0
        for i, x in enumerate(single):
            if x in matched:
                continue
            sx, gx = positions[x], c.goal[x]
            for y in single[i + 1 :]:
                if y in matched:
                    continue
                sy, gy = positions[y], c.goal[y]
                if (ok(x, sx, sy) and ok(y, sy, gx)) or (ok(y, sy, sx) and ok(x, sx, gy)):
                    continue
                matched |= {x, y}
                pairs += 1
                break
        return pairs

    def _order_cycle(self, positions: tuple[int, ...], reached: int, fixed: int) -> int:
        """1 if the single-move objects cannot be ordered with one move each
        while the idle objects stay where they are (at ``fixed``), else 0.

        Only used when no idle object is in the way (no blocking set) and no
        other extra move is counted: a plan as short as the rest of the
        heuristic then moves every needy object exactly as often as it needs
        and no idle object at all — the idle objects are fixed obstacles and
        supports, and each *single* object (final goal, no pending subgoal)
        makes exactly one move, source → goal. In such a plan, when X moves,
        every single object Y moved before it stands at its goal and every one
        moved after it at its source. So for each of X's grasps the places
        that forbid the move (blocking the grasp at the source, standing on
        the source, blocking the put-down, exclusive with or at the goal) give
        "Y before X" (Y's source is such a place) and "Y after X" (Y's goal
        is); a grasp forbidden by a fixed object, or by some Y both ways, is
        unusable. What every usable grasp demands is a precedence; so are the
        supports of X's goal, which must be occupied: by a fixed object, else
        by the one object starting there (it moves after X) or the one ending
        there (it moves before X) — when only one of them exists, and when
        objects with pending subgoals (which may stand anywhere) are absent.
        No usable grasp, an unsupportable goal or a cycle of precedences means
        some needy object moves twice: +1, which like the deadlock bound
        counts a needy object's second move.
        """
        c = self.c
        goal_of, grasps_of = c.goal, c.grasps_of
        single: list[int] = []
        wildcards = False
        for obj, location in enumerate(positions):
            goal = goal_of[obj]
            pending = any(not reached >> s & 1 for s in c.subgoals_of[obj])
            if pending:
                wildcards = True
            elif goal >= 0 and goal != location:
                if not grasps_of[obj]:
                    return 0  # a dead end is another bound's business
                single.append(obj)
        if not single:
            return 0
        index_at_source: dict[int, int] = {}
        index_at_goal: dict[int, int] = {}
        sources = goals = 0
        for i, obj in enumerate(single):
            index_at_source[positions[obj]] = i
            index_at_goal[goal_of[obj]] = i
            sources |= 1 << positions[obj]
            goals |= 1 << goal_of[obj]
        block, above, exclusive, below = c.block, c.above, c.exclusive, c.below
        everyone = (1 << len(single)) - 1
        before = [0] * len(single)  # i -> mask of the indices that must move before i
        for i, obj in enumerate(single):
            source, goal = positions[obj], goal_of[obj]
            must_before = must_after = 0
            if not wildcards:
                support = below[goal] & ~fixed
                while support:
                    low = support & -support
                    support ^= low
                    location = low.bit_length() - 1
                    starter = index_at_source.get(location, -1) if location != source else -1
                    ender = index_at_goal.get(location, -1)
                    if starter < 0 and ender < 0:
                        return 1  # nothing can ever hold the goal up
                    if ender < 0:
                        must_after |= 1 << starter
                    elif starter < 0:
                        must_before |= 1 << ender
            common_before = common_after = everyone
            usable = False
            for g in grasps_of[obj]:
                forbid = (
                    block[source][g] | above[source] | block[goal][g] | exclusive[goal] | 1 << goal
                )
                if forbid & fixed:
                    continue
                b = _indices(forbid & sources & ~(1 << source), index_at_source)
                a = _indices(forbid & goals & ~(1 << goal), index_at_goal)
                if b & a:
                    continue
                usable = True
                common_before &= b
                common_after &= a
            if not usable:
                return 1
            must_before |= common_before
            must_after |= common_after
            if must_before & must_after:
                return 1
            before[i] |= must_before & ~(1 << i)
            after = must_after & ~(1 << i)
            while after:
                low = after & -after
                after ^= low
                before[low.bit_length() - 1] |= 1 << i
        # Take away objects with nothing left to wait for; what stays holds a cycle.
        remaining = everyone
        changed = True
        while changed and remaining:
            changed = False
            rest = remaining
            while rest:
                low = rest & -rest
                rest ^= low
                if not before[low.bit_length() - 1] & remaining:
                    remaining ^= low
                    changed = True
        return 1 if remaining else 0

    def _move_ok(self, obj: int, source: int, obstacle: int) -> bool:
        """Can ``obj`` move from ``source`` to its goal with one other object at ``obstacle``?"""
        cache_key = (obj, source, obstacle)
        known = self._move_cache.get(cache_key)
        if known is None:
            c = self.c
            goal = c.goal[obj]
            bit = 1 << obstacle
            known = (
                obstacle != goal
                and not c.above[source] & bit
                and not c.exclusive[goal] & bit
                and any(not (c.block[source][g] | c.block[goal][g]) & bit for g in c.grasps_of[obj])
            )
            self._move_cache[cache_key] = known
        return known

    def _placement_deadlock(self, positions: tuple[int, ...]) -> int:
        """1 if the objects away from their final places cannot all be put down
        there with one move each, else 0.

        With one move each, the object put down last finds all the others at
        their goals, so one of its grasps must be free of them. Peel off
        objects that could go last until none can: the peeling order reversed
        is a feasible order, and getting stuck proves that some of these
        objects needs a second move. Idle objects are left out on purpose:
        the moves they need are counted apart (the blocking sets), and this
        bound must not count them again.
        """
        return 0 if self._peel_order(positions) is not None else 1

    def _peel_order(self, positions: tuple[int, ...]) -> list[int] | None:
        """The objects away from their final places in an order in which each
        can be put down there, one move each (last first); None if stuck."""
        c = self.c
        remaining = []
        goals = 0
        for obj, location in enumerate(positions):
            goal = c.goal[obj]
            if goal >= 0 and goal != location and c.grasps_of[obj]:
                remaining.append(obj)
                goals |= 1 << goal
        block, grasps_of, goal_of = c.block, c.grasps_of, c.goal
        peeled: list[int] = []
        while remaining:
            kept = []
            for obj in remaining:
                target = goal_of[obj]
                others = goals & ~(1 << target)  # not idle ones: their moves count apart
                if any(not block[target][g] & others for g in grasps_of[obj]):
                    goals &= ~(1 << target)
                    peeled.append(obj)
                else:
                    kept.append(obj)
            if len(kept) == len(remaining):
                return None
            remaining = kept
        return peeled

    def key(self, positions: tuple[int, ...], reached: int) -> tuple[int, ...]:
        plain = self.c.plain
        if not plain:
            return (*positions, reached)
        return (*(-1 if plain >> p & 1 else p for p in positions), reached)

    def run(self) -> SearchOutcome:
        """A* with deferred heuristic evaluation and pathmax.

        A child is queued with its parent's f — a lower bound of its own, since
        a move lowers the true distance by at most one (pathmax:
        ``h(child) ≥ h(parent) − 1``) — and its heuristic is computed only when
        it is popped; if its f then turns out larger it is queued again. Among
        equal f the deepest node comes first, and among equal depth a move of a
        needy object onto its goal (or a subgoal) before other moves, so that
        where the heuristic is exact the search walks straight to a plan whose
        length equals the root's lower bound — which proves it shortest.
        Where h is just the objects' needs, a bounded depth-first search for a
        finish with one straight move per object (:meth:`_direct_plan`) ends
        the search at once, or proves h one too low for that state.
        """
        c = self.c
        start = (c.start, c.start_reached)
        start_key = self.key(*start)
        best_g = {start_key: 0}
        known_h: dict[tuple[int, ...], int] = {}
        parent = self.parent
        parent[start_key] = None
        concrete = {start_key: start}
        # Entry: (f lower bound, -g, h or "unknown", place-first rank, -counter, key,
        # h of the parent).
        heap: list[tuple[int, int, int, int, int, tuple[int, ...], int]] = [
            (0, 0, 0, 0, 0, start_key, 0)
        ]
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
        plain, goal_of, unmovable = c.plain, c.goal, self.unmovable
        while heap:
            f, negative_g, _, _, _, key, parent_h = heapq.heappop(heap)
            g = best_g[key]
            if -negative_g != g:  # stale: the state was reached more cheaply since
                continue
            h = known_h.get(key)
            if h is None:
                h = known_h[key] = self.heuristic(*concrete[key])
            if h >= DEAD_END:
                continue
            h = max(h, parent_h - 1)  # pathmax
            if g + h > f:
                counter += 1
                heapq.heappush(heap, (g + h, negative_g, 0, 0, -counter, key, parent_h))
                continue
            positions, reached = concrete[key]
            if h == 0 and _is_goal(c, positions, reached):
                return SearchOutcome(self.unwind(key), expanded, len(best_g), False)
            if (
                reached == c.all_subgoals
                and h == self.needs(positions, reached)
                and positions not in self._no_direct
                and len(positions) < _MAX_DIRECT_DEPTH
            ):
                # Where h is just the needs, try to finish with one move per
                # object: found, it is a plan of length g + h <= f, and no plan
                # is shorter than the smallest f in the queue (A*), so it is
                # shortest; shown impossible, h grows by one (see _direct_plan).
                try:
                    direct = self._direct_plan(positions, _DIRECT_NODES)
                except _OutOfNodesError:
                    direct = []
                if direct:
                    actions = list(self.unwind(key))
                    for move in direct:
                        actions += self.c.move_actions(*move)
                    return SearchOutcome(tuple(actions), expanded, len(best_g), False)
                if direct is None:
                    h = known_h[key] = h + 1
                    if g + h > f:
                        counter += 1
                        heapq.heappush(heap, (g + h, negative_g, 0, 0, -counter, key, parent_h))
                        continue
            limit = self.clock.stop(expanded)
            if limit:
                return SearchOutcome(None, expanded, len(best_g), False, limit, 2 * bound)
            expanded += 1
            bound = max(bound, f)
            # A move that reaches no goal and no subgoal leaves every object's
            # need as it was or raises it (an object taken off its goal needs one
            # more), and h is at least the sum of the needs: such a child's f is
            # at least g + 1 + needs — one more than f when h is just the needs.
            unproductive_f = max(f, g + 1 + self.needs(positions, reached))
            # Put objects down in an order that keeps the rest placeable: the
            # reverse of the peeling order goes first among equals.
            order = self._peel_order(positions) or []
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
                        best_g[child] = g + 1
                        parent[child] = (key, (obj, source, target, grasp))
                        concrete[child] = (moved, now_reached)
                        counter += 1
                        if target == goal or now_reached != reached:
                            # Productive: evaluate now, so the best of them comes first.
                            child_h = known_h.get(child)
                            if child_h is None:
                                child_h = known_h[child] = self.heuristic(moved, now_reached)
                            if child_h >= DEAD_END:
                                continue
                            child_h = max(child_h, h - 1)
                            heapq.heappush(
                                heap,
                                (
                                    g + 1 + child_h,
                                    -(g + 1),
                                    child_h,
                                    (0 if waited_for >> source & 1 else 1 << 20)
                                    + first.get(obj, 1 << 19),
                                    -counter,
                                    child,
                                    h,
                                ),
                            )
                        else:  # deferred, with the lower bound above (and pathmax)
                            heapq.heappush(
                                heap, (unproductive_f, -(g + 1), 1 << 30, 0, -counter, child, h)
                            )
        return SearchOutcome(None, expanded, len(best_g), True)

    def unwind(self, key: tuple[int, ...]) -> tuple[Action, ...]:
        actions: list[Action] = []
        link = self.parent[key]
        while link is not None:
            key, (obj, source, target, grasp) = link
            actions[:0] = self.c.move_actions(obj, source, target, grasp)
            link = self.parent[key]
        return tuple(actions)


def _indices(mask: int, index_at: dict[int, int]) -> int:
    """The indices (as a mask) of the objects at the locations of ``mask``."""
    found = 0
    while mask:
        low = mask & -mask
        mask ^= low
        found |= 1 << index_at[low.bit_length() - 1]
    return found


def _all_grasps_hit(per_grasp: list[int], always: int, idle: int) -> int:
    """The idle places blocking a grasp, if every grasp is blocked; else 0."""
    union = 0
    for mask in per_grasp:
        hit = (mask | always) & idle
        if not hit:
            return 0
        union |= hit
    return union


SEARCHES: dict[str, Callable[[Problem, Budget], SearchOutcome]] = {
    "astar": astar_search,
    "bfs": breadth_first_search,
}


def explain_unsolvable(problem: Problem) -> list[str]:
    """Reasons, where they can be shown without search, why no plan exists."""
    c = compile_problem(problem)
    reasons = []
    finals: dict[int, int] = {}
    for obj, goal in enumerate(c.goal):
        if goal < 0:
            continue
        if goal in finals:
            first, second = c.objects[finals[goal]], c.objects[obj]
            reasons.append(f"{first} and {second} must both end at {c.locations[goal]}")
        finals[goal] = obj
    for obj, name in enumerate(c.objects):
        needs_move = (c.goal[obj] >= 0 and c.goal[obj] != c.start[obj]) or any(
            not c.start_reached >> s & 1 for s in c.subgoals_of[obj]
        )
        if needs_move and not c.grasps_of[obj]:
            reasons.append(f"{name} must move but allows no grasp")
    frozen = c.frozen(c.start)
    stuck = [c.objects[o] for o, loc in enumerate(c.start) if frozen >> loc & 1]
    must_move = [
        c.objects[o]
        for o, loc in enumerate(c.start)
        if frozen >> loc & 1
        and (
            (c.goal[o] >= 0 and c.goal[o] != loc)
            or any(not c.start_reached >> s & 1 for s in c.subgoals_of[o])
        )
    ]
    if must_move:
        reasons.append(
            f"{', '.join(must_move)} must move but can never be grasped: "
            f"{', '.join(stuck)} block every grasp of one another where they stand"
        )
    unmovable = c.never_placed()
    must_place = [
        c.objects[o]
        for o, loc in enumerate(c.start)
        if unmovable >> o & 1
        and c.grasps_of[o]
        and (c.goal[o] != loc or any(not c.start_reached >> s & 1 for s in c.subgoals_of[o]))
    ]
    if must_place:
        circle = [c.objects[o] for o in range(len(c.objects)) if unmovable >> o & 1]
        reasons.append(
            f"{', '.join(must_place)} must be put down at places where every grasp "
            f"collides with another final place of {', '.join(circle)}: "
            "the last of them put down cannot be"
        )
    for obj, goal in enumerate(c.goal):
        for other in range(obj + 1, len(c.goal)):
            place = c.goal[other]
            if goal >= 0 and place >= 0 and c.exclusive[goal] >> place & 1:
                reasons.append(
                    f"{c.objects[obj]} and {c.objects[other]} cannot both stand at their final "
                    f"places: {c.locations[goal]} and {c.locations[place]} overlap"
                )
    cycle = find_cycle(problem.precedences)
    if cycle:
        reasons.append(f"subgoals must come before themselves: {' < '.join(cycle)}")
    return reasons


def solve(
    problem: Problem,
    search: str = "astar",
    budget: Budget = Budget(),
) -> Plan:
    """A shortest plan, or NoPlanError (with the reason) / LimitReachedError."""
    if search not in SEARCHES:
        raise ValueError(f"unknown search {search!r}; one of {sorted(SEARCHES)}")
    reasons = explain_unsolvable(problem)
    if reasons:
        raise NoPlanError("no plan: " + "; ".join(reasons))
    started = time.perf_counter()
    outcome = SEARCHES[search](problem, budget)
    seconds = time.perf_counter() - started
    if outcome.actions is not None:
        return Plan(outcome.actions, outcome.expanded, outcome.generated, seconds, search)
    if outcome.limit:
        raise LimitReachedError(
            f"{outcome.limit} reached after expanding {outcome.expanded} states "
            f"({outcome.generated} generated, {seconds:.2f} s) with no plan yet"
            + (f"; every plan needs at least {outcome.bound} actions" if outcome.bound else "")
        )
    raise NoPlanError(
        f"no plan: search space exhausted after {outcome.expanded} states "
        "(every reachable arrangement tried)"
    )
