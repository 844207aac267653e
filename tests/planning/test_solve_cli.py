"""`demoplan solve` and `demoplan pddl` (docs/formats.md "Plan output", docs/cli.md exit codes)."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest

from demoplan.planning.problem import Action, Problem
from demoplan.planning.strips import validate
from demoplan.planning.xml import load_problem, save_problem
from tests.planning.test_problem_xml import BOMB
from tests.support.cli import invoke
from tests.support.helpers import EXAMPLES
from tests.support.planning_families import CROWDED_FAMILIES, parking_problem

PAPER = EXAMPLES / "planning" / "paper-example.xml"
LINE = re.compile(r"(GRASP|PUT_DOWN) (\S+) (\S+) (\S+)")


def one_line_error(result: Any, code: int, *fragments: str) -> str:
    """Exit ``code``, nothing on stdout, exactly one line on stderr with every fragment."""
    assert result.exit_code == code, (result.exit_code, result.stdout, result.stderr)
    assert result.stdout == ""
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("demoplan: error: ")
    for fragment in fragments:
        assert fragment in lines[0], (fragment, lines[0])
    return str(lines[0])


def parse_plan(text: str) -> list[Action]:
    actions = []
    for line in text.splitlines():
        match = LINE.fullmatch(line)
        assert match, f"not an action in the paper's format: {line!r}"
        actions.append(Action(*match.groups()))
    return actions


@pytest.mark.parametrize("search", [None, "astar", "bfs"])
def test_solve_prints_the_paper_plan(search: str | None) -> None:
    # --timeout inf here and below: the proof (or the exhausted search) must not
    # race the default 2 s on a loaded machine; the budgets are tested apart
    result = invoke("solve", PAPER, "--timeout", "inf", *(["--search", search] if search else []))
    assert result.exit_code == 0, result.stderr
    assert result.stderr == "demoplan: 8 actions, proved shortest\n"
    actions = parse_plan(result.stdout)
    assert len(actions) == 8
    assert [a.kind for a in actions] == ["GRASP", "PUT_DOWN"] * 4
    validate(load_problem(PAPER), actions)


@pytest.mark.parametrize("search", ["astar", "bfs"])
def test_solve_json(search: str) -> None:
    result = invoke("solve", PAPER, "--json", "--search", search, "--timeout", "inf")
    assert result.exit_code == 0, result.stderr
    data = json.loads(result.stdout)  # stdout holds the JSON and nothing else
    assert data["length"] == 8
    assert data["optimal"] is True and data["bound"] == 8
    names = {"tight", "plateau", "greedy", "greedy+astar"} if search == "astar" else {search}
    assert data["search"] in names
    assert result.stderr == "demoplan: 8 actions, proved shortest\n"
    assert isinstance(data["actions"], list)
    assert all(isinstance(a, list) and len(a) == 4 for a in data["actions"])
    validate(load_problem(PAPER), [Action(*a) for a in data["actions"]])


def two_objects(goal: list[tuple[str, str]], **extra: Any) -> Problem:
    return Problem.create(
        objects=["a", "b"],
        locations=["l1", "l2", *extra.pop("locations", [])],
        grasps=["g"],
        allowed=[("a", "g"), ("b", "g")],
        initial=[("a", "l1"), ("b", "l2")],
        goal=goal,
        name="two",
        **extra,
    )


def test_no_plan_shared_goal_location(tmp_path: Path) -> None:
    """A reason found without search: two objects must end at one location."""
    path = tmp_path / "shared.xml"
    save_problem(two_objects([("a", "l3"), ("b", "l3")], locations=["l3"]), path)
    one_line_error(invoke("solve", path), 3, "no plan", "a and b must both end at l3")


@pytest.mark.parametrize("search", ["astar", "bfs"])
def test_no_plan_found_by_search(tmp_path: Path, search: str) -> None:
    """a and b must swap places and there is no third place: nothing shows it up
    front, the search exhausts every arrangement."""
    problem = two_objects([("a", "l2"), ("b", "l1")])
    path = tmp_path / "swap.xml"
    save_problem(problem, path)
    line = one_line_error(
        invoke("solve", path, "--search", search, "--timeout", "inf"), 3, "no plan"
    )
    assert "exhausted" in line
    # with a free place the same swap is solvable: the failure was the search's finding
    roomy = tmp_path / "roomy.xml"
    save_problem(two_objects([("a", "l2"), ("b", "l1")], locations=["freespace1"]), roomy)
    result = invoke("solve", roomy, "--search", search, "--timeout", "inf")
    assert result.exit_code == 0, result.stderr
    assert len(parse_plan(result.stdout)) == 6


@pytest.mark.parametrize("search", ["astar", "bfs"])
def test_max_nodes_limit_exits_4(search: str, tmp_path: Path) -> None:
    """A problem whose plan (82 actions) needs many expansions: the node limit
    holds in every phase (the greedy first plan's too), so one expansion finds
    no plan. ``--timeout 10``: ten times what the phases need, so the node
    limit stops the search, not the clock."""
    path = tmp_path / "parking.xml"
    save_problem(parking_problem(20, 2, **CROWDED_FAMILIES["crowded-stacks"]), path)
    args = ("--search", search, "--max-nodes", "1", "--optimal", "--timeout", "10")
    line = one_line_error(
        invoke("solve", path, *args),
        4,
        "--max-nodes 1",
    )
    assert "no plan yet" in line
    assert "every plan needs at least" in line


def test_entity_bomb_exits_1(tmp_path: Path) -> None:
    path = tmp_path / "bomb.xml"
    path.write_text(BOMB)
    one_line_error(invoke("solve", path), 1, str(path), "not allowed")


def test_bad_field_exits_1(tmp_path: Path) -> None:
    path = tmp_path / "bad.xml"
    path.write_text(PAPER.read_text().replace('"cup loc22"', '"cup loc99"'))
    one_line_error(invoke("solve", path), 1, str(path), "state/arg[2]", "'loc99'")


def test_missing_file_exits_1(tmp_path: Path) -> None:
    one_line_error(invoke("solve", tmp_path / "nope.xml"), 1, "nope.xml", "no such file")


def test_unknown_search_is_a_usage_error() -> None:
    assert invoke("solve", PAPER, "--search", "dfs").exit_code == 2


def test_pddl_writes_domain_and_problem(tmp_path: Path) -> None:
    folder = tmp_path / "out" / "pddl"  # created as needed
    result = invoke("pddl", PAPER, "-o", folder)
    assert result.exit_code == 0, result.stderr
    assert result.stdout == ""
    domain, problem = folder / "domain.pddl", folder / "problem.pddl"
    assert domain.read_text().startswith("(define (domain demoplan-paper-example)")
    problem_text = problem.read_text()
    assert problem_text.startswith("(define (problem paper-example)")
    assert "(located box loc264)" in problem_text
    assert str(domain) in result.stderr
    # lifted by default: a schema per kind of action, the facts in the problem
    assert re.findall(r"\(:action (\S+)", domain.read_text()) == ["grasp", "put-down"]
    assert "(guard loc264 grasp6 loc293)" in problem_text


def test_pddl_grounded(tmp_path: Path) -> None:
    result = invoke("pddl", PAPER, "-o", tmp_path, "--grounded")
    assert result.exit_code == 0, result.stderr
    domain = (tmp_path / "domain.pddl").read_text()
    assert "(:action grasp__box__loc264__grasp6" in domain
    assert ":parameters ()" in domain and ":typing" not in domain


def test_pddl_bad_input_exits_1(tmp_path: Path) -> None:
    path = tmp_path / "bomb.xml"
    path.write_text(BOMB)
    one_line_error(invoke("pddl", path, "-o", tmp_path / "out"), 1, "not allowed")
    assert not (tmp_path / "out").exists()
