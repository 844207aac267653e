"""One clock per command (demoplan.budget.Clock): a part of it keeps every
limit but the share of time, and the time limit is named as the option that
sets it."""

from __future__ import annotations

import math
import time

import pytest
from hypothesis import given
from hypothesis import strategies as st

from demoplan.budget import MAX_STATES, Budget, Clock
from demoplan.errors import LimitReachedError

limits = st.builds(
    Budget,
    max_nodes=st.none() | st.integers(1, 10_000),
    timeout=st.none() | st.floats(0.0, 1e4) | st.just(math.inf),
    max_states=st.none() | st.integers(1, 10**7),
)


@given(budget=limits, fraction=st.floats(0.0, 1.0), unbounded=st.none() | st.floats(0.0, 100.0))
def test_a_part_keeps_every_limit_and_takes_a_share_of_the_time_left(
    budget: Budget, fraction: float, unbounded: float | None
) -> None:
    clock = Clock(budget)
    before = time.monotonic()
    left = clock.remaining()
    part = clock.part(fraction, unbounded)
    after = time.monotonic()
    assert part.budget == clock.budget  # expansions, states, the timeout's name
    assert part.max_states == (MAX_STATES if budget.max_states is None else budget.max_states)
    if left is None or math.isinf(left):  # no deadline: a share of the unbounded default
        if unbounded is None:
            assert part.deadline is None
        else:
            assert part.deadline is not None
            assert before + fraction * unbounded <= part.deadline <= after + fraction * unbounded
    else:
        assert part.deadline is not None and clock.deadline is not None
        # never more than the whole (a spent clock's part is spent from now)
        assert part.deadline <= max(clock.deadline, after) + 1e-6
        assert part.deadline <= after + fraction * left + 1e-6


def test_the_time_limit_is_named_as_its_option_and_raises_exit_4() -> None:
    spent = Clock(Budget(timeout=0.0, deadline=time.monotonic() - 1.0))
    assert spent.time_limit() == "--timeout 0 s"
    assert Clock(Budget(deadline=time.monotonic() - 1.0)).time_limit() == "the time budget"
    with pytest.raises(LimitReachedError, match=r"^--timeout 0 s reached compiling") as caught:
        spent.check("compiling")
    assert caught.value.exit_code == 4
    Clock().check("anything")  # no deadline: never spent
    assert spent.at_least(60.0).remaining() == pytest.approx(60.0, abs=1.0)
    spent.at_least(60.0).check("a grace")  # the grace holds


def test_the_node_and_state_limits_stop_before_the_time() -> None:
    clock = Clock(Budget(max_nodes=3, max_states=10))
    assert clock.stop(2, 9) is None
    assert clock.stop(3, 0) == "--max-nodes 3"
    assert clock.stop(0, 10) == "the memory limit of 10 states"
    assert clock.part(0.5).stop(3, 0) == "--max-nodes 3"  # a part keeps them
