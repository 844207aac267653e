"""A fast plan, not necessarily shortest: greedy best-first search, then shortening.

The anytime planner (:func:`demoplan.planning.search.solve`) starts with this
plan and lets A* prove it shortest, or find a shorter one, within the budget.

**Greedy best-first search** expands the state with the smallest *guidance*
(:func:`guidance`, an estimate that may overshoot — it is not a bound),
fewest moves first among equals, until it reaches the goal. Guidance counts
each needy object's own moves, plus for each the objects that must make way
(on its target, or blocking its cheapest grasp at its source and target),
twice where they stand at their own goals, plus two where the objects away
cannot all come home in some order while those at home stay put.
Only *helpful* moves are generated: the productive ones (a needy object to
its goal, or to its next subgoal once the subgoal's predecessors are
reached), and parking moves of the objects that matter — every needy object,
and every object standing on, blocking or overlapping a place a needy object
is grasped from or put down at — to the few free places that get in the way
of the fewest of those places. Like Fast Downward's lama-first (FF's helpful
actions), this is incomplete: it can miss a plan A* would find.

**Shortening**: a move is dropped where the plan stays valid without it (the
object's next move then starts where this one started), until no move can be
dropped: a parked object that could have gone straight home, an object moved
twice in a row.
"""

from __future__ import annotations

import heapq

from demoplan.planning.bounds import DEAD_END, LowerBounds, Move
from demoplan.planning.budget import Clock
from demoplan.planning.compiled import Compiled

__all__ = ["greedy_moves", "guidance", "helpful_moves", "shorten", "valid_moves"]

_PARKING_PLACES = 3
"""Free places tried per object for a helpful parking move."""

State = tuple[tuple[int, ...], int]  # object locations, reached subgoals (mask)


def greedy_moves(
    c: Compiled,
    bounds: LowerBounds,
    clock: Clock,
    *,
    weight: float | None = None,
    upper: int | None = None,
) -> list[Move] | None:
    """A plan as moves, shortened; None where the search reaches a limit of
    ``clock`` (time, expansions, states kept: read within an expansion too)
    or runs out of helpful moves.

    ``weight`` None: greedy best-first search on the guidance. A number w:
    weighted A* on g + w × guidance, for a shorter plan once one is known —
    LAMA's way of improving its first plan. ``upper``: only plans of fewer
    moves are of interest (states that need at least that many are dropped,
    by the objects' needs, a lower bound).
    """
    start: State = (c.start, c.start_reached)
    if bounds.estimate(*start) >= DEAD_END:
        return None
    scale = 0 if weight is None else 1
    factor = 1.0 if weight is None else weight
    parent: dict[State, tuple[State, Move] | None] = {start: None}
    best_g = {start: 0}
    heap = [(factor * guidance(c, *start), 0, 0, start)]
    counter = expanded = 0
    limit = upper if upper is not None else 1 << 60
    while heap:
        _, g, _, state = heapq.heappop(heap)
        if best_g[state] < g:
            continue  # reached more cheaply since
        if c.is_goal(*state):
            moves: list[Move] = []
            link = parent[state]
            while link is not None:
                state, move = link
                moves.append(move)
                link = parent[state]
            return shorten(c, moves[::-1])
        if clock.stop(expanded, len(best_g)):
            return None
        expanded += 1
        children = helpful_moves(c, *state, clock)
        if clock.expired():  # the moves may be cut short: no plan from them
            return None
        for move, child in children:
            if best_g.get(child, 1 << 60) <= g + 1:
                continue
            if upper is not None and g + 1 + bounds.needs(*child) >= limit:
                continue
            best_g[child] = g + 1
            parent[child] = (state, move)
            counter += 1
            if not counter & 7 and clock.stop(expanded, len(best_g)):
                return None  # read within an expansion: a child's guidance is O(objects)
            priority = scale * (g + 1) + factor * guidance(c, *child)
            heapq.heappush(heap, (priority, g + 1, counter, child))
    return None


def guidance(c: Compiled, positions: tuple[int, ...], reached: int) -> int:
    """An estimate of the moves left, for guidance only (not a bound): each
    needy object's own moves, plus for each the objects that must make way —
    on its target, or blocking its cheapest grasp at its source and target —
    counted twice where they stand at their own goals (they must come back),
    plus two where the objects away cannot all come home as things stand."""
    occupant = {location: obj for obj, location in enumerate(positions)}
    total = 0

    def cost_of(mask: int, mover: int) -> int:
        cost = 0
        while mask:
            low = mask & -mask
            mask ^= low
            other = occupant.get(low.bit_length() - 1)
            if other is not None and other != mover:
                cost += 2 if c.goal[other] == positions[other] else 1
        return cost

    for obj, target in _targets(c, positions, reached).items():
        pending = sum(1 for s in c.subgoals_of[obj] if not reached >> s & 1)
        total += max(pending, 1)
        if target < 0:
            continue
        source = positions[obj]
        total += cost_of(1 << target | c.exclusive[target], obj)
        total += min(
            (
                cost_of(c.block[source][g] | c.above[source], obj)
                + cost_of(c.block[target][g], obj)
                for g in c.grasps_of[obj]
            ),
            default=0,
        )
    if not _all_can_come_home(c, positions):
        total += 2
    return total


def _targets(c: Compiled, positions: tuple[int, ...], reached: int) -> dict[int, int]:
    """Where each needy object should go next: its first unreached subgoal, or
    its goal once every subgoal of it is reached (-1: it must wait for
    another object's subgoal first)."""
    wanted: dict[int, int] = {}
    for obj, location in enumerate(positions):
        pending = [s for s in c.subgoals_of[obj] if not reached >> s & 1]
        if pending:
            first = pending[0]
            ready = not c.subgoal_before[first] & ~reached
            wanted[obj] = c.subgoal_location[first] if ready else -1
        elif c.goal[obj] >= 0 and c.goal[obj] != location:
            wanted[obj] = c.goal[obj]
    return wanted


def helpful_moves(
    c: Compiled, positions: tuple[int, ...], reached: int, clock: Clock | None = None
) -> list[tuple[Move, State]]:
    """The helpful moves from a state (see the module docstring); ``clock``:
    read per mover, the moves found so far returned once its time is up (a
    thousand movers take a large part of a second; the caller then stops)."""
    occupied = 0
    for location in positions:
        occupied |= 1 << location
    wanted = _targets(c, positions, reached)
    # Places that matter: where needy objects are grasped and put down, and
    # what blocks, overlaps or stands on them.
    hot = 0
    for obj, target in wanted.items():
        source = positions[obj]
        hot |= c.above[source]
        for g in c.grasps_of[obj]:
            hot |= c.block[source][g]
            if target >= 0:
                hot |= c.block[target][g]
        if target >= 0:
            hot |= 1 << target | c.exclusive[target] | c.below[target]
    movers = set(wanted) | {obj for obj, at in enumerate(positions) if hot >> at & 1}
    # Free places, those in the way of the fewest needed places first; one
    # interchangeable free-space place stands for all of them.
    wanted_places = {target for target in wanted.values() if target >= 0}
    free = []
    plain_seen = False
    for place in range(len(c.locations)):
        if occupied >> place & 1:
            continue
        if c.plain >> place & 1:
            if plain_seen:
                continue
            plain_seen = True
        free.append(((hot >> place & 1) * 4 + (place in wanted_places) * 8, place))
    free.sort()
    productive: list[tuple[Move, State]] = []
    parking: list[tuple[Move, State]] = []
    for obj in sorted(movers):
        if clock is not None and clock.expired():
            break
        source = positions[obj]
        if occupied & c.above[source]:
            continue
        others = occupied & ~(1 << source)
        grasps = [g for g in c.grasps_of[obj] if not others & c.block[source][g]]
        target = wanted.get(obj, -1)
        if target >= 0 and target != source:
            for g in grasps:
                if c.put_ok(others, target, g):
                    now = c.put_down(obj, target, reached)
                    if now >= 0:
                        moved = positions[:obj] + (target,) + positions[obj + 1 :]
                        productive.append(((obj, source, target, g), (moved, now)))
                    break  # another grasp gives the same state
        options: list[tuple[int, int, int]] = []  # (badness, place, grasp)
        for badness, place in free:
            if len(options) >= 2 * _PARKING_PLACES:
                break
            if place == target:
                continue
            for g in grasps:
                if c.put_ok(others, place, g) and c.put_down(obj, place, reached) == reached:
                    options.append((badness + (c.block[place][g] & hot).bit_count(), place, g))
                    break
        options.sort()
        for _, place, g in options[:_PARKING_PLACES]:
            moved = positions[:obj] + (place,) + positions[obj + 1 :]
            parking.append(((obj, source, place, g), (moved, reached)))
    return productive + parking


def _all_can_come_home(c: Compiled, positions: tuple[int, ...]) -> bool:
    """Whether the objects away from their goals can be put down there one by
    one with the objects already home staying where they are: peel off an
    object that could go last — a grasp at its goal clear of every other goal
    place still to be filled and of every object already home."""
    home = 0
    away = []
    for obj, location in enumerate(positions):
        if c.goal[obj] == location:
            home |= 1 << location
        elif c.goal[obj] >= 0:
            away.append(obj)
    return not c.peel(away, fixed=home)[1]


def valid_moves(c: Compiled, moves: list[Move]) -> bool:
    """Whether ``moves`` are applicable in turn from the start and end at the goal."""
    positions = list(c.start)
    reached = c.start_reached
    occupied = 0
    for location in positions:
        occupied |= 1 << location
    for obj, source, target, grasp in moves:
        if positions[obj] != source or target == source or grasp not in c.grasps_of[obj]:
            return False
        if not c.grasp_ok(occupied, source, grasp):
            return False
        others = occupied & ~(1 << source)
        if not c.put_ok(others, target, grasp):
            return False
        reached = c.put_down(obj, target, reached)
        if reached < 0:
            return False
        positions[obj] = target
        occupied = others | 1 << target
    return c.is_goal(tuple(positions), reached)


def shorten(c: Compiled, moves: list[Move]) -> list[Move]:
    """``moves`` with every move dropped that the plan can do without: a
    move whose object's next move can start where it started (the object
    waits), or whose object's next move can be made in its place (the object
    goes straight to where that move took it — a parking skipped)."""
    plan = list(moves)
    changed = True
    while changed:
        changed = False
        for index in range(len(plan) - 1, -1, -1):
            shorter = _without(c, plan, index) or _sooner(c, plan, index)
            if shorter is not None:
                plan, changed = shorter, True
                break
    return plan


def _without(c: Compiled, plan: list[Move], index: int) -> list[Move] | None:
    """The plan without move ``index`` (the object's next move starting where
    this one started, with any grasp that works), if it is still valid."""
    obj, source, _, _ = plan[index]
    rest = plan[:index] + plan[index + 1 :]
    following = _next_move_of(rest, obj, index)
    if following is None:
        return rest if valid_moves(c, rest) else None
    _, _, target, _ = rest[following]
    if target == source:  # the next move would bring it back: drop both
        rest = rest[:following] + rest[following + 1 :]
        return rest if valid_moves(c, rest) else None
    return _with_move(c, rest, following, (obj, source, target))


def _sooner(c: Compiled, plan: list[Move], index: int) -> list[Move] | None:
    """The plan with move ``index`` going straight to where the object's next
    move takes it, and that next move dropped (with any grasp that works),
    if it is still valid. Where the next move brings it back, :func:`_without`
    has tried dropping both."""
    obj, source, _, _ = plan[index]
    following = _next_move_of(plan, obj, index + 1)
    if following is None:
        return None
    _, _, target, _ = plan[following]
    if target == source:
        return None
    rest = plan[:following] + plan[following + 1 :]
    return _with_move(c, rest, index, (obj, source, target))


def _with_move(
    c: Compiled, plan: list[Move], index: int, move: tuple[int, int, int]
) -> list[Move] | None:
    """``plan`` with move ``index`` replaced by ``move`` (object, source,
    target) with the first of its object's grasps that keeps the plan valid."""
    obj, source, target = move
    for grasp in c.grasps_of[obj]:
        patched = list(plan)
        patched[index] = (obj, source, target, grasp)
        if valid_moves(c, patched):
            return patched
    return None


def _next_move_of(plan: list[Move], obj: int, start: int) -> int | None:
    """The index of ``obj``'s first move in ``plan`` from ``start`` on, if any."""
    return next((i for i in range(start, len(plan)) if plan[i][0] == obj), None)
