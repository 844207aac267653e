"""A plan as short as the lower bound, by a depth-first dive: the phase of the
anytime planner (:func:`demoplan.planning.search.solve`) after the first
greedy plan.

When the admissible bound of the start (:mod:`demoplan.planning.bounds`) is
exact, every state of a shortest plan has f = g + h equal to it: the plan lies
on A*'s last plateau. On the parking problems that plateau holds millions of
states (every order of the parking moves, every free place to park at), and
A* ranks them all before it commits to any: in the benchmark's dense families
it found no plan within 2 s where this dive finds one in tens of milliseconds.

The dive goes depth first over the *helpful* moves of
:mod:`demoplan.planning.greedy` (an object to its goal or next subgoal, the
objects in the way to the few free places that hurt least), the children of a
state in the order of their guidance, and drops a child whose moves so far
plus its admissible bound exceed ``limit``. Each state is entered once, at
the fewest moves it was reached with. A plan it returns has at most ``limit``
moves — with ``limit`` the start's bound, it is shortest. The dive is
incomplete (helpful moves only, one child order): finding nothing proves
nothing, and the planner goes on with its other phases.
"""

from __future__ import annotations

from demoplan.planning.bounds import LowerBounds, Move
from demoplan.planning.budget import Clock
from demoplan.planning.compiled import Compiled
from demoplan.planning.greedy import State, guidance, helpful_moves

__all__ = ["plateau_moves"]

_Children = list[tuple[int, Move, State]]  # (guidance, move, state), best first


def plateau_moves(c: Compiled, bounds: LowerBounds, clock: Clock, limit: int) -> list[Move] | None:
    """Moves of a plan of at most ``limit`` moves found by the dive (module
    docstring), or None: none found before a limit of ``clock`` (time,
    expansions, states kept), or the helpful moves were exhausted."""
    start: State = (c.start, c.start_reached)
    if c.is_goal(*start):
        return []
    fewest = {start: 0}  # state -> the fewest moves it was entered with
    expanded = 0

    def children(state: State, g: int) -> _Children:
        """The children worth entering, best first (an expansion); none once a
        limit is reached — read per child, whose guidance is O(objects)."""
        nonlocal expanded
        expanded += 1
        found: _Children = []
        for move, child in helpful_moves(c, *state, clock):
            if clock.stop(expanded, len(fewest)):
                return []
            if fewest.get(child, limit + 1) <= g + 1 or g + 1 + bounds.needs(*child) > limit:
                continue
            found.append((guidance(c, *child), move, child))
        found.sort(key=lambda item: item[0])  # stable: productive moves first among equals
        return found

    path: list[Move] = []
    frames = [(children(start, 0), 0)]  # per depth: the children and the next to try
    while frames:
        candidates, next_index = frames[-1]
        if next_index == len(candidates):
            frames.pop()
            if path:
                path.pop()
            continue
        frames[-1] = (candidates, next_index + 1)
        _, move, child = candidates[next_index]
        g = len(path) + 1
        if fewest.get(child, limit + 1) <= g:
            continue  # entered since with as few moves
        fewest[child] = g
        if clock.stop(expanded, len(fewest)):
            return None
        if g + bounds.estimate(*child) > limit:
            continue
        path.append(move)
        if c.is_goal(*child):
            return path
        frames.append((children(child, g), 0))
    return None
