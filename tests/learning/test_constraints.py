"""Task generalization (paper §IV.B): constraints from state sequences."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from demoplan.errors import InputError
from demoplan.learning.constraints import (
    Requirement,
    anchor_requirements,
    goal_states,
    learn_constraints,
    ordered_pairs,
    parse_requirements,
    required_pairs,
    visit_sequence,
)
from demoplan.model import State, StateOrientation, StatePosition


def test_fig_2_nine_constraints_b_and_e_unconstrained_redundant_a_g_kept() -> None:
    result = learn_constraints(["ABEFG", "AEBFG"])
    assert len(result.constraints) == 9
    assert ("B", "E") not in result.constraints
    assert ("E", "B") not in result.constraints
    assert ("A", "G") in result.constraints  # redundant given A<B, B<G, but kept
    assert result.contradicted == (("B", "E"),)
    assert set(result.constraints) == {
        ("A", "B"),
        ("A", "E"),
        ("A", "F"),
        ("A", "G"),
        ("B", "F"),
        ("B", "G"),
        ("E", "F"),
        ("E", "G"),
        ("F", "G"),
    }


def test_repeated_visits_are_numbered_and_never_contradict_themselves() -> None:
    """Table I: the knife goes up (C) and down (D) several times."""
    sequence = ["A", "B", "C", "D", "C", "D", "C", "D"]
    assert visit_sequence(sequence) == ("A", "B", "C", "D", "C#2", "D#2", "C#3", "D#3")
    result = learn_constraints([sequence])
    assert result.contradicted == ()
    assert len(result.constraints) == 8 * 7 // 2
    assert ("C", "D") in result.constraints and ("D", "C#2") in result.constraints
    assert ("D", "C") not in result.constraints


def test_contradictions_are_permanent_whatever_the_order() -> None:
    sequences = ["ABC", "BAC", "ABC"]
    expected = learn_constraints(sequences).constraints
    assert expected == (("A", "C"), ("B", "C"))
    assert learn_constraints(reversed(sequences)).constraints == expected


def test_teacher_constraints_are_never_removed_and_violations_reported() -> None:
    result = learn_constraints(["ABC", "BAC"], required=[("A", "B")])
    assert ("A", "B") in result.constraints
    assert result.violations == ((1, "A", "B"),)
    # A learned constraint that reverses the teacher's is dropped.
    result = learn_constraints(["ABC"], required=[("C", "A")])
    assert ("A", "C") not in result.constraints and ("C", "A") in result.constraints
    assert result.violations == ((0, "C", "A"),)


def _state(state_id: str, obj: str) -> State:
    return State(
        state_id,
        obj,
        StatePosition(None, (0.0, 0.0, 0.0), 0.0),
        StateOrientation(None, None, 0.0),
        (),
    )


STATES = [_state("A", "plate"), _state("B", "knife"), _state("C", "napkin"), _state("D", "knife")]
SEQUENCES = [["A", "B", "C", "C"], ["A", "D", "C"]]


def pairs(texts: list[str]) -> tuple[tuple[str, str], ...]:
    return required_pairs(parse_requirements(texts), STATES, SEQUENCES)


def test_requirements_are_parsed_once_into_their_sides() -> None:
    (requirement,) = parse_requirements([" C#2 < A "])
    assert requirement == Requirement(" C#2 < A ", ("C#2", "A"))


def test_requirements_accept_state_ids_visits_and_object_names() -> None:
    assert pairs(["A<B", " C#2 < A "]) == (("A", "B"), ("C#2", "A"))
    assert pairs(["knife<napkin"]) == (("B", "C"), ("D", "C"))
    # @d.s: the state of step s of demonstration d (1-based), here D and C#2.
    assert pairs(["@2.2<@1.4"]) == (("D", "C#2"),)


def test_requirements_are_anchored_to_steps_for_updates() -> None:
    anchored = anchor_requirements(parse_requirements(["A<C#2", "knife<C"]), SEQUENCES)
    assert [r.text for r in anchored] == ["@1.1<@1.4", "knife<@1.3"]
    assert anchored == parse_requirements(["@1.1<@1.4", "knife<@1.3"])


def test_cyclic_requirements_are_refused() -> None:
    with pytest.raises(InputError, match="cycle"):
        pairs(["A<B", "B<C", "C<A"])


@pytest.mark.parametrize(
    "text",
    ["A", "A<", "A<<B", "A<Q", "A<A", "spoon<A", "C#x<A", "A#2#3<B", "C#0<A", "A<A#2", "@3.1<A"],
)
def test_bad_requirements_are_refused(text: str) -> None:
    """Unknown names, visits never made (A#2), malformed labels, steps that do not exist."""
    with pytest.raises(InputError, match="require"):
        pairs([text])


def test_goal_is_the_state_set_a_demonstration_ends_in() -> None:
    assert goal_states(["A", "B", "D", "C"], STATES) == ("A", "C", "D")


sequences_strategy = st.lists(
    st.lists(st.sampled_from("ABCDEFG"), min_size=1, max_size=8), min_size=1, max_size=5
)


@given(sequences_strategy)
def test_no_constraint_is_contradicted_by_any_demonstration(sequences: list[list[str]]) -> None:
    constraints = set(learn_constraints(sequences).constraints)
    for sequence in sequences:
        for x, y in ordered_pairs(sequence):
            assert (y, x) not in constraints


@given(sequences_strategy, st.randoms(use_true_random=False))
def test_constraints_do_not_depend_on_the_order_of_demonstrations(
    sequences: list[list[str]], random: object
) -> None:
    shuffled = list(sequences)
    random.shuffle(shuffled)  # type: ignore[attr-defined]
    assert learn_constraints(shuffled) == learn_constraints(sequences)


@given(sequences_strategy, st.lists(st.sampled_from("ABCDEFG"), min_size=1, max_size=8))
def test_a_new_demonstration_only_removes_or_adds_uncontradicted_pairs(
    sequences: list[list[str]], new: list[str]
) -> None:
    before = set(learn_constraints(sequences).constraints)
    after = set(learn_constraints([*sequences, new]).constraints)
    seen_before = set().union(*(ordered_pairs(s) for s in sequences))
    for x, y in after - before:
        assert (y, x) not in seen_before  # never re-adds what a previous demo contradicted
