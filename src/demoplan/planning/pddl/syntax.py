"""PDDL text: names a reader accepts (letters, digits and "-", no reserved
word, one name per problem name) and the text of an action or a schema."""

from __future__ import annotations

import re
from collections.abc import Callable

from demoplan.planning.problem import Problem

__all__ = [
    "LIFTED_RESERVED",
    "RESERVED",
    "action_text",
    "away_elsewhere",
    "namer",
    "pddl_name",
    "schema_text",
    "unique_names",
]

_SAFE = re.compile(r"[^a-z0-9]")  # no "_": "__" separates the parts of action names
# Words a PDDL reader may take for syntax where a name stands (PDDL 1.2 to 3.1).
_RESERVED_WORDS = (
    "and or not imply exists forall when either object number at over start end all "
    "define domain problem preference always sometime within increase decrease assign "
    "minimize maximize total-time total-cost"
)
RESERVED = frozenset(_RESERVED_WORDS.split())
# The lifted domain's own words: unified-planning's reader keeps types, predicates,
# actions and objects in one namespace, so no name of the problem may be one of them.
_LIFTED_WORDS = (
    "item location grip subgoal grasp put-down put-down-reaching handempty located free "
    "occupied holding allowed guarded guard loaded carries raised rests-on overlapping "
    "overlaps restricted accepts subgoal-of pending reached ordered after subgoal-place "
    "subgoals-at repeated revisit away"
)
LIFTED_RESERVED = RESERVED | frozenset(_LIFTED_WORDS.split())


def _atom(*parts: str) -> str:
    return "-".join(_SAFE.sub("-", p.lower()) for p in parts)


def pddl_name(text: str) -> str:
    """A PDDL name from ``text``: letters, digits and "-", starting with a letter."""
    name = _atom(text) or "x"
    if not name[0].isalpha():
        name = "n" + name
    return name


def unique_names(
    problem: Problem, reserved: frozenset[str] = RESERVED
) -> tuple[dict[str, str], dict[str, str]]:
    """PDDL-safe, distinct names for every object, location and grasp, and for
    every subgoal id (a separate namespace in demoplan, one with them in PDDL).

    PDDL is case-insensitive and allows fewer characters than demoplan, so
    ``Cup`` / ``cup`` or ``loc_1`` / ``loc-1`` get distinct names (``cup-2``);
    a name a reader could take for a keyword — or, in the lifted export, for
    one of the domain's own words — gets a prefix (``and`` → ``n-and``).
    """
    unique = namer(reserved)
    names = {n: unique(n) for n in (*problem.objects, *problem.locations, *problem.grasps)}
    subgoal_names = {s.id: unique(s.id) for s in problem.subgoals}
    return names, subgoal_names


def namer(reserved: frozenset[str]) -> Callable[[str], str]:
    """A function giving each name it is called with a PDDL name none before had."""
    used: set[str] = set()

    def unique(original: str) -> str:
        base = pddl_name(original)
        if base in reserved:
            base = "n-" + base
        name, k = base, 2
        while name in used:
            name, k = f"{base}-{k}", k + 1
        used.add(name)
        return name

    return unique


def action_text(name: str, pre: list[str], add: list[str], delete: list[str]) -> str:
    precondition = " ".join(f"({p})" for p in dict.fromkeys(pre))
    effect = " ".join([*(f"({a})" for a in add), *(f"(not ({d}))" for d in delete)])
    return (
        f"  (:action {name}\n"
        "    :parameters ()\n"
        f"    :precondition (and {precondition})\n"
        f"    :effect (and {effect}))\n"
    )


def schema_text(name: str, parameters: str, pre: list[str], effect: list[str]) -> str:
    return (
        f"  (:action {name}\n"
        f"    :parameters ({parameters})\n"
        "    :precondition (and\n" + "".join(f"      {p}\n" for p in pre) + "    )\n"
        "    :effect (and\n" + "".join(f"      {e}\n" for e in effect) + "    ))\n"
    )


def away_elsewhere(moved: str, place: str, variable: str) -> str:
    """The effect "``moved`` is away from every place it revisits but ``place``"."""
    return (
        f"(forall ({variable} - location) (when (and (revisit {moved} {variable}) "
        f"(not (= {variable} {place}))) (away {moved} {variable})))"
    )
