"""Runs in worker threads: each run of ``POST /api/runs`` goes on in its own
thread through the command layer's :func:`demoplan.commands.execution.run`,
its events kept for ``GET /api/runs/{id}``; a cancel flag, checked each time
the run reports an event, stops it (``DELETE``). At most
:data:`MAX_ACTIVE_RUNS` run at once (the machine's cores are few): one more
is refused (HTTP 429)."""

from __future__ import annotations

import secrets
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

from demoplan.errors import DemoplanError
from demoplan.studio.workfolder import FileMissingError

__all__ = [
    "MAX_ACTIVE_RUNS",
    "MAX_KEPT_RUNS",
    "Job",
    "Jobs",
    "RunCancelledError",
    "TooManyRunsError",
]

MAX_ACTIVE_RUNS = 2
"""Runs going on at once."""
MAX_ACTIVE_WORK = 2
"""Learning and planning requests answered at once."""
MAX_KEPT_RUNS = 50
"""Finished runs remembered (the oldest is forgotten beyond)."""
MAX_EVENTS = 10_000
"""Events kept per run (a run of 25 replans has a few hundred)."""


class RunCancelledError(Exception):
    """Raised inside a run's thread, from its event callback, when it was cancelled."""


class TooManyRunsError(Exception):
    """:data:`MAX_ACTIVE_RUNS` runs are going on (HTTP 429)."""


@dataclass
class Job:
    """One run: its state, its events so far, and its result or error."""

    id: str
    state: str = "running"
    events: list[dict[str, Any]] = field(default_factory=list)
    result: dict[str, Any] | None = None
    error: str | None = None
    cancel: threading.Event = field(default_factory=threading.Event)
    lock: threading.Lock = field(default_factory=threading.Lock)
    thread: threading.Thread | None = None

    def add_event(self, event: dict[str, Any]) -> None:
        """Keep ``event``; stop the run here if it was cancelled."""
        if self.cancel.is_set():
            raise RunCancelledError
        with self.lock:
            if len(self.events) < MAX_EVENTS:
                self.events.append(event)

    def to_json(self) -> dict[str, Any]:
        with self.lock:
            return {
                "run": self.id,
                "state": self.state,
                "events": list(self.events),
                "result": self.result,
                "error": self.error,
            }


Work = Callable[[Job], tuple[dict[str, Any], list[dict[str, Any]] | None]]
"""A run's work: given its job (to report events to), its result and, where
the finished run tells more of them, its events in full."""


class Jobs:
    """The runs of one studio."""

    def __init__(self) -> None:
        self._jobs: dict[str, Job] = {}
        self._lock = threading.Lock()
        self._slots = threading.BoundedSemaphore(MAX_ACTIVE_WORK)

    def start(self, work: Work) -> Job:
        """Start ``work`` in a new thread (TooManyRunsError beyond the limit)."""
        with self._lock:
            active = sum(1 for job in self._jobs.values() if _busy(job))
            if active >= MAX_ACTIVE_RUNS:
                raise TooManyRunsError(
                    f"{active} runs are going on, at most {MAX_ACTIVE_RUNS} at once; "
                    "wait for one to end or cancel it"
                )
            job = Job(secrets.token_hex(8))
            self._jobs[job.id] = job
            finished = [j for j in self._jobs.values() if not _busy(j)]
            for old in finished[: max(0, len(self._jobs) - MAX_KEPT_RUNS)]:
                del self._jobs[old.id]
        job.thread = threading.Thread(
            target=self._work, args=(job, work), name=f"studio-run-{job.id}", daemon=True
        )
        job.thread.start()
        return job

    def _work(self, job: Job, work: Work) -> None:
        try:
            result, events = work(job)
        except RunCancelledError:
            self._finish(job, "cancelled")
        except DemoplanError as exc:
            self._finish(job, "failed", error=" ".join(str(exc).split()))
        except Exception as exc:  # a fault of the studio itself: one line, never a traceback
            self._finish(job, "failed", error=f"internal error ({type(exc).__name__})")
        else:
            self._finish(job, "done", result=result, events=events)

    def _finish(
        self,
        job: Job,
        state: str,
        *,
        result: dict[str, Any] | None = None,
        events: list[dict[str, Any]] | None = None,
        error: str | None = None,
    ) -> None:
        with job.lock:
            if job.state == "cancelled":  # cancelled while it finished: it stays so
                return
            job.state, job.result, job.error = state, result, error
            if events is not None:
                job.events = events

    @contextmanager
    def working(self) -> Iterator[None]:
        """A learning or planning request: at most :data:`MAX_ACTIVE_WORK` at
        once (TooManyRunsError beyond, HTTP 429), each under the command
        layer's time budget."""
        if not self._slots.acquire(blocking=False):
            raise TooManyRunsError(
                f"{MAX_ACTIVE_WORK} learning or planning requests are going on, at most "
                f"{MAX_ACTIVE_WORK} at once; try again when one has answered"
            )
        try:
            yield
        finally:
            self._slots.release()

    def get(self, run_id: str) -> Job:
        with self._lock:
            job = self._jobs.get(run_id)
        if job is None:
            raise FileMissingError(f"run: no run {run_id!r}")
        return job

    def cancel(self, run_id: str) -> Job:
        """Cancel the run: it is ``cancelled`` at once, and its thread stops at
        its next event (within one (re)planning's budget)."""
        job = self.get(run_id)
        job.cancel.set()
        with job.lock:
            if job.state == "running":
                job.state = "cancelled"
        return job

    def cancel_all(self) -> None:
        with self._lock:
            ids = list(self._jobs)
        for run_id in ids:
            self.cancel(run_id)


def _busy(job: Job) -> bool:
    """The run goes on (a cancelled one until its thread has stopped)."""
    return job.state == "running" or (job.thread is not None and job.thread.is_alive())
