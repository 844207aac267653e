"""A newcomer's work folder holds two tasks (the studio's Learn view ticks
every demonstration of it): demonstrations that move no object in common
are two tasks, not one. Learned together they made a model that needs both
tasks' objects at once — a scene no demonstration ever had — and every plan
failed on a missing object. Now `learn` refuses, naming both groups."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from demoplan.errors import InputError
from demoplan.learning import learn
from demoplan.model import Demonstration, ObjectGeometry, Pose, Step


def task(names: list[str], name: str, shift: float) -> Demonstration:
    """One demonstration moving ``names`` in a row, from a row beside it."""
    geometry = ObjectGeometry("box", (0.04, 0.04, 0.04))
    return Demonstration(
        name=name,
        source=f"{name}.json",
        objects=tuple((n, geometry) for n in names),
        initial=tuple((n, Pose((0.1 * k, 0.0, 0.0))) for k, n in enumerate(names)),
        steps=tuple(Step(n, Pose((0.1 * k + shift, 0.3, 0.0))) for k, n in enumerate(names)),
    )


@settings(max_examples=25, deadline=None)
@given(
    st.lists(st.sampled_from("abcdef"), min_size=1, max_size=3, unique=True),
    st.lists(st.sampled_from("uvwxyz"), min_size=1, max_size=3, unique=True),
    st.integers(1, 3),
    st.integers(1, 3),
)
def test_demonstrations_of_two_tasks_are_refused_naming_both(
    first: list[str], second: list[str], m: int, n: int
) -> None:
    demos = [task(first, f"one-{k}", 0.001 * k) for k in range(m)]
    demos += [task(second, f"two-{k}", 0.001 * k) for k in range(n)]
    with pytest.raises(InputError) as error:
        learn(demos)
    message = str(error.value)
    assert error.value.source == "two-0.json"
    assert "one-0.json" in message
    assert all(name in message for name in first + second)


@settings(max_examples=25, deadline=None)
@given(
    st.lists(st.sampled_from("abcdef"), min_size=2, max_size=4, unique=True),
    st.integers(0, 3),
)
def test_demonstrations_sharing_an_object_are_one_task(names: list[str], cut: int) -> None:
    """Two demonstrations linked through a third (a-b, b-c, c-d) are one task."""
    chain = [task(names[k : k + 2], f"d{k}", 0.0) for k in range(len(names) - 1)]
    chain.append(task(names[: 1 + cut % len(names)], "whole", 0.001))
    assert {s.object for s in learn(chain).states} == set(names)
