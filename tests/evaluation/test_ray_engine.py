"""RayEngine's rows stopped from outside (a Ctrl-C's unwinding closes them):
what is left of them goes with the Ray they ran on, and no other is started.

``ray.cancel`` starts a local Ray of its own where none runs (Ray's
auto-init): the rows' clean-up, reached after the evaluation's session had
ended (a Ctrl-C's unwinding that closes the generator late), would start a
whole new Ray in a process that is stopping. And ``ray.cancel`` racing a task
that finishes at that moment fails a check in Ray's core worker ("Tried to
complete task that was not pending"), ending the process with exit 1 where a
Ctrl-C must give 130 (tests/evaluation/test_evaluate.py's Ctrl-C test failed so
under load): runs on a Ray the engine started end with it, uncancelled; only a
Ray that outlives the evaluation has them cancelled. The tests watch
``ray.cancel`` (a spy that cancels nothing, so the race cannot strike here)."""

from __future__ import annotations

from collections.abc import Generator
from functools import partial
from typing import Any

import pytest

from demoplan.evaluation.engine import RayEngine
from demoplan.evaluation.runs import RunSpec, error_row

SPECS = [RunSpec(f"random-{k}", None, k) for k in range(20)]
RUNNER = partial(error_row, reason="made by the test")  # a row at once, in any worker


def _watch_cancel(ray: Any, monkeypatch: pytest.MonkeyPatch) -> list[Any]:
    cancelled: list[Any] = []
    monkeypatch.setattr(ray, "cancel", lambda ref, **options: cancelled.append(ref))
    return cancelled


def test_rows_on_the_engine_s_own_ray_closed_in_or_after_its_session_cancel_nothing(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Closed within the session (a Ctrl-C while runs are in flight), the runs
    go with the session's Ray, uncancelled; closed after it, they start no new
    Ray. One Ray for both."""
    ray = pytest.importorskip("ray")
    if ray.is_initialized():  # a Ray another module of this process left running
        ray.shutdown()
    cancelled = _watch_cancel(ray, monkeypatch)
    engine = RayEngine(workers=1, in_flight=2)
    try:
        with engine.session():
            stopped = engine.rows(SPECS, RUNNER)
            late = engine.rows(SPECS, RUNNER)
            assert isinstance(stopped, Generator) and isinstance(late, Generator)
            assert next(stopped).run_id == next(late).run_id == "random-0/seed-0"
            stopped.close()  # with a run in flight, the session's Ray still up
            assert ray.is_initialized()
        assert not ray.is_initialized()  # the runs in flight went with the Ray
        late.close()  # its runs still in flight when the session ended
        assert not ray.is_initialized()
        assert cancelled == []
    finally:
        if ray.is_initialized():
            ray.shutdown()


@pytest.mark.slow
def test_runs_in_flight_on_a_ray_that_outlives_the_evaluation_are_cancelled(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    ray = pytest.importorskip("ray")
    if not ray.is_initialized():
        ray.init(
            address="local",
            num_cpus=1,
            include_dashboard=False,
            log_to_driver=False,
            configure_logging=False,
        )
    try:
        cancelled = _watch_cancel(ray, monkeypatch)
        rows = RayEngine(in_flight=2).rows(SPECS, RUNNER)
        assert isinstance(rows, Generator)
        assert next(rows).run_id == "random-0/seed-0"
        rows.close()
        assert len(cancelled) == 1  # the second run, in flight
        assert ray.is_initialized()  # the caller's Ray goes on
    finally:
        ray.shutdown()
