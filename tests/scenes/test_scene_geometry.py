"""Scene geometry (paper §V.B) and target resolution (docs/scenes.md "Planning")."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.errors import InputError
from demoplan.model import (
    Demonstration,
    ObjectGeometry,
    Pose,
    State,
    StateOrientation,
    StatePosition,
    Step,
    TaskModel,
)
from demoplan.rotations import quat_from_rpy, quat_from_yaw
from demoplan.scenes.geometry import (
    GeometrySettings,
    Location,
    accepted_objects,
    collision_facts,
    exclusions,
    supports,
)
from demoplan.scenes.problems import build_problem
from demoplan.scenes.scene import Gripper, Scene, SceneObject
from demoplan.scenes.targets import candidate_goals
from tests.support.planning_families import grasp_collides

BLOCK = ObjectGeometry("box", (0.04, 0.04, 0.04))
PLATE = ObjectGeometry("cylinder", (0.07, 0.07, 0.015))
FORK = ObjectGeometry("box", (0.012, 0.07, 0.005))
FOOD = ObjectGeometry("cylinder", (0.08, 0.08, 0.04))
GRIPPER = Gripper(finger_radius=0.02)


def loc(
    name: str, x: float, y: float, z: float = 0.0, yaw: float = 0.0, shape: ObjectGeometry = BLOCK
) -> Location:
    return Location(name, (x, y, z), yaw, "current", (name,), (shape,))


def hits(
    a: Location, b: Location, axis: float, shape: ObjectGeometry = BLOCK, gripper: Gripper = GRIPPER
) -> bool:
    facts = collision_facts([a, b], [("g", "o", shape, axis)], gripper)
    return (a.name, b.name, "g") in facts


@pytest.mark.parametrize(
    ("b", "axis", "expected"),
    [
        # fingers of a 4 cm block at (±0.04, 0): |b − finger| < r + g_r = 0.04
        ((0.06, 0.0, 0.0), 0.0, True),  # 0.02 from a finger
        ((0.085, 0.0, 0.0), 0.0, False),  # 0.045
        ((0.0, 0.06, 0.0), 0.0, False),  # beside, not in line with the fingers
        ((0.0, 0.06, 0.0), 90.0, True),  # the other grasp
        ((0.04, 0.0, 0.05), 0.0, False),  # above the finger: 0.05 in 3-D
        ((0.04, 0.0, 0.03), 0.0, True),
    ],
)
def test_paper_rule_hand_computed(
    b: tuple[float, float, float], axis: float, expected: bool
) -> None:
    assert hits(loc("a", 0, 0), loc("b", *b), axis) is expected


@pytest.mark.parametrize(
    ("yaw", "b", "axis", "expected"),
    [
        (90.0, (0.0, 0.06), 0.0, True),  # ĝ rotated with a: the x-grasp now points along y
        (90.0, (0.06, 0.0), 0.0, False),
        (45.0, (0.05, 0.05), 0.0, True),  # fingers at ±(0.0283, 0.0283): 0.0307 away
        (45.0, (0.06, 0.06), 0.0, False),  # 0.0448 away
        (45.0, (-0.05, 0.05), 90.0, True),
    ],
)
def test_paper_rule_rotated(
    yaw: float, b: tuple[float, float], axis: float, expected: bool
) -> None:
    assert hits(loc("a", 0, 0, yaw=yaw), loc("b", *b), axis) is expected


coordinate = st.floats(-0.15, 0.15)


@settings(max_examples=300, deadline=None)
@given(
    ax=coordinate,
    ay=coordinate,
    bx=coordinate,
    by=coordinate,
    bz=st.sampled_from([0.0, 0.04]),
    yaw=st.floats(-180, 180),
    axis=st.sampled_from(["x", "y"]),
)
def test_paper_rule_matches_the_generator(
    ax: float, ay: float, bx: float, by: float, bz: float, yaw: float, axis: str
) -> None:
    """Two implementations of §V.B: the scene geometry and the benchmark generator's."""
    b = (bx, by, bz)
    finger_distances = []
    for sign in (1, -1):
        angle = math.radians(yaw + (0 if axis == "x" else 90))
        finger = (ax + sign * 0.04 * math.cos(angle), ay + sign * 0.04 * math.sin(angle), 0.0)
        finger_distances.append(math.dist(finger, b))
    if min(abs(d - 0.04) for d in finger_distances) < 1e-9:
        return  # on the boundary: rounding decides
    expected = grasp_collides((ax, ay, 0.0), yaw, b, axis)
    got = hits(loc("a", ax, ay, yaw=yaw), loc("b", *b), 0.0 if axis == "x" else 90.0)
    assert got is expected


def test_footprint_rule_for_other_shapes() -> None:
    """A fork beside a plate: the finger that reaches over the rim collides, the one
    along the fork does not; a flat thing lower than the grasp does not."""
    plate = loc("plate", 0.52, 0.44, shape=PLATE)
    fork = loc("fork", 0.45, 0.44, shape=FORK)
    assert hits(fork, plate, 0.0, FORK)  # fingers at x = 0.45 ± 0.026: 0.009 from the rim
    assert not hits(fork, plate, 90.0, FORK)  # fingers at y = 0.44 ± 0.055
    far_fork = loc("fork", 0.40, 0.44, shape=FORK)
    assert not hits(far_fork, plate, 0.0, FORK)
    napkin_on_top = Location("top", (0.45, 0.44, 0.02), 0.0, "current", ("top",), (FORK,))
    assert not hits(napkin_on_top, plate, 0.0, FORK)  # the plate's top (0.015) is below


def test_support_of_a_bridging_block_and_a_stack() -> None:
    wood, green = loc("wood", 0.30, 0.04), loc("green", 0.34, 0.04)
    red = loc("red", 0.32, 0.04, 0.04)
    single = loc("single", 0.30, 0.04, 0.08)  # on red? no: red spans 0.30..0.34 at 0.04..0.08
    floating = loc("floating", 0.60, 0.04, 0.04)
    pairs, nothing_under = supports([wood, green, red, single, floating])
    assert sorted(p for p in pairs if p[0] == "red") == [("red", "green"), ("red", "wood")]
    assert pairs.count(("single", "red")) == 1
    assert nothing_under == ["floating"]


def test_exclusions_overlap_but_not_touching() -> None:
    a, touching, overlapping = loc("a", 0, 0), loc("t", 0.04, 0), loc("o", 0.03, 0)
    stacked = loc("s", 0.0, 0.0, 0.04)
    pairs, _ = supports([a, touching, overlapping, stacked])
    excl = {frozenset(p) for p in exclusions([a, touching, overlapping, stacked], pairs)}
    assert excl == {frozenset("ao"), frozenset("ot")}  # a–t touch; s stands on a (support)


@settings(max_examples=60, deadline=None)
@given(
    thin=st.floats(0.001, 0.02),
    tall=st.floats(0.001, 0.2),
    offset=st.floats(0.0, 0.015),
    yaw=st.floats(-90.0, 90.0),
)
def test_overlapping_places_on_one_level_exclude_each_other_however_thin(
    thin: float, tall: float, offset: float, yaw: float
) -> None:
    """A thin part's place (a 1–20 mm knife) and another object's place
    overlapping it on the table cannot both be occupied, whatever the heights
    (found on the arm: a 5 mm knife's target under a 4 cm obstacle was taken
    as free, since the height overlap did not exceed the 5 mm level
    tolerance); the same knife on top of the other object is stacked, not
    excluded."""
    knife = ObjectGeometry("box", (0.012, 0.09, thin))
    other = ObjectGeometry("box", (0.04, 0.04, tall))
    target = Location("knife", (0.6 + offset, 0.44, 0.0), yaw, "target", ("knife",), (knife,))
    obstacle = Location("obstacle", (0.6, 0.44, 0.0), 0.0, "current", ("obstacle",), (other,))
    assert exclusions([target, obstacle], []) == [("knife", "obstacle")]
    on_top = Location("up", (0.6, 0.44, tall), yaw, "target", ("knife",), (knife,))
    assert exclusions([on_top, obstacle], [("up", "obstacle")]) == []


def test_what_a_location_takes() -> None:
    shapes = {"fork": FORK, "food": FOOD, "plate": PLATE, "b1": BLOCK, "b2": BLOCK}
    fork_spot = Location("l1", (0.45, 0.44, 0.0), 0.0, "target", ("fork",), (FORK,))
    assert accepted_objects(fork_spot, shapes) == ["fork"]
    food_spot = Location("l2", (0.6, 0.5, 0.0), 0.0, "current", ("food",), (FOOD,))
    # blocks are as tall as the food and fit inside its outline; the plate is lower
    assert accepted_objects(food_spot, shapes) == ["food", "b1", "b2"]
    block_spot = Location("l3", (0.3, 0.0, 0.0), 30.0, "current", ("b1",), (BLOCK,))
    assert accepted_objects(block_spot, shapes) == ["b1", "b2"]  # put down turned like b1
    knife = ObjectGeometry("box", (0.012, 0.09, 0.005))
    knife_spot = Location("l4", (0.6, 0.4, 0.0), 0.0, "target", ("knife",), (knife,))
    cutlery = {"knife": knife, "fork": FORK}
    assert accepted_objects(knife_spot, cutlery) == ["knife", "fork"]  # the fork is shorter
    assert accepted_objects(fork_spot, cutlery) == ["fork"]  # the knife is not
    spot = Location("freespace1", (0.0, 0.0, 0.0), 0.0, "freespace", (), (FOOD,))
    assert accepted_objects(spot, shapes) == list(shapes)


def block_scene(
    freespace: tuple[tuple[float, float, float], ...] | None = None, **poses: tuple[float, ...]
) -> Scene:
    objects = tuple(
        SceneObject(
            name, Pose((p[0], p[1], p[2] if len(p) > 2 else 0.0), quat_from_yaw(0.0)), BLOCK
        )
        for name, p in poses.items()
    )
    return Scene(objects=objects, freespace=freespace, gripper=GRIPPER, source="scene.json")


def absolute(state_id: str, obj: str, x: float, y: float, z: float = 0.0) -> State:
    return State(
        state_id, obj, StatePosition(None, (x, y, z), 0.0), StateOrientation(None, None, 0.0), ()
    )


def relative(
    state_id: str,
    obj: str,
    ref: str,
    dx: float,
    dy: float,
    dz: float = 0.0,
    yaw: float | None = None,
) -> State:
    orientation = StateOrientation(
        ref if yaw is not None else None, None if yaw is None else quat_from_yaw(yaw), 0.0
    )
    return State(state_id, obj, StatePosition(ref, (dx, dy, dz), 0.0), orientation, ())


def model_of(
    states: list[State],
    sequences: list[list[str]],
    constraints: tuple[tuple[str, str], ...] = (),
    landmarks: tuple[tuple[str, Pose], ...] = (),
) -> TaskModel:
    objects = sorted({s.object for s in states})
    demo = Demonstration(
        "d",
        tuple(Step(o, Pose((0.0, 0.0, 0.0))) for o in objects),
        objects=tuple((o, BLOCK) for o in objects),
        landmarks=landmarks,
    )
    return TaskModel(
        states=tuple(states),
        sequences=tuple(tuple(s) for s in sequences),
        constraints=tuple(constraints),
        goals=tuple(tuple(s) for s in sequences),
        demonstrations=(demo,) * len(sequences),
    )


def test_targets_through_references() -> None:
    """b relative to a (placed before it), c relative to d (placed after it in this
    demonstration: its final target), e relative to an unmoved object (its pose now)."""
    states = [
        absolute("A", "a", 0.5, 0.1),
        relative("B", "b", "a", 0.1, 0.0),
        relative("C", "c", "d", 0.0, 0.1),
        absolute("D", "d", 0.5, 0.3),
        relative("E", "e", "f", 0.0, 0.05, 0.04),
    ]
    model = model_of(states + [absolute("F", "f", 0.0, 0.0)], [["A", "B", "C", "D", "E"]])
    scene = block_scene(
        a=(0.1, 0.1), b=(0.1, 0.2), c=(0.1, 0.3), d=(0.2, 0.1), e=(0.2, 0.2), f=(0.3, -0.1)
    )
    (candidate,) = candidate_goals(model, scene)
    poses = {s.label: s.pose.position for s in candidate.subtasks}
    assert poses["B"] == pytest.approx((0.6, 0.1, 0.0))
    assert poses["C"] == pytest.approx((0.5, 0.4, 0.0))
    assert poses["E"] == pytest.approx((0.3, -0.05, 0.04))


def test_orientation_through_its_reference() -> None:
    states = [absolute("A", "a", 0.5, 0.1), relative("B", "b", "a", 0.1, 0.0, yaw=10.0)]
    model = model_of(states, [["A", "B"]])
    scene = block_scene(a=(0.1, 0.1), b=(0.1, 0.2))
    scene = Scene(
        objects=(
            SceneObject("a", Pose((0.1, 0.1, 0.0), quat_from_yaw(30.0)), BLOCK),
            SceneObject("b", Pose((0.1, 0.2, 0.0), quat_from_yaw(-5.0)), BLOCK),
        ),
    )
    (candidate,) = candidate_goals(model, scene)
    a_target, b_target = (s.pose for s in candidate.subtasks)
    assert a_target.yaw == pytest.approx(30.0)  # no learned orientation: kept
    assert b_target.yaw == pytest.approx(40.0)  # 30 + 10 through a


def test_landmark_reference_prefers_the_scene() -> None:
    states = [relative("A", "a", "board", 0.0, 0.1)]
    model = model_of(states, [["A"]], landmarks=(("board", Pose((0.4, 0.1, 0.0))),))
    scene = block_scene(a=(0.1, 0.1))
    (candidate,) = candidate_goals(model, scene)
    assert candidate.subtasks[0].pose.position == pytest.approx((0.4, 0.2, 0.0))
    moved = Scene(objects=scene.objects, landmarks=(("board", Pose((0.6, 0.1, 0.0))),))
    (candidate,) = candidate_goals(model, moved)
    assert candidate.subtasks[0].pose.position == pytest.approx((0.6, 0.2, 0.0))


def test_duplicate_goals_are_one_candidate() -> None:
    states = [absolute("A", "a", 0.5, 0.1), absolute("B", "b", 0.6, 0.1)]
    model = model_of(states, [["A", "B"], ["B", "A"], ["A", "B"]])
    scene = block_scene(a=(0.1, 0.1), b=(0.1, 0.2))
    candidates = candidate_goals(model, scene)
    assert [c.demonstrations for c in candidates] == [(0, 1, 2)]  # no constraints: same goal


def test_a_target_on_an_occupied_spot_is_that_spot() -> None:
    states = [absolute("A", "a", 0.3, 0.0), absolute("B", "b", 0.5, 0.0)]
    model = model_of(states, [["A", "B"]])
    scene = block_scene(a=(0.1, 0.1), b=(0.305, 0.0))  # b stands (5 mm off) on a's target
    (candidate,) = candidate_goals(model, scene)
    built = build_problem(scene, candidate)
    at = dict(built.problem.initial)
    assert dict(built.problem.goal)["a"] == at["b"]
    assert built.location(at["b"]).kind == "current+target"


def test_generated_free_space_is_clear_of_everything() -> None:
    states = [absolute("A", "a", 0.3, 0.0), absolute("B", "b", 0.34, 0.0)]
    model = model_of(states, [["A", "B"]])
    scene = block_scene(a=(0.1, 0.1), b=(0.12, 0.2), c=(0.2, 0.0))
    model = model_of(states + [absolute("C", "c", 0.0, 0.0)], [["A", "B"]])
    for n in (1, 3, 6):
        (candidate,) = candidate_goals(model, scene)
        built = build_problem(scene, candidate, GeometrySettings(n_freespace=n))
        spots = set(built.problem.freespace)
        assert len(spots) == n
        mentioned = {name for fact in built.problem.collisions for name in fact[:2]}
        mentioned |= {name for pair in built.problem.exclusions for name in pair}
        assert not spots & mentioned


def test_floating_object_in_the_scene_is_an_input_error() -> None:
    model = model_of([absolute("A", "a", 0.3, 0.0)], [["A"]])
    scene = block_scene(a=(0.1, 0.1, 0.04))
    (candidate,) = candidate_goals(model, scene)
    with pytest.raises(InputError, match=r"objects\.a\.position.*nothing is under it"):
        build_problem(scene, candidate)


@settings(max_examples=30, deadline=None)
@given(st.floats(5.0, 40.0), st.floats(0.0, 0.004), st.sampled_from([1.0, -1.0]))
def test_a_box_leaning_with_its_lowest_edge_on_the_table_stands(
    tilt: float, lift: float, side: float
) -> None:
    """A 10 × 3 × 15 cm box tilted about its x axis (leaning on a bin's wall),
    its lower edge within the level tolerance of the table: standing, though
    its bottom centre is up to 2.6 cm high; lifted 2 cm more it floats."""
    shape = ObjectGeometry("box", (0.1, 0.03, 0.15))
    centre = 0.015 * math.sin(math.radians(tilt)) + lift
    model = model_of([absolute("A", "a", 0.3, 0.0)], [["A"]])
    for z, stands in ((centre, True), (centre + 0.02, False)):
        pose = Pose((0.1, 0.1, z), quat_from_rpy((side * tilt, 0.0, 0.0)))
        scene = Scene(objects=(SceneObject("a", pose, shape),), gripper=GRIPPER, source="s.json")
        (candidate,) = candidate_goals(model, scene)
        if stands:
            build_problem(scene, candidate)
        else:
            with pytest.raises(InputError, match="nothing is under it"):
                build_problem(scene, candidate)


def test_target_on_nothing_is_an_obstacle() -> None:
    model = model_of([absolute("A", "a", 0.3, 0.0, 0.04)], [["A"]])
    scene = block_scene(a=(0.1, 0.1))
    (candidate,) = candidate_goals(model, scene)
    assert "would stand on nothing" in build_problem(scene, candidate).obstacles[0]


def test_free_space_on_a_huge_table_is_searched_on_a_coarser_grid() -> None:
    """A kilometre-wide table must not allocate a grid of 10^10 spots."""
    model = model_of([absolute("A", "a", 0.3, 0.0)], [["A"]])
    scene = Scene(
        objects=(SceneObject("a", Pose((0.1, 0.1, 0.0), quat_from_yaw(0.0)), BLOCK),),
        table=((-1000.0, -1000.0), (1000.0, 1000.0)),
    )
    (candidate,) = candidate_goals(model, scene)
    built = build_problem(scene, candidate)
    assert len(built.problem.freespace) == 3


def test_a_target_with_a_learned_orientation_is_not_a_turned_spot() -> None:
    """wood stands on its target but turned 30°: its goal (yaw 0) is a place of its
    own, so the plan puts it down again; a cylinder's turn does not matter."""
    turned = State(
        "A",
        "a",
        StatePosition(None, (0.3, 0.0, 0.0), 0.0),
        StateOrientation(None, quat_from_yaw(0.0), 0.0),
        (),
    )
    model = model_of([turned], [["A"]])
    scene = Scene(objects=(SceneObject("a", Pose((0.3, 0.0, 0.0), quat_from_yaw(30.0)), BLOCK),))
    (candidate,) = candidate_goals(model, scene)
    built = build_problem(scene, candidate)
    assert dict(built.problem.goal)["a"] != dict(built.problem.initial)["a"]
    square = Scene(objects=(SceneObject("a", Pose((0.3, 0.0, 0.0), quat_from_yaw(90.0)), BLOCK),))
    (candidate,) = candidate_goals(model, square)
    built = build_problem(square, candidate)  # a cube turned 90° looks the same
    assert dict(built.problem.goal)["a"] == dict(built.problem.initial)["a"]
