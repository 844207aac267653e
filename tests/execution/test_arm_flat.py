"""Flat wide boxes and books on the arm's suction cup: the pre-check accepts
what the cup carries — a 10 × 10 × 3 cm sandwich of wood (0.18 kg), a
15 × 10 × 3 cm book of 0.2 kg — which it refused, blaming their weight,
while the pad's contacts dropped a load of a fifth of a kilogram as the cup
lifted it; and what is too heavy is refused, naming its weight, only when its
weight is the cause."""

from __future__ import annotations

import math
import os

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from demoplan.model import ObjectGeometry, Pose

os.environ.setdefault("MUJOCO_GL", "egl")
pytest.importorskip("mujoco", reason="MuJoCo is not installed (pip install -e '.[sim]')")
pytest.importorskip("mink", reason="mink is not installed (pip install -e '.[sim]')")

from demoplan.execution import arm_model
from demoplan.execution.arm import (
    TRIAL_MARGIN,
    ArmWorld,
    carries,
    choose_tool,
)
from demoplan.execution.arm_tools import _why_not_by_fingers, _why_not_by_suction
from demoplan.scenes.scene import Scene, SceneObject
from tests.support.lunch_box import LUNCH, lunch_demonstrations

CUP_CARRIES = 0.44
"""kg: the heaviest load the 5 N cup carries in the trial carry, whatever the
box (benchmarks/arm_capacity.py; docs/execution.md)."""
FLAT_MASSES = (0.02, 0.9 * CUP_CARRIES / TRIAL_MARGIN)
"""kg: the flat boxes drawn, up to a tenth below what the pre-check accepts."""
SANDWICH = ObjectGeometry("box", (0.10, 0.10, 0.03))  # wood: 0.18 kg
BOOK = ObjectGeometry("box", (0.15, 0.10, 0.03), 0.2)


def _pose(distance: float, angle: float, yaw: float) -> Pose:
    a, half = math.radians(angle), math.radians(yaw) / 2
    return Pose(
        (distance * math.cos(a), distance * math.sin(a), 0.0),
        (0.0, 0.0, math.sin(half), math.cos(half)),
    )


_flat_boxes = st.builds(
    lambda x, y, z, mass: ObjectGeometry("box", (x, y, z), mass),
    st.floats(0.06, 0.16),
    st.floats(0.06, 0.16),
    st.floats(0.02, 0.05),
    st.floats(*FLAT_MASSES),
)
_places = st.tuples(
    st.builds(_pose, st.floats(0.3, 0.5), st.floats(-45.0, -18.0), st.floats(-90, 90)),
    st.builds(_pose, st.floats(0.3, 0.5), st.floats(18.0, 45.0), st.floats(-90, 90)),
)


@settings(
    max_examples=3, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow]
)
@given(shape=_flat_boxes, where=_places)
@example(shape=SANDWICH, where=(_pose(0.35, -30.0, 0.0), _pose(0.45, 25.0, 60.0)))
@example(shape=BOOK, where=(_pose(0.45, -25.0, 30.0), _pose(0.35, 30.0, -45.0)))
def test_flat_boxes_the_cup_lifts_are_accepted_and_carried(
    shape: ObjectGeometry, where: tuple[Pose, Pose]
) -> None:
    """Boxes 6–16 cm wide, 2–5 cm tall, of any mass the cup lifts with the
    pre-check's margin: accepted for the cup, and carried by it at their own
    weight between two places the check's trial never went (within 1 cm)."""
    choice = choose_tool(shape)
    assert choice.tool == "suction", (shape, choice)
    assert carries(shape, *where, "suction") == (True, True), (shape, where)


def test_the_cup_keeps_a_box_of_its_capacity_flat_on_its_pad() -> None:
    """A 15 × 10 × 3 cm box of 0.4 kg (4 N of the cup's 5) lifted and held up
    high: it stays pressed flat to the pad — no corner lifts off, no tilt —
    where the pad's contacts, found no farther than they push, lost three of
    their four corners as the lift began and dropped a 0.225 kg box."""
    shape = ObjectGeometry("box", (0.15, 0.10, 0.03), 0.4)
    world = ArmWorld(
        Scene(objects=(SceneObject("book", Pose((0.42, -0.14, 0.0)), shape),), robot=(0, 0, 0))
    )
    try:
        world.tools["book"] = "suction"
        world.grasp("book", 0.0)
        assert world.observe().held == "book"
        here, _ = world._cup()
        world._go([here[0], here[1], here[2] + 0.1])
        world._settle(0.5)
        frame = world._object_frame("book")
        assert frame[2, 2] > math.cos(math.radians(1.0))  # level within 1°
        cup, _ = world._cup()
        assert abs(cup[2] - (frame[2, 3] + shape.size[2] / 2)) < 0.002  # its top on the pad
        pad = [c for c in world.data.contact[: world.data.ncon] if world.pad in (c.geom1, c.geom2)]
        assert len(pad) == 4  # the pad's four corners
    finally:
        world.close()


def test_a_book_too_heavy_for_the_cup_is_refused_naming_its_weight() -> None:
    """A 15 × 10 × 3 cm book of 0.6 kg: more than the cup's 5 N hold, wider
    than the fingers open — refused, its weight and the force the trial needed
    named, and the cup indeed drops it at its own weight."""
    book = ObjectGeometry("box", (0.15, 0.10, 0.03), 0.6)
    choice = choose_tool(book)
    assert choice.tool is None
    assert choice.why is not None
    assert choice.why.startswith(
        "weighs 0.6 kg; the suction cup (5 N) does not lift 1.25 times that (7.4 N)"
    ), choice.why
    assert "10.0 cm across its narrowest grasp" in choice.why
    assert carries(book, Pose((0.42, -0.14, 0.0)), Pose((0.42, 0.14, 0.0)), "suction") == (
        False,
        False,
    )


def test_a_cup_that_fails_at_any_weight_is_not_said_to_fail_for_the_weight(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """With no suction at all (the cup's force 0 N), the trial loses even a
    10 g copy of a light box: the refusal says what the cup felt, not the
    box's weight."""
    monkeypatch.setattr(arm_model, "SUCTION_FORCE", 0.0)
    why = _why_not_by_suction(ObjectGeometry("box", (0.08, 0.08, 0.03), 0.05), ArmWorld)
    assert why is not None
    assert "weighs" not in why, why
    assert why.startswith("the suction cup cannot carry it in a trial carry, even at 10 g: "), why
    assert "slipped from the suction cup" in why or "did not seal" in why, why


def test_fingers_that_do_not_lift_a_heavy_cup_say_it_is_its_weight() -> None:
    """A 7 kg cup 7 cm across (a tool caddy's, docs/studio.md): the fingers
    lift the same cup at 50 g, so its weight is why they refuse it — not a
    slip "even at 10 g", which the fingers do not lift in the simulation."""
    why = _why_not_by_fingers(
        ObjectGeometry("cylinder", (0.07, 0.07, 0.09), 7.0), 0.0, False, ArmWorld
    )
    assert why is not None
    assert why.startswith("weighs 7 kg; the fingers (40 N) do not lift 1.25 times that"), why


def test_the_lunch_box_task_at_its_default_weights_goes_by_the_arms_tools() -> None:
    """The lunch box task's food at the weights of wood (no masses given): the
    sandwich (0.18 kg), the carrot, the juice box and the cookie by the cup,
    the 7 cm apple — a sphere, no flat top — by the fingers."""
    objects = {n: g for n, g in lunch_demonstrations()[0].objects if n in LUNCH}
    assert set(objects) == set(LUNCH) and all(g.mass is None for g in objects.values())
    tools = {name: choose_tool(shape).tool for name, shape in objects.items()}
    assert tools == {
        "sandwich": "suction",
        "apple": "fingers",
        "juice": "suction",
        "carrot": "suction",
        "cookie": "suction",
    }
