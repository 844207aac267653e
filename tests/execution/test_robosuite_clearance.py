"""The Panda's hand over a bin's walls (demoplan.execution.robosuite_clearance) and
the grasps its opening allows (robosuite_scene.grasp_axes): plain geometry, no
robosuite needed."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.execution.robosuite_clearance import HAND_MARGIN, HandShape, Wall, lowest_grip
from demoplan.execution.robosuite_scene import (
    GRIPPER_OPENING,
    EnvLandmarks,
    EnvObject,
    bin_walls,
    grasp_axes,
)
from demoplan.model import ObjectGeometry, Pose

PANDA = HandShape(half_length=0.104, half_width=0.032, bottom=0.026)
"""About robosuite 1.5.2's Panda hand (the world measures its own from the model)."""

THICKNESS = 0.02


def _compartment(
    centre: tuple[float, float], inner: tuple[float, float], yaw: float, top: float
) -> list[Wall]:
    """Four walls enclosing ``inner`` (length along the yaw, width across) around ``centre``."""
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    half_x, half_y = inner[0] / 2 + THICKNESS / 2, inner[1] / 2 + THICKNESS / 2
    walls = []
    for along, across, size in (
        (half_x, 0.0, (THICKNESS / 2, inner[1] / 2 + THICKNESS)),
        (-half_x, 0.0, (THICKNESS / 2, inner[1] / 2 + THICKNESS)),
        (0.0, half_y, (inner[0] / 2 + THICKNESS, THICKNESS / 2)),
        (0.0, -half_y, (inner[0] / 2 + THICKNESS, THICKNESS / 2)),
    ):
        where = (centre[0] + c * along - s * across, centre[1] + s * along + c * across)
        walls.append(Wall(where, size, yaw, top))
    return walls


spot = st.floats(-1.0, 1.0)
turn = st.floats(-180.0, 180.0)
rim = st.floats(0.8, 1.0)
roomy = st.floats(2 * (PANDA.half_length + HAND_MARGIN) + 0.002, 0.4)
"""A compartment's length the hand fits in along its fingers."""
narrow = st.floats(2 * (PANDA.half_width + HAND_MARGIN) + 0.002, 2 * PANDA.half_length - 0.01)
"""A compartment's width the hand fits in only across its fingers."""


@settings(max_examples=60)
@given(x=spot, y=spot, yaw=turn, top=rim, length=roomy, width=narrow)
def test_a_hand_along_the_compartments_length_goes_down_to_the_floor(
    x: float, y: float, yaw: float, top: float, length: float, width: float
) -> None:
    walls = _compartment((x, y), (length, width), yaw, top)
    assert lowest_grip(PANDA, (x, y), yaw, walls) == -math.inf
    assert lowest_grip(PANDA, (x, y), yaw + 180.0, walls) == -math.inf


@settings(max_examples=60)
@given(x=spot, y=spot, yaw=turn, top=rim, length=roomy, width=narrow)
def test_a_hand_across_the_compartment_stays_above_its_walls(
    x: float, y: float, yaw: float, top: float, length: float, width: float
) -> None:
    """Turned a quarter, the hand is longer than the compartment is wide: its
    bottom stays the margin above the walls' top."""
    walls = _compartment((x, y), (length, width), yaw, top)
    lowest = lowest_grip(PANDA, (x, y), yaw + 90.0, walls)
    assert math.isclose(lowest + PANDA.bottom, top + HAND_MARGIN, abs_tol=1e-12)


@settings(max_examples=60)
@given(x=spot, y=spot, yaw=turn, top=rim, length=roomy, width=narrow, off=st.floats(0.0, 0.1))
def test_a_hand_off_the_middle_meets_the_end_wall_it_reaches(
    x: float, y: float, yaw: float, top: float, length: float, width: float, off: float
) -> None:
    """Along the length, shifted towards an end: it clears the walls while its
    end (and the margin) stays off the end wall's face, not once it reaches it."""
    walls = _compartment((x, y), (length, width), yaw, top)
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    lowest = lowest_grip(PANDA, (x + c * off, y + s * off), yaw, walls)
    gap = length / 2 - off - (PANDA.half_length + HAND_MARGIN)
    if gap > 1e-6:
        assert lowest == -math.inf
    elif gap < -1e-6:
        assert math.isclose(lowest + PANDA.bottom, top + HAND_MARGIN, abs_tol=1e-12)


@given(x=spot, y=spot, fingers=turn)
def test_no_walls_no_limit(x: float, y: float, fingers: float) -> None:
    assert lowest_grip(PANDA, (x, y), fingers, []) == -math.inf


def _object(size: tuple[float, float, float], handle: int | None = None) -> EnvObject:
    return EnvObject("thing", 1, None, handle, 0.0, ObjectGeometry("box", size))


@given(
    wide=st.floats(GRIPPER_OPENING + 0.001, 0.2),
    slim=st.floats(0.01, GRIPPER_OPENING - 0.001),
    height=st.floats(0.02, 0.3),
)
def test_an_object_is_grasped_only_across_a_side_the_gripper_spans(
    wide: float, slim: float, height: float
) -> None:
    """PickPlace's cereal box (10 cm by 3 cm) is taken across its 3 cm only."""
    assert grasp_axes(_object((wide, slim, height))) == (90.0,)
    assert grasp_axes(_object((slim, wide, height))) == (0.0,)
    assert grasp_axes(_object((slim, slim, height))) == (0.0, 90.0)
    assert grasp_axes(_object((wide, wide, height))) == (0.0, 90.0)  # none spans: as before
    assert grasp_axes(_object((slim, slim, height), handle=3)) == (90.0,)  # a nut: its handle


@given(top=st.floats(-0.5, 1.5), yaw=st.floats(-179.0, 179.0))
def test_the_walls_are_the_bins_parts_in_the_world(top: float, yaw: float) -> None:
    """A bin's walls and dividers, and nothing else (a peg, another bin's
    body), turned with their landmark, their top lifted by the table's."""
    quarter = (0.0, 0.0, math.sin(math.radians(yaw) / 2), math.cos(math.radians(yaw) / 2))
    wall = ObjectGeometry("box", (0.02, 0.5, 0.1))
    found = EnvLandmarks(
        poses=(
            ("bin2", Pose((0.1, 0.28, -0.02), quarter)),
            ("bin2_wall1", Pose((-0.1, 0.28, -0.02), quarter)),
            ("peg1", Pose((0.2, 0.1, 0.0), quarter)),
        ),
        shapes=(("bin2_wall1", wall), ("peg1", ObjectGeometry("box", (0.02, 0.02, 0.1)))),
        compartments=(("bin2", ((-0.1, -0.1, 0.0, 0.1, 0.1, 0.08),)),),
        tops={"bin2": 0.08, "bin2_wall1": 0.08, "peg1": 0.1},
    )
    (only,) = bin_walls(found, top)
    assert only.centre == (-0.1, 0.28)
    assert only.half_size == (0.01, 0.25)
    assert math.isclose(only.yaw, yaw, abs_tol=1e-9)
    assert math.isclose(only.top, top + 0.08, abs_tol=1e-12)
