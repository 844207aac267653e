"""The paper's XML problem format (docs/formats.md "Planning problem"): parsing, the
round trip through problem_to_xml, and refusal of bad or hostile files."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

import pytest

from demoplan.errors import InputError
from demoplan.planning.problem import Problem, Subgoal
from demoplan.planning.xml import load_problem, problem_from_xml, problem_to_xml, save_problem
from tests.support.helpers import EXAMPLES
from tests.support.planning_families import blocks_problem, table_problem

PAPER = EXAMPLES / "planning" / "paper-example.xml"


def test_paper_example_parses() -> None:
    problem = load_problem(PAPER)
    assert problem.objects == ("fork", "food", "cup", "box")
    assert len(problem.locations) == 8
    assert {"loc10", "loc15", "loc22", "loc35", "loc264", "loc293"} < set(problem.locations)
    assert problem.freespace == {"freespace1", "freespace2"}
    assert problem.grasps == tuple(f"grasp{i}" for i in range(1, 7))
    assert problem.allowed == {
        ("fork", "grasp1"),
        ("food", "grasp2"),
        ("food", "grasp3"),
        ("cup", "grasp4"),
        ("cup", "grasp5"),
        ("box", "grasp6"),
    }
    assert len(problem.collisions) == 7
    assert ("loc15", "loc15", "grasp4") in problem.collisions
    assert ("loc264", "loc293", "grasp6") in problem.collisions
    assert problem.initial == (
        ("fork", "loc10"),
        ("food", "loc15"),
        ("cup", "loc22"),
        ("box", "loc264"),
    )
    assert problem.goal == (("fork", "loc35"), ("food", "loc264"), ("cup", "loc293"))
    assert not (problem.supports or problem.exclusions or problem.subgoals or problem.reached)
    assert problem.name == "paper-example"


def extended_problem() -> Problem:
    """Every extension arg, a Location marked free space by attribute, and one whose
    name starts with "freespace" but is not free space."""
    return Problem.create(
        objects=["a", "b", "c"],
        locations=["l1", "l2", "top", "park", "freespace-not", "spot"],
        grasps=["g1", "g2"],
        allowed=[("a", "g1"), ("b", "g1"), ("b", "g2"), ("c", "g2")],
        collisions=[("l1", "l2", "g1"), ("spot", "l1", "g2")],
        initial=[("a", "l1"), ("b", "l2"), ("c", "park")],
        goal=[("c", "top")],
        freespace=["park"],
        supports=[("top", "l1"), ("top", "l2")],
        exclusions=[("spot", "park")],
        subgoals=[Subgoal("A", "a", "spot"), Subgoal("B", "b", "l1"), Subgoal("C", "a", "l1")],
        precedences=[("A", "B"), ("B", "C")],
        reached=["A"],
        name="extended",
    )


def round_trip(problem: Problem) -> Problem:
    return problem_from_xml(problem_to_xml(problem), "round-trip.xml")


def test_round_trip_paper_example() -> None:
    problem = load_problem(PAPER)
    again = round_trip(problem)
    assert again == problem
    assert again.name == problem.name


@pytest.mark.parametrize("n", [1, 3, 6, 9])
@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("generate", [table_problem, blocks_problem])
def test_round_trip_generated(generate: Callable[[int, int], Problem], n: int, seed: int) -> None:
    problem = generate(n, seed)
    assert round_trip(problem) == problem
    if generate is blocks_problem and n >= 3:
        assert problem.supports  # the round trip covers the support extension


def test_round_trip_extensions(tmp_path: Path) -> None:
    problem = extended_problem()
    text = problem_to_xml(problem)
    assert 'freespace="true"' in text  # "park" is free space only by the attribute
    assert 'freespace="false"' in text  # "freespace-not" is not, despite its name
    again = problem_from_xml(text, "extended.xml")
    assert again == problem
    assert again.freespace == {"park"}
    save_problem(problem, tmp_path / "extended.xml")
    assert load_problem(tmp_path / "extended.xml") == problem


def test_a_location_named_freespace_is_free_space() -> None:
    text = PAPER.read_text()
    assert 'freespace="' not in text  # free space by name only, as in the paper
    assert {"freespace1", "freespace2"} <= load_problem(PAPER).freespace


# --- hostile XML: refused at once --------------------------------------------------------

BOMB = """<?xml version="1.0"?>
<!DOCTYPE problem [
  <!ENTITY a "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa">
  <!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;">
  <!ENTITY c "&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;">
  <!ENTITY d "&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;">
  <!ENTITY e "&d;&d;&d;&d;&d;&d;&d;&d;&d;&d;&d;&d;&d;&d;&d;&d;&d;&d;&d;&d;">
  <!ENTITY f "&e;&e;&e;&e;&e;&e;&e;&e;&e;&e;&e;&e;&e;&e;&e;&e;&e;&e;&e;&e;">
  <!ENTITY g "&f;&f;&f;&f;&f;&f;&f;&f;&f;&f;&f;&f;&f;&f;&f;&f;&f;&f;&f;&f;">
  <!ENTITY h "&g;&g;&g;&g;&g;&g;&g;&g;&g;&g;&g;&g;&g;&g;&g;&g;&g;&g;&g;&g;">
]>
<problem><object name="&h;" type="Object"/><state><arg name="hand-empty"/></state></problem>
"""

EXTERNAL = """<?xml version="1.0"?>
<!DOCTYPE problem [<!ENTITY x SYSTEM "file:///etc/passwd">]>
<problem>
  <object name="o" type="Object"/><object name="l" type="Location"/>
  <state><arg name="o l"/><arg name="hand-empty"/></state>
  <goal><arg name="&x;"/></goal>
</problem>
"""


@pytest.mark.parametrize("text", [BOMB, EXTERNAL], ids=["billion-laughs", "external-entity"])
def test_entities_are_refused_at_once(tmp_path: Path, text: str) -> None:
    path = tmp_path / "hostile.xml"
    path.write_text(text)
    started = time.perf_counter()
    with pytest.raises(InputError) as caught:
        load_problem(path)
    # A hang guard, not a speed target: expanding the bomb is 79 GB of text.
    assert time.perf_counter() - started < 30.0
    message = str(caught.value)
    assert str(path) in message
    assert "not allowed" in message
    assert "root:" not in message  # nothing of /etc/passwd leaks into the message


# --- bad input: InputError naming the file and the field ----------------------------------

DECLARATIONS = """
  <object name="a" type="Object"/>
  <object name="b" type="Object"/>
  <object name="l1" type="Location"/>
  <object name="l2" type="Location"/>
  <object name="g" type="Grasp"/>
"""


def document(state: str, goal: str = '<arg name="a l2"/>', declarations: str = DECLARATIONS) -> str:
    return f"<problem>{declarations}<state>{state}</state><goal>{goal}</goal></problem>"


GOOD_STATE = '<arg name="a l1"/><arg name="b l2"/><arg name="a g"/><arg name="hand-empty"/>'

BAD: list[tuple[str, str, list[str]]] = [
    ("malformed", "<problem><object name='a' type='Object'></problem>", ["line 1", "malformed"]),
    ("not XML", "just text", ["malformed XML", "line 1 column 1"]),
    ("wrong root", "<task><state/></task>", ["bad.xml: root: ", "<problem> expected"]),
    (
        "unknown element",
        "<problem><object name='a' type='Object'/><goals/></problem>",
        ["problem/goals[1]", "unknown element <goals>"],
    ),
    (
        "undeclared name in a state arg",
        document('<arg name="a l1"/><arg name="b l3"/><arg name="hand-empty"/>'),
        ["state/arg[1]", "'l3'", "not declared"],
    ),
    (
        "undeclared name in an extension arg",
        document(GOOD_STATE + '<arg name="support l1 nowhere"/>'),
        ["state/arg[4]", "'nowhere'", "not declared"],
    ),
    (
        "unknown fact",
        document('<arg name="a l1"/><arg name="b l2"/><arg name="l1 g"/><arg name="hand-empty"/>'),
        ["state/arg[2]", "(Location Grasp) is not a known fact"],
    ),
    (
        "a type other than Object, Location or Grasp",
        document(GOOD_STATE, declarations=DECLARATIONS + '<object name="t" type="Table"/>'),
        ["object[5].type", "'Table'", "Object, Location or Grasp expected"],
    ),
    (
        "a name declared twice",
        document(GOOD_STATE, declarations=DECLARATIONS + '<object name="l1" type="Grasp"/>'),
        ["object[5]", "'l1' declared twice"],
    ),
    (
        "a name with a space",
        document(GOOD_STATE, declarations=DECLARATIONS + '<object name="x y" type="Grasp"/>'),
        ["object[5].name", "'x y'", "without spaces"],
    ),
    (
        "a bad freespace attribute",
        document(
            GOOD_STATE,
            declarations=DECLARATIONS + '<object name="l3" type="Location" freespace="maybe"/>',
        ),
        ["object[5].freespace", "'maybe'"],
    ),
    (
        "no hand-empty",
        document('<arg name="a l1"/><arg name="b l2"/>'),
        ["state:", "hand-empty"],
    ),
    (
        "two objects at one location",
        document('<arg name="a l1"/><arg name="b l1"/><arg name="hand-empty"/>'),
        ["state/arg[1]", "'l1' already holds 'a'", "one object per location"],
    ),
    (
        "an object at two locations",
        document('<arg name="a l1"/><arg name="a l2"/><arg name="hand-empty"/>'),
        ["state/arg[1]", "'a' is already placed", "one location per object"],
    ),
    (
        "an object with no location",
        document('<arg name="a l1"/><arg name="hand-empty"/>'),
        ["state:", "['b'] have no location"],
    ),
    (
        "a goal naming an undeclared location",
        document(GOOD_STATE, '<arg name="b l2"/><arg name="a l9"/>'),
        ["goal/arg[1]", "'l9'", "not declared"],
    ),
    (
        "two goals for one object",
        document(GOOD_STATE, '<arg name="a l2"/><arg name="a l1"/>'),
        ["goal/arg[1]", "'a' already has a goal"],
    ),
    (
        "a precedence naming an unknown subgoal",
        document(GOOD_STATE, '<arg name="subgoal S a l2"/><arg name="before S T"/>'),
        ["goal/arg[1]", "'T' is not a subgoal id"],
    ),
    (
        "reached naming an unknown subgoal",
        document(GOOD_STATE + '<arg name="reached Q"/>'),
        ["state/arg[4]", "'Q' is not a subgoal id"],
    ),
    (
        "two states",
        "<problem><state/><state/></problem>",
        ["state:", "exactly one expected"],
    ),
    (
        "an empty arg",
        document('<arg name="  "/>' + GOOD_STATE),
        ["state/arg[0]", "empty arg"],
    ),
    (
        "not an arg",
        document(GOOD_STATE + "<fact/>"),
        ["state/fact[4]", "<fact>"],
    ),
]


@pytest.mark.parametrize(("text", "fragments"), [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_problem_names_file_and_field(tmp_path: Path, text: str, fragments: list[str]) -> None:
    path = tmp_path / "bad.xml"
    path.write_text(text)
    with pytest.raises(InputError) as caught:
        load_problem(path)
    message = str(caught.value)
    assert message.startswith(f"{path}: "), message
    for fragment in fragments:
        assert fragment in message, (fragment, message)


def test_good_document_of_the_bad_cases_parses() -> None:
    """The base of the cases above is valid, so each case fails for its own reason."""
    problem = problem_from_xml(document(GOOD_STATE), "good.xml")
    assert problem.initial == (("a", "l1"), ("b", "l2"))
    assert problem.goal == (("a", "l2"),)


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(InputError, match=r"missing\.xml: no such file; a problem file"):
        load_problem(tmp_path / "missing.xml")
