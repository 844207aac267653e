"""TaskModelLearner: incremental learning, order independence, scikit-learn habits."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan import TaskModelLearner, load_demonstrations
from demoplan.errors import InputError, NotFittedError
from demoplan.learning import update
from demoplan.learning.constraints import ordered_pairs
from demoplan.learning.settings import PAPER_SETTINGS
from demoplan.model import Demonstration, Pose, Step, TaskModel
from tests.support.helpers import EXAMPLES, random_task_demonstrations


def _signature(model: TaskModel, label: str) -> tuple[object, ...]:
    """What a visit label stands for, independent of lettering."""
    state_id, _, occurrence = label.partition("#")
    state = model.state(state_id)
    value = tuple(round(v, 9) for v in state.position.value)
    orientation = (
        None
        if state.orientation.value is None
        else tuple(round(v, 6) for v in state.orientation.value)
    )
    return (
        state.object,
        state.position.reference,
        value,
        state.orientation.reference,
        orientation,
        int(occurrence or 1),
    )


def _constraint_signatures(model: TaskModel) -> set[tuple[object, object]]:
    return {(_signature(model, x), _signature(model, y)) for x, y in model.constraints}


def test_reading_learned_results_before_fit_raises() -> None:
    with pytest.raises(NotFittedError):
        _ = TaskModelLearner().states_
    with pytest.raises(NotFittedError):
        _ = TaskModelLearner().constraints_


def test_fit_without_demonstrations_is_an_input_error() -> None:
    with pytest.raises(InputError, match="at least one"):
        TaskModelLearner().fit([])


def test_partial_fit_gives_the_same_model_as_fit_on_everything() -> None:
    demos = load_demonstrations([EXAMPLES / "set_table"])
    incremental = TaskModelLearner()
    for demo in demos:
        incremental.partial_fit(demo)
    assert incremental.model_ == TaskModelLearner().fit(demos).model_


def test_teacher_constraints_survive_and_violations_are_reported() -> None:
    demos = load_demonstrations([EXAMPLES / "blocks" / "demonstrations.json"])
    # Table IV's states: the shipped blocks were drawn for the paper's reading.
    learner = TaskModelLearner(PAPER_SETTINGS, require=["green<wood"]).fit(demos)
    # green's states B and D before wood's A; demonstration 1 put wood first.
    assert ("D", "A") in learner.constraints_ and ("B", "A") in learner.constraints_
    assert ("A", "B") not in learner.constraints_
    assert learner.violations_ == ((0, "B", "A"),)
    assert learner.model_.teacher_constraints == (("B", "A"), ("D", "A"))


@given(
    seed=st.integers(0, 10_000),
    n_demos=st.integers(2, 5),
    n_objects=st.integers(2, 6),
    oriented=st.booleans(),
    order=st.randoms(use_true_random=False),
)
@settings(max_examples=40, deadline=None)
def test_model_does_not_depend_on_the_order_of_demonstrations(
    seed: int, n_demos: int, n_objects: int, oriented: bool, order: object
) -> None:
    demos = random_task_demonstrations(seed, n_demos, n_objects, oriented=oriented)
    shuffled = list(demos)
    order.shuffle(shuffled)  # type: ignore[attr-defined]
    a = TaskModelLearner().fit(demos).model_
    b = TaskModelLearner().fit(shuffled).model_
    assert {_signature(a, s.id) for s in a.states} == {_signature(b, s.id) for s in b.states}
    assert _constraint_signatures(a) == _constraint_signatures(b)
    goals_a = {frozenset(_signature(a, g) for g in goal) for goal in a.goals}
    goals_b = {frozenset(_signature(b, g) for g in goal) for goal in b.goals}
    assert goals_a == goals_b


@given(seed=st.integers(0, 10_000), n_demos=st.integers(1, 5), n_objects=st.integers(2, 6))
@settings(max_examples=40, deadline=None)
def test_no_constraint_is_contradicted_and_a_new_demonstration_respects_the_old(
    seed: int, n_demos: int, n_objects: int
) -> None:
    demos = random_task_demonstrations(seed, n_demos + 1, n_objects)
    before = TaskModelLearner().fit(demos[:-1]).model_
    after = TaskModelLearner().fit(demos).model_
    for model in (before, after):
        constraints = set(model.constraints)
        for sequence in model.sequences:
            for x, y in ordered_pairs(sequence):
                assert (y, x) not in constraints
    # Every constraint of the updated model holds in every earlier demonstration.
    for sequence in after.sequences[:-1]:
        for x, y in ordered_pairs(sequence):
            assert (y, x) not in set(after.constraints)


def test_a_failed_partial_fit_leaves_the_learner_as_it_was() -> None:
    demos = load_demonstrations([EXAMPLES / "blocks" / "demonstrations.json"])
    learner = TaskModelLearner(PAPER_SETTINGS).fit(demos[:1])
    before = learner.model_
    moved_landmark = Demonstration(
        "bad", (Step("wood", Pose((0.3, 0.0, 0.0))),), landmarks=(("green", Pose((0.0, 0.0, 0.0))),)
    )
    with pytest.raises(InputError):
        learner.partial_fit(moved_landmark)
    assert learner.model_ is before
    learner.partial_fit(demos[1])  # still usable
    assert learner.sequences_ == (("A", "B", "C"), ("D", "A", "C"))


@pytest.mark.parametrize(
    "settings",
    [
        {"position_noise": 0.0},
        {"orientation_noise": -1.0},
        {"position_separation": 0},
        {"n_init": 0},
    ],
)
def test_settings_out_of_range_are_input_errors(settings: dict[str, float]) -> None:
    with pytest.raises(InputError, match=next(iter(settings))):
        TaskModelLearner(**settings)  # type: ignore[arg-type]


def test_update_keeps_teacher_requirements_on_the_same_states() -> None:
    """State ids can change when a demonstration is added, so a requirement
    stated by id is stored as the steps it was learned from (``@d.s``) and keeps
    naming their states (demonstration 1, steps 3 and 5). (The demonstration
    added here repeats one, which since repeats add no evidence changes no id;
    the anchoring is what is checked.)"""
    demos = load_demonstrations([EXAMPLES / "set_table"])
    model = TaskModelLearner(require=["C<E"]).fit(demos).model_
    assert model.sequences[0][2] == "C" and model.sequences[0][4] == "E"
    updated = update(model, [demos[0]])
    assert updated.settings.require == ("@1.3<@1.5",)
    ((x, y),) = updated.teacher_constraints
    assert (x, y) == (updated.sequences[0][2], updated.sequences[0][4])
    assert updated.state(x).object == "fork" and updated.state(y).object == "glass"


def test_a_partly_oriented_object_is_reported(caplog: pytest.LogCaptureFixture) -> None:
    from demoplan.rotations import quat_from_yaw

    demos = [
        Demonstration(f"d{k}", (Step("knife", Pose((0.3, 0.2, 0.0), q)),))
        for k, q in enumerate([quat_from_yaw(0), None, quat_from_yaw(90)])
    ]
    with caplog.at_level("WARNING"):
        (state,) = TaskModelLearner().fit(demos).states_
    assert state.orientation.value is None
    assert "knife has an orientation in some steps but not in others" in caplog.text


def test_max_clusters_caps_the_scan_of_eq_2() -> None:
    demos = random_task_demonstrations(3, 12, 4)
    free = TaskModelLearner().fit(demos)
    capped = TaskModelLearner(max_clusters=1).fit(demos)
    assert max(s.clustering.n_clusters for s in capped.reference_scores_) == 1
    assert all(c <= 1 for s in capped.reference_scores_ for c, _ in s.clustering.tried)
    assert max(len(s.clustering.tried) for s in free.reference_scores_) > 1
