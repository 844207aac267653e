"""The paper's breadth-first search over primitive GRASP / PUT_DOWN actions
(§IV.C): the first plan found is shortest. Exponential; the reference the
other searches are checked against on small problems."""

from __future__ import annotations

from collections import deque

from demoplan.planning.budget import Clock, SearchOutcome
from demoplan.planning.compiled import Compiled, compile_problem
from demoplan.planning.problem import Action, Problem

__all__ = ["breadth_first_search"]

# BFS state: object locations (-1 for the held one), held (object, grasp, where it
# was taken from — or -1, see below) or None, reached.
_BfsState = tuple[tuple[int, ...], tuple[int, int, int] | None, int]
# The action that reached a state, as indices: (GRASP?, object, location, grasp).
# Most successors are seen before, so the Action itself is made only for the plan.
_Move = tuple[bool, int, int, int]


def breadth_first_search(
    problem: Problem, clock: Clock | None = None, compiled: Compiled | None = None
) -> SearchOutcome:
    """The paper's breadth-first search over primitive GRASP / PUT_DOWN actions
    within ``clock``'s limits (None: only the state limit; ``compiled``: the
    problem already compiled)."""
    c = compiled or compile_problem(problem)
    clock = clock or Clock()
    n_locations = len(c.locations)
    revisits = 0  # objects with two subgoals at one place
    for obj, subgoals in enumerate(c.subgoals_of):
        places = [c.subgoal_location[s] for s in subgoals]
        if len(set(places)) < len(places):
            revisits |= 1 << obj
    start: _BfsState = (c.start, None, c.start_reached)
    parents: dict[_BfsState, tuple[_BfsState, _Move] | None] = {start: None}
    queue = deque([(start, 0)])
    expanded = 0
    while queue:
        state, depth = queue.popleft()
        positions, held, reached = state
        if held is None and c.is_goal(positions, reached):
            return SearchOutcome(
                _unwind(c, parents, state), expanded, len(parents), False, bound=depth
            )
        limit = clock.stop(expanded, len(parents))
        if limit:  # every state fewer actions away was tried: no plan is shorter
            return SearchOutcome(None, expanded, len(parents), False, limit, depth, False)
        expanded += 1
        occupied = 0
        for location in positions:
            if location >= 0:
                occupied |= 1 << location
        successors: list[tuple[_BfsState, _Move]] = []
        if held is None:
            for obj, location in enumerate(positions):
                for grasp in c.grasps_of[obj]:
                    if c.grasp_ok(occupied, location, grasp):
                        moved = positions[:obj] + (-1,) + positions[obj + 1 :]
                        # Where it came from matters only to an object with two subgoals at
                        # one place: for any other, putting it back gives the state before
                        # the GRASP, already seen, so duplicate detection drops it.
                        source = location if revisits >> obj & 1 else -1
                        successors.append(
                            ((moved, (obj, grasp, source), reached), (True, obj, location, grasp))
                        )
        else:
            obj, grasp, source = held
            for location in range(n_locations):
                if location == source or not c.put_ok(occupied, location, grasp):
                    continue
                now_reached = c.put_down(obj, location, reached)
                if now_reached < 0:
                    continue
                placed = positions[:obj] + (location,) + positions[obj + 1 :]
                successors.append(((placed, None, now_reached), (False, obj, location, grasp)))
        for successor, move in successors:
            if successor not in parents:
                parents[successor] = (state, move)
                queue.append((successor, depth + 1))
    return SearchOutcome(None, expanded, len(parents), True)


def _unwind(
    c: Compiled, parents: dict[_BfsState, tuple[_BfsState, _Move] | None], state: _BfsState
) -> tuple[Action, ...]:
    actions: list[Action] = []
    link = parents[state]
    while link is not None:
        state, (grasping, obj, location, grasp) = link
        kind = "GRASP" if grasping else "PUT_DOWN"
        actions.append(Action(kind, c.objects[obj], c.locations[location], c.grasps[grasp]))
        link = parents[state]
    return tuple(reversed(actions))
