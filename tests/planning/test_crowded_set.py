"""The lama-first comparison set (issue 44): demoplan's plan is never longer.

``tests/data/planning/crowded/`` holds the hardest crowded tables
``benchmarks/crowded_set.py`` found (demoplan's plan longest relative to Fast
Downward's lama-first), each as the paper's XML and the lifted PDDL Fast
Downward read, with lama-first's plan length stored beside them in
``cases.json``. Fast Downward is not run here.

The anytime search never answers with a plan longer than its first one (a
later phase only keeps a shorter plan), so the first plan — the greedy
phase's, with a count of expansions rather than a time limit, so that the
outcome does not hang on the machine's speed — bounds what ``demoplan solve``
returns once that phase has finished.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from demoplan.budget import Budget, Clock
from demoplan.planning.bounds import LowerBounds
from demoplan.planning.compiled import compile_problem
from demoplan.planning.greedy import greedy_moves
from demoplan.planning.strips import validate
from demoplan.planning.xml import load_problem, problem_to_xml
from tests.support.planning_families import CROWDED_FAMILIES, PARKING_FAMILIES, parking_problem

SET = Path(__file__).resolve().parents[1] / "data" / "planning" / "crowded"
INDEX: dict[str, Any] = json.loads((SET / "cases.json").read_text())
CASES: list[dict[str, Any]] = INDEX["cases"]
GREEDY_NODES: int = INDEX["greedy_nodes"]


def test_the_set_covers_every_crowded_family() -> None:
    families = {case["family"] for case in CASES}
    assert set(CROWDED_FAMILIES) <= families
    assert all(isinstance(case["lama"], int) for case in CASES)


@pytest.mark.parametrize("case", CASES, ids=[case["name"] for case in CASES])
def test_first_plan_never_longer_than_lama_first(case: dict[str, Any]) -> None:
    problem = load_problem(SET / f"{case['name']}.xml")
    compiled = compile_problem(problem)
    bounds = LowerBounds(compiled)
    moves = greedy_moves(compiled, bounds, Clock(Budget(max_nodes=GREEDY_NODES)))
    assert moves is not None, f"no plan within {GREEDY_NODES} expansions"
    actions = [action for move in moves for action in compiled.move_actions(*move)]
    validate(problem, actions)
    assert len(actions) >= 2 * bounds.estimate(compiled.start, compiled.start_reached)
    assert len(actions) <= case["lama"]


@pytest.mark.parametrize("case", CASES[::3], ids=[case["name"] for case in CASES[::3]])
def test_the_files_are_the_generated_draws(case: dict[str, Any]) -> None:
    """The files are the families' draws, as benchmarks/planning.py draws them
    (so its hard-family run includes the set, and the script remakes it)."""
    options = {**PARKING_FAMILIES, **CROWDED_FAMILIES}[case["family"]]
    problem = parking_problem(case["n"], case["seed"], **options)
    assert problem_to_xml(problem) == (SET / f"{case['name']}.xml").read_text()
    assert (SET / f"{case['name']}.problem.pddl").is_file()
