"""An independent plan validator: the SPEC's operator semantics, read literally.

Written apart from the library's search (no shared code), so the tests can
check plans without trusting the planner's own model of the rules.
"""

from __future__ import annotations

from demoplan.planning.problem import Action, Problem


class InvalidPlanError(AssertionError):
    pass


def validate(problem: Problem, actions: list[Action] | tuple[Action, ...]) -> None:
    """Raise InvalidPlanError unless ``actions`` are applicable in turn and reach the goal."""
    at = dict(problem.initial)
    held: tuple[str, str] | None = None
    reached = set(problem.reached)
    subgoals = list(problem.subgoals)

    def occupant(location: str) -> str | None:
        return next((o for o, loc in at.items() if loc == location), None)

    def preds_done(sid: str) -> bool:
        return all(a in reached for a, b in problem.precedences if b == sid)

    # Subgoals true at the start count if their predecessors are reached too.
    counted: set[str] = set()
    progress = True
    while progress:
        progress = False
        for obj, loc in at.items():
            if obj in counted:
                continue
            for s in subgoals:
                if (
                    s.object == obj
                    and s.location == loc
                    and s.id not in reached
                    and preds_done(s.id)
                ):
                    reached.add(s.id)
                    counted.add(obj)
                    progress = True
                    break

    for step, action in enumerate(actions):
        o, loc, g = action.object, action.location, action.grasp
        where = f"step {step + 1} ({action})"
        if (o, g) not in problem.allowed:
            raise InvalidPlanError(f"{where}: grasp {g} not allowed for {o}")
        if action.kind == "GRASP":
            if held is not None:
                raise InvalidPlanError(f"{where}: hand not empty")
            if at.get(o) != loc:
                raise InvalidPlanError(f"{where}: {o} is not at {loc}")
            for la, lb, grasp in problem.collisions:
                other = occupant(lb)
                if la == loc and grasp == g and other is not None and other != o:
                    raise InvalidPlanError(f"{where}: {other} at {lb} collides")
            for upper, lower in problem.supports:
                if lower == loc and occupant(upper) is not None:
                    raise InvalidPlanError(f"{where}: {occupant(upper)} stands on it")
            del at[o]
            held = (o, g)
        elif action.kind == "PUT_DOWN":
            if held != (o, g):
                raise InvalidPlanError(f"{where}: not holding {o} with {g}")
            if occupant(loc) is not None:
                raise InvalidPlanError(f"{where}: {loc} is occupied")
            for lb, lc, grasp in problem.collisions:
                if lb == loc and grasp == g and lc != loc and occupant(lc) is not None:
                    raise InvalidPlanError(f"{where}: {occupant(lc)} at {lc} collides")
            for upper, lower in problem.supports:
                if upper == loc and occupant(lower) is None:
                    raise InvalidPlanError(f"{where}: nothing under it at {lower}")
            for a, b in problem.exclusions:
                if loc in (a, b) and occupant(b if loc == a else a) is not None:
                    raise InvalidPlanError(f"{where}: overlaps an occupied location")
            takes = {obj for place, obj in problem.accepts if place == loc}
            if takes and o not in takes:
                raise InvalidPlanError(f"{where}: {loc} does not accept {o}")
            at[o] = loc
            held = None
            for s in subgoals:
                if s.object == o and s.location == loc and s.id not in reached and preds_done(s.id):
                    reached.add(s.id)
                    break
        else:
            raise InvalidPlanError(f"{where}: unknown action")
    if held is not None:
        raise InvalidPlanError("the hand is not empty at the end")
    for obj, loc in problem.goal:
        if at.get(obj) != loc:
            raise InvalidPlanError(f"goal: {obj} ends at {at.get(obj)}, not {loc}")
    missing = {s.id for s in subgoals} - reached
    if missing:
        raise InvalidPlanError(f"subgoals never reached: {sorted(missing)}")
