"""The edges of learning's rules are visible and consistent (docs/learning.md,
"Notes"): the roles of one type are placed by one rule, decided on their
pooled spread, and a decision near its threshold is told in words.

The family is the table for two of ``tests/support/identical_families.py`` with the
seats scattered by 1–5 cm between demonstrations (a user's seats about 3 cm
apart learned ``plate#1`` *anywhere* at 53.8 mm and ``plate#2`` at its place
at 43.6 mm); the truth of each plate's spread is taken from the
demonstrations, through the roles the model records.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan import learn
from demoplan.learning.tables import diagnostic_lines, state_rows
from demoplan.model import TaskModel
from tests.support.identical_families import TABLE_TYPES, table_for_two

SEPARATION = 0.05  # m: the default position_separation


@st.composite
def scattered_tables(draw: st.DrawFn) -> tuple[TaskModel, dict[str, np.ndarray]]:
    """A table for two taught 3–5 times, seats scattered by 1–5 cm; the model
    learned, and each plate role's placements (from the demonstrations)."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    count = draw(st.integers(3, 5))
    orders: list[dict[str, Sequence[int]]] = [
        {kind: [int(i) for i in rng.permutation(2)] for kind in TABLE_TYPES} for _ in range(count)
    ]
    taught = table_for_two(rng, orders, seat_noise=draw(st.floats(0.01, 0.05)))
    model = learn(taught.demonstrations)
    placements = {}
    for role in (r for r in model.roles if r.type == "plate"):
        rows = []
        for demo, instance in zip(taught.demonstrations, role.instances, strict=True):
            (step,) = [s for s in demo.steps if s.object == instance]
            rows.append(step.pose.position)
        placements[role.name] = np.array(rows, dtype=float)
    return model, placements


@settings(max_examples=40, deadline=None)
@given(table=scattered_tables())
def test_the_plates_of_a_table_for_two_are_placed_by_one_rule(
    table: tuple[TaskModel, dict[str, np.ndarray]],
) -> None:
    """Both plates anywhere, or both at their places, as their pooled spread
    (over the demonstrations' placements) says; a pooled spread within 20 % of
    the threshold, or a plate whose own spread alone would have gone the other
    way, is told in the state's notes, the states table and the warnings. (The
    plate laid second may be learned relative to the first, which then decides
    alone.)"""
    model, placements = table
    assert model.precision is not None
    plates = [s for s in model.states if s.object.startswith("plate#")]
    assert len(plates) == 2
    plates = [s for s in plates if s.position.reference is None]
    assert plates
    assert len({s.position.anywhere for s in plates}) == 1  # one rule
    own = [float(np.trace(np.cov(placements[s.object].T))) for s in plates]
    pooled = math.sqrt(sum(own) / len(own))  # as many placements each
    threshold = max(SEPARATION, 5 * model.precision[0])
    assert plates[0].position.anywhere == (pooled >= threshold)
    near = abs(pooled - threshold) <= 0.2 * threshold
    turned = any((math.sqrt(v) >= threshold) != (pooled >= threshold) for v in own)
    rows = {row[0]: row for row in state_rows(model)}
    lines = diagnostic_lines(model)
    for state in plates:
        told = [n for n in state.notes if n.startswith(("anywhere", "at its place"))]
        assert bool(told) == (near or turned), (state.notes, pooled, threshold)
        if told:
            (note,) = told
            spread = "their pooled spread" if len(plates) == 2 else "spread"
            assert f"{spread} {1000 * pooled:.1f} mm" in note
            assert ("within 20 %" in note) == near
            assert rows[state.id][2] == note
            assert f"state {state.id} ({state.object}): {note}" in lines


def test_an_object_of_its_own_type_near_the_edge_is_told() -> None:
    """An object without a type is decided alone, as before; near the edge its
    state says how near: a tray put down at four places scattered by about
    45 mm (RMS) is at its place, within 20 % of the 50 mm."""
    from demoplan.model import Demonstration, Pose, Step

    corners = [(0.030, 0.030), (-0.030, 0.030), (0.030, -0.030), (-0.030, -0.030)]
    demos = [
        Demonstration(
            f"tray-{k}",
            (Step("tray", Pose((0.5 + dx, 0.2 + dy, 0.0))), Step("cup", Pose((0.9, 0.1, 0.0)))),
        )
        for k, (dx, dy) in enumerate(corners)
    ]
    model = learn(demos)
    (tray,) = [s for s in model.states if s.object == "tray"]
    rms = math.sqrt(tray.position.spread)  # sample covariance: 0.03·√(4/3)·√2 = 49 mm
    assert 0.04 <= rms < 0.05 and not tray.position.anywhere
    assert tray.notes == (
        f"at its place: spread {1000 * rms:.1f} mm, within 20 % of the 50.0 mm from which "
        "placements are anywhere",
    )
