"""How much each constraint rests on: its support (the demonstrations that show
it) and ``min_support`` (``learn --min-support K``), against a brute-force count."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.documents.demonstrations import load_demonstrations
from demoplan.errors import InputError
from demoplan.learning import TaskModelLearner
from demoplan.learning.constraints import constraint_support, learn_constraints
from demoplan.learning.modelfile import load_model, save_model
from demoplan.learning.settings import LearningSettings, paper_overrides
from tests.support.cli import invoke
from tests.support.helpers import EXAMPLES

STATES = "ABCDEFG"
# Families of demonstrations: 1-8 sequences over up to 7 states, a state
# sometimes visited twice (the knife going up and down).
SEQUENCES = st.lists(
    st.lists(st.sampled_from(STATES), min_size=1, max_size=9), min_size=1, max_size=8
)


def labels(sequence: list[str]) -> list[str]:
    """Visit labels, numbered here independently: the k-th visit of C is C#k (k > 1)."""
    out, seen = [], {}
    for state in sequence:
        seen[state] = seen.get(state, 0) + 1
        out.append(state if seen[state] == 1 else f"{state}#{seen[state]}")
    return out


def brute_support(sequences: list[list[str]], x: str, y: str) -> int:
    """In how many sequences visit x comes before visit y."""
    count = 0
    for sequence in sequences:
        visits = labels(sequence)
        if x in visits and y in visits and visits.index(x) < visits.index(y):
            count += 1
    return count


def every_pair(sequences: list[list[str]]) -> set[tuple[str, str]]:
    visits = {v for s in sequences for v in labels(s)}
    return {(x, y) for x in visits for y in visits if x != y}


@given(SEQUENCES)
def test_support_is_the_number_of_demonstrations_showing_each_constraint(
    sequences: list[list[str]],
) -> None:
    result = learn_constraints(sequences)
    assert len(result.support) == len(result.constraints)
    for (x, y), support in zip(result.constraints, result.support, strict=True):
        assert support == brute_support(sequences, x, y) >= 1
        assert brute_support(sequences, y, x) == 0  # the paper's rule: never contradicted
    # constraint_support counts any pair, kept or not.
    pairs = sorted(every_pair(sequences))
    assert constraint_support(sequences, pairs) == tuple(
        brute_support(sequences, x, y) for x, y in pairs
    )


@given(SEQUENCES, st.integers(1, 9))
def test_min_support_drops_exactly_the_constraints_under_k(
    sequences: list[list[str]], k: int
) -> None:
    paper = learn_constraints(sequences)
    kept = learn_constraints(sequences, min_support=k)
    expected = {c for c in paper.constraints if brute_support(sequences, *c) >= k}
    assert set(kept.constraints) == expected
    assert set(kept.below_support) == set(paper.constraints) - expected
    assert kept.contradicted == paper.contradicted


@given(SEQUENCES, st.integers(2, 9), st.data())
def test_min_support_keeps_teacher_constraints(
    sequences: list[list[str]], k: int, data: st.DataObject
) -> None:
    visits = sorted({v for s in sequences for v in labels(s)})
    if len(visits) < 2:
        return
    x, y = data.draw(st.permutations(visits))[:2]
    result = learn_constraints(sequences, [(x, y)], min_support=k)
    assert (x, y) in result.constraints and (y, x) not in result.constraints
    support = dict(zip(result.constraints, result.support, strict=True))
    assert support[(x, y)] == brute_support(sequences, x, y)  # 0 when never shown


def test_min_support_is_a_setting_the_scikit_learn_way() -> None:
    demos = load_demonstrations([EXAMPLES / "blocks" / "demonstrations.json"])
    # The paper's reading: sequences A-B-C and D-A-C (its Table III).
    learner = TaskModelLearner(min_support=2, **paper_overrides()).fit(demos)
    assert learner.sequences_ == (("A", "B", "C"), ("D", "A", "C"))
    assert learner.settings.min_support == 2
    assert learner.constraints_ == (("A", "C"),) and learner.support_ == (2,)
    assert set(learner.below_support_) == {("A", "B"), ("B", "C"), ("D", "A"), ("D", "C")}
    assert learner.model_.settings.min_support == 2
    with pytest.raises(InputError, match="min_support: expected a whole number ≥ 1"):
        LearningSettings(min_support=0)


def test_the_model_file_keeps_support_and_min_support(tmp_path: Path) -> None:
    demos = load_demonstrations([EXAMPLES / "set_table"])
    model = TaskModelLearner(min_support=2).fit(demos).model_
    save_model(model, tmp_path / "model.json")
    document = json.loads((tmp_path / "model.json").read_text())
    assert document["settings"]["min_support"] == 2
    assert document["support"] == [
        brute_support([list(s) for s in model.sequences], x, y) for x, y in model.constraints
    ]
    assert min(document["support"]) >= 2
    again = load_model(tmp_path / "model.json")
    assert again.settings.min_support == 2 and again.constraints == model.constraints
    # A model file written before support existed reads as the paper's rule.
    del document["support"], document["settings"]["min_support"]
    (tmp_path / "old.json").write_text(json.dumps(document))
    assert load_model(tmp_path / "old.json").settings.min_support == 1


@settings(max_examples=5, deadline=None)
@given(st.integers(1, 4))
def test_learn_prints_support_and_min_support_drops_the_rest(k: int) -> None:
    folder = EXAMPLES / "set_table"
    everything = json.loads(invoke("learn", folder, "--json", "--paper").stdout)
    sequences = everything["sequences"]
    support = {
        tuple(c): s for c, s in zip(everything["constraints"], everything["support"], strict=True)
    }
    assert all(s == brute_support(sequences, *c) for c, s in support.items())
    result = invoke("learn", folder, "--json", "--paper", "--min-support", k)
    assert result.exit_code == 0, result.output
    kept = json.loads(result.stdout)
    assert {tuple(c) for c in kept["constraints"]} == {c for c, s in support.items() if s >= k}
    table = invoke("learn", folder, "-o", "/dev/null", "--paper", "--min-support", k).stdout
    first = min(support, key=lambda c: (-support[c], c))
    if support[first] >= k:
        assert f"{first[0]}<{first[1]} ({support[first]})" in table
    assert ("Left out by --min-support" in table) == (k > 1)


def test_min_support_zero_is_a_usage_error() -> None:
    result = invoke("learn", EXAMPLES / "blocks", "--json", "--min-support", "0")
    assert result.exit_code == 2
