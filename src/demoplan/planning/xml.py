"""The paper's XML problem format (§IV.C; docs/formats.md), read safely with defusedxml.

A file in the paper's form stays valid::

    <problem>
      <object name="box" type="Object"/>
      <object name="loc264" type="Location"/>
      <object name="freespace1" type="Location"/>
      <object name="grasp6" type="Grasp"/>
      <state>
        <arg name="box loc264"/>          <!-- object at location -->
        <arg name="box grasp6"/>          <!-- grasp allowed for the object -->
        <arg name="loc264 loc293 grasp6"/> <!-- collision fact -->
        <arg name="hand-empty"/>
      </state>
      <goal><arg name="box loc293"/></goal>
    </problem>

Extensions (documented in docs/planning.md): a Location may carry
``freespace="true"`` (without the attribute, names starting with ``freespace``
count as free space; ``freespace="false"`` says otherwise); state args
``support UPPER LOWER``, ``exclusive LA LB``, ``accepts LOC OBJ``, ``reached ID``; goal args
``subgoal ID OBJECT LOCATION`` and ``before ID1 ID2``.

Parsing refuses DTDs, entity declarations and external references
(``defusedxml``), so an entity bomb fails at once instead of expanding.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from xml.etree.ElementTree import Element, ParseError, SubElement, indent, tostring

import defusedxml
import defusedxml.ElementTree as SafeElementTree

from demoplan.errors import InputError
from demoplan.fileio import display_path, read_input_text
from demoplan.planning.problem import Problem, Subgoal

__all__ = ["load_problem", "problem_from_xml", "problem_to_xml", "save_problem"]

MAX_XML_BYTES = 32 * 1024 * 1024
_TYPES = {"object": "Object", "location": "Location", "grasp": "Grasp"}
_TRUE, _FALSE = {"true", "1", "yes"}, {"false", "0", "no"}
_KEYWORDS = {"support", "exclusive", "accepts", "reached", "subgoal", "before"}


def problem_from_xml(text: str, source: str = "<xml>") -> Problem:
    """Parse the paper's XML into a checked :class:`Problem`."""
    root = _parse_root(text, source)
    kinds, freespace = _declarations(root, source)
    state, goal = _sections(root, source)
    facts = _state_facts(state, kinds, source)
    wanted = _goal_facts(goal, kinds, source)
    _check_subgoal_ids(wanted, facts, source)
    return Problem.create(
        objects=[n for n, k in kinds.items() if k == "Object"],
        locations=[n for n, k in kinds.items() if k == "Location"],
        grasps=[n for n, k in kinds.items() if k == "Grasp"],
        allowed=facts.allowed,
        collisions=facts.collisions,
        initial=facts.initial,
        goal=wanted.goal,
        freespace=freespace,
        supports=facts.supports,
        exclusions=facts.exclusions,
        accepts=facts.accepts,
        subgoals=wanted.subgoals,
        precedences=wanted.precedences,
        reached=facts.reached,
        name=root.get("name") or Path(source).stem,
        source=source,
    )


def _parse_root(text: str, source: str) -> Element:
    """The ``<problem>`` element, parsed safely, with only known children."""
    try:
        root: Element = SafeElementTree.fromstring(text, forbid_dtd=True)
    except defusedxml.DefusedXmlException as exc:
        raise InputError(
            f"refused: {type(exc).__name__} "
            "(DTDs, entities and external references are not allowed)",
            source=source,
        ) from None
    except ParseError as exc:
        line, column = exc.position
        raise InputError(
            f"malformed XML ({_reason(exc)}); a well-formed <problem> document expected",
            source=source,
            field=f"line {line} column {column + 1}",
        ) from None
    if root.tag != "problem":
        raise InputError(
            f"root element <{root.tag}>; <problem> expected", source=source, field="root"
        )
    for index, child in enumerate(root):
        if child.tag not in {"object", "state", "goal"}:
            raise InputError(
                f"unknown element <{child.tag}>; <object>, <state> or <goal> expected",
                source=source,
                field=f"problem/{child.tag}[{index}]",
            )
    return root


def _declarations(root: Element, source: str) -> tuple[dict[str, str], list[str]]:
    """The ``<object>`` declarations: each name's type (Object, Location or
    Grasp) in file order, and the locations that are free space."""
    kinds: dict[str, str] = {}
    freespace: list[str] = []
    for index, element in enumerate(root.findall("object")):
        name, kind = element.get("name"), element.get("type", "")
        where = f"object[{index}]"
        if not name or not name.strip() or len(name.split()) != 1:
            raise InputError(
                f"name {name!r}; a name without spaces expected",
                source=source,
                field=f"{where}.name",
            )
        if kind.lower() not in _TYPES:
            raise InputError(
                f"type {kind!r}; Object, Location or Grasp expected",
                source=source,
                field=f"{where}.type",
            )
        if name in kinds:
            raise InputError(
                f"{name!r} declared twice; each name once expected", source=source, field=where
            )
        kinds[name] = _TYPES[kind.lower()]
        marked = element.get("freespace")
        if marked is None:
            free = name.lower().startswith("freespace")
        elif marked.strip().lower() in _TRUE | _FALSE and kinds[name] == "Location":
            free = marked.strip().lower() in _TRUE
        else:
            raise InputError(
                f'freespace={marked!r}; "true" or "false" on a Location expected',
                source=source,
                field=f"{where}.freespace",
            )
        if kinds[name] == "Location" and free:
            freespace.append(name)
    return kinds, freespace


def _sections(root: Element, source: str) -> tuple[Element, Element | None]:
    """The one ``<state>`` and the ``<goal>``, if any."""
    states, goals = root.findall("state"), root.findall("goal")
    if len(states) != 1:
        raise InputError(
            f"{len(states)} <state> elements; exactly one expected", source=source, field="state"
        )
    if len(goals) > 1:
        raise InputError(
            f"{len(goals)} <goal> elements; at most one expected", source=source, field="goal"
        )
    return states[0], goals[0] if goals else None


@dataclass
class _StateFacts:
    """The facts of ``<state>``, and where each ``reached`` fact was given."""

    allowed: list[tuple[str, str]] = field(default_factory=list)
    collisions: list[tuple[str, str, str]] = field(default_factory=list)
    initial: list[tuple[str, str]] = field(default_factory=list)
    supports: list[tuple[str, str]] = field(default_factory=list)
    exclusions: list[tuple[str, str]] = field(default_factory=list)
    accepts: list[tuple[str, str]] = field(default_factory=list)
    reached: list[str] = field(default_factory=list)
    reached_at: dict[str, str] = field(default_factory=dict)


def _state_facts(state: Element, kinds: dict[str, str], source: str) -> _StateFacts:
    """The facts of ``<state>``: one location per object and one object per
    location, every object placed, the hand empty."""
    facts = _StateFacts()
    hand_empty = False
    placed: dict[str, str] = {}  # object -> where its location was given
    holder: dict[str, tuple[str, str]] = {}  # location -> (object, where)
    for index, tokens in _args(state, source, "state"):
        where = f"state/arg[{index}]"
        types = [kinds.get(t) for t in tokens]
        if tokens == ["hand-empty"]:
            hand_empty = True
        elif types == ["Object", "Location"]:
            obj, loc = tokens
            if obj in placed:
                raise InputError(
                    f"{obj!r} is already placed by {placed[obj]}; one location per object",
                    source=source,
                    field=where,
                )
            if loc in holder:
                other, first = holder[loc]
                raise InputError(
                    f"{loc!r} already holds {other!r} ({first}); one object per location",
                    source=source,
                    field=where,
                )
            placed[obj], holder[loc] = where, (obj, where)
            facts.initial.append((obj, loc))
        elif types == ["Object", "Grasp"]:
            facts.allowed.append((tokens[0], tokens[1]))
        elif types == ["Location", "Location", "Grasp"]:
            facts.collisions.append((tokens[0], tokens[1], tokens[2]))
        elif tokens[0] in {"support", "exclusive"} and types[1:] == ["Location", "Location"]:
            pairs = facts.supports if tokens[0] == "support" else facts.exclusions
            pairs.append((tokens[1], tokens[2]))
        elif tokens[0] == "accepts" and types[1:] == ["Location", "Object"]:
            facts.accepts.append((tokens[1], tokens[2]))
        elif tokens[0] == "reached" and len(tokens) == 2:
            facts.reached.append(tokens[1])
            facts.reached_at[tokens[1]] = where
        else:
            raise InputError(_unknown_arg(tokens, types), source=source, field=where)
    if not hand_empty:
        raise InputError(
            "no 'hand-empty' arg; the state must hold it (the hand starts empty)",
            source=source,
            field="state",
        )
    unplaced = [n for n, k in kinds.items() if k == "Object" and n not in placed]
    if unplaced:
        raise InputError(
            f"objects {unplaced} have no location; an arg 'OBJECT LOCATION' for each expected",
            source=source,
            field="state",
        )
    return facts


@dataclass
class _GoalFacts:
    """The facts of ``<goal>``, and where each ``before`` fact was given."""

    goal: list[tuple[str, str]] = field(default_factory=list)
    subgoals: list[Subgoal] = field(default_factory=list)
    precedences: list[tuple[str, str]] = field(default_factory=list)
    before_at: dict[tuple[str, str], str] = field(default_factory=dict)


def _goal_facts(goal: Element | None, kinds: dict[str, str], source: str) -> _GoalFacts:
    """The facts of ``<goal>`` (none without one): one goal per object."""
    wanted = _GoalFacts()
    goal_at: dict[str, str] = {}
    for index, tokens in _args(goal, source, "goal") if goal is not None else []:
        where = f"goal/arg[{index}]"
        types = [kinds.get(t) for t in tokens]
        if types == ["Object", "Location"]:
            if tokens[0] in goal_at:
                raise InputError(
                    f"{tokens[0]!r} already has a goal ({goal_at[tokens[0]]}); one per object",
                    source=source,
                    field=where,
                )
            goal_at[tokens[0]] = where
            wanted.goal.append((tokens[0], tokens[1]))
        elif tokens[0] == "subgoal" and types[2:] == ["Object", "Location"] and len(tokens) == 4:
            wanted.subgoals.append(Subgoal(tokens[1], tokens[2], tokens[3]))
        elif tokens[0] == "before" and len(tokens) == 3:
            wanted.precedences.append((tokens[1], tokens[2]))
            wanted.before_at[(tokens[1], tokens[2])] = where
        else:
            raise InputError(_unknown_arg(tokens, types), source=source, field=where)
    return wanted


def _check_subgoal_ids(wanted: _GoalFacts, facts: _StateFacts, source: str) -> None:
    """Every id a ``before`` or ``reached`` fact names is a declared subgoal's."""
    ids = {s.id for s in wanted.subgoals}
    for pair, where in wanted.before_at.items():
        for sid in pair:
            if sid not in ids:
                raise InputError(
                    f"{sid!r} is not a subgoal id; one declared by 'subgoal ID OBJECT LOCATION'",
                    source=source,
                    field=where,
                )
    for sid, where in facts.reached_at.items():
        if sid not in ids:
            raise InputError(
                f"{sid!r} is not a subgoal id; one declared by 'subgoal ID OBJECT LOCATION'",
                source=source,
                field=where,
            )


def _args(parent: Element, source: str, where: str) -> list[tuple[int, list[str]]]:
    out = []
    for index, element in enumerate(parent):
        if element.tag != "arg":
            raise InputError(
                f'unknown element <{element.tag}>; <arg name="..."/> expected',
                source=source,
                field=f"{where}/{element.tag}[{index}]",
            )
        tokens = (element.get("name") or "").split()
        if not tokens:
            raise InputError(
                'empty arg; <arg name="..."/> with a fact expected',
                source=source,
                field=f"{where}/arg[{index}]",
            )
        out.append((index, tokens))
    return out


def _reason(exc: ParseError) -> str:
    """expat's reason without its "line L, column C" tail (the field says where)."""
    return str(exc).split(":")[0].strip() or "syntax error"


def _unknown_arg(tokens: list[str], types: list[str | None]) -> str:
    text = " ".join(tokens)
    names = list(zip(tokens, types, strict=True))
    if tokens[0] in _KEYWORDS - {"reached", "before"}:
        names = names[2:] if tokens[0] == "subgoal" else names[1:]
    elif tokens[0] in {"reached", "before"}:
        names = []
    undeclared = [t for t, k in names if k is None]
    if undeclared:
        return (
            f"{text!r}: {undeclared} not declared; an <object> of type Object, Location "
            "or Grasp expected for each name"
        )
    shape = " ".join(k or "?" for k in types)
    return (
        f"{text!r} ({shape}) is not a known fact; expected 'OBJECT LOCATION', "
        "'OBJECT GRASP', 'LOCATION LOCATION GRASP', 'hand-empty' or an extension"
    )


def load_problem(path: str | Path) -> Problem:
    """Read a problem file."""
    path = Path(path)
    text = read_input_text(path, "a problem file in the paper's XML", MAX_XML_BYTES)
    return problem_from_xml(text, display_path(path))


def problem_to_xml(problem: Problem) -> str:
    """The problem in the paper's XML (extensions only where the problem uses them)."""
    root = Element("problem", {"name": problem.name})
    for name in problem.objects:
        SubElement(root, "object", {"name": name, "type": "Object"})
    for name in problem.locations:
        attributes = {"name": name, "type": "Location"}
        free, by_name = name in problem.freespace, name.lower().startswith("freespace")
        if free != by_name:  # the attribute only where the name alone would mislead
            attributes["freespace"] = "true" if free else "false"
        SubElement(root, "object", attributes)
    for name in problem.grasps:
        SubElement(root, "object", {"name": name, "type": "Grasp"})
    state = SubElement(root, "state")
    rows = [f"{o} {loc}" for o, loc in problem.initial]
    rows += [f"{o} {g}" for o, g in sorted(problem.allowed)]
    rows += [f"{a} {b} {g}" for a, b, g in sorted(problem.collisions)]
    rows += [f"support {a} {b}" for a, b in sorted(problem.supports)]
    rows += [f"exclusive {a} {b}" for a, b in sorted(problem.exclusions)]
    rows += [f"accepts {loc} {o}" for loc, o in sorted(problem.accepts)]
    rows += [f"reached {s}" for s in sorted(problem.reached)]
    rows.append("hand-empty")
    for row in rows:
        SubElement(state, "arg", {"name": row})
    goal = SubElement(root, "goal")
    rows = [f"{o} {loc}" for o, loc in problem.goal]
    rows += [f"subgoal {s.id} {s.object} {s.location}" for s in problem.subgoals]
    rows += [f"before {a} {b}" for a, b in sorted(problem.precedences)]
    for row in rows:
        SubElement(goal, "arg", {"name": row})
    indent(root)
    return tostring(root, encoding="unicode") + "\n"


def save_problem(problem: Problem, path: str | Path) -> None:
    """Write ``problem`` as XML, atomically."""
    from demoplan.fileio import write_atomic

    write_atomic(Path(path), problem_to_xml(problem))
