"""Identical objects in the PDDL export: the model's roles of a type and the
scene's instances that may play them (:class:`Roles`), cast into PDDL names
and the binding actions (:class:`Cast`)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace

from demoplan.planning.pddl.syntax import (
    LIFTED_RESERVED,
    away_elsewhere,
    namer,
    schema_text,
)
from demoplan.planning.problem import Problem, Subgoal
from demoplan.planning.strips import Rules

__all__ = [
    "ROLES_RESERVED",
    "ROLE_KEY",
    "Cast",
    "Roles",
    "cast_roles",
]

# The words of the lifted domain with roles for binding them (syntax.LIFTED_RESERVED).
_ROLE_WORDS = (
    "bind bind-reaching plays may-play unbound bound unfilled start-reaching start-reaches "
    "turn then last"
)
ROLES_RESERVED = LIFTED_RESERVED | frozenset(_ROLE_WORDS.split())
ROLE_KEY = "\0"
"""Prefixes a role's name where the problem's names are keys: apart from every instance's."""


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


@dataclass(frozen=True, slots=True)
class Cast:
    """The lifted export with roles: ``problem`` is the one given with its
    subgoals and goal naming roles (keys :data:`ROLE_KEY` + role, declared
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
            effect.append(away_elsewhere("?r", "?l", "?x"))
        if not self.starts:
            return [schema_text("bind", parameters, pre, effect)]
        return [
            schema_text("bind", parameters, [*pre, "(not (start-reaching ?r ?l))"], effect),
            schema_text(
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


def cast_roles(problem: Problem, roles: Roles) -> Cast:
    """The role export's view of ``problem`` (:class:`Cast`)."""
    roles.check(problem)
    key = {o: ROLE_KEY + roles.filled[o] for o in problem.objects if o in roles.filled}
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
    unique = namer(ROLES_RESERVED)
    names = {n: unique(n) for n in (*problem.objects, *problem.locations, *problem.grasps)}
    subgoal_names = {s.id: unique(s.id) for s in problem.subgoals}
    names |= {r: unique(r.removeprefix(ROLE_KEY)) for r in role_kinds}
    kind_names = {kind: unique(kind) for kind in dict.fromkeys(kinds.values())}
    rules = Rules(renamed)
    starts: dict[tuple[str, str], str] = {}
    for r, kind in role_kinds.items():
        for o, loc in problem.initial:
            if kinds.get(o) == kind:
                done = rules.reached_where_they_stand({r: loc}, renamed.reached)
                for sid in done - renamed.reached:  # one at most
                    starts[r, loc] = sid
    return Cast(renamed, names, subgoal_names, kinds, role_kinds, kind_names, starts)
