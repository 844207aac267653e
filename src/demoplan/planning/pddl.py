"""PDDL export of a planning problem, for Fast Downward, unified-planning, pyperplan.

Two forms with one meaning, that of :mod:`demoplan.planning.strips` (docs/formats.md
and the order rule of §5). Every action costs 1 (no ``:action-costs``), so an
optimal PDDL plan has as many actions as an optimal demoplan plan, and
:func:`action_from_pddl` maps a planner's action back to the paper's
``GRASP o l g`` / ``PUT_DOWN o l g``.

**Lifted** (the default): a typed domain (``item``, ``location``, ``grip``,
``subgoal``) with the schemas ``grasp ?o ?l ?g``, ``put-down ?o ?l ?g`` and,
when there are subgoals, ``put-down-reaching ?o ?l ?g ?s``; the problem's
facts — allowed grasps, collisions, supports, exclusions, accepts, subgoals
and their order — are static facts in ``:init``. A rule over a *set* ("every
location that blocks grasp g at l is free") is not a ``forall``: Fast
Downward's translator makes a universal precondition an axiom, which its
optimal heuristic (LM-cut) refuses, as it refuses conditional effects. So
each set is one static fact listing it (:class:`_AllOf`), and the
precondition an existential over that listing, which a planner grounds over
the one listing there is. The disjunctions ("no such set, or ...") and the
negations are on static facts only, and the one universal effect has a
static condition: the translator evaluates them all while grounding, and
Fast Downward searches the same operators as on the grounded export (3440
for 20 objects either way) — from about 2 % of the text.

**Grounded** (``grounded=True``): plain STRIPS, one parameterless action
per GRASP of an object at a location with a grasp, and per PUT_DOWN likewise
(plus one variant per subgoal a PUT_DOWN can reach). Collision facts,
stacking and exclusion become plain preconditions on ``free`` / ``occupied``
atoms, so the domain needs no quantifiers, conditional effects or negative
preconditions — every STRIPS planner reads it, pyperplan included. Its
predicates keep their arguments — ``(located o l)``, ``(free l)``,
``(occupied l)``, ``(holding o g)``, ``(reached s)``, ``(pending s)``,
``(away o l)`` over the domain's constants — rather than being flattened into
one nullary atom per fact: Fast Downward's translator then finds the state
invariants (an object is at one place or held, a place is free or occupied)
at once, where with hundreds of nullary atoms its invariant synthesis runs
into its candidate limit (about 10 s even for three objects).

In both, the order rule of docs/planning.md is in the preconditions: the plain
PUT_DOWN at a place of one of the object's subgoals needs every subgoal there
reached; the variant that reaches a subgoal needs its predecessors (and the
object's earlier subgoals there) reached. So Fast Downward's plans, like
demoplan's, never put an object on its place before its predecessors.

**Roles** (identical objects, :class:`Roles`): the problem of
one binding of the model's roles (``plate#1``) to the scene's instances
(``plate-a``) would fix which instance goes where, so the export lets the
planner choose. Each type is a subtype of ``item`` holding its instances
and its roles; subgoals, their order and the goal name roles, and what is
moved is a role (an object not of such a type is its own role:
``(plays blue blue)``), by the instance that ``plays`` it — its grasps,
its size. First ``bind ?o ?r ?l ?n`` gives each instance in turn a role of
its type or itself (spare), and the role stands where the instance does
(``bind-reaching`` where standing there reaches a subgoal at the start, as
:mod:`demoplan.planning.strips` counts it); a grasp waits for the last
bind. The binds are in one fixed order, since any order gives the same
plans (and every order would multiply the search: 69 s against 4 s for
Fast Downward on the table for two). So an optimal plan has one bind per
instance of a type with roles, then as many moves as demoplan's shortest
plan over every binding (:func:`plan_from_pddl` reads it back). The
grounded form writes the same binds and moves out, one action per instance,
role it may fill (or itself), location and grasp: ``bind__plate-b__plate-1``,
``grasp__plate-b__loc2__grasp3__plate-1``.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

from demoplan.planning.compiled import Compiled, compile_problem
from demoplan.planning.problem import Action, Problem, Subgoal
from demoplan.planning.strips import Rules

__all__ = [
    "Roles",
    "action_from_pddl",
    "pddl_domain_path",
    "plan_from_pddl",
    "problem_to_pddl",
    "save_pddl",
    "save_pddl_problem",
]

_SAFE = re.compile(r"[^a-z0-9]")  # no "_": "__" separates the parts of action names
# Words a PDDL reader may take for syntax where a name stands (PDDL 1.2 to 3.1).
_RESERVED_WORDS = (
    "and or not imply exists forall when either object number at over start end all "
    "define domain problem preference always sometime within increase decrease assign "
    "minimize maximize total-time total-cost"
)
_RESERVED = frozenset(_RESERVED_WORDS.split())
# The lifted domain's own words: unified-planning's reader keeps types, predicates,
# actions and objects in one namespace, so no name of the problem may be one of them.
_LIFTED_WORDS = (
    "item location grip subgoal grasp put-down put-down-reaching handempty located free "
    "occupied holding allowed guarded guard loaded carries raised rests-on overlapping "
    "overlaps restricted accepts subgoal-of pending reached ordered after subgoal-place "
    "subgoals-at repeated revisit away"
)
_LIFTED_RESERVED = _RESERVED | frozenset(_LIFTED_WORDS.split())
# ... and, with roles, its words for binding them.
_ROLE_WORDS = (
    "bind bind-reaching plays may-play unbound bound unfilled start-reaching start-reaches "
    "turn then last"
)
_ROLES_RESERVED = _LIFTED_RESERVED | frozenset(_ROLE_WORDS.split())
_ROLE_KEY = "\0"
"""Prefixes a role's name where the problem's names are keys: apart from every instance's."""
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


def _atom(*parts: str) -> str:
    return "-".join(_SAFE.sub("-", p.lower()) for p in parts)


def _name(text: str) -> str:
    """A PDDL name from ``text``: letters, digits and "-", starting with a letter."""
    name = _atom(text) or "x"
    if not name[0].isalpha():
        name = "n" + name
    return name


@dataclass(frozen=True, slots=True)
class Roles:
    """Identical objects in a problem (docs/planning.md, "Identical objects").

    ``kinds`` gives the type of every instance of a type whose instances are
    interchangeable; ``filled`` the role (``plate#1``) each instance fills in
    ``problem`` — the problem names the instances, as under one binding of
    roles to instances — the instances of a type filling none standing spare.
    The export lets a planner choose the binding (see :func:`problem_to_pddl`).
    """

    kinds: Mapping[str, str]  # instance -> its type
    filled: Mapping[str, str]  # instance -> the role it fills in the problem

    def check(self, problem: Problem) -> None:
        """ValueError unless these roles fit ``problem``."""
        unknown = sorted(set(self.kinds) - set(problem.objects))
        untyped = sorted(set(self.filled) - set(self.kinds))
        if unknown or untyped:
            raise ValueError(f"roles name {unknown or untyped}, not typed objects of the problem")
        if len(set(self.filled.values())) != len(self.filled):
            raise ValueError("two instances fill one role")
        named = {s.object for s in problem.subgoals} | {o for o, _ in problem.goal}
        spare = sorted(o for o in named & set(self.kinds) if o not in self.filled)
        if spare:
            raise ValueError(f"{spare} have goals but fill no role")

    def rebind(self, problem: Problem, binding: Mapping[str, str]) -> Problem:
        """``problem`` with the instances of ``binding`` (role → instance, a
        role for every filled instance) in the roles, as demoplan plans it
        under that binding."""
        self.check(problem)
        instance = {o: binding[role] for o, role in self.filled.items()}
        if sorted(instance.values()) != sorted(set(instance.values())) or any(
            self.kinds.get(new) != self.kinds[old] for old, new in instance.items()
        ):
            raise ValueError(
                f"{dict(binding)} is not a binding of roles to instances of their types"
            )
        subgoals = tuple(
            Subgoal(s.id, instance.get(s.object, s.object), s.location) for s in problem.subgoals
        )
        goal = tuple((instance.get(o, o), loc) for o, loc in problem.goal)
        return replace(problem, subgoals=subgoals, goal=goal)


def problem_to_pddl(
    problem: Problem, *, grounded: bool = False, roles: Roles | None = None
) -> tuple[str, str]:
    """``(domain, problem)`` PDDL texts for ``problem``: a lifted domain with the
    problem's facts in ``:init``, or with ``grounded`` the grounded STRIPS export.

    With ``roles`` (identical objects), the lifted export lets a planner bind
    the roles to the instances: ``bind`` actions first give every instance of
    a type a role (or itself: spare), then the moves are of roles; an optimal
    plan has one ``bind`` per instance of a type with roles and as many moves
    as the shortest demoplan plan over every binding; grounded, the same
    actions written out per instance and role it may fill."""
    if roles is not None and roles.kinds and grounded:
        return _grounded_roles_pddl(problem, _cast(problem, roles))
    if grounded:
        return _grounded_pddl(problem)
    return _lifted_pddl(problem, roles)


def _grounded_pddl(problem: Problem) -> tuple[str, str]:
    """One parameterless action per GRASP / PUT_DOWN (and per subgoal reached)."""
    c = compile_problem(problem)
    facts = _GroundedFacts(*_unique_names(problem))
    revisits = _revisits(problem, c.objects)
    domain_name = _name(f"demoplan-{problem.name}")
    actions = _grounded_actions(problem, c, facts, revisits)
    domain = _grounded_domain(problem, c, facts, domain_name, actions)
    return domain, _grounded_problem(problem, c, facts, domain_name, revisits)


def _grounded_roles_pddl(problem: Problem, cast: _Cast) -> tuple[str, str]:
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
                        _action(
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
    domain_name = _name(f"demoplan-{problem.name}")
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
        f"(define (problem {_name(problem.name)})\n"
        f"  (:domain {domain_name})\n"
        "  (:init\n" + "".join(f"    ({fact})\n" for fact in init) + "  )\n"
        "  (:goal (and\n" + "".join(f"    ({fact})\n" for fact in goal) + "  ))\n"
        ")\n"
    )
    return domain, text


def _plays(cast: _Cast, o: str, r: str) -> str:
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
    cast: _Cast, facts: _GroundedFacts, revisits: dict[str, list[str]], o: str, n: str
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
        actions.append(_action(f"bind__{names[o]}__{names[r]}", pre, add, delete))
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
                    _action(
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
    actions = [_action(base, [*pre, *(facts.reached(s.id) for s in here)], add, delete)]
    for i, s in enumerate(here):  # the same PUT_DOWN, reaching a subgoal
        before = [facts.reached(a) for a, b in sorted(problem.precedences) if b == s.id]
        earlier = [facts.reached(e.id) for e in here[:i]]
        earlier += [facts.away(o, loc)] if i else []
        actions.append(
            _action(
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
        f"(define (problem {_name(problem.name)})\n"
        f"  (:domain {domain_name})\n"
        "  (:init\n" + "".join(f"    ({fact})\n" for fact in init) + "  )\n"
        "  (:goal (and\n" + "".join(f"    ({fact})\n" for fact in goal) + "  ))\n"
        ")\n"
    )


def _action(name: str, pre: list[str], add: list[str], delete: list[str]) -> str:
    precondition = " ".join(f"({p})" for p in dict.fromkeys(pre))
    effect = " ".join([*(f"({a})" for a in add), *(f"(not ({d}))" for d in delete)])
    return (
        f"  (:action {name}\n"
        "    :parameters ()\n"
        f"    :precondition (and {precondition})\n"
        f"    :effect (and {effect}))\n"
    )


# --- the lifted export -------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class _AllOf:
    """A static set per key (a place's blockers for a grasp, a subgoal's
    predecessors, ...) whose every member must have a dynamic property ``test``.

    Fast Downward turns a universally quantified precondition into an axiom,
    which its optimal heuristic (LM-cut) refuses; so each non-empty set is one
    static fact ``(listing key... m1 ... mk)``, padded by repeating its first
    member to the problem's largest set, and marked by ``(flag key...)``. The
    precondition "not ``flag``, or some listing of the set whose members all
    have ``test``" needs only an existential, which a planner grounds over the
    one listing there is; a plan's action keeps its own parameters only.
    """

    flag: str
    listing: str
    keys: tuple[str, ...]  # the key's types
    variable: str  # prefix of the existential variables
    sets: dict[tuple[str, ...], list[str]]
    member: str = "location"  # the members' type
    test: str = "free"  # the dynamic predicate every member must satisfy

    @property
    def arity(self) -> int:
        return max((len(members) for members in self.sets.values()), default=0)

    def predicates(self, *key: str) -> list[str]:
        """The flag's and the listing's declarations (none if every set is empty)."""
        if not self.arity:
            return []
        typed = " ".join(f"{v} - {t}" for v, t in zip(key, self.keys, strict=True))
        members = " ".join(f"?m{i}" for i in range(1, self.arity + 1))
        return [f"({self.flag} {typed})", f"({self.listing} {typed} {members} - {self.member})"]

    def precondition(self, *key: str) -> list[str]:
        """Every member of ``key``'s set has ``test`` (as a list of zero or one conditions)."""
        if not self.arity:
            return []
        members = [f"?{self.variable}{i}" for i in range(1, self.arity + 1)]
        listing = f"({self.listing} {' '.join(key)} {' '.join(members)})"
        tests = " ".join(f"({self.test} {m})" for m in members)
        return [
            f"(or (not ({self.flag} {' '.join(key)})) "
            f"(exists ({' '.join(members)} - {self.member}) (and {listing} {tests})))"
        ]

    def facts(self) -> list[str]:
        """The ``:init`` facts: a flag and a listing per non-empty set."""
        facts = []
        for key, members in self.sets.items():
            if members:
                padded = [*members, *[members[0]] * (self.arity - len(members))]
                facts.append(f"{self.flag} {' '.join(key)}")
                facts.append(f"{self.listing} {' '.join((*key, *padded))}")
        return facts


@dataclass(frozen=True, slots=True)
class _Lifted:
    """What the lifted domain and problem are written from: PDDL names, the sets
    of places and subgoals each action checks, and the ``away`` bookkeeping."""

    names: dict[str, str]  # objects, locations, grasps
    subgoal_names: dict[str, str]
    guard: _AllOf  # (l, g): where another object blocks grasp g at l
    carries: _AllOf  # l: the places standing on l (free to grasp at l)
    rests_on: _AllOf  # l: the places l stands on (occupied to put down at l)
    overlaps: _AllOf  # l: the places l excludes (free to put down at l)
    order: _AllOf  # s: what must be reached before s is
    settled: _AllOf  # (o, l): o's subgoals at l (all reached for a plain put-down)
    repeated: tuple[str, ...]  # subgoals with an earlier one of their object at their place
    revisits: tuple[tuple[str, str], ...]  # (o, l) with two subgoals of o at l


def _lifted(
    problem: Problem, named: tuple[dict[str, str], dict[str, str]] | None = None
) -> _Lifted:
    names, subgoal_names = named or _unique_names(problem, _LIFTED_RESERVED)
    rank = {name: i for i, name in enumerate((*problem.locations, *problem.grasps))}

    def places(by_key: dict[tuple[str, ...], set[str]]) -> dict[tuple[str, ...], list[str]]:
        """The sets in the problem's order, in PDDL names."""
        return {
            tuple(names[k] for k in key): [names[p] for p in sorted(members, key=rank.__getitem__)]
            for key, members in sorted(by_key.items(), key=lambda item: [rank[k] for k in item[0]])
        }

    blockers: dict[tuple[str, ...], set[str]] = {}
    for la, lb, g in problem.collisions:
        if la != lb:  # "no *other* object at lb": the grasped object itself stands at la
            blockers.setdefault((la, g), set()).add(lb)
    above: dict[tuple[str, ...], set[str]] = {}
    below: dict[tuple[str, ...], set[str]] = {}
    for upper, lower in problem.supports:
        above.setdefault((lower,), set()).add(upper)
        below.setdefault((upper,), set()).add(lower)
    exclusive: dict[tuple[str, ...], set[str]] = {}
    for a, b in problem.exclusions:
        exclusive.setdefault((a,), set()).add(b)
        exclusive.setdefault((b,), set()).add(a)

    # The order rule (docs/planning.md; demoplan.planning.strips): o is put down at the place of
    # one of its subgoals only to reach the first one there not yet reached, once its
    # predecessors are (put-down-reaching), or once all of them there are (put-down).
    here: dict[tuple[str, str], list[str]] = {}
    for subgoal in problem.subgoals:
        here.setdefault((subgoal.object, subgoal.location), []).append(subgoal.id)
    after: dict[tuple[str, ...], list[str]] = {}
    repeated: list[str] = []
    for ids in here.values():
        for i, sid in enumerate(ids):
            first = sorted(a for a, b in problem.precedences if b == sid)
            after[(subgoal_names[sid],)] = [
                subgoal_names[e] for e in dict.fromkeys([*first, *ids[:i]])
            ]
            repeated += [subgoal_names[sid]] if i else []
    at_place: dict[tuple[str, ...], list[str]] = {
        (names[o], names[loc]): [subgoal_names[sid] for sid in ids]
        for (o, loc), ids in here.items()
    }
    place, grasp_at, subgoal_type = ("location",), ("location", "grip"), "subgoal"
    return _Lifted(
        names=names,
        subgoal_names=subgoal_names,
        guard=_AllOf("guarded", "guard", grasp_at, "b", places(blockers)),
        carries=_AllOf("loaded", "carries", place, "u", places(above)),
        rests_on=_AllOf("raised", "rests-on", place, "d", places(below), test="occupied"),
        overlaps=_AllOf("overlapping", "overlaps", place, "x", places(exclusive)),
        order=_AllOf("ordered", "after", ("subgoal",), "p", after, subgoal_type, "reached"),
        settled=_AllOf(
            "subgoal-place",
            "subgoals-at",
            ("item", "location"),
            "q",
            at_place,
            subgoal_type,
            "reached",
        ),
        repeated=tuple(repeated),
        # "No move ends where it started" (docs/planning.md) changes no fact, so no shortest
        # plan needs a rule for it — except where an object has two subgoals at one
        # place: putting it back there would reach the second. For those places
        # (away o l) says o has been put down elsewhere since it last stood at l.
        revisits=tuple(key for key, ids in here.items() if len(ids) > 1),
    )


@dataclass(frozen=True, slots=True)
class _Cast:
    """The lifted export with roles: ``problem`` is the one given with its
    subgoals and goal naming roles (keys :data:`_ROLE_KEY` + role, declared
    after the instances among its objects); the PDDL names of everything; and
    which subgoal a role reaches at the start by standing at a place (the
    rule of :meth:`Rules.reached_where_they_stand`, for the instance that
    will fill it)."""

    problem: Problem
    names: dict[str, str]  # objects, role keys, locations, grasps
    subgoal_names: dict[str, str]
    kinds: dict[str, str]  # instance -> type, for the types with roles
    role_kinds: dict[str, str]  # role key -> type
    kind_names: dict[str, str]  # type -> PDDL type
    starts: dict[tuple[str, str], str]  # (role key, location) -> the subgoal reached there

    def typed_objects(self) -> list[tuple[list[str], str]]:
        """Per type, its instances and its roles, in PDDL names."""
        typed = {**self.kinds, **self.role_kinds}
        return [
            ([self.names[o] for o in self.problem.objects if typed.get(o) == kind], name)
            for kind, name in self.kind_names.items()
        ]

    def predicates(self) -> list[str]:
        found = [
            "(plays ?o - item ?r - item)",
            "(may-play ?o - item ?r - item)",
            "(unbound ?o - item)",
            "(bound ?o - item)",
            "(unfilled ?r - item)",
            "(turn ?o - item)",
            "(then ?o - item ?n - item)",
            "(last ?o - item)",
        ]
        if self.starts:
            found += [
                "(start-reaching ?r - item ?l - location)",
                "(start-reaches ?r - item ?l - location ?s - subgoal)",
            ]
        return found

    def schemas(self, revisits: bool) -> list[str]:
        """``bind ?o ?r ?l ?n``: instance o, standing at l, fills role r (or r = o:
        o stands spare) and r stands at l from then on; instance n is next;
        ``bind-reaching`` the same where r standing at l counts as having
        reached subgoal s."""
        parameters = "?o - item ?r - item ?l - location ?n - item"
        pre = ["(turn ?o)", "(then ?o ?n)", "(unbound ?o)", "(unfilled ?r)", "(may-play ?o ?r)"]
        pre.append("(located ?o ?l)")
        effect = [
            "(not (turn ?o))",
            "(turn ?n)",  # added after the delete: the last instance's turn stays
            "(not (unbound ?o))",
            "(bound ?o)",
            "(not (unfilled ?r))",
            "(plays ?o ?r)",
            "(not (located ?o ?l))",
            "(located ?r ?l)",  # added after the delete: a spare stays where it stands
        ]
        if revisits:
            effect.append(_away_elsewhere("?r", "?l", "?x"))
        if not self.starts:
            return [_schema("bind", parameters, pre, effect)]
        return [
            _schema("bind", parameters, [*pre, "(not (start-reaching ?r ?l))"], effect),
            _schema(
                "bind-reaching",
                f"{parameters} ?s - subgoal",
                [*pre, "(start-reaches ?r ?l ?s)"],
                [*effect, "(reached ?s)", "(not (pending ?s))"],
            ),
        ]

    def facts(self) -> list[str]:
        """The ``:init`` facts of the binding: every object not of a type with
        roles plays itself; every instance of one is unbound and may fill the
        roles of its type, or itself."""
        names = self.names
        typed = {**self.kinds, **self.role_kinds}
        facts = [f"plays {names[o]} {names[o]}" for o in self.problem.objects if o not in typed]
        facts += [f"unbound {names[o]}" for o in self.kinds]
        # the instances are bound in turn (one order of the binds, not every one)
        order = [names[o] for o in self.kinds]
        facts.append(f"turn {order[0]}")
        facts += [f"then {o} {n}" for o, n in zip(order, [*order[1:], order[-1]], strict=True)]
        facts.append(f"last {order[-1]}")
        facts += [f"unfilled {names[r]}" for r in (*self.role_kinds, *self.kinds)]
        for o, kind in self.kinds.items():
            fills = [r for r, k in self.role_kinds.items() if k == kind]
            facts += [f"may-play {names[o]} {names[r]}" for r in (*fills, o)]
        for (r, loc), sid in self.starts.items():
            facts.append(f"start-reaching {names[r]} {names[loc]}")
            facts.append(f"start-reaches {names[r]} {names[loc]} {self.subgoal_names[sid]}")
        return facts


def _cast(problem: Problem, roles: Roles) -> _Cast:
    """The role export's view of ``problem`` (:class:`_Cast`)."""
    roles.check(problem)
    key = {o: _ROLE_KEY + roles.filled[o] for o in problem.objects if o in roles.filled}
    kinds = {o: roles.kinds[o] for o in problem.objects if o in roles.kinds}
    role_kinds = {key[o]: kinds[o] for o in key}
    renamed = replace(
        problem,
        objects=(*problem.objects, *role_kinds),
        subgoals=tuple(
            Subgoal(s.id, key.get(s.object, s.object), s.location) for s in problem.subgoals
        ),
        goal=tuple((key.get(o, o), loc) for o, loc in problem.goal),
    )
    unique = _namer(_ROLES_RESERVED)
    names = {n: unique(n) for n in (*problem.objects, *problem.locations, *problem.grasps)}
    subgoal_names = {s.id: unique(s.id) for s in problem.subgoals}
    names |= {r: unique(r.removeprefix(_ROLE_KEY)) for r in role_kinds}
    kind_names = {kind: unique(kind) for kind in dict.fromkeys(kinds.values())}
    rules = Rules(renamed)
    starts: dict[tuple[str, str], str] = {}
    for r, kind in role_kinds.items():
        for o, loc in problem.initial:
            if kinds.get(o) == kind:
                done = rules.reached_where_they_stand({r: loc}, renamed.reached)
                for sid in done - renamed.reached:  # one at most
                    starts[r, loc] = sid
    return _Cast(renamed, names, subgoal_names, kinds, role_kinds, kind_names, starts)


def _lifted_pddl(problem: Problem, roles: Roles | None = None) -> tuple[str, str]:
    """A typed domain of up to three schemas (five with roles) and a problem
    whose ``:init`` holds the facts."""
    cast = None if roles is None or not roles.kinds else _cast(problem, roles)
    if cast is None:
        lifted = _lifted(problem)
    else:
        problem = cast.problem
        lifted = _lifted(problem, (cast.names, cast.subgoal_names))
    domain_name = _name(f"demoplan-{problem.name}")
    return _lifted_domain(problem, lifted, domain_name, cast), _lifted_problem(
        problem, lifted, domain_name, cast
    )


def _lifted_predicates(problem: Problem, lifted: _Lifted, cast: _Cast | None) -> list[str]:
    """The lifted domain's predicates: the world's, the static facts' listings,
    the roles' (with ``cast``) and the subgoals'."""
    guard, carries, rests_on, overlaps = (
        lifted.guard,
        lifted.carries,
        lifted.rests_on,
        lifted.overlaps,
    )
    predicates = [
        "(handempty)",
        "(located ?o - item ?l - location)",
        "(free ?l - location)",
        "(occupied ?l - location)",
        "(holding ?o - item ?g - grip)",
        "(allowed ?o - item ?g - grip)",
        *guard.predicates("?l", "?g"),
        *carries.predicates("?l"),
        *rests_on.predicates("?l"),
        *overlaps.predicates("?l"),
    ]
    if problem.accepts:
        predicates += ["(restricted ?l - location)", "(accepts ?l - location ?o - item)"]
    if cast is not None:
        predicates += cast.predicates()
    if problem.subgoals:
        predicates += [
            "(subgoal-of ?s - subgoal ?o - item ?l - location)",
            "(pending ?s - subgoal)",
            "(reached ?s - subgoal)",
            *lifted.order.predicates("?s"),
            *lifted.settled.predicates("?o", "?l"),
        ]
    if lifted.revisits:
        predicates += [
            "(repeated ?s - subgoal)",
            "(revisit ?o - item ?l - location)",
            "(away ?o - item ?l - location)",
        ]
    return predicates


def _lifted_domain(
    problem: Problem, lifted: _Lifted, domain_name: str, cast: _Cast | None = None
) -> str:
    guard, carries, rests_on, overlaps = (
        lifted.guard,
        lifted.carries,
        lifted.rests_on,
        lifted.overlaps,
    )
    predicates = _lifted_predicates(problem, lifted, cast)
    # With roles, ?r is what is moved (a role, or an object that is its own role)
    # and ?o the instance playing it, whose grasps and size count.
    m = "?o" if cast is None else "?r"
    put_pre = ["(plays ?o ?r)"] if cast is not None else []
    put_pre += [f"(holding {m} ?g)", "(free ?l)", *guard.precondition("?l", "?g")]
    put_pre += rests_on.precondition("?l") + overlaps.precondition("?l")
    if problem.accepts:
        put_pre.append("(or (not (restricted ?l)) (accepts ?l ?o))")
    put_effect = [
        "(handempty)",
        f"(located {m} ?l)",
        "(occupied ?l)",
        "(not (free ?l))",
        f"(not (holding {m} ?g))",
    ]
    if lifted.revisits:
        put_effect += [
            _away_elsewhere(m, "?l", "?r" if cast is None else "?x"),
            f"(not (away {m} ?l))",
        ]
    parameters = "?o - item ?l - location ?g - grip"
    grasp_pre = ["(handempty)"]
    if cast is not None:  # every instance bound first (the last is bound last)
        grasp_pre += ["(exists (?z - item) (and (last ?z) (bound ?z)))", "(plays ?o ?r)"]
    grasp_pre += [f"(located {m} ?l)", "(allowed ?o ?g)"]
    grasp_pre += guard.precondition("?l", "?g") + carries.precondition("?l")
    grasp_effect = [
        "(not (handempty))",
        f"(not (located {m} ?l))",
        "(not (occupied ?l))",
        "(free ?l)",
        f"(holding {m} ?g)",
    ]
    if cast is not None:
        parameters += " ?r - item"
    schemas = [
        _schema("grasp", parameters, grasp_pre, grasp_effect),
        _schema("put-down", parameters, put_pre + lifted.settled.precondition(m, "?l"), put_effect),
    ]
    if problem.subgoals:
        reaching = [f"(subgoal-of ?s {m} ?l)", "(pending ?s)", *lifted.order.precondition("?s")]
        if lifted.revisits:
            reaching.append(f"(or (not (repeated ?s)) (away {m} ?l))")
        schemas.append(
            _schema(
                "put-down-reaching",
                f"{parameters} ?s - subgoal",
                put_pre + reaching,
                [*put_effect, "(reached ?s)", "(not (pending ?s))"],
            )
        )
    types = "item location grip subgoal"
    if cast is not None:
        schemas += cast.schemas(bool(lifted.revisits))
        types += f" - object\n    {' '.join(cast.kind_names.values())} - item"
    requirements = ":strips :typing :negative-preconditions :disjunctive-preconditions"
    requirements += " :existential-preconditions"
    if lifted.revisits:
        requirements += " :equality :conditional-effects"
    return (
        f"(define (domain {domain_name})\n"
        f"  (:requirements {requirements})\n"
        f"  (:types {types})\n"
        "  (:predicates\n"
        + "".join(f"    {p}\n" for p in predicates)
        + "  )\n"
        + "".join(schemas)
        + ")\n"
    )


def _away_elsewhere(moved: str, place: str, variable: str) -> str:
    """The effect "``moved`` is away from every place it revisits but ``place``"."""
    return (
        f"(forall ({variable} - location) (when (and (revisit {moved} {variable}) "
        f"(not (= {variable} {place}))) (away {moved} {variable})))"
    )


def _schema(name: str, parameters: str, pre: list[str], effect: list[str]) -> str:
    return (
        f"  (:action {name}\n"
        f"    :parameters ({parameters})\n"
        "    :precondition (and\n" + "".join(f"      {p}\n" for p in pre) + "    )\n"
        "    :effect (and\n" + "".join(f"      {e}\n" for e in effect) + "    ))\n"
    )


def _lifted_problem(
    problem: Problem, lifted: _Lifted, domain_name: str, cast: _Cast | None = None
) -> str:
    names, subgoal_names = lifted.names, lifted.subgoal_names
    start = Rules(problem).start()
    typed = {} if cast is None else {**cast.kinds, **cast.role_kinds}
    objects = [
        ([names[o] for o in problem.objects if o not in typed], "item"),
        *(cast.typed_objects() if cast is not None else []),
        ([names[loc] for loc in problem.locations], "location"),
        ([names[g] for g in problem.grasps], "grip"),
        ([subgoal_names[s.id] for s in problem.subgoals], "subgoal"),
    ]
    taken = set(start.at.values())
    init = ["handempty"]
    init += [f"located {names[o]} {names[loc]}" for o, loc in problem.initial]
    init += [f"{'occupied' if loc in taken else 'free'} {names[loc]}" for loc in problem.locations]
    init += sorted(f"allowed {names[o]} {names[g]}" for o, g in problem.allowed)
    for sets in (lifted.guard, lifted.carries, lifted.rests_on, lifted.overlaps):
        init += sets.facts()
    for loc in (loc for loc in problem.locations if any(la == loc for la, _ in problem.accepts)):
        init.append(f"restricted {names[loc]}")
        init += sorted(f"accepts {names[loc]} {names[o]}" for la, o in problem.accepts if la == loc)
    for s in problem.subgoals:
        sid = subgoal_names[s.id]
        init.append(f"subgoal-of {sid} {names[s.object]} {names[s.location]}")
        init.append(f"{'reached' if s.id in start.reached else 'pending'} {sid}")
    init += lifted.order.facts() + lifted.settled.facts()
    init += [f"repeated {sid}" for sid in lifted.repeated]
    for o, loc in lifted.revisits:
        init.append(f"revisit {names[o]} {names[loc]}")
        if o in start.at and start.at[o] != loc:  # a role's: when it is bound
            init.append(f"away {names[o]} {names[loc]}")
    init += [] if cast is None else cast.facts()
    goal = ["handempty", *(f"located {names[o]} {names[loc]}" for o, loc in problem.goal)]
    goal += [f"reached {subgoal_names[s.id]}" for s in problem.subgoals]
    goal += [] if cast is None else [f"bound {names[o]}" for o in cast.kinds]
    return (
        f"(define (problem {_name(problem.name)})\n"
        f"  (:domain {domain_name})\n"
        "  (:objects\n"
        + "".join(f"    {' '.join(group)} - {kind}\n" for group, kind in objects if group)
        + "  )\n"
        "  (:init\n" + "".join(f"    ({fact})\n" for fact in init) + "  )\n"
        "  (:goal (and\n" + "".join(f"    ({fact})\n" for fact in goal) + "  ))\n"
        ")\n"
    )


def _unique_names(
    problem: Problem, reserved: frozenset[str] = _RESERVED
) -> tuple[dict[str, str], dict[str, str]]:
    """PDDL-safe, distinct names for every object, location and grasp, and for
    every subgoal id (a separate namespace in demoplan, one with them in PDDL).

    PDDL is case-insensitive and allows fewer characters than demoplan, so
    ``Cup`` / ``cup`` or ``loc_1`` / ``loc-1`` get distinct names (``cup-2``);
    a name a reader could take for a keyword — or, in the lifted export, for
    one of the domain's own words — gets a prefix (``and`` → ``n-and``).
    """
    unique = _namer(reserved)
    names = {n: unique(n) for n in (*problem.objects, *problem.locations, *problem.grasps)}
    subgoal_names = {s.id: unique(s.id) for s in problem.subgoals}
    return names, subgoal_names


def _namer(reserved: frozenset[str]) -> Callable[[str], str]:
    """A function giving each name it is called with a PDDL name none before had."""
    used: set[str] = set()

    def unique(original: str) -> str:
        base = _name(original)
        if base in reserved:
            base = "n-" + base
        name, k = base, 2
        while name in used:
            name, k = f"{base}-{k}", k + 1
        used.add(name)
        return name

    return unique


def action_from_pddl(problem: Problem, name: str, roles: Roles | None = None) -> Action:
    """The demoplan action behind a PDDL action as a planner prints it: lifted,
    ``(grasp box loc264 grasp6)``, ``(put-down box freespace1 grasp6)`` or
    ``(put-down-reaching o l g s)``; grounded, ``(grasp__box__loc264__grasp6)``.
    With ``roles``, of the export with them: ``(grasp plate-a loc1 grasp3
    plate-1)`` is plate-a's GRASP (filling role plate#1); a ``bind`` is no
    action (ValueError; :func:`plan_from_pddl` reads whole plans)."""
    if roles is not None and roles.kinds:
        return _role_action(problem, name, _cast(problem, roles))
    text = name.strip("() ").lower()
    lifted = " " in text
    names = _unique_names(problem, _LIFTED_RESERVED if lifted else _RESERVED)
    reverse = {v: k for k, v in names[0].items()}
    if lifted:
        parts = text.split()
        kinds = {"grasp": ("GRASP", 4), "put-down": ("PUT_DOWN", 4)}
        kinds["put-down-reaching"] = ("PUT_DOWN", 5)
        valid = parts[0] in kinds and len(parts) == kinds[parts[0]][1]
        valid = valid and (len(parts) == 4 or parts[4] in names[1].values())
    else:
        parts = text.split("__")
        kinds = {"grasp": ("GRASP", 4), "put_down": ("PUT_DOWN", 4)}
        valid = parts[0] in kinds
    try:
        if not valid:
            raise KeyError(name)
        o, loc, g = (reverse[p] for p in parts[1:4])
    except (KeyError, ValueError):
        raise ValueError(f"{name!r} is not an action of this problem's PDDL export") from None
    return Action(kinds[parts[0]][0], o, loc, g)


def _role_action(problem: Problem, name: str, cast: _Cast) -> Action:
    text = name.strip("() ").lower()
    reverse = {v: k for k, v in cast.names.items() if not k.startswith(_ROLE_KEY)}
    if " " in text:  # lifted: (grasp o l g r), (put-down-reaching o l g r s)
        parts = text.split()
        kinds = {"grasp": ("GRASP", 5), "put-down": ("PUT_DOWN", 5)}
        kinds["put-down-reaching"] = ("PUT_DOWN", 6)
        valid = parts[0] in kinds and len(parts) == kinds[parts[0]][1]
    else:  # grounded: grasp__o__l__g[__r], put_down__o__l__g[__r][__reach__s]
        parts = text.split("__")
        kinds = {"grasp": ("GRASP", 0), "put_down": ("PUT_DOWN", 0)}
        valid = parts[0] in kinds and 4 <= len(parts) <= 7
    if valid:
        try:
            o, loc, g = (reverse[p] for p in parts[1:4])
            return Action(kinds[parts[0]][0], o, loc, g)
        except KeyError:
            pass
    raise ValueError(f"{name!r} is not an action of this problem's PDDL export")


def plan_from_pddl(
    problem: Problem, names: Sequence[str], roles: Roles | None = None
) -> tuple[list[Action], dict[str, str]]:
    """A planner's plan of the export of ``problem`` as demoplan actions, and
    the binding its ``bind`` actions chose (role → instance; empty without
    ``roles``): the plan is demoplan's for ``roles.rebind(problem, binding)``."""
    if roles is None or not roles.kinds:
        return [action_from_pddl(problem, name) for name in names], {}
    cast = _cast(problem, roles)
    reverse = {v: k for k, v in cast.names.items()}
    actions: list[Action] = []
    binding: dict[str, str] = {}
    for name in names:
        text = name.strip("() ").lower()
        parts = text.split() if " " in text else text.split("__")
        if parts[:1] in (["bind"], ["bind-reaching"]) and len(parts) >= 3:
            o, r = reverse.get(parts[1], ""), reverse.get(parts[2], "")
            if o in cast.kinds and r in cast.role_kinds:
                binding[r.removeprefix(_ROLE_KEY)] = o
            elif not (o in cast.kinds and r == o):
                raise ValueError(f"{name!r} is not a binding of this problem's PDDL export")
            continue
        actions.append(_role_action(problem, name, cast))
    return actions, binding


def save_pddl(
    problem: Problem, folder: str | Path, *, grounded: bool = False, roles: Roles | None = None
) -> tuple[Path, Path]:
    """Write ``domain.pddl`` and ``problem.pddl`` into ``folder`` (both or neither):
    lifted, or with ``grounded`` the grounded STRIPS export (see :func:`problem_to_pddl`)."""
    from demoplan.fileio import check_output_folder

    domain, problem_text = problem_to_pddl(problem, grounded=grounded, roles=roles)
    folder = Path(folder)
    check_output_folder(folder)
    paths = (folder / "domain.pddl", folder / "problem.pddl")
    _write_both(paths, (domain, problem_text))
    return paths


def save_pddl_problem(
    problem: Problem, path: str | Path, *, grounded: bool = False, roles: Roles | None = None
) -> Path:
    """Write the PDDL problem to ``path`` and its domain beside it, to
    ``<stem>-domain.pddl`` (both or neither); returns the domain's path.
    ``roles``: identical objects, bound by the planner (:func:`problem_to_pddl`)."""
    path = Path(path)
    domain, problem_text = problem_to_pddl(problem, grounded=grounded, roles=roles)
    domain_path = pddl_domain_path(path)
    _write_both((domain_path, path), (domain, problem_text))
    return domain_path


def _write_both(paths: tuple[Path, Path], texts: tuple[str, str]) -> None:
    """The domain and the problem, written both or neither (atomically)."""
    from demoplan.fileio import StagedOutputs

    with StagedOutputs() as outputs:
        for path, text in zip(paths, texts, strict=True):
            outputs.add(path, text.encode("utf-8", "backslashreplace"))


def pddl_domain_path(problem_path: str | Path) -> Path:
    """Where :func:`save_pddl_problem` puts the domain of ``problem_path``."""
    path = Path(problem_path)
    return path.with_name(f"{path.stem}-domain.pddl")
