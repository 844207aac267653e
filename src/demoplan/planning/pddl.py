"""PDDL export of a planning problem, for Fast Downward, pyperplan and friends.

The export is *grounded STRIPS*: one parameterless action per GRASP of an
object at a location with a grasp, and per PUT_DOWN likewise (plus one
variant per subgoal a PUT_DOWN can reach). Collision facts, stacking and
exclusion become plain preconditions on ``free`` / ``occupied`` atoms, so
the domain needs no quantifiers, conditional effects or negative
preconditions — every STRIPS planner reads it, pyperplan included. Each
action costs 1 (no ``:action-costs``), so an optimal PDDL plan has as many
actions as an optimal demoplan plan; action names map back to the paper's
``GRASP o l g`` / ``PUT_DOWN o l g``.

The order rule of SPEC §5 is in the preconditions: the plain PUT_DOWN at a
place of one of the object's subgoals needs every subgoal there reached; the
variant that reaches a subgoal needs its predecessors reached. So Fast
Downward's plans, like demoplan's, never put an object on its place before
its predecessors.

The predicates keep their arguments — ``(located o l)``, ``(free l)``,
``(occupied l)``, ``(holding o g)``, ``(reached s)``, ``(pending s)``, ``(away o l)`` over the
domain's constants — rather than being flattened into one nullary atom per
fact: Fast Downward's translator then finds the state invariants (an object
is at one place or held, a place is free or occupied) at once, where with
hundreds of nullary atoms its invariant synthesis runs into its candidate
limit (about 10 s even for three objects).
"""

from __future__ import annotations

import re
from pathlib import Path

from demoplan.planning.compiled import compile_problem
from demoplan.planning.problem import Action, Problem

__all__ = ["action_from_pddl", "problem_to_pddl", "save_pddl"]

_SAFE = re.compile(r"[^a-z0-9]")  # no "_": "__" separates the parts of action names
# Words a PDDL reader may take for syntax where a name stands (PDDL 1.2 to 3.1).
_RESERVED_WORDS = (
    "and or not imply exists forall when either object number at over start end all "
    "define domain problem preference always sometime within increase decrease assign "
    "minimize maximize total-time total-cost"
)
_RESERVED = frozenset(_RESERVED_WORDS.split())
_PREDICATES = (
    "(handempty)",
    "(located ?o ?l)",
    "(free ?l)",
    "(occupied ?l)",
    "(holding ?o ?g)",
    "(reached ?s)",
    "(pending ?s)",
    "(away ?o ?l)",
)


def _atom(*parts: str) -> str:
    return "-".join(_SAFE.sub("-", p.lower()) for p in parts)


def _name(text: str) -> str:
    """A PDDL name from ``text``: letters, digits and "-", starting with a letter."""
    name = _atom(text) or "x"
    if not name[0].isalpha():
        name = "n" + name
    return name


def problem_to_pddl(problem: Problem) -> tuple[str, str]:
    """``(domain, problem)`` PDDL texts for ``problem``."""
    c = compile_problem(problem)
    names, subgoal_names = _unique_names(problem)
    locations, objects, grasps = c.locations, c.objects, c.grasps

    def at(o: str, loc: str) -> str:
        return f"located {names[o]} {names[loc]}"

    def free(loc: str) -> str:
        return f"free {names[loc]}"

    def occupied(loc: str) -> str:
        return f"occupied {names[loc]}"

    def holding(o: str, g: str) -> str:
        return f"holding {names[o]} {names[g]}"

    def reached(sid: str) -> str:
        return f"reached {subgoal_names[sid]}"

    def pending(sid: str) -> str:
        return f"pending {subgoal_names[sid]}"

    def mask(bits: int) -> list[str]:
        return [locations[i] for i in range(len(locations)) if bits >> i & 1]

    def away(o: str, loc: str) -> str:
        return f"away {names[o]} {names[loc]}"

    # "No move ends where it started" (SPEC §5) changes no fact, so no shortest
    # plan needs a rule for it — except where an object has two subgoals at one
    # place: putting it back there would reach the second. For those places
    # (away o l) says o has been put down elsewhere since it last stood at l.
    revisits: dict[str, list[str]] = {}
    for o in objects:
        places = [s.location for s in problem.subgoals if s.object == o]
        revisits[o] = sorted({p for p in places if places.count(p) > 1})

    actions: list[str] = []
    for oi, o in enumerate(objects):
        for gi in c.grasps_of[oi]:
            g = grasps[gi]
            for li, loc in enumerate(locations):
                pre = ["handempty", at(o, loc)]
                pre += [free(b) for b in mask(c.block[li][gi] | c.above[li])]
                actions.append(
                    _action(
                        f"grasp__{names[o]}__{names[loc]}__{names[g]}",
                        pre,
                        add=[holding(o, g), free(loc)],
                        delete=["handempty", at(o, loc), occupied(loc)],
                    )
                )
                if not c.accepts[li] >> oi & 1:
                    continue  # this location does not take o: no such PUT_DOWN
                pre = [holding(o, g), free(loc)]
                pre += [free(b) for b in mask(c.block[li][gi] | c.exclusive[li])]
                pre += [occupied(b) for b in mask(c.below[li])]
                add = ["handempty", at(o, loc), occupied(loc)]
                add += [away(o, p) for p in revisits[o] if p != loc]
                delete = [holding(o, g), free(loc)]
                delete += [away(o, loc)] if loc in revisits[o] else []
                base = f"put_down__{names[o]}__{names[loc]}__{names[g]}"
                # The order rule (SPEC §5): o is put down at the place of a subgoal
                # only to reach it — the first one there not yet reached, once its
                # predecessors are — or once all of them there are reached.
                here = [s for s in problem.subgoals if s.object == o and s.location == loc]
                actions.append(_action(base, [*pre, *(reached(s.id) for s in here)], add, delete))
                for i, s in enumerate(here):  # the same PUT_DOWN, reaching a subgoal
                    before = [reached(a) for a, b in sorted(problem.precedences) if b == s.id]
                    earlier = [reached(e.id) for e in here[:i]]
                    earlier += [away(o, loc)] if i else []
                    actions.append(
                        _action(
                            f"{base}__reach__{subgoal_names[s.id]}",
                            [*pre, pending(s.id), *earlier, *before],
                            [*add, reached(s.id)],
                            [*delete, pending(s.id)],
                        )
                    )
    constants = [names[n] for n in (*objects, *locations, *grasps)]
    constants += [subgoal_names[s.id] for s in problem.subgoals]
    domain_name = _name(f"demoplan-{problem.name}")
    domain = (
        f"(define (domain {domain_name})\n"
        "  (:requirements :strips)\n"
        "  (:constants\n" + "".join(f"    {n}\n" for n in constants) + "  )\n"
        "  (:predicates\n"
        + "".join(f"    {p}\n" for p in _PREDICATES)
        + "  )\n"
        + "".join(actions)
        + ")\n"
    )
    taken = {loc for _, loc in problem.initial}
    init = ["handempty"]
    init += [at(o, loc) for o, loc in problem.initial]
    init += [occupied(loc) if loc in taken else free(loc) for loc in locations]
    start = dict(problem.initial)
    init += [away(o, p) for o in objects for p in revisits[o] if start[o] != p]
    for i, s in enumerate(problem.subgoals):
        init.append(reached(s.id) if c.start_reached >> i & 1 else pending(s.id))
    goal = ["handempty", *(at(o, loc) for o, loc in problem.goal)]
    goal += [reached(s.id) for s in problem.subgoals]
    problem_text = (
        f"(define (problem {_name(problem.name)})\n"
        f"  (:domain {domain_name})\n"
        "  (:init\n" + "".join(f"    ({fact})\n" for fact in init) + "  )\n"
        "  (:goal (and\n" + "".join(f"    ({fact})\n" for fact in goal) + "  ))\n"
        ")\n"
    )
    return domain, problem_text


def _action(name: str, pre: list[str], add: list[str], delete: list[str]) -> str:
    precondition = " ".join(f"({p})" for p in dict.fromkeys(pre))
    effect = " ".join([*(f"({a})" for a in add), *(f"(not ({d}))" for d in delete)])
    return (
        f"  (:action {name}\n"
        "    :parameters ()\n"
        f"    :precondition (and {precondition})\n"
        f"    :effect (and {effect}))\n"
    )


def _unique_names(problem: Problem) -> tuple[dict[str, str], dict[str, str]]:
    """PDDL-safe, distinct names for every object, location and grasp, and for
    every subgoal id (a separate namespace in demoplan, one with them in PDDL).

    PDDL is case-insensitive and allows fewer characters than demoplan, so
    ``Cup`` / ``cup`` or ``loc_1`` / ``loc-1`` get distinct names (``cup-2``);
    a name a reader could take for a keyword gets a prefix (``and`` → ``n-and``).
    """
    used: set[str] = set()

    def unique(original: str) -> str:
        base = _name(original)
        if base in _RESERVED:
            base = "n-" + base
        name, k = base, 2
        while name in used:
            name, k = f"{base}-{k}", k + 1
        used.add(name)
        return name

    names = {n: unique(n) for n in (*problem.objects, *problem.locations, *problem.grasps)}
    subgoal_names = {s.id: unique(s.id) for s in problem.subgoals}
    return names, subgoal_names


def action_from_pddl(problem: Problem, name: str) -> Action:
    """The demoplan action behind a PDDL action name (as a planner prints it)."""
    reverse = {v: k for k, v in _unique_names(problem)[0].items()}
    parts = name.strip("() ").lower().split("__")
    kinds = {"grasp": "GRASP", "put_down": "PUT_DOWN"}
    try:
        kind, o, loc, g = kinds[parts[0]], *(reverse[p] for p in parts[1:4])
    except (KeyError, ValueError):
        raise ValueError(f"{name!r} is not an action of this problem's PDDL export") from None
    return Action(kind, o, loc, g)


def save_pddl(problem: Problem, folder: str | Path) -> tuple[Path, Path]:
    """Write ``domain.pddl`` and ``problem.pddl`` into ``folder`` (atomically)."""
    from demoplan.fileio import write_atomic

    domain, problem_text = problem_to_pddl(problem)
    folder = Path(folder)
    paths = (folder / "domain.pddl", folder / "problem.pddl")
    write_atomic(paths[0], domain)
    write_atomic(paths[1], problem_text)
    return paths
