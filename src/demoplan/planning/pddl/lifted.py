"""The lifted export: a typed domain with the schemas ``grasp``,
``put-down`` and ``put-down-reaching``, the problem's facts static facts in
``:init``, each set a rule ranges over one static fact listing it
(:class:`_AllOf`)."""

from __future__ import annotations

from dataclasses import dataclass

from demoplan.planning.pddl.roles import (
    Cast,
    Roles,
    cast_roles,
)
from demoplan.planning.pddl.syntax import (
    LIFTED_RESERVED,
    away_elsewhere,
    pddl_name,
    schema_text,
    unique_names,
)
from demoplan.planning.problem import Problem
from demoplan.planning.strips import Rules

__all__ = [
    "lifted_pddl",
]


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
    names, subgoal_names = named or unique_names(problem, LIFTED_RESERVED)
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


def lifted_pddl(problem: Problem, roles: Roles | None = None) -> tuple[str, str]:
    """A typed domain of up to three schemas (five with roles) and a problem
    whose ``:init`` holds the facts."""
    cast = None if roles is None or not roles.kinds else cast_roles(problem, roles)
    if cast is None:
        lifted = _lifted(problem)
    else:
        problem = cast.problem
        lifted = _lifted(problem, (cast.names, cast.subgoal_names))
    domain_name = pddl_name(f"demoplan-{problem.name}")
    return _lifted_domain(problem, lifted, domain_name, cast), _lifted_problem(
        problem, lifted, domain_name, cast
    )


def _lifted_predicates(problem: Problem, lifted: _Lifted, cast: Cast | None) -> list[str]:
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
    problem: Problem, lifted: _Lifted, domain_name: str, cast: Cast | None = None
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
            away_elsewhere(m, "?l", "?r" if cast is None else "?x"),
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
        schema_text("grasp", parameters, grasp_pre, grasp_effect),
        schema_text(
            "put-down", parameters, put_pre + lifted.settled.precondition(m, "?l"), put_effect
        ),
    ]
    if problem.subgoals:
        reaching = [f"(subgoal-of ?s {m} ?l)", "(pending ?s)", *lifted.order.precondition("?s")]
        if lifted.revisits:
            reaching.append(f"(or (not (repeated ?s)) (away {m} ?l))")
        schemas.append(
            schema_text(
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


def _lifted_problem(
    problem: Problem, lifted: _Lifted, domain_name: str, cast: Cast | None = None
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
        f"(define (problem {pddl_name(problem.name)})\n"
        f"  (:domain {domain_name})\n"
        "  (:objects\n"
        + "".join(f"    {' '.join(group)} - {kind}\n" for group, kind in objects if group)
        + "  )\n"
        "  (:init\n" + "".join(f"    ({fact})\n" for fact in init) + "  )\n"
        "  (:goal (and\n" + "".join(f"    ({fact})\n" for fact in goal) + "  ))\n"
        ")\n"
    )
