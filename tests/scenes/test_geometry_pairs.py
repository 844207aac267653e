"""The vectorised pair geometry of scenes (collision facts, exclusions) against
the rules written plainly, pair by pair (docs/scenes.md; the module docstring
of demoplan.scenes.geometry): the same facts, in the same order, on
generated scenes of boxes, cylinders and spheres — on a 1 cm grid, where
fingers and footprints touch exactly, and anywhere."""

from __future__ import annotations

import math

import numpy as np
import shapely
from hypothesis import example, given, settings
from hypothesis import strategies as st

from demoplan.model import ObjectGeometry
from demoplan.scenes.geometry import (
    TOUCHING,
    GeometrySettings,
    Location,
    collision_facts,
    exclusions,
    finger_offset,
    is_block,
    location_footprint,
)
from demoplan.scenes.scene import Gripper


def plain_facts(
    locations: list[Location],
    grasps: list[tuple[str, str, ObjectGeometry, float]],
    gripper: Gripper,
    tolerance: float,
) -> list[tuple[str, str, str]]:
    """§V.B's rule for blocks, the finger disc reaching a footprint above a's
    bottom for other shapes; every (grasp, a, b) in turn."""
    facts = []
    for grasp, _obj, shape, axis in grasps:
        for a in locations:
            offset = finger_offset(shape, axis, gripper)
            angle = math.radians(a.yaw + axis)
            g = np.array([offset * math.cos(angle), offset * math.sin(angle), 0.0])
            tips = [np.asarray(a.position) + g, np.asarray(a.position) - g]
            for b in locations:
                if b is a:
                    continue
                hit = False
                for tip in tips:
                    if is_block(shape) and all(is_block(s) for s in b.shapes):
                        radius = max(s.size[0] for s in b.shapes) / 2
                        hit |= bool(
                            np.linalg.norm(np.asarray(b.position) - tip)
                            < radius + gripper.finger_radius - TOUCHING
                        )
                    else:
                        reach = location_footprint(b).distance(shapely.Point(tip[0], tip[1]))
                        hit |= reach < gripper.finger_radius and b.top > a.bottom + tolerance
                if hit:
                    facts.append((a.name, b.name, grasp))
    return facts


def plain_exclusions(
    locations: list[Location], support: list[tuple[str, str]], tolerance: float, touch: float
) -> list[tuple[str, str]]:
    """Overlapping shrunk footprints, neither on top of the other nor a support pair."""
    supported = set(support) | {(b, a) for a, b in support}

    def above(upper: Location, lower: Location) -> bool:
        return upper.bottom >= lower.top - tolerance and upper.bottom > lower.bottom + tolerance

    pairs = []
    for i, a in enumerate(locations):
        for b in locations[i + 1 :]:
            if (a.name, b.name) in supported or above(a, b) or above(b, a):
                continue
            if (
                location_footprint(a)
                .buffer(-touch)
                .intersects(location_footprint(b).buffer(-touch))
            ):
                pairs.append((a.name, b.name))
    return pairs


THIN = ObjectGeometry("box", (0.03, 0.005, 0.005))
CUBE = ObjectGeometry("box", (0.04, 0.04, 0.04))
shapes = st.builds(
    ObjectGeometry,
    st.sampled_from(["box", "box", "cylinder", "sphere"]),
    st.tuples(
        st.sampled_from([0.03, 0.04, 0.05]),
        st.sampled_from([0.005, 0.04, 0.06]),
        st.sampled_from([0.005, 0.02, 0.04]),
    ),
)
on_grid = st.tuples(
    st.integers(0, 12).map(lambda k: 0.3 + 0.01 * k),
    st.integers(0, 12).map(lambda k: 0.01 * k),
    st.sampled_from([0.0, 0.0, 0.005, 0.02, 0.04]),
)
anywhere = st.tuples(
    st.floats(0.25, 0.45), st.floats(-0.05, 0.15), st.sampled_from([0.0, 0.02, 0.04])
)


@st.composite
def scenes(draw: st.DrawFn) -> tuple[list[Location], list[tuple[str, str, ObjectGeometry, float]]]:
    count = draw(st.integers(1, 12))
    locations, grasps = [], []
    for k in range(count):
        shape = draw(shapes)
        if draw(st.booleans()):  # a cube, the paper's blocks
            shape = ObjectGeometry("box", (0.04, 0.04, 0.04))
        position = draw(st.one_of(on_grid, anywhere))
        yaw = draw(st.sampled_from([0.0, 0.0, 45.0, 90.0, 17.0]))
        kind = draw(st.sampled_from(["current", "target", "freespace"]))
        locations.append(Location(f"loc{k}", position, yaw, kind, (f"o{k}",), (shape,)))
        for axis in draw(st.lists(st.sampled_from([0.0, 90.0, 45.0]), min_size=1, max_size=2)):
            grasps.append((f"grasp{len(grasps) + 1}", f"o{k}", shape, axis))
    return locations, grasps


TOUCHING_EXACTLY = (
    [
        Location("loc0", (0.25, 0.0, 0.04), 17.0, "current", ("o0",), (THIN,)),
        Location("loc1", (0.25, 0.0, 0.04), 0.0, "current", ("o1",), (CUBE,)),
    ],
    [("grasp1", "o0", THIN, 0.0), ("grasp2", "o1", CUBE, 90.0)],
)
"""Found by hypothesis in CI: a cube's finger at loc0 exactly touching the cube
at loc1 (3 cm from its centre, its half side plus the finger), which NumPy's
norm of a row and of a vector rounded to either side."""


@settings(max_examples=150, deadline=None)
@given(scenes(), st.sampled_from([0.02, 0.01, 0.005]))
@example(TOUCHING_EXACTLY, 0.01)
def test_collision_facts_are_the_rule_pair_by_pair(
    scene: tuple[list[Location], list[tuple[str, str, ObjectGeometry, float]]], finger: float
) -> None:
    locations, grasps = scene
    gripper = Gripper(finger_radius=finger)
    tolerance = GeometrySettings().level_tolerance
    assert collision_facts(locations, grasps, gripper) == plain_facts(
        locations, grasps, gripper, tolerance
    )


@settings(max_examples=150, deadline=None)
@given(scenes(), st.data())
def test_exclusions_are_the_rule_pair_by_pair(
    scene: tuple[list[Location], list[tuple[str, str, ObjectGeometry, float]]], data: st.DataObject
) -> None:
    locations, _ = scene
    names = [loc.name for loc in locations]
    support = data.draw(st.lists(st.tuples(st.sampled_from(names), st.sampled_from(names))))
    defaults = GeometrySettings()
    assert exclusions(locations, support) == plain_exclusions(
        locations, support, defaults.level_tolerance, defaults.touch_tolerance
    )


def test_the_generated_scenes_have_facts_of_both_rules() -> None:
    """The oracle is not vacuous: a block grasped beside a block (the paper's
    rule) and a cylinder beside a box (the footprint rule) both give facts."""
    cube = ObjectGeometry("box", (0.04, 0.04, 0.04))
    can = ObjectGeometry("cylinder", (0.04, 0.04, 0.04))
    pair = [
        Location("loc1", (0.3, 0.0, 0.0), 0.0, "current", ("a",), (cube,)),
        Location("loc2", (0.36, 0.0, 0.0), 0.0, "current", ("b",), (cube,)),
    ]
    grasp = [("grasp1", "a", cube, 0.0)]
    assert ("loc1", "loc2", "grasp1") in collision_facts(pair, grasp, Gripper())
    mixed = [pair[0], Location("loc2", (0.36, 0.0, 0.0), 0.0, "current", ("b",), (can,))]
    assert ("loc1", "loc2", "grasp1") in collision_facts(mixed, grasp, Gripper())
    far = [pair[0], Location("loc2", (0.46, 0.0, 0.0), 0.0, "current", ("b",), (can,))]
    assert collision_facts(far, grasp, Gripper()) == []
