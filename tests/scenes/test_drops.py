"""Where a released object comes to rest (demoplan.scenes.drops), the rule the
studio's drag and drop asks the command layer for: checked against the support
rule itself over generated tables (hypothesis) and on a stack."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.errors import InputError
from demoplan.model import ObjectGeometry
from demoplan.scenes.drops import Standing, carried_by, landing, landmark_clear
from demoplan.scenes.geometry import GeometrySettings

SETTINGS = GeometrySettings()
CUBE = ObjectGeometry("box", (0.04, 0.04, 0.04))


def _box(x: float, y: float, z: float, yaw: float, size: float, height: float) -> Standing:
    return Standing((x, y, z), yaw, ObjectGeometry("box", (size, size, height)))


def test_a_cube_released_over_a_stack_lands_on_its_top_and_not_on_what_it_carries() -> None:
    objects = {
        "base": _box(0.0, 0.0, 0.0, 0.0, 0.1, 0.05),
        "middle": _box(0.0, 0.0, 0.05, 0.0, 0.06, 0.05),
        "cube": Standing((0.5, 0.0, 0.0), 0.0, CUBE),
    }
    rest = landing("cube", (0.0, 0.0), 30.0, objects, {}, SETTINGS)
    assert rest.on == "middle" and rest.position == pytest.approx((0.0, 0.0, 0.1))
    assert carried_by("base", objects, SETTINGS) == {"middle"}
    with pytest.raises(InputError, match="stands on it and moves with it"):
        landing("base", (0.0, 0.0), 0.0, objects, {}, SETTINGS)
    with pytest.raises(InputError, match="unknown object 'lid'"):
        landing("lid", (0.0, 0.0), 0.0, objects, {}, SETTINGS)


def test_a_release_beside_a_taller_thing_that_it_overlaps_is_refused() -> None:
    """A plank 0.2 m long overlapping a tower by 3 mm along its end: too little
    of it to stand on (1.5 % of its outline, the support share is 5 %), more than
    the 2 mm touch tolerance — it would pass through; by 0.5 mm it only touches."""
    objects = {
        "tower": _box(0.0, 0.0, 0.0, 0.0, 0.1, 0.3),
        "plank": Standing((0.5, 0.0, 0.0), 0.0, ObjectGeometry("box", (0.2, 0.04, 0.02))),
    }
    with pytest.raises(InputError, match="would pass through 'tower'") as caught:
        landing("plank", (0.147, 0.0), 0.0, objects, {}, SETTINGS)
    assert caught.value.field == "position"
    rest = landing("plank", (0.1505, 0.0), 0.0, objects, {}, SETTINGS)
    assert rest.on is None and rest.position[2] == 0.0


def test_a_landmark_is_not_put_down_on_an_object() -> None:
    objects = {"cube": Standing((0.0, 0.0, 0.0), 0.0, CUBE)}
    tray = _box(0.02, 0.0, 0.0, 0.0, 0.2, 0.02)
    with pytest.raises(InputError, match="landmark 'tray' would be put down on 'cube'"):
        landmark_clear("tray", tray, objects, {"tray": tray}, SETTINGS)
    landmark_clear("tray", _box(0.3, 0.0, 0.0, 0.0, 0.2, 0.02), objects, {}, SETTINGS)


things = st.lists(
    st.tuples(
        st.floats(-0.3, 0.3),
        st.floats(-0.3, 0.3),
        st.floats(0, 90),
        st.floats(0.03, 0.2),
        st.floats(0.01, 0.2),
    ),
    min_size=1,
    max_size=6,
)


@settings(max_examples=60, deadline=None)
@given(things, st.floats(-0.3, 0.3), st.floats(-0.3, 0.3), st.floats(-180, 180))
def test_a_landing_rests_on_the_highest_top_that_holds_it_and_passes_through_nothing(
    table: list[tuple[float, float, float, float, float]], x: float, y: float, yaw: float
) -> None:
    """Over generated tables of boxes on the table (they may overlap: the rule
    only reads outlines and tops), a landing is either refused with the field
    named, or rests at the top of the highest thing covering the support share
    of its outline (the table when none does), overlapping nothing higher."""
    objects = {
        f"box{i}": _box(bx, by, 0.0, byaw, size, height)
        for i, (bx, by, byaw, size, height) in enumerate(table)
    }
    objects["cube"] = Standing((1.0, 1.0, 0.0), 0.0, CUBE)
    try:
        rest = landing("cube", (x, y), yaw, objects, {}, SETTINGS)
    except InputError as refused:
        assert refused.field == "position"
        return
    placed = Standing(rest.position, rest.yaw, CUBE)
    outline = placed.outline
    holding = [
        (thing.top, name)
        for name, thing in objects.items()
        if name != "cube"
        and outline.intersection(thing.outline).area >= SETTINGS.support_fraction * outline.area
    ]
    expected_top = max(holding)[0] if holding else 0.0
    assert rest.position[2] == pytest.approx(expected_top)
    assert (rest.on is None) == (not holding)
    core = outline.buffer(-SETTINGS.touch_tolerance)
    for name, thing in objects.items():
        if name != "cube" and thing.top > rest.position[2] + 1e-6:
            assert not core.intersects(thing.outline), f"the cube passes through {name}"
