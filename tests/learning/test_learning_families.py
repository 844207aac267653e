"""What learning must produce at default settings over generated families of
demonstrations (hypothesis; generators in ``tests/support/learning_families.py``).

The families are the acceptance list of state generation (docs/learning.md): scenes
shifted by metres with 1 cm noise, a fixture turned by ±30° carrying its
items, symmetric objects released at any yaw, placement precision from
0.2 mm to 3 cm, stability under a repeated or reordered demonstration, and a
fresh draw of the paper's Experiment 1. Each family must learn one state per
intended placement with the intended reference.
"""

from __future__ import annotations

import math
from collections import Counter
from typing import cast

import numpy as np
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from demoplan import learn
from demoplan.experiments.paper import PAPER_TABLE_II as LIBRARY_TABLE_II
from demoplan.learning.settings import PAPER_SETTINGS
from demoplan.model import Demonstration, Pose, TaskModel
from demoplan.rotations import quat_from_yaw
from demoplan.scenes.scene import Scene, SceneObject
from demoplan.scenes.targets import candidate_goals
from tests.support.learning_families import (
    PAPER_ORDERS,
    PAPER_TABLE_II,
    PAPER_TABLE_III,
    SYMMETRIC_SHAPES,
    Family,
    constraints_from_sequences,
    distinct_places,
    paper_experiment_1,
    precision_family,
    rotate,
    shifted_scene_family,
    slots_family,
    symmetric_family,
    table_places,
    tray_family,
    unambiguous,
)

SEEDS = st.integers(0, 2**32 - 1)
NOISES = [0.0002, 0.001, 0.005, 0.01, 0.02, 0.03]


def describe(model: TaskModel) -> str:
    return "; ".join(
        f"{s.id} {s.object}→{s.position.reference} "
        f"({', '.join(f'{v:.3f}' for v in s.position.value)}) n={len(s.members)}"
        for s in model.states
    )


def rigid_references(family: Family, obj: str) -> list[str | None]:
    """The intended reference of ``obj`` and the references of that one, up the
    chain: ``obj`` is rigid with each (its noise grows by √2 a link), and docs/learning.md
    gives a tie to a reference available in every demonstration — the root of
    a chain is, an intermediate one often is not."""
    chain: list[str | None] = [family.references[obj]]
    while chain[-1] is not None:
        chain.append(family.references.get(chain[-1]))
    return chain


def assert_one_state_per_object(family: Family, model: TaskModel) -> dict[str, str]:
    """One state per object, with its intended position reference or one up that
    reference's chain (:func:`rigid_references`); returns object → state id."""
    counts = Counter(s.object for s in model.states)
    assert counts == Counter(list(family.references)), describe(model)
    wrong = {
        s.object: (s.position.reference, family.references[s.object])
        for s in model.states
        if s.position.reference not in rigid_references(family, s.object)
        or (family.references[s.object] is not None and s.position.reference is None)
    }
    assert not wrong, f"(learned, intended) references {wrong}; {describe(model)}"
    return {s.object: s.id for s in model.states}


def assert_constraints_follow_orders(family: Family, model: TaskModel, ids: dict[str, str]) -> None:
    """Constraints: exactly the pairs ordered the same way in every demonstration."""
    expected = {(ids[a], ids[b]) for a, b in constraints_from_sequences(family.orders)}
    assert set(model.constraints) == expected
    assert len(model.constraints) == len(expected)


# 1. Scenes shifted by metres with 1 cm noise.


@st.composite
def shifted_families(draw: st.DrawFn) -> Family:
    rng = np.random.default_rng(draw(SEEDS))
    family = shifted_scene_family(rng, draw(st.integers(2, 5)), draw(st.integers(2, 5)))
    assume(unambiguous(family))
    return family


@settings(max_examples=30, deadline=None)
@given(family=shifted_families())
def test_scenes_shifted_by_metres_keep_one_state_per_object(family: Family) -> None:
    """Each relative object is one state against its intended reference, its mean
    offset within 1 cm + 3σ/√n of the truth; constraints are the pairs ordered
    alike in every demonstration."""
    model = learn(family.demos)
    ids = assert_one_state_per_object(family, model)
    tolerance = 0.01 + 3 * family.sigma / math.sqrt(len(family.demos))
    for state in model.states:
        truth = family.offsets[state.object]
        if truth is None or state.position.reference != family.references[state.object]:
            continue
        error = math.dist(state.position.value[:2], truth[:2])
        assert error <= tolerance, f"{state.object}: {error * 1000:.1f} mm off"
    assert_constraints_follow_orders(family, model, ids)
    assert model.sequences == tuple(tuple(ids[o] for o in order) for order in family.orders)


# 2. A fixture turned by ±30° between demonstrations, items rigid in its frame.


@st.composite
def tray_families(draw: st.DrawFn, landmark: bool = False) -> Family:
    rng = np.random.default_rng(draw(SEEDS))
    return tray_family(
        rng,
        draw(st.integers(2, 4)),
        draw(st.integers(3, 5)),
        oriented=draw(st.booleans()),
        landmark=landmark,
    )


def offsets_in_tray_frame(family: Family) -> dict[str, np.ndarray]:
    """Each item's mean placement in the tray's frame over the demonstrations,
    R(−tray yaw)·(item − tray): the truth plus the mean of the noise."""
    rows: dict[str, list[np.ndarray]] = {}
    for demo in family.demos:
        tray = dict(demo.landmarks).get("tray") or next(
            s.pose for s in demo.steps if s.object == "tray"
        )
        for step in demo.steps:
            if step.object != "tray":
                local = rotate(-tray.yaw, np.subtract(step.pose.position, tray.position)[:2])
                rows.setdefault(step.object, []).append(
                    np.array([*local, step.pose.position[2] - tray.position[2]])
                )
    return {name: np.mean(values, axis=0) for name, values in rows.items()}


@settings(max_examples=30, deadline=None)
@given(family=tray_families())
def test_items_on_a_turned_tray_are_learned_in_the_trays_frame(family: Family) -> None:
    """Each item is one state against the tray whose value is the item's offset
    in the tray's frame (docs/learning.md) as demonstrated (the mean over the
    demonstrations, so that the noise does not count), within 3 mm."""
    model = learn(family.demos)
    items = [s for s in model.states if s.object != "tray"]
    assert Counter(s.object for s in items) == Counter(
        o for o in family.references if o != "tray"
    ), describe(model)
    for state in items:
        assert state.position.reference == "tray", describe(model)
        error = math.dist(state.position.value, offsets_in_tray_frame(family)[state.object])
        assert error <= 0.003, f"{state.object}: {error * 1000:.1f} mm off; {describe(model)}"


def _scene_with_tray_at(family: Family, tray: Pose, *, landmark: bool) -> Scene:
    """The items away from the tray (on a row at y = −0.5 m); the tray at ``tray``."""
    items = sorted(o for o in family.references if o != "tray")
    objects = [
        SceneObject(name, Pose((0.2 + 0.1 * k, -0.5, 0.0), quat_from_yaw(0.0)), None)
        for k, name in enumerate(items)
    ]
    if landmark:
        return Scene(tuple(objects), landmarks=(("tray", tray),))
    return Scene((SceneObject("tray", tray, None), *objects))


@settings(max_examples=25, deadline=None)
@given(family=tray_families(landmark=True), place=st.tuples(st.floats(-1, 2), st.floats(-1, 2)))
def test_a_tray_turned_by_90_degrees_carries_its_items_targets(
    family: Family, place: tuple[float, float]
) -> None:
    """The tray as a landmark, demonstrated at ±30°, turned by 90° at a new place
    in the scene: every item's resolved target is tray + R(90°)·offset (3 mm)."""
    model = learn(family.demos)
    tray = Pose((place[0], place[1], 0.0), quat_from_yaw(90.0))
    candidates = candidate_goals(model, _scene_with_tray_at(family, tray, landmark=True))
    assert candidates
    offsets = offsets_in_tray_frame(family)
    for candidate in candidates:
        for subtask in candidate.subtasks:
            want = np.array(place) + rotate(90.0, offsets[subtask.object][:2])
            error = math.dist(subtask.pose.position[:2], want)
            assert error <= 0.003, f"{subtask.object}: target {error * 1000:.1f} mm off"


@settings(max_examples=25, deadline=None)
@given(family=tray_families(), place=st.tuples(st.floats(-1, 2), st.floats(-1, 2)))
def test_items_targets_follow_the_trays_target_pose(
    family: Family, place: tuple[float, float]
) -> None:
    """The tray moved in the demonstrations (so it is put down at its learned
    pose in every candidate): a scene with the tray turned by 90° elsewhere;
    every item's target is the tray's target + R(tray's target yaw)·offset (3 mm)."""
    model = learn(family.demos)
    tray = Pose((place[0], place[1], 0.0), quat_from_yaw(90.0))
    candidates = candidate_goals(model, _scene_with_tray_at(family, tray, landmark=False))
    assert candidates
    offsets = offsets_in_tray_frame(family)
    for candidate in candidates:
        tray_target: Pose | None = None
        for subtask in candidate.subtasks:
            if subtask.object == "tray":
                tray_target = subtask.pose
                continue
            assert tray_target is not None, "the tray must come before its items"
            want = np.array(tray_target.position[:2]) + rotate(
                tray_target.yaw, offsets[subtask.object][:2]
            )
            error = math.dist(subtask.pose.position[:2], want)
            assert error <= 0.003, f"{subtask.object}: target {error * 1000:.1f} mm off"


# 3. Symmetric objects at random yaw.


@st.composite
def symmetric_families(draw: st.DrawFn) -> Family:
    rng = np.random.default_rng(draw(SEEDS))
    kinds = draw(st.lists(st.sampled_from(sorted(SYMMETRIC_SHAPES)), min_size=1, max_size=4))
    return symmetric_family(rng, kinds, draw(st.integers(2, 5)), relative=draw(st.booleans()))


@settings(max_examples=30, deadline=None)
@given(family=symmetric_families())
def test_symmetric_objects_at_any_yaw_are_one_state_each(family: Family) -> None:
    """Cans at any yaw, square boxes turned by 90°·k, rectangular ones by 180°·k:
    orientations compare modulo the symmetry, so no extra states."""
    model = learn(family.demos)
    assert len(model.states) == len(family.references), describe(model)
    assert Counter(s.object for s in model.states) == Counter(list(family.references))


# 4. Precision from 0.2 mm to 3 cm.


@st.composite
def precision_families(draw: st.DrawFn) -> Family:
    rng = np.random.default_rng(draw(SEEDS))
    family = precision_family(
        rng, draw(st.sampled_from(NOISES)), draw(st.integers(3, 5)), draw(st.integers(3, 6))
    )
    assume(unambiguous(family))
    return family


# Derandomized: the F test splits by chance at a small rate. Over 400 random
# draws of this family none split; hypothesis once found a draw in which one
# object's four placements (σ = 2 cm) fell as two pairs 0.4 mm and 11 mm tight,
# 6 cm apart — two places by any test of those data. CI must not depend on it.
@settings(max_examples=40, deadline=None, derandomize=True)
@given(family=precision_families())
def test_the_same_task_is_learned_from_0_2_mm_to_3_cm_noise(family: Family) -> None:
    """One state per placement with the intended reference (absolute vs relative),
    whatever the placement noise; fixed and relative values within 3σ/√n + 1 mm."""
    model = learn(family.demos)
    ids = assert_one_state_per_object(family, model)
    tolerance = 0.001 + 3 * family.sigma / math.sqrt(len(family.demos)) * math.sqrt(2)
    for state in model.states:
        truth = family.offsets[state.object]
        if truth is None:
            continue
        error = math.dist(state.position.value[:2], truth[:2])
        assert error <= tolerance, f"{state.object}: {error * 1000:.1f} mm off (σ {family.sigma})"
    assert_constraints_follow_orders(family, model, ids)


@st.composite
def slots_families(draw: st.DrawFn) -> Family:
    rng = np.random.default_rng(draw(SEEDS))
    return slots_family(
        rng,
        draw(st.sampled_from(NOISES)),
        n_slotted=draw(st.integers(1, 3)),
        n_fixed=draw(st.integers(1, 3)),
        n_relative=draw(st.integers(0, 3)),
        n_demos=draw(st.integers(6, 14)),
    )


# Derandomized: over 1,000 seeded draws of this family 7 miss (0.7 %, measured
# with the generator's own seeds 300-1299). The misses: a slotted object whose
# own precision no other object confirms within a factor of 2 is judged by the
# median one's, a jig's tenfold finer, and its slots merge (or one 3 cm
# placement splits off). Hypothesis, hunting, finds such draws within a few
# hundred examples; CI must not depend on it (docs/learning.md, Limits).
@settings(max_examples=40, deadline=None, derandomize=True)
@given(family=slots_families())
def test_objects_with_two_slots_learn_two_states_beside_precise_ones(family: Family) -> None:
    """Two states for each object put into one of two slots, at those slots
    (within 3σ/√3 + 1 mm), one for every other object with its intended
    reference — though most objects have two places (which once made the
    median precision the gap between slots, 78 mm, and merged them) and the
    jigged ones are placed ten times more precisely than the rest."""
    model = learn(family.demos)
    slots = cast(dict[str, tuple[np.ndarray, np.ndarray]], family.extra["slots"])
    for obj, reference in family.references.items():
        states = [s for s in model.states if s.object == obj]
        if obj not in slots:
            # A jig may be learned against another jig on the same object: the
            # two are rigid (docs/learning.md's tie goes to the nearer reference).
            rigid = {reference} | {
                other
                for other, theirs in family.references.items()
                if reference is not None and theirs == reference and other != obj
            }
            (state,) = states
            assert state.position.reference in rigid, describe(model)
            continue
        assert len(states) == 2, f"{obj}: {describe(model)}"
        tolerance = 0.001 + 3 * family.sigma / math.sqrt(3) * math.sqrt(2)
        nearest = set()
        for state in states:
            assert state.position.reference is None, describe(model)
            error, spot = min(
                (math.dist(state.position.value[:2], p), k) for k, p in enumerate(slots[obj])
            )
            assert error <= tolerance, f"{obj}: {error * 1000:.1f} mm off; {describe(model)}"
            nearest.add(spot)
        assert nearest == {0, 1}


# 5. Stability: a repeated demonstration, a permutation of the demonstrations.


@st.composite
def any_family(draw: st.DrawFn) -> Family:
    return draw(
        st.one_of(shifted_families(), tray_families(), symmetric_families(), precision_families())
    )


def _identity(model: TaskModel) -> list[tuple[str, str, str | None, str | None]]:
    return [(s.id, s.object, s.position.reference, s.orientation.reference) for s in model.states]


@settings(max_examples=30, deadline=None)
@given(family=any_family(), data=st.data())
def test_a_repeated_demonstration_changes_no_state(family: Family, data: st.DataObject) -> None:
    """Learning on the demonstrations plus a copy of one of them: the same states
    (ids, objects, references), the same sequences for the original ones, the
    same constraints; only member counts may change."""
    demos = family.demos
    k = data.draw(st.integers(0, len(demos) - 1))
    copy = Demonstration(
        f"{demos[k].name}-again",
        demos[k].steps,
        demos[k].objects,
        demos[k].landmarks,
        demos[k].initial,
    )
    base, repeated = learn(demos), learn([*demos, copy])
    assert _identity(repeated) == _identity(base), f"{describe(base)}\n→ {describe(repeated)}"
    assert repeated.sequences[: len(demos)] == base.sequences
    assert repeated.sequences[-1] == base.sequences[k]
    assert set(repeated.constraints) == set(base.constraints)


def _keys(model: TaskModel) -> dict[str, tuple[object, ...]]:
    return {
        s.id: (
            s.object,
            s.position.reference,
            s.orientation.reference,
            tuple(round(v, 4) + 0.0 for v in s.position.value),
        )
        for s in model.states
    }


def _relabelled(model: TaskModel) -> set[tuple[object, object]]:
    keys = _keys(model)

    def key(label: str) -> tuple[object, ...]:
        state, _, visit = label.partition("#")
        return (*keys[state], visit)

    return {(key(x), key(y)) for x, y in model.constraints}


@settings(max_examples=30, deadline=None)
@given(family=any_family(), data=st.data())
def test_the_order_of_the_demonstrations_does_not_matter(
    family: Family, data: st.DataObject
) -> None:
    """Learning on a permutation of the demonstrations: the same states as
    (object, references, value to 0.1 mm) and the same constraints up to the
    relabelling."""
    permutation = data.draw(st.permutations(range(len(family.demos))))
    base = learn(family.demos)
    permuted = learn([family.demos[i] for i in permutation])
    assert sorted(map(str, _keys(permuted).values())) == sorted(map(str, _keys(base).values())), (
        f"{describe(base)}\n→ {describe(permuted)}"
    )
    assert _relabelled(permuted) == _relabelled(base)


# 6. A fresh draw of precise data with the paper's structure (Experiment 1).


@settings(max_examples=30, deadline=None)
@given(seed=SEEDS)
def test_a_fresh_draw_of_experiment_1_learns_table_ii_and_its_32_constraints(seed: int) -> None:
    """Three demonstrations in the orders of Table III, σ = 0.3 mm, a new scene
    each draw: the states of Table II (ids, objects, references, values within
    5 mm), the sequences of Table III and the 32 constraints of §IV.B — with
    the paper's reading (fixed 3 mm ties, the plain comparison). Table II's
    decisions compare spreads of 1–2 cm over three placements (the knife:
    12 mm to the plate against 23 mm absolute); at the defaults' F test
    three placements do not support them (test below)."""
    # σ = 0.3 mm: the draws' designed margins are 4–5 mm against the paper's
    # fixed 3 mm tie, and at σ = 0.5 mm one draw in 300 lost one (measured);
    # at 0.3 mm none of 1,800 did.
    draw = paper_experiment_1(np.random.default_rng(seed), sigma=0.0003)
    model = learn(draw.demos, settings=PAPER_SETTINGS)
    got = [(s.id, s.object, s.position.reference) for s in model.states]
    assert got == [(i, o, r) for i, o, r, _ in PAPER_TABLE_II], describe(model)
    for state, (_, _, _, xy) in zip(model.states, PAPER_TABLE_II, strict=True):
        error = math.dist(state.position.value[:2], xy)
        assert error <= 0.005, f"{state.id}: {error * 1000:.1f} mm off; {describe(model)}"
    assert [("".join(s)) for s in model.sequences] == PAPER_TABLE_III
    expected = constraints_from_sequences([list(s) for s in PAPER_TABLE_III])
    assert len(expected) == 32
    assert set(model.constraints) == expected
    assert [tuple(d.steps[k].object for k in range(7)) for d in draw.demos] == list(PAPER_ORDERS)


@settings(max_examples=20, deadline=None)
@given(seed=SEEDS)
def test_at_defaults_a_fresh_draw_of_experiment_1_learns_the_seven_places_of_table_ii(
    seed: int,
) -> None:
    """The same draws at the defaults: Table II's ten states name seven places (I
    is B's spot beside the plate, H is D's, J is C's — the tables' own numbers,
    tests/learning/test_states.py); the defaults learn one state per place, within 1 cm
    of it (the fork's designed deviations do not average out: up to 7.4 mm
    over 60 seeds), in Table III's order, with §IV.B's constraints over the
    places; the napkin on the plate (0.4 mm against centimetres)."""
    draw = paper_experiment_1(np.random.default_rng(seed))
    model = learn(draw.demos)
    sequences = [tuple(s) for s in PAPER_TABLE_III]
    paper = table_places(LIBRARY_TABLE_II, sequences)
    merged = distinct_places(paper)
    as_paper: dict[str, str] = {}
    for state in model.states:
        place = np.mean([draw.demos[d].steps[k].pose.position[:2] for d, k in state.members], 0)
        (as_paper[state.id],) = (
            p
            for p in set(merged.values())
            if paper[p][0] == state.object and math.dist(paper[p][1], place) <= 0.01
        )
    assert sorted(as_paper.values()) == sorted(set(merged.values())), describe(model)
    place_sequences = [[merged[s] for s in sequence] for sequence in sequences]
    assert [[as_paper[s] for s in seq] for seq in model.sequences] == place_sequences
    constraints = {(as_paper[a], as_paper[b]) for a, b in model.constraints}
    assert constraints == constraints_from_sequences(place_sequences)
    napkin = [s for s in model.states if s.object == "napkin"]
    assert [s.position.reference for s in napkin] == ["plate"]
