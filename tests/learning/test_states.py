"""State generation (paper §IV.A): golden tests against Tables II and IV and
the other shipped datasets."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan import TaskModelLearner, load_demonstrations
from demoplan.experiments.paper import PAPER_TABLE_II, PAPER_TABLE_IV, PaperState
from demoplan.learning import LearningSettings
from demoplan.learning.settings import PAPER_SETTINGS
from demoplan.learning.states import generate_states, state_letters
from demoplan.model import Demonstration, Pose, Step
from demoplan.rotations import angle_between, quat_from_yaw
from tests.support.helpers import EXAMPLES, TABLE_II
from tests.support.learning_families import (
    constraints_from_sequences,
    distinct_places,
    table_places,
)

TABLE_III = [tuple("ABCDEFG"), tuple("AEHIJFG"), tuple("ACBFEDG")]

# Table IV: state, object, relative position, relative orientation, (x, y, z), θ.
TABLE_IV = [
    ("A", "wood", None, None, (0.34, 0.04, 0.00), 0),
    ("B", "green", "wood", "wood", (0.06, 0.00, 0.00), 0),
    ("C", "red", "wood", "wood", (0.03, 0.00, 0.04), 0),
    ("D", "green", None, None, (0.40, 0.04, 0.00), 0),
]
TABLE_V = [("A", "B", "C"), ("D", "A", "C")]


@pytest.fixture(scope="module")
def set_table() -> TaskModelLearner:
    """The shipped examples were drawn for the paper's reading (PAPER_SETTINGS)."""
    return TaskModelLearner(PAPER_SETTINGS).fit(load_demonstrations([EXAMPLES / "set_table"]))


@pytest.fixture(scope="module")
def blocks() -> TaskModelLearner:
    return TaskModelLearner(PAPER_SETTINGS).fit(
        load_demonstrations([EXAMPLES / "blocks" / "demonstrations.json"])
    )


def test_experiment_1_reproduces_table_ii(set_table: TaskModelLearner) -> None:
    got = [
        (s.id, s.object, s.position.reference, tuple(round(v, 2) for v in s.position.value[:2]))
        for s in set_table.states_
    ]
    assert got == [(i, o, r, tuple(float(v) for v in xy)) for i, o, r, xy in TABLE_II]


def test_experiment_1_reproduces_table_iii_and_32_constraints(set_table: TaskModelLearner) -> None:
    assert list(set_table.sequences_) == TABLE_III
    assert len(set_table.constraints_) == 32


def test_experiment_1_state_j_exists_because_the_glass_was_placed_first(
    set_table: TaskModelLearner,
) -> None:
    """The fork is relative to the glass only in demonstration 2, the only one in
    which the glass was already placed (paper §V.A)."""
    fork_scores = {
        s.reference: s.rms
        for s in set_table.reference_scores_
        if s.object == "fork" and s.kind == "position"
    }
    assert fork_scores["glass"] < fork_scores["plate"] < fork_scores[None]
    state_j = next(s for s in set_table.states_ if s.id == "J")
    assert state_j.members == ((1, 4),)


def test_experiment_2_reproduces_table_iv(blocks: TaskModelLearner) -> None:
    got = []
    for s in blocks.states_:
        rpy = s.orientation.rpy
        assert rpy is not None
        assert abs(rpy[0]) < 1e-6 and abs(rpy[1]) < 1e-6  # planar blocks
        got.append(
            (
                s.id,
                s.object,
                s.position.reference,
                s.orientation.reference,
                tuple(round(v, 2) + 0.0 for v in s.position.value),
                round(rpy[2]) + 0,
            )
        )
    assert got == TABLE_IV


def test_experiment_2_reproduces_table_v(blocks: TaskModelLearner) -> None:
    assert list(blocks.sequences_) == TABLE_V
    # Five by the rule of §IV.B (the paper's text says four; docs/learning.md).
    assert blocks.constraints_ == (("A", "B"), ("A", "C"), ("B", "C"), ("D", "A"), ("D", "C"))
    assert blocks.goals_ == (("A", "B", "C"), ("A", "C", "D"))


def test_kmeans_separates_two_genuinely_different_spoon_placements() -> None:
    demos = load_demonstrations([EXAMPLES / "two_placements" / "demonstrations.json"])
    learner = TaskModelLearner(PAPER_SETTINGS).fit(demos)
    spoon = [s for s in learner.states_ if s.object == "spoon"]
    assert len(spoon) == 2
    assert {s.position.reference for s in spoon} == {"plate"}
    behind, right = sorted(spoon, key=lambda s: s.position.value[0])
    assert math.dist(behind.position.value, right.position.value) >= 0.10
    assert behind.position.value[1] == pytest.approx(0.14, abs=0.005)
    assert right.position.value[0] == pytest.approx(0.14, abs=0.005)
    # Demonstrations 1, 3, 5 put it behind the plate, 2 and 4 to its right.
    assert sorted(d for d, _ in behind.members) == [0, 2, 4]
    assert sorted(d for d, _ in right.members) == [1, 3]
    # The plate and the fork keep one state each.
    assert sum(s.object == "plate" for s in learner.states_) == 1
    assert sum(s.object == "fork" for s in learner.states_) == 1


def test_cucumber_table_i_references_and_repeated_knife_states() -> None:
    """Table I's structure: the knife moves down and up once per slice (states C
    and D, repeated visits), relative to what holds the cucumber. Since docs/learning.md's
    update, offsets are in the reference's frame and orientations are compared
    modulo symmetry: the example's cucumber is a cylinder (any turn about its
    axis looks the same, so its orientation is the same everywhere: a tie, to
    absolute), and the knife's offsets in the board's frame (turned ±4° between
    the demonstrations) are tighter than towards the cylinder, whose frame has
    no turn."""
    demos = load_demonstrations([EXAMPLES / "cucumber" / "demonstrations.json"])
    learner = TaskModelLearner(PAPER_SETTINGS).fit(demos)
    by_id = {s.id: s for s in learner.states_}
    assert [(s.object, s.position.reference, s.orientation.reference) for s in learner.states_] == [
        ("board", None, None),
        ("cucumber", "board", None),
        ("knife", "board", "board"),
        ("knife", "board", "board"),
    ]
    cucumber = by_id["B"].position.value[2]
    up, down = by_id["C"], by_id["D"]
    assert up.position.value[2] - cucumber == pytest.approx(0.06, abs=0.003)  # 6 cm above
    assert down.position.value[2] - cucumber == pytest.approx(0.0, abs=0.003)  # on it
    # Up and down share the knife's orientation relative to the cucumber.
    assert up.orientation.value is not None and down.orientation.value is not None
    assert angle_between(up.orientation.value, down.orientation.value) < 1.0
    assert learner.sequences_[0] == ("A", "B", "C", "D", "C", "D", "C", "D")


def test_orientation_reference_is_chosen_independently_of_position() -> None:
    """The box's position follows the tray, its orientation follows the sign.

    Relative positions are in the reference's frame (docs/learning.md): the box sits
    10 cm along the turned tray's x axis, not at a fixed offset in world axes.
    """
    rng = np.random.default_rng(3)
    demos = []
    for d in range(4):
        tray = np.array([0.4, 0.3]) + rng.normal(0, 0.03, 2)
        sign_yaw = float(rng.uniform(-60, 60))
        tray_yaw = float(rng.uniform(-60, 60))
        turn = math.radians(tray_yaw)
        along_tray = 0.1 * np.array([math.cos(turn), math.sin(turn)])
        box = tray + along_tray + rng.normal(0, 0.001, 2)
        steps = (
            Step("tray", Pose((*tray, 0.0), quat_from_yaw(tray_yaw))),
            Step("sign", Pose((0.8 + d * 0.03, 0.1, 0.0), quat_from_yaw(sign_yaw))),
            Step("box", Pose((*box, 0.0), quat_from_yaw(sign_yaw + 30 + rng.normal(0, 0.1)))),
        )
        demos.append(Demonstration(f"d{d}", steps))
    # Two of the three objects are turned at random here, so the estimated
    # orientation precision (a median over the objects) would be their scatter
    # (about 25°, beyond the 15° separation: no orientation learned); the
    # teacher states it instead, as a user may (docs/learning.md).
    learner = TaskModelLearner(orientation_noise=0.5).fit(demos)
    box = [s for s in learner.states_ if s.object == "box"]
    assert len(box) == 1
    assert box[0].position.reference == "tray"
    assert box[0].orientation.reference == "sign"
    assert box[0].orientation.rpy is not None
    assert box[0].orientation.rpy[2] == pytest.approx(30, abs=0.5)


def test_landmarks_are_usable_as_references() -> None:
    rng = np.random.default_rng(5)
    demos = []
    for d in range(4):
        shelf = np.array([0.2 + 0.1 * d, 0.5 - 0.05 * d])
        cup = shelf + [0.05, 0.02] + rng.normal(0, 0.001, 2)
        demos.append(
            Demonstration(
                f"d{d}",
                (Step("cup", Pose((*cup, 0.0))),),
                landmarks=(("shelf", Pose((*shelf, 0.0))),),
            )
        )
    (cup,) = TaskModelLearner().fit(demos).states_
    assert cup.position.reference == "shelf"
    assert cup.position.value[:2] == pytest.approx((0.05, 0.02), abs=0.002)


def test_a_single_demonstration_is_reproduced_in_absolute_coordinates() -> None:
    demo = load_demonstrations([EXAMPLES / "set_table" / "demonstration-1.json"])
    learner = TaskModelLearner().fit(demo)
    assert all(s.position.reference is None for s in learner.states_)
    assert learner.sequences_ == (tuple("ABCDEFG"),)
    for state, step in zip(learner.states_, demo[0].steps, strict=True):
        assert state.position.value == pytest.approx(step.pose.position)


def test_yaw_wraps_at_180_degrees() -> None:
    """179° and −179° are 2° apart: one cluster, mean 180°, spread about 1°."""
    demos = [
        Demonstration(f"d{k}", (Step("box", Pose((0.3, 0.2, 0.0), quat_from_yaw(yaw))),))
        for k, yaw in enumerate([179.0, -179.0, 179.5, -179.5])
    ]
    (state,) = TaskModelLearner().fit(demos).states_
    assert state.orientation.rpy is not None
    assert abs(abs(state.orientation.rpy[2]) - 180.0) < 1e-6
    assert math.sqrt(state.orientation.spread) < 2.0


def test_orientations_near_gimbal_lock_are_compared_as_rotations() -> None:
    """Pitch 90°: Euler angles jump (roll and yaw trade off) but rotations do not."""
    from demoplan.rotations import quat_from_rpy

    rpys = [(0, 90, 0), (30, 89.9, 30), (-45, 89.95, -45), (10, 90, 10)]
    demos = [
        Demonstration(f"d{k}", (Step("knife", Pose((0.3, 0.2, 0.0), quat_from_rpy(rpy))),))
        for k, rpy in enumerate(rpys)
    ]
    (state,) = TaskModelLearner().fit(demos).states_
    assert math.sqrt(state.orientation.spread) < 0.2


def test_an_object_moved_twice_uses_its_current_placement_as_reference() -> None:
    """docs/learning.md: for an object moved more than once, the placement current at the step."""
    demos = []
    for d in range(3):
        base = 0.1 * d
        steps = (
            Step("board", Pose((0.30 + base, 0.2, 0.0))),
            Step("cup", Pose((0.35 + base, 0.2, 0.0))),
            Step("board", Pose((0.60 + base, 0.5, 0.0))),
            Step("lid", Pose((0.62 + base, 0.5, 0.0))),
        )
        demos.append(Demonstration(f"d{d}", steps))
    learner = TaskModelLearner().fit(demos)
    lid = next(s for s in learner.states_ if s.object == "lid")
    assert lid.position.reference == "board"
    assert lid.position.value[:2] == pytest.approx((0.02, 0.0), abs=1e-9)


def test_state_letters_follow_the_spec() -> None:
    assert [state_letters(i) for i in (0, 1, 25, 26, 27, 51, 52, 701, 702)] == [
        "A",
        "B",
        "Z",
        "AA",
        "AB",
        "AZ",
        "BA",
        "ZZ",
        "AAA",
    ]


def test_each_state_keeps_its_statistics() -> None:
    demos = load_demonstrations([EXAMPLES / "set_table"])
    generation = generate_states(demos, LearningSettings())
    for state in generation.states:
        assert state.members
        for d, s in state.members:
            assert demos[d].steps[s].object == state.object
            assert generation.sequences[d][s] == state.id
        assert state.position.spread >= 0


@pytest.mark.parametrize("noise", [0.002, 0.0025, 0.003, 0.0035])
def test_experiment_1_holds_over_a_range_of_noise_settings(noise: float) -> None:
    demos = load_demonstrations([EXAMPLES / "set_table"])
    learner = TaskModelLearner(PAPER_SETTINGS, position_noise=noise).fit(demos)
    assert list(learner.sequences_) == TABLE_III
    assert [(s.object, s.position.reference) for s in learner.states_] == [
        (o, r) for _, o, r, _ in TABLE_II
    ]


@pytest.mark.parametrize(("noise", "angular_noise"), [(0.002, 0.5), (0.004, 0.6), (0.003, 0.55)])
def test_experiment_2_holds_over_a_range_of_noise_settings(
    noise: float, angular_noise: float
) -> None:
    demos = load_demonstrations([EXAMPLES / "blocks" / "demonstrations.json"])
    learner = TaskModelLearner(
        PAPER_SETTINGS, position_noise=noise, orientation_noise=angular_noise
    ).fit(demos)
    assert list(learner.sequences_) == TABLE_V
    assert [(s.position.reference, s.orientation.reference) for s in learner.states_] == [
        (r, o) for _, _, r, o, _, _ in TABLE_IV
    ]


@given(
    offsets=st.lists(st.floats(-2.0, 2.0), min_size=2, max_size=8),
    centre=st.sampled_from([180.0, -180.0, 179.0, 0.0, 90.0]),
)
@settings(max_examples=60, deadline=None)
def test_yaws_a_few_degrees_apart_are_one_state_wherever_they_wrap(
    offsets: list[float], centre: float
) -> None:
    """Yaws within ±2° of a centre (across the ±180° seam too) are one state whose
    mean is the centre on the circle."""
    yaws = [((centre + d + 180.0) % 360.0) - 180.0 for d in offsets]
    demos = [
        Demonstration(f"d{k}", (Step("box", Pose((0.3, 0.2, 0.0), quat_from_yaw(yaw))),))
        for k, yaw in enumerate(yaws)
    ]
    (state,) = TaskModelLearner().fit(demos).states_
    assert state.orientation.value is not None
    # A demonstration that repeats an earlier one exactly is evidence of nothing
    # new: the statistics are over the distinct demonstrations (generate_states).
    distinct: dict[float, list[float]] = {}
    for yaw, d in zip(yaws, offsets, strict=True):
        distinct.setdefault(yaw, []).append(d)
    firsts = [ds[0] for ds in distinct.values()]
    mean_offset = sum(firsts) / len(firsts)
    assert angle_between(state.orientation.value, quat_from_yaw(centre + mean_offset)) < 0.01


# At the defaults: the places the paper's tables name. Tables II and IV give one
# place several states where the reference that won a near tie differs (the
# knife relative to the plate, B, or to the spoon, I — the same spot beside the
# plate); decisions the data support (docs/learning.md) merge them, so the defaults
# must learn exactly the tables' distinct places, in the tables' orders.


def learned_places(learner: TaskModelLearner, demos: list[Demonstration]) -> dict[str, np.ndarray]:
    """Each learned state's mean absolute place over its members."""
    return {
        s.id: np.mean([demos[d].steps[k].pose.position for d, k in s.members], axis=0)
        for s in learner.states_
    }


def test_table_ii_names_seven_places_and_table_iv_three() -> None:
    """The paper's own tables: I is B's place, H is D's, J is C's (Table II);
    D is B's (Table IV) — e.g. I = H + (0.08, −0.04) = A + (0.10, 0.00) = B."""
    two = distinct_places(table_places(PAPER_TABLE_II, TABLE_III))
    assert {s: p for s, p in two.items() if s != p} == {"H": "D", "I": "B", "J": "C"}
    four = distinct_places(table_places(PAPER_TABLE_IV, TABLE_V))
    assert {s: p for s, p in four.items() if s != p} == {"D": "B"}


@pytest.mark.parametrize(
    ("folder", "rows", "sequences"),
    [
        ("set_table", PAPER_TABLE_II, TABLE_III),
        ("blocks", PAPER_TABLE_IV, TABLE_V),
    ],
)
def test_at_the_defaults_the_shipped_examples_learn_the_tables_places(
    folder: str,
    rows: tuple[PaperState, ...],
    sequences: list[tuple[str, ...]],
) -> None:
    """One learned state per distinct place of Table II (7) / IV (3), at that place
    within 1.5 cm (the tables round to 1 cm), in the tables' order per
    demonstration; the constraints are §IV.B's over those places — for the
    blocks exactly "red last", which §V.B calls the only real constraint."""
    demos = load_demonstrations([EXAMPLES / folder])
    learner = TaskModelLearner().fit(demos)
    paper = table_places(rows, sequences)
    merged = distinct_places(paper)
    learned = learned_places(learner, demos)
    as_paper: dict[str, str] = {}
    for state in learner.states_:
        (match,) = (
            p
            for p in set(merged.values())
            if paper[p][0] == state.object
            and math.dist(paper[p][1], learned[state.id][: len(paper[p][1])]) <= 0.015
        )
        as_paper[state.id] = match
    assert sorted(as_paper.values()) == sorted(set(merged.values()))
    place_sequences = [[merged[s] for s in sequence] for sequence in sequences]
    assert [[as_paper[s] for s in sequence] for sequence in learner.sequences_] == place_sequences
    got = {(as_paper[a], as_paper[b]) for a, b in learner.constraints_}
    assert got == constraints_from_sequences(place_sequences)
    if folder == "blocks":
        assert got == {("A", "C"), ("B", "C")}
