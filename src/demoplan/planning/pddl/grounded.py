"""The grounded STRIPS export: one parameterless action per GRASP and
PUT_DOWN of an object at a location with a grasp (and per subgoal a PUT_DOWN
reaches), with roles one per instance and role it may fill; every STRIPS
planner reads it, pyperplan included."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from demoplan.planning.compiled import Compiled, compile_problem
from demoplan.planning.pddl.roles import (
    Cast,
)
from demoplan.planning.pddl.syntax import (
    action_text,
    pddl_name,
    unique_names,
)
from demoplan.planning.problem import Problem
from demoplan.planning.strips import Rules

__all__ = [
    "grounded_pddl",
    "grounded_roles_pddl",
]

_GROUNDED_PREDICATES = (
    "(handempty)",
    "(located ?o ?l)",
    "(free ?l)",
    "(occupied ?l)",
    "(holding ?o ?g)",
    "(reached ?s)",
    "(pending ?s)",
    "(away ?o ?l)",
)


def grounded_pddl(problem: Problem) -> tuple[str, str]:
    """One parameterless action per GRASP / PUT_DOWN (and per subgoal reached)."""
    c = compile_problem(problem)
    facts = _GroundedFacts(*unique_names(problem))
    revisits = _revisits(problem, c.objects)
    domain_name = pddl_name(f"demoplan-{problem.name}")
    actions = _grounded_actions(problem, c, facts, revisits)
    domain = _grounded_domain(problem, c, facts, domain_name, actions)
    return domain, _grounded_problem(problem, c, facts, domain_name, revisits)


def grounded_roles_pddl(problem: Problem, cast: Cast) -> tuple[str, str]:
    """The grounded export with roles: the lifted one's binds and moves, one
    parameterless action per instance, role it may fill (or itself), and
    location, grasp (and subgoal reached)."""
    c = compile_problem(problem)  # the masks are per instance, grasp and location
    roles = cast.problem  # subgoals, their order and the goal name roles
    facts = _GroundedFacts(cast.names, cast.subgoal_names)
    revisits = _revisits(roles, roles.objects)
    grouped = list(cast.kinds)
    last = grouped[-1]
    actions: list[str] = []
    for o, n in zip(grouped, [*grouped[1:], last], strict=True):
        actions += _grounded_binds(cast, facts, revisits, o, n)
    for oi, o in enumerate(c.objects):
        kind = cast.kinds.get(o)
        fills = [o] if kind is None else [*(r for r, k in cast.role_kinds.items() if k == kind), o]
        for r in fills:
            plays = [] if kind is None else [_plays(cast, o, r)]
            for gi in c.grasps_of[oi]:
                for li, loc in enumerate(c.locations):
                    pre = ["handempty", f"bound {cast.names[last]}", *plays, facts.at(r, loc)]
                    pre += [facts.free(b) for b in _places(c, c.block[li][gi] | c.above[li])]
                    g = c.grasps[gi]
                    suffix = "" if kind is None else f"__{cast.names[r]}"
                    actions.append(
                        action_text(
                            f"grasp__{cast.names[o]}__{cast.names[loc]}__{cast.names[g]}{suffix}",
                            pre,
                            add=[facts.holding(r, g), facts.free(loc)],
                            delete=["handempty", facts.at(r, loc), facts.occupied(loc)],
                        )
                    )
                    if c.accepts[li] >> oi & 1:
                        actions += [
                            _with_role(a, suffix, plays)
                            for a in _put_downs(roles, c, facts, revisits[r], (oi, gi, li), r)
                        ]
    domain_name = pddl_name(f"demoplan-{problem.name}")
    names = cast.names
    constants = [names[n] for n in (*roles.objects, *c.locations, *problem.grasps)]
    constants += [cast.subgoal_names[s.id] for s in problem.subgoals]
    predicates = [*_GROUNDED_PREDICATES, "(plays ?o ?r)", "(unbound ?o)", "(bound ?o)"]
    predicates += ["(unfilled ?r)", "(turn ?o)"]
    domain = (
        f"(define (domain {domain_name})\n"
        "  (:requirements :strips)\n"
        "  (:constants\n" + "".join(f"    {n}\n" for n in constants) + "  )\n"
        "  (:predicates\n"
        + "".join(f"    {p}\n" for p in predicates)
        + "  )\n"
        + "".join(actions)
        + ")\n"
    )
    start = Rules(roles).start()
    taken = {loc for _, loc in problem.initial}
    init = ["handempty", *(facts.at(o, loc) for o, loc in problem.initial)]
    init += [facts.occupied(loc) if loc in taken else facts.free(loc) for loc in c.locations]
    init += [facts.away(o, p) for o in start.at for p in revisits[o] if start.at[o] != p]
    init += [
        facts.reached(s.id) if s.id in start.reached else facts.pending(s.id)
        for s in roles.subgoals
    ]
    init += [f"unbound {names[o]}" for o in grouped]
    init += [f"unfilled {names[r]}" for r in (*cast.role_kinds, *grouped)]
    init.append(f"turn {names[grouped[0]]}")
    goal = ["handempty", *(facts.at(o, loc) for o, loc in roles.goal)]
    goal += [facts.reached(s.id) for s in roles.subgoals]
    goal += [f"bound {names[o]}" for o in grouped]
    text = (
        f"(define (problem {pddl_name(problem.name)})\n"
        f"  (:domain {domain_name})\n"
        "  (:init\n" + "".join(f"    ({fact})\n" for fact in init) + "  )\n"
        "  (:goal (and\n" + "".join(f"    ({fact})\n" for fact in goal) + "  ))\n"
        ")\n"
    )
    return domain, text


def _plays(cast: Cast, o: str, r: str) -> str:
    return f"plays {cast.names[o]} {cast.names[r]}"


def _with_role(action: str, suffix: str, plays: list[str]) -> str:
    """A grounded put-down of :func:`_put_downs` named with its role and
    needing the instance to play it."""
    if not suffix:
        return action
    head, rest = action.split("\n", 1)
    name = head.removeprefix("  (:action ")
    base, _, reach = name.partition("__reach__")
    named = f"  (:action {base}{suffix}" + (f"__reach__{reach}" if reach else "")
    return (
        named + "\n" + rest.replace(":precondition (and ", f":precondition (and ({plays[0]}) ", 1)
    )


def _grounded_binds(
    cast: Cast, facts: _GroundedFacts, revisits: dict[str, list[str]], o: str, n: str
) -> list[str]:
    """Instance o, standing at its start, fills each role of its type, or
    itself (spare); then n's turn."""
    names = cast.names
    start = dict(cast.problem.initial)[o]
    kind = cast.kinds[o]
    actions = []
    for r in [*(r for r, k in cast.role_kinds.items() if k == kind), o]:
        pre = [f"turn {names[o]}", f"unbound {names[o]}", f"unfilled {names[r]}"]
        pre.append(facts.at(o, start))
        add = [f"bound {names[o]}", _plays(cast, o, r), facts.at(r, start)]
        add += [f"turn {names[n]}"] if n != o else []
        add += [facts.away(r, p) for p in revisits.get(r, []) if p != start]
        delete = [f"unbound {names[o]}", f"unfilled {names[r]}"]
        delete += [f"turn {names[o]}"] if n != o else []
        delete += [facts.at(o, start)] if r != o else []
        reached = cast.starts.get((r, start))
        if reached is not None:
            add.append(facts.reached(reached))
            delete.append(facts.pending(reached))
        actions.append(action_text(f"bind__{names[o]}__{names[r]}", pre, add, delete))
    return actions


@dataclass(frozen=True, slots=True)
class _GroundedFacts:
    """The grounded export's facts, written with the PDDL names of things."""

    names: dict[str, str]  # object, location or grasp -> its PDDL name
    subgoal_names: dict[str, str]  # subgoal id -> its PDDL name

    def at(self, o: str, loc: str) -> str:
        return f"located {self.names[o]} {self.names[loc]}"

    def free(self, loc: str) -> str:
        return f"free {self.names[loc]}"

    def occupied(self, loc: str) -> str:
        return f"occupied {self.names[loc]}"

    def holding(self, o: str, g: str) -> str:
        return f"holding {self.names[o]} {self.names[g]}"

    def reached(self, sid: str) -> str:
        return f"reached {self.subgoal_names[sid]}"

    def pending(self, sid: str) -> str:
        return f"pending {self.subgoal_names[sid]}"

    def away(self, o: str, loc: str) -> str:
        return f"away {self.names[o]} {self.names[loc]}"


def _revisits(problem: Problem, objects: Sequence[str]) -> dict[str, list[str]]:
    """Per object, the places where it has two subgoals or more.

    "No move ends where it started" (docs/planning.md) changes no fact, so no
    shortest plan needs a rule for it — except where an object has two
    subgoals at one place: putting it back there would reach the second. For
    those places (away o l) says o has been put down elsewhere since it last
    stood at l."""
    revisits: dict[str, list[str]] = {}
    for o in objects:
        places = [s.location for s in problem.subgoals if s.object == o]
        revisits[o] = sorted({p for p in places if places.count(p) > 1})
    return revisits


def _grounded_actions(
    problem: Problem, c: Compiled, facts: _GroundedFacts, revisits: dict[str, list[str]]
) -> list[str]:
    """Every GRASP of an object with a grasp it allows at a location, and the
    PUT_DOWNs that go with it."""
    names, locations = facts.names, c.locations
    actions: list[str] = []
    for oi, o in enumerate(c.objects):
        for gi in c.grasps_of[oi]:
            g = c.grasps[gi]
            for li, loc in enumerate(locations):
                pre = ["handempty", facts.at(o, loc)]
                pre += [facts.free(b) for b in _places(c, c.block[li][gi] | c.above[li])]
                actions.append(
                    action_text(
                        f"grasp__{names[o]}__{names[loc]}__{names[g]}",
                        pre,
                        add=[facts.holding(o, g), facts.free(loc)],
                        delete=["handempty", facts.at(o, loc), facts.occupied(loc)],
                    )
                )
                if c.accepts[li] >> oi & 1:  # else this location does not take o
                    actions += _put_downs(problem, c, facts, revisits[o], (oi, gi, li))
    return actions


def _put_downs(
    problem: Problem,
    c: Compiled,
    facts: _GroundedFacts,
    revisits: list[str],
    move: tuple[int, int, int],
    role: str | None = None,
) -> list[str]:
    """The PUT_DOWN of ``move`` (object, grasp, location indices): a plain one,
    and one per subgoal of the object at that place that it reaches
    (``role``: of the role the object fills, which the facts are of)."""
    oi, gi, li = move
    g, loc = c.grasps[gi], c.locations[li]
    o = c.objects[oi] if role is None else role
    names = facts.names
    pre = [facts.holding(o, g), facts.free(loc)]
    pre += [facts.free(b) for b in _places(c, c.block[li][gi] | c.exclusive[li])]
    pre += [facts.occupied(b) for b in _places(c, c.below[li])]
    add = ["handempty", facts.at(o, loc), facts.occupied(loc)]
    add += [facts.away(o, p) for p in revisits if p != loc]
    delete = [facts.holding(o, g), facts.free(loc)]
    delete += [facts.away(o, loc)] if loc in revisits else []
    base = f"put_down__{names[c.objects[oi]]}__{names[loc]}__{names[g]}"
    # The order rule (docs/planning.md): o is put down at the place of a subgoal
    # only to reach it — the first one there not yet reached, once its
    # predecessors are — or once all of them there are reached.
    here = [s for s in problem.subgoals if s.object == o and s.location == loc]
    actions = [action_text(base, [*pre, *(facts.reached(s.id) for s in here)], add, delete)]
    for i, s in enumerate(here):  # the same PUT_DOWN, reaching a subgoal
        before = [facts.reached(a) for a, b in sorted(problem.precedences) if b == s.id]
        earlier = [facts.reached(e.id) for e in here[:i]]
        earlier += [facts.away(o, loc)] if i else []
        actions.append(
            action_text(
                f"{base}__reach__{facts.subgoal_names[s.id]}",
                [*pre, facts.pending(s.id), *earlier, *before],
                [*add, facts.reached(s.id)],
                [*delete, facts.pending(s.id)],
            )
        )
    return actions


def _places(c: Compiled, bits: int) -> list[str]:
    """The locations of the mask ``bits``."""
    return [c.locations[i] for i in range(len(c.locations)) if bits >> i & 1]


def _grounded_domain(
    problem: Problem, c: Compiled, facts: _GroundedFacts, domain_name: str, actions: list[str]
) -> str:
    """The grounded domain: every name a constant, and the ``actions``."""
    names = facts.names
    constants = [names[n] for n in (*c.objects, *c.locations, *problem.grasps)]
    constants += [facts.subgoal_names[s.id] for s in problem.subgoals]
    return (
        f"(define (domain {domain_name})\n"
        "  (:requirements :strips)\n"
        "  (:constants\n" + "".join(f"    {n}\n" for n in constants) + "  )\n"
        "  (:predicates\n"
        + "".join(f"    {p}\n" for p in _GROUNDED_PREDICATES)
        + "  )\n"
        + "".join(actions)
        + ")\n"
    )


def _grounded_problem(
    problem: Problem,
    c: Compiled,
    facts: _GroundedFacts,
    domain_name: str,
    revisits: dict[str, list[str]],
) -> str:
    """The grounded problem: the start's facts and the goal's."""
    taken = {loc for _, loc in problem.initial}
    init = ["handempty"]
    init += [facts.at(o, loc) for o, loc in problem.initial]
    init += [facts.occupied(loc) if loc in taken else facts.free(loc) for loc in c.locations]
    start = dict(problem.initial)
    init += [facts.away(o, p) for o in c.objects for p in revisits[o] if start[o] != p]
    for i, s in enumerate(problem.subgoals):
        init.append(facts.reached(s.id) if c.start_reached >> i & 1 else facts.pending(s.id))
    goal = ["handempty", *(facts.at(o, loc) for o, loc in problem.goal)]
    goal += [facts.reached(s.id) for s in problem.subgoals]
    return (
        f"(define (problem {pddl_name(problem.name)})\n"
        f"  (:domain {domain_name})\n"
        "  (:init\n" + "".join(f"    ({fact})\n" for fact in init) + "  )\n"
        "  (:goal (and\n" + "".join(f"    ({fact})\n" for fact in goal) + "  ))\n"
        ")\n"
    )
