"""Admissible lower bounds on the moves a state still needs (A*'s heuristic).

:meth:`LowerBounds.estimate` sums bounds on disjoint groups of moves; each
part is a method of one state (object places and reached subgoals) of one
compiled problem: the objects' own needs (:meth:`~LowerBounds.needs`), idle
objects in the way (blocking sets), objects that cannot all go straight home
(:meth:`~LowerBounds.placement_deadlock`, :meth:`~LowerBounds.pair_conflicts`,
:meth:`~LowerBounds.order_cycle`) and dead ends
(:meth:`~LowerBounds.dead_end`). :meth:`~LowerBounds.direct_plan` finds, or
rules out, a finish with one straight move per object.
"""

from __future__ import annotations

from typing import NamedTuple

from demoplan.graphs import disjoint_cycles, minimum_feedback_set, strongly_connected
from demoplan.planning.compiled import Compiled

__all__ = [
    "DEAD_END",
    "DIRECT_NODES",
    "MAX_DIRECT_DEPTH",
    "MAX_EXACT_COMPONENT",
    "LowerBounds",
    "Move",
    "OutOfNodesError",
]

DEAD_END = 1 << 40
"""Heuristic value of a state from which no plan exists."""

Move = tuple[int, int, int, int]  # object, source, target, grasp
DIRECT_NODES = 1000
"""States one search for a straight finish may visit (:meth:`LowerBounds.direct_plan`)."""
MAX_DIRECT_DEPTH = 500  # objects; that search recurses once per move
MAX_EXACT_COMPONENT = 12
"""Largest precedence cycle component whose minimum feedback set is found exactly."""


class OutOfNodesError(Exception):
    """The search for a straight finish ran out of states."""


class LowerBounds:
    """The bounds of one compiled problem, with what they cache between states."""

    def __init__(self, c: Compiled):
        self.c = c
        self._move_cache: dict[tuple[int, int, int], bool] = {}
        self._mask_cache: dict[tuple[int, int], int] = {}
        self._feedback_cache: dict[tuple[tuple[int, int], ...], int] = {}
        self._hard_cache: dict[tuple[int, int], int] = {}
        # Objects no plan can move (Compiled.never_placed): they are never moved,
        # and a state in which one of them still needs a move is a dead end.
        self.unmovable = c.never_placed()
        # States (object locations, every subgoal reached) from which the objects
        # away from their goals cannot each go straight there (see direct_plan).
        self.no_direct: set[tuple[int, ...]] = set()

    def estimate(self, positions: tuple[int, ...], reached: int) -> int:
        """Admissible lower bound on the moves still needed: the larger of the
        sum over disjoint groups (:meth:`summed`) and the feedback-set bound
        (:meth:`feedback`), or :data:`DEAD_END`."""
        summed = self.summed(positions, reached)
        if summed >= DEAD_END:
            return summed
        return max(summed, self.feedback(positions, reached))

    def summed(self, positions: tuple[int, ...], reached: int) -> int:
        """Admissible lower bound on the moves still needed, summed over groups.

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
        if needy and self.dead_end(positions, needy):
            return DEAD_END
        extra = max(self.placement_deadlock(positions), self.pair_conflicts(positions, reached))
        total += extra
        if not idle or not needy:
            if not extra and needy:
                total += self.order_cycle(positions, reached, idle) or int(
                    reached == c.all_subgoals and positions in self.no_direct
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
            taken_or_overlapping = exclusive[target] | 1 << target
            union = _all_grasps_hit([block[target][g] for g in grasps], taken_or_overlapping, idle)
            if union:
                blocking_sets.append(union)
        if not blocking_sets:
            if not extra:
                total += self.order_cycle(positions, reached, idle) or int(
                    reached == c.all_subgoals and positions in self.no_direct
                )
            return total
        blocking_sets.sort(key=int.bit_count)
        taken = 0
        movers = 0
        for union in blocking_sets:
            if not union & taken:
                taken |= union
                movers += 1
        return total + movers

    def feedback(self, positions: tuple[int, ...], reached: int) -> int:
        """The needs plus the fewest extra moves that a plan's precedences force:
        a minimum feedback vertex set (the rearrangement bound of Han et al.,
        "Complexity results and fast methods for optimal tabletop rearrangement
        with overhand grasps", IJRR 2018, with grasp collisions as precedences).

        Take the objects with no pending subgoal. A *needy* one is away from
        its goal; an *idle* one is at its goal or has none. In any plan, let F
        be the needy objects moved more than once and the idle ones moved at
        all; every other needy object moves once, straight from where it is to
        its goal, and every other idle one stays. Among those, "Y before X" is
        forced when Y where it stands, or X where it ends, keeps every grasp
        of X's move from happening (it stands on X's goal, overlaps it, blocks
        every grasp at X's source or goal, or stands on X: :meth:`move_mask`),
        and "Y before X" when Y's goal holds X's goal up. An idle object that
        keeps every grasp from picking a needy object up, or from putting it
        down at its goal (:meth:`hard_mask`: true however often that object
        moves), must be in F: one move if it has no goal, two (away and back)
        if it stands at its goal. The needy objects
        outside F obey these precedences, so they contain no cycle: F holds a
        feedback vertex set of the precedence graph, and a plan makes at least
        needs + (idle objects forced into F, weighted) + (a minimum feedback
        vertex set) moves. Each strongly connected component's minimum set is
        found exactly up to :data:`MAX_EXACT_COMPONENT` objects (and cached),
        beyond that bounded below by disjoint cycles. Objects with pending
        subgoals may stand anywhere meanwhile: they add no precedence.
        """
        graph = self.precedence_graph(positions, reached)
        if graph is None:
            return self.needs(positions, reached)
        _, after, forced_objects = graph
        forced = sum(
            1 if self.c.goal[y] < 0 else 2 for y in range(len(positions)) if forced_objects >> y & 1
        )
        return self.needs(positions, reached) + forced + self._feedback_set_size(after)

    def precedence_graph(
        self, positions: tuple[int, ...], reached: int
    ) -> tuple[list[int], dict[int, list[int]], int] | None:
        """The parts of :meth:`feedback`: the needy objects, the precedences
        among them (Y -> the X that must wait for Y) and the mask of the idle
        objects forced to move; None when no object is needy."""
        c = self.c
        occupant: dict[int, int] = {}
        needy_goal: dict[int, int] = {}
        needy: list[int] = []
        occupied = goals = 0
        for obj, location in enumerate(positions):
            if any(not reached >> s & 1 for s in c.subgoals_of[obj]):
                continue
            occupant[location] = obj
            occupied |= 1 << location
            goal = c.goal[obj]
            if goal >= 0 and goal != location:
                needy.append(obj)
                needy_goal[goal] = obj
                goals |= 1 << goal
        if not needy:
            return None
        after: dict[int, list[int]] = {obj: [] for obj in needy}  # Y -> the X that wait for Y
        forced_objects = 0
        for x in needy:
            hit = self.move_mask(x, positions[x])
            hard = self.hard_mask(x, positions[x])
            standing = hit & occupied & ~(1 << positions[x])
            while standing:
                low = standing & -standing
                standing ^= low
                y = occupant[low.bit_length() - 1]
                if y in after:
                    after[y].append(x)
                elif hard & low:
                    forced_objects |= 1 << y
            ending = (hit | c.below[c.goal[x]]) & goals & ~(1 << c.goal[x])
            while ending:
                low = ending & -ending
                ending ^= low
                y = needy_goal[low.bit_length() - 1]
                if c.below[c.goal[x]] & low:
                    after[y].append(x)  # y holds x's goal up: y first
                else:
                    after[x].append(y)  # y at its goal would keep x from moving: x first
        return needy, after, forced_objects

    def hard_mask(self, obj: int, source: int) -> int:
        """The places where another object keeps every grasp from picking
        ``obj`` up at ``source``, or every grasp from putting it down at its
        goal — whatever moves ``obj`` makes in between."""
        known = self._hard_cache.get((obj, source))
        if known is None:
            c = self.c
            goal = c.goal[obj]
            pick = put = -1 if c.grasps_of[obj] else 0
            for g in c.grasps_of[obj]:
                pick &= c.block[source][g]
                put &= c.block[goal][g]
            known = pick | put | c.above[source] | c.exclusive[goal] | 1 << goal
            self._hard_cache[obj, source] = known
        return known

    def _feedback_set_size(self, after: dict[int, list[int]]) -> int:
        """The size of a minimum feedback vertex set of the digraph ``after``
        (exact per strongly connected component up to
        :data:`MAX_EXACT_COMPONENT` nodes, else a lower bound)."""
        waiting = {x for successors in after.values() for x in successors}
        in_cycles = {y: after[y] for y in waiting if after[y]}  # in and out edges
        if len(in_cycles) < 2:
            return 0
        for y in in_cycles:
            in_cycles[y] = [x for x in in_cycles[y] if x in in_cycles]
        total = 0
        for component in strongly_connected(in_cycles):
            if len(component) < 2:
                continue
            members = set(component)
            edges = tuple(
                sorted((y, x) for y in component for x in in_cycles[y] if x in members and x != y)
            )
            known = self._feedback_cache.get(edges)
            if known is None:
                if len(component) > MAX_EXACT_COMPONENT:
                    known = disjoint_cycles(
                        {y: [x for x in in_cycles[y] if x in members] for y in component}
                    )
                else:
                    known = minimum_feedback_set(component, edges)
                self._feedback_cache[edges] = known
            total += known
        return total

    def direct_plan(self, positions: tuple[int, ...], nodes: int) -> list[Move] | None:
        """Moves taking every object away from its goal straight there, one
        move each, in some order: the moves (a plan, if every subgoal is
        reached), or None if there is no such order; raises
        :class:`OutOfNodesError` if ``nodes`` states did not settle it.

        A depth-first search over the orders with the real operator tests;
        a state shown to have no such completion is remembered in
        ``_no_direct``. The heuristic adds 1 for a remembered state when its
        other terms are just the needs (no blocking set, no extra move): a
        plan of that length would move each object away from its goal exactly
        once, straight to its goal, and no other object — such an order.
        """
        c = self.c
        goal_of, grasps_of, block, above = c.goal, c.grasps_of, c.block, c.above
        failed = self.no_direct
        left = [
            obj
            for obj, location in enumerate(positions)
            if goal_of[obj] >= 0 and goal_of[obj] != location
        ]
        occupied = 0
        for location in positions:
            occupied |= 1 << location
        budget = [nodes]

        def search(at: tuple[int, ...], occupied: int, left: list[int]) -> list[Move] | None:
            if not left:
                return []
            if at in failed:
                return None
            if budget[0] <= 0:
                raise OutOfNodesError
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

    def dead_end(self, positions: tuple[int, ...], needy: list[tuple[int, int, int]]) -> bool:
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

    def pair_conflicts(self, positions: tuple[int, ...], reached: int) -> int:
        """Disjoint pairs — and longer cycles — of objects that cannot all reach
        their goals in one move each.

        For objects X and Y that each need exactly one move (source → final
        goal), X may go first only if X's move is possible with Y still at its
        source and Y's move with X already at its goal, and likewise the other
        way round; other objects can only get in the way more. When neither
        order works, X or Y moves twice: +1 per pair of a greedy matching
        (e.g. X on Y's goal and Y on X's). Among the objects left, "Y must move
        before X" where Y at its source, or X at its goal, keeps the other's
        move from happening (X on Y's goal, Y on Z's, Z on X's); each cycle of
        such precedences needs a second move of one of its members, and
        disjoint cycles distinct ones: +1 per cycle found. The second moves
        are those of the needy objects, so this bound and the deadlock bound
        share moves: the heuristic takes the larger of the two.
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
        # Only objects whose places meet the other's move can conflict: Y's source
        # or goal where X's move is hit (move_mask), or X's in Y's. Index who
        # stands or ends where, and whose move each place hits.
        order = {obj: i for i, obj in enumerate(single)}
        near: dict[int, set[int]] = {obj: set() for obj in single}
        standing: dict[int, list[int]] = {}
        for obj in single:
            standing.setdefault(positions[obj], []).append(obj)
            standing.setdefault(c.goal[obj], []).append(obj)
        for x in single:
            mask = self.move_mask(x, positions[x])
            while mask:
                low = mask & -mask
                mask ^= low
                for y in standing.get(low.bit_length() - 1, ()):
                    if y != x:
                        near[x].add(y)
                        near[y].add(x)
        ok = self.move_ok
        matched: set[int] = set()
        pairs = 0
        for x in single:
            if x in matched:
                continue
            sx, gx = positions[x], c.goal[x]
            for y in sorted(near[x], key=order.__getitem__):
                if order[y] < order[x] or y in matched:
                    continue
                sy, gy = positions[y], c.goal[y]
                if (ok(x, sx, sy) and ok(y, sy, gx)) or (ok(y, sy, sx) and ok(x, sx, gy)):
                    continue
                matched |= {x, y}
                pairs += 1
                break
        # Longer cycles among the objects left: "Y must move before X" when Y at
        # its source, or X at its goal, keeps the other's move from happening.
        before: dict[int, list[int]] = {}
        for x in single:
            if x in matched:
                continue
            for y in near[x]:
                if y not in matched and (
                    not ok(x, positions[x], positions[y]) or not ok(y, positions[y], c.goal[x])
                ):
                    before.setdefault(x, []).append(y)  # y before x
        return pairs + disjoint_cycles(before)

    def move_mask(self, obj: int, source: int) -> int:
        """The places where another object keeps ``obj`` from moving from
        ``source`` straight to its goal (:meth:`move_ok` false): its goal, what
        stands on the source or overlaps the goal, and what blocks every grasp
        at the source or the goal."""
        known = self._mask_cache.get((obj, source))
        if known is None:
            c = self.c
            goal = c.goal[obj]
            every_grasp = -1
            for g in c.grasps_of[obj]:
                every_grasp &= c.block[source][g] | c.block[goal][g]
            if not c.grasps_of[obj]:
                every_grasp = 0
            known = 1 << goal | c.above[source] | c.exclusive[goal] | every_grasp
            self._mask_cache[obj, source] = known
        return known

    def order_cycle(self, positions: tuple[int, ...], reached: int, fixed: int) -> int:
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
        found = self._single_movers(positions, reached)
        if found is None:
            return 0
        single, wildcards = found
        order = _SingleMoves.of(single, positions, self.c.goal)
        before = [0] * len(single)  # i -> mask of the indices that must move before i
        for i, obj in enumerate(single):
            demands = self._order_demands(obj, positions[obj], fixed, order, wildcards)
            if demands is None:
                return 1
            must_before, must_after = demands
            before[i] |= must_before & ~(1 << i)
            after = must_after & ~(1 << i)
            while after:
                low = after & -after
                after ^= low
                before[low.bit_length() - 1] |= 1 << i
        return 1 if _holds_cycle(before, order.everyone) else 0

    def _single_movers(
        self, positions: tuple[int, ...], reached: int
    ) -> tuple[list[int], bool] | None:
        """For :meth:`order_cycle`: the objects away from their final goals with
        no pending subgoal, and whether some object has a pending subgoal (it
        may stand anywhere); None when there is no such object, or one cannot
        be grasped (a dead end is another bound's business)."""
        c = self.c
        single: list[int] = []
        wildcards = False
        for obj, location in enumerate(positions):
            goal = c.goal[obj]
            if any(not reached >> s & 1 for s in c.subgoals_of[obj]):
                wildcards = True
            elif goal >= 0 and goal != location:
                if not c.grasps_of[obj]:
                    return None
                single.append(obj)
        return (single, wildcards) if single else None

    def _order_demands(
        self, obj: int, source: int, fixed: int, order: _SingleMoves, wildcards: bool
    ) -> tuple[int, int] | None:
        """For :meth:`order_cycle`: the single objects (masks of indices) that
        must move before and after ``obj``'s one move, from the supports of its
        goal (unless ``wildcards``) and what every usable grasp demands; None
        when they cannot be met (no usable grasp, an unsupportable goal, or an
        object needed both before and after)."""
        must_before = must_after = 0
        if not wildcards:
            supports = self._support_demands(source, self.c.goal[obj], fixed, order)
            if supports is None:
                return None
            must_before, must_after = supports
        grasps = self._grasp_demands(obj, source, fixed, order)
        if grasps is None:
            return None
        must_before |= grasps[0]
        must_after |= grasps[1]
        if must_before & must_after:
            return None
        return must_before, must_after

    def _support_demands(
        self, source: int, goal: int, fixed: int, order: _SingleMoves
    ) -> tuple[int, int] | None:
        """The single objects that must move before / after a move to ``goal``
        to hold it up: the one object ending on a support (before) or the one
        starting there (after), where only one of them exists; None when
        nothing can ever hold the goal up."""
        must_before = must_after = 0
        support = self.c.below[goal] & ~fixed
        while support:
            low = support & -support
            support ^= low
            location = low.bit_length() - 1
            starter = order.index_at_source.get(location, -1) if location != source else -1
            ender = order.index_at_goal.get(location, -1)
            if starter < 0 and ender < 0:
                return None
            if ender < 0:
                must_after |= 1 << starter
            elif starter < 0:
                must_before |= 1 << ender
        return must_before, must_after

    def _grasp_demands(
        self, obj: int, source: int, fixed: int, order: _SingleMoves
    ) -> tuple[int, int] | None:
        """The single objects that every usable grasp of ``obj``'s move needs
        moved before / after it (their sources, resp. goals, forbid the
        grasp); None when no grasp is usable (a fixed object forbids it, or a
        single object would have to move both before and after)."""
        c = self.c
        goal = c.goal[obj]
        block, above, exclusive = c.block, c.above, c.exclusive
        common_before = common_after = order.everyone
        usable = False
        for g in c.grasps_of[obj]:
            forbid = block[source][g] | above[source] | block[goal][g] | exclusive[goal] | 1 << goal
            if forbid & fixed:
                continue
            b = _indices(forbid & order.sources & ~(1 << source), order.index_at_source)
            a = _indices(forbid & order.goals & ~(1 << goal), order.index_at_goal)
            if b & a:
                continue
            usable = True
            common_before &= b
            common_after &= a
        return (common_before, common_after) if usable else None

    def move_ok(self, obj: int, source: int, obstacle: int) -> bool:
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

    def placement_deadlock(self, positions: tuple[int, ...]) -> int:
        """How many disjoint groups of the objects away from their final places
        block one another there: each group needs a second move of one of its
        members.

        A group S *blocks itself* when every grasp of each member at its goal
        collides with another member's goal. Then if each member moved once,
        the member put down last would find all the others at their goals —
        impossible; so one member of S moves twice. Disjoint such groups need
        distinct second moves, so their number is a bound. Groups are found by
        peeling off objects that could go last until none can (what is left
        blocks itself), shrinking that to a smallest self-blocking group one
        member at a time, setting it aside and peeling the rest again. Idle
        objects are left out on purpose: the moves they need are counted
        apart (the blocking sets), and this bound must not count them again.
        """
        c = self.c
        remaining = [
            obj
            for obj, location in enumerate(positions)
            if c.goal[obj] >= 0 and c.goal[obj] != location and c.grasps_of[obj]
        ]
        groups = 0
        while True:
            core = self._stuck(remaining)
            if not core:
                return groups
            for obj in list(core):
                if obj in core:
                    smaller = self._stuck([o for o in core if o != obj])
                    if smaller:
                        core = smaller
            groups += 1
            chosen = set(core)
            remaining = [obj for obj in remaining if obj not in chosen]

    def _stuck(self, objects: list[int]) -> list[int]:
        """What is left of ``objects`` after peeling (:meth:`Compiled.peel`;
        empty: all peel)."""
        return self.c.peel(objects)[1]

    def peel_order(self, positions: tuple[int, ...]) -> list[int] | None:
        """The objects away from their final places in an order in which each
        can be put down there, one move each (last first); None if stuck.
        Idle objects are left out: their moves count apart."""
        c = self.c
        away = [
            obj
            for obj, location in enumerate(positions)
            if c.goal[obj] >= 0 and c.goal[obj] != location and c.grasps_of[obj]
        ]
        peeled, stuck = c.peel(away)
        return None if stuck else peeled


class _SingleMoves(NamedTuple):
    """The single objects of :meth:`LowerBounds.order_cycle` by index: which
    index starts / ends at a location, their sources and goals as masks, and
    the mask of every index."""

    index_at_source: dict[int, int]
    index_at_goal: dict[int, int]
    sources: int
    goals: int
    everyone: int

    @classmethod
    def of(
        cls, single: list[int], positions: tuple[int, ...], goal_of: tuple[int, ...]
    ) -> _SingleMoves:
        index_at_source: dict[int, int] = {}
        index_at_goal: dict[int, int] = {}
        sources = goals = 0
        for i, obj in enumerate(single):
            index_at_source[positions[obj]] = i
            index_at_goal[goal_of[obj]] = i
            sources |= 1 << positions[obj]
            goals |= 1 << goal_of[obj]
        return cls(index_at_source, index_at_goal, sources, goals, (1 << len(single)) - 1)


def _holds_cycle(before: list[int], everyone: int) -> bool:
    """Whether the precedences ``before`` (index -> mask of the indices that
    must come first) hold a cycle: objects with nothing left to wait for are
    taken away until none is; what stays holds one."""
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
    return bool(remaining)


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
