"""RayEngine's rows stopped from outside after the Ray they ran on was shut
down: what is left of them goes with that Ray, and no other is started.

``ray.cancel`` starts a local Ray of its own where none runs (Ray's
auto-init): the rows' clean-up, reached after the evaluation's session had
ended (a Ctrl-C's unwinding that closes the generator late), would start a
whole new Ray in a process that is stopping."""

from __future__ import annotations

from collections.abc import Generator
from functools import partial

import pytest

from demoplan.evaluation.engine import RayEngine
from demoplan.evaluation.runs import RunSpec, error_row


def test_rows_closed_after_ray_was_shut_down_start_no_new_ray() -> None:
    ray = pytest.importorskip("ray")
    if ray.is_initialized():  # a Ray another module of this process left running
        ray.shutdown()
    specs = [RunSpec(f"random-{k}", None, k) for k in range(20)]
    engine = RayEngine(workers=1, in_flight=2)
    runner = partial(error_row, reason="made by the test")  # a row at once, in any worker
    try:
        with engine.session():
            rows = engine.rows(specs, runner)
            assert isinstance(rows, Generator)
            first = next(rows)
            assert first.run_id == "random-0/seed-0"
        assert not ray.is_initialized()
        rows.close()  # its runs still in flight when the session ended
        assert not ray.is_initialized()
    finally:
        if ray.is_initialized():
            ray.shutdown()
