"""Task generalization (paper §IV.B, Fig. 2; docs/learning.md).

Every ordered pair (X, Y) with X before Y in some demonstration is a
constraint "X before Y"; a pair also seen in the other order, in any
demonstration, is contradicted and removed for good, so the result does not
depend on the order the demonstrations arrive in. Redundant (transitive)
constraints are kept: the paper notes they prune the planner's search.

Repeated moves of one object in a demonstration (Table I: the knife goes up
and down while cutting) visit the same state several times. Each visit is
numbered — the first is the state id itself, later ones ``C#2``, ``C#3`` — and
constraints relate visits, so a demonstration never contradicts itself
(C before D before C#2 rather than C < D and D < C).

Teacher-given constraints (the journal version of the paper) are never
removed; a learned constraint that reverses one is dropped, and a
demonstration that contradicts one is reported.

The *support* of a constraint (X, Y) is the number of demonstrations that
show it: those in which visit X comes before visit Y
(:func:`constraint_support`). The paper's rule keeps every uncontradicted
pair, so a learned constraint has a support of at least 1 — and, since a
demonstration visiting both shows them in some order, its support is the
number of demonstrations that visit both. A constraint shown once rests on
one demonstration's order, which may be chance; ``min_support`` (``learn
--min-support K``) keeps only learned constraints shown by at least K
demonstrations (default 1: the paper's rule). Teacher constraints are kept
whatever their support (which may be 0).
"""

from __future__ import annotations

import re
from collections import Counter
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

from demoplan.errors import InputError
from demoplan.graphs import find_cycle
from demoplan.model import State, visit_label
from demoplan.wording import did_you_mean

__all__ = [
    "ConstraintSet",
    "GoalOrder",
    "Requirement",
    "anchor_requirements",
    "constraint_support",
    "goal_order",
    "goal_states",
    "learn_constraints",
    "ordered_pairs",
    "parse_requirements",
    "required_pairs",
    "visit_sequence",
]

Pair = tuple[str, str]
_REQUIREMENT = re.compile(r"^\s*([A-Za-z0-9_.\-#@]+)\s*<\s*([A-Za-z0-9_.\-#@]+)\s*$")


@dataclass(frozen=True, slots=True)
class ConstraintSet:
    """Constraints over visit labels, and what the teacher's requirements found.

    ``constraints`` : learned (uncontradicted) plus required pairs, sorted.
    ``contradicted`` : pairs seen in both orders (each once, as (X, Y) with X < Y).
    ``violations`` : ``(demonstration index, X, Y)`` where a required X < Y was
    demonstrated the other way round.
    ``support`` : per constraint, the demonstrations that show it (module docstring).
    ``below_support`` : uncontradicted pairs left out because fewer than
    ``min_support`` demonstrations show them, sorted.
    """

    constraints: tuple[Pair, ...]
    contradicted: tuple[Pair, ...]
    violations: tuple[tuple[int, str, str], ...]
    support: tuple[int, ...] = ()
    below_support: tuple[Pair, ...] = ()


def visit_sequence(sequence: Sequence[str]) -> tuple[str, ...]:
    """State ids → visit labels: ``A C D C`` → ``A C D C#2``."""
    seen: dict[str, int] = {}
    labels = []
    for state in sequence:
        seen[state] = seen.get(state, 0) + 1
        labels.append(visit_label(state, seen[state]))
    return tuple(labels)


def ordered_pairs(sequence: Sequence[str]) -> set[Pair]:
    """Every (X, Y) with X visited before Y in one demonstration."""
    visits = visit_sequence(sequence)
    return {(visits[a], visits[b]) for a in range(len(visits)) for b in range(a + 1, len(visits))}


def constraint_support(
    sequences: Iterable[Sequence[str]], pairs: Iterable[Pair]
) -> tuple[int, ...]:
    """Per pair (X, Y) of visit labels, the number of sequences that show it:
    in which X is visited before Y (the module docstring's support)."""
    shown = _shown(sequences)
    return tuple(shown[pair] for pair in pairs)


def _shown(sequences: Iterable[Sequence[str]]) -> Counter[Pair]:
    """How many sequences show each ordered pair."""
    shown: Counter[Pair] = Counter()
    for sequence in sequences:
        shown.update(ordered_pairs(sequence))
    return shown


def learn_constraints(
    sequences: Iterable[Sequence[str]], required: Iterable[Pair] = (), min_support: int = 1
) -> ConstraintSet:
    """Constraints from state sequences (paper §IV.B) plus teacher requirements.

    ``min_support``: a learned constraint must be shown by at least this many
    sequences (1: the paper's rule, every uncontradicted pair); teacher
    requirements are kept whatever their support."""
    sequences = [tuple(s) for s in sequences]
    shown = _shown(sequences)
    seen = set(shown)
    contradicted = {pair for pair in seen if (pair[1], pair[0]) in seen}
    required_set = set(required)
    uncontradicted = seen - contradicted - {(y, x) for x, y in required_set}
    learned = {pair for pair in uncontradicted if shown[pair] >= min_support}
    violations = []
    for index, sequence in enumerate(sequences):
        demonstrated = ordered_pairs(sequence)
        violations += [(index, x, y) for x, y in sorted(required_set) if (y, x) in demonstrated]
    constraints = tuple(sorted(learned | required_set, key=_pair_key))
    return ConstraintSet(
        constraints=constraints,
        contradicted=tuple(sorted({_unordered(p) for p in contradicted}, key=_pair_key)),
        violations=tuple(violations),
        support=tuple(shown[pair] for pair in constraints),
        below_support=tuple(sorted(uncontradicted - learned - required_set, key=_pair_key)),
    )


def goal_states(sequence: Sequence[str], states: Sequence[State]) -> tuple[str, ...]:
    """The state set a demonstration ends in: each moved object's last state."""
    object_of = {s.id: s.object for s in states}
    last: dict[str, str] = {}
    for state_id in sequence:
        last[object_of[state_id]] = state_id
    return tuple(sorted(set(last.values()), key=label_key))


@dataclass(frozen=True, slots=True)
class Requirement:
    """A teacher requirement ``"X<Y"``: the text as given and its two sides.

    Each side is a state id (``C``), a visit label (``C#2``), an object name,
    which stands for every state of that object (``plate``), or ``@d.s``, the
    state of step s of demonstration d (both 1-based).
    """

    text: str
    tokens: tuple[str, str]


@dataclass(frozen=True, slots=True)
class GoalOrder:
    """The constraints among one demonstration's visits, as a figure draws them.

    ``labels`` : the demonstration's visit labels, in its order.
    ``constraints`` : the model's constraints between two of them.
    ``drawn`` : their transitive reduction — no drawn edge follows from a path
    of others — so every constraint is a path of drawn edges.
    ``implied`` : orders the drawn paths imply that are not constraints
    themselves: a plan for this goal keeps them all the same (E before J
    before F puts E before F, though another demonstration placed F first, in
    a goal without J). Empty where the constraints among the labels are
    transitively closed.
    """

    labels: tuple[str, ...]
    constraints: frozenset[Pair]
    drawn: frozenset[Pair]
    implied: frozenset[Pair]


def goal_order(sequence: Sequence[str], constraints: Iterable[Pair]) -> GoalOrder:
    """:class:`GoalOrder` of the demonstration with state ``sequence``.

    The constraints are acyclic among one demonstration's visits (it visits
    them in one order), so the reduction is unique.
    """
    labels = visit_sequence(sequence)
    position = {label: k for k, label in enumerate(labels)}
    among = frozenset((x, y) for x, y in constraints if x in position and y in position)
    after: dict[str, set[str]] = {label: set() for label in labels}
    for x, y in among:
        after[x].add(y)
    reach: dict[str, set[str]] = {}
    for label in reversed(labels):  # every constraint points forward in the sequence
        reach[label] = set(after[label])
        for y in after[label]:
            reach[label] |= reach[y]
    drawn = frozenset(
        (x, y) for x, y in among if not any(y in reach[z] for z in after[x] if z != y)
    )
    closure = {(x, y) for x in labels for y in reach[x]}
    return GoalOrder(labels, among, drawn, frozenset(closure - among))


def parse_requirements(texts: Iterable[str]) -> tuple[Requirement, ...]:
    """Split ``"X<Y"`` texts into their two sides, or raise an InputError."""
    requirements = []
    for text in texts:
        match = _REQUIREMENT.match(text)
        if not match:
            raise InputError(f"expected a requirement like 'A<B', got {text!r}", field="require")
        requirements.append(Requirement(text, (match.group(1), match.group(2))))
    return tuple(requirements)


def required_pairs(
    requirements: Iterable[Requirement],
    states: Sequence[State],
    sequences: Sequence[Sequence[str]],
    types: Mapping[str, str] | None = None,
) -> tuple[Pair, ...]:
    """Teacher requirements → pairs of visit labels.

    A state id or visit label must occur in some demonstration, an object
    name stands for every state of that object (``plate<napkin``), a role's
    (``plate#2``) for its states and a type's (``types``: object → type) for
    every state of its roles, ``@d.s`` must name a step (stable when
    demonstrations are added). Required pairs that form a cycle are refused:
    no plan could satisfy them.
    """
    by_object: dict[str, list[str]] = {}
    for state in states:
        by_object.setdefault(state.object, []).append(state.id)
    for state in states:
        kind = (types or {}).get(state.object, state.object)
        if kind != state.object and kind not in by_object:
            by_object[kind] = [s.id for s in states if (types or {}).get(s.object) == kind]
    visits = {label for sequence in sequences for label in visit_sequence(sequence)}
    pairs: set[Pair] = set()
    for requirement in requirements:
        text = requirement.text
        sides = [_expand(token, visits, by_object, sequences, text) for token in requirement.tokens]
        for x in sides[0]:
            for y in sides[1]:
                if x == y:
                    raise InputError(f"{text!r} requires {x} before itself", field="require")
                pairs.add((x, y))
    cycle = find_cycle(pairs, order=label_key)
    if cycle:
        raise InputError(
            f"the required constraints form a cycle {' < '.join(cycle)}; no order satisfies them",
            field="require",
        )
    return tuple(sorted(pairs, key=_pair_key))


_ANCHOR = re.compile(r"^@(\d+)\.(\d+)$")


def _expand(
    token: str,
    visits: set[str],
    by_object: dict[str, list[str]],
    sequences: Sequence[Sequence[str]],
    text: str,
) -> list[str]:
    if token in visits:
        return [token]
    if token in by_object:
        return by_object[token]
    anchor = _ANCHOR.match(token)
    if anchor:
        demo, step = int(anchor.group(1)), int(anchor.group(2))
        if 1 <= demo <= len(sequences) and 1 <= step <= len(sequences[demo - 1]):
            return [visit_sequence(sequences[demo - 1])[step - 1]]
        raise InputError(
            f"{text!r}: {token!r} names no step of the demonstrations", field="require"
        )
    known = ", ".join(sorted(visits, key=label_key) + sorted(by_object))
    raise InputError(
        f"{text!r}: {token!r} is neither a visited state nor an object (known: {known})"
        + did_you_mean(token, by_object),
        field="require",
    )


def anchor_requirements(
    requirements: Iterable[Requirement], sequences: Sequence[Sequence[str]]
) -> tuple[Requirement, ...]:
    """Rewrite state-id sides as ``@d.s`` anchors (their first occurrence).

    State ids follow the order of the demonstrations and can change when a
    demonstration is added; the step a state was learned from does not, so
    ``learn --update`` keeps the teacher's requirements meaning the same states.
    """
    where: dict[str, str] = {}
    for d, sequence in enumerate(sequences):
        for s, label in enumerate(visit_sequence(sequence)):
            where.setdefault(label, f"@{d + 1}.{s + 1}")
    anchored = []
    for requirement in requirements:
        x, y = (where.get(t, t) for t in requirement.tokens)
        anchored.append(Requirement(f"{x}<{y}", (x, y)))
    return tuple(anchored)


def label_key(label: str) -> tuple[int, str, int]:
    """Sort key of visit labels: A < B < … < Z < AA, and C < C#2 < C#3."""
    state, _, occurrence = label.partition("#")
    return (len(state), state, int(occurrence or 1))


def _pair_key(pair: Pair) -> tuple[tuple[int, str, int], tuple[int, str, int]]:
    return (label_key(pair[0]), label_key(pair[1]))


def _unordered(pair: Pair) -> Pair:
    a, b = pair
    return (a, b) if label_key(a) <= label_key(b) else (b, a)
