"""learn --update's change summary (demoplan.learning.changes)."""

from __future__ import annotations

from demoplan.documents.demonstrations import load_demonstrations
from demoplan.learning import learn
from demoplan.learning.changes import model_changes
from demoplan.learning.settings import PAPER_SETTINGS
from tests.support.helpers import EXAMPLES


def test_a_new_demonstration_reports_the_states_and_constraints_it_adds() -> None:
    demos = load_demonstrations([EXAMPLES / "blocks" / "demonstrations.json"])
    first = learn(demos[:1], settings=PAPER_SETTINGS)
    both = learn(demos, settings=PAPER_SETTINGS)
    changes = model_changes(first, both)
    # Demonstration 2 starts with green on the table (Table IV's D): a new state,
    # and the order it shows removes B<… pairs nothing; D's pairs are added.
    assert changes.added == ("D",)
    assert ("D", "C") in changes.constraints_added
    assert not changes.split and not changes.merged
    assert any(line.startswith("states added: D") for line in changes.lines())


def test_the_same_demonstrations_change_nothing() -> None:
    demos = load_demonstrations([EXAMPLES / "set_table"])
    model = learn(demos)
    changes = model_changes(model, learn([*demos, demos[0]]))
    assert changes.unchanged
    assert changes.lines() == ["no state, reference or constraint changed"]


def test_a_teacher_constraint_closing_a_cycle_is_refused_with_the_cycle() -> None:
    from dataclasses import replace

    import pytest

    from demoplan.errors import InputError

    demos = load_demonstrations([EXAMPLES / "blocks" / "demonstrations.json"])
    with pytest.raises(InputError, match=r"cycle A < C < D < A .* demonstration 2"):
        learn(demos, settings=replace(PAPER_SETTINGS, require=("red<green",)))
    # green<red agrees with both demonstrations' orders: no cycle.
    model = learn(demos, settings=replace(PAPER_SETTINGS, require=("green<red",)))
    assert model.teacher_constraints


def test_a_split_is_reported_and_requirements_stay_on_their_steps() -> None:
    """Three demonstrations put the spoon behind the plate twice and to its right
    once: one state (a place seen once is none of its own). Two more (right,
    behind) split it; the update says so, and a requirement stated by id on the
    first model keeps naming the steps it was learned from (``@d.s``)."""
    from dataclasses import replace

    from demoplan.learning import TaskModelLearner, update

    demos = load_demonstrations([EXAMPLES / "two_placements" / "demonstrations.json"])
    first = TaskModelLearner(replace(PAPER_SETTINGS, require=("B<C",))).fit(demos[:3]).model_
    assert [(s.id, s.object) for s in first.states] == [
        ("A", "plate"),
        ("B", "spoon"),
        ("C", "fork"),
    ]
    updated = update(first, demos[3:])
    changes = model_changes(first, updated)
    assert changes.split == (("B", ("B", "D")),)
    assert "state B split into B, D" in changes.lines()
    assert updated.settings.require == ("@1.2<@1.3",)
    assert updated.teacher_constraints == (("B", "C"),)
    assert updated.sequences[1] == ("A", "C", "D")  # demonstration 2's spoon: the right one
