"""Runs, each in a child process of its own: ``POST /api/runs`` starts
``python -m demoplan.studio.worker`` (:mod:`demoplan.studio.worker`), which
runs the request through the command layer's
:func:`demoplan.commands.execution.run` and writes the run's events and its
result as JSON lines on its stdout; a thread of the studio reads them into the
run's :class:`Job` for ``GET /api/runs/{id}``. At most :data:`MAX_ACTIVE_RUNS`
run at once (the machine's cores are few): one more is refused (HTTP 429).

Why a process, and why a plain subprocess rather than ``multiprocessing``:

- MuJoCo renders through GL contexts bound to a thread and a process: a second
  renderer made in another thread of the same process can deadlock in
  ``mujoco.Renderer`` (EGL). A process per run has GL to itself.
- Cancelling must not wait for the run's next event (a whole replanning
  budget, longer on the arm): a process can be stopped where it is. Cancel
  (``DELETE``, the studio shutting down) sends SIGTERM to the run's process
  group — the worker stops through the CLI's own SIGTERM path
  (:mod:`demoplan.frontends.interrupts`: the world is closed, ffmpeg stopped, the
  video's private folder removed) — then SIGKILL after
  :data:`TERMINATE_GRACE_S` to whatever is left of the group.
- Each run is a session and process group of its own (``start_new_session``),
  and ffmpeg is kept in it (:class:`~demoplan.execution.encoder.FrameEncoder`
  gives ffmpeg a session of its own only under a process that does not lead
  its session, one a terminal's Ctrl-C reaches; ``IMAGEIO_FFMPEG_NO_PREVENT_SIGINT``
  does the same for imageio-ffmpeg's own writers), so ``killpg`` leaves no
  grandchild behind; the group is swept with SIGKILL whenever the worker ends.
- JSON lines over a pipe survive a killed child (at worst a cut last line,
  ignored); a ``multiprocessing`` queue shares a lock with the child that a
  kill can leave held, and the "spawn" start method re-imports the parent's
  ``__main__`` (pytest's, uvicorn's). The subprocess is a fresh interpreter
  that imports only demoplan.
- A worker that dies without its final line (killed from outside, out of
  memory) makes the run ``failed`` with one line saying how it ended — never a
  run left ``running``.

Each run that ends (done, failed or cancelled) is written, whole and
atomically, to the work folder's hidden :data:`LAST_RUN_FILE` with its request
(``GET /api/last-run``): a page opened again, after its tab was closed or the
studio restarted, shows it.
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import secrets
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

from demoplan.errors import DemoplanError
from demoplan.studio.workfolder import FileMissingError

__all__ = [
    "LAST_RUN_FILE",
    "MAX_ACTIVE_RUNS",
    "MAX_KEPT_RUNS",
    "TERMINATE_GRACE_S",
    "WORKER",
    "Job",
    "Jobs",
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
TERMINATE_GRACE_S = 1.0
"""s: a cancelled run's process has this long after SIGTERM to clean up before SIGKILL."""
KILLED_WAIT_S = 10.0
"""s: at most this long for the process to be gone after SIGKILL (it is at once)."""
WORKER = (sys.executable, "-m", "demoplan.studio.worker")
"""The command of a run's process."""

LAST_RUN_FILE = ".studio-last-run.json"
"""The work folder's record of the run that ended last (hidden: not listed)."""
LAST_RUN_FORMAT = "demoplan/studio-run-1"
REQUEST_FIELDS = ("scene", "sim", "faults", "seed", "clutter")
"""What the last run's record keeps of its request (and the model's file name)."""

Order = Callable[[str], dict[str, Any]]
"""A run's request for its process, given the run's id."""


class TooManyRunsError(Exception):
    """:data:`MAX_ACTIVE_RUNS` runs are going on (HTTP 429)."""


@dataclass
class Job:
    """One run: its state, its events so far, and its result or error; the
    process it goes on in (None once it failed to start)."""

    id: str
    state: str = "running"
    events: list[dict[str, Any]] = field(default_factory=list)
    result: dict[str, Any] | None = None
    error: str | None = None
    lock: threading.Lock = field(default_factory=threading.Lock)
    process: subprocess.Popen[bytes] | None = None
    ended: threading.Event = field(default_factory=threading.Event)
    """Set once the process is gone (reaped, its group swept) and the state final."""
    reaped: bool = False  # the process's id is free again: never signal it (under ``lock``)
    video: Path | None = None
    request: dict[str, Any] = field(default_factory=dict)
    """What the run's process was told (:data:`Order`)."""
    record: Path | None = None
    """Where the run is written once it has ended (None: nowhere)."""

    def add_event(self, event: dict[str, Any]) -> None:
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

    def signal(self, signum: int) -> None:
        """Send ``signum`` to the run's process group (nothing once it is reaped)."""
        with self.lock:
            if self.process is None or self.reaped:
                return
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(self.process.pid, signum)


class Jobs:
    """The runs of one studio."""

    def __init__(self, worker: Sequence[str] = WORKER, record: Path | None = None) -> None:
        """``record``: the file each run is written to when it ends
        (:data:`LAST_RUN_FILE` of the work folder; None: none)."""
        self._jobs: dict[str, Job] = {}
        self._lock = threading.Lock()
        self._slots = threading.BoundedSemaphore(MAX_ACTIVE_WORK)
        self.worker = tuple(worker)
        self.record = record

    def start(self, order: Order, worker: Sequence[str] | None = None) -> Job:
        """Start a run of ``order`` in a new process (TooManyRunsError beyond
        the limit); ``worker``: its command (default: the studio's worker)."""
        with self._lock:
            active = sum(1 for job in self._jobs.values() if _busy(job))
            if active >= MAX_ACTIVE_RUNS:
                raise TooManyRunsError(
                    f"{active} runs are going on, at most {MAX_ACTIVE_RUNS} at once; "
                    "wait for one to end or cancel it"
                )
            job = Job(secrets.token_hex(8), record=self.record)
            self._jobs[job.id] = job
            finished = [j for j in self._jobs.values() if not _busy(j)]
            for old in finished[: max(0, len(self._jobs) - MAX_KEPT_RUNS)]:
                del self._jobs[old.id]
        request = order(job.id)
        job.request = request
        job.video = Path(request["video"]) if request.get("video") else None
        try:
            process = subprocess.Popen(
                worker or self.worker,
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                start_new_session=True,  # a process group: killpg reaches ffmpeg too
                env=_worker_environment(),
            )
        except OSError as exc:
            _finish(job, "failed", error=f"the run's process could not start ({exc.strerror})")
            _write_record(job)
            job.ended.set()
            return job
        job.process = process
        assert process.stdin is not None
        with contextlib.suppress(OSError):  # a worker gone at once says so at its end
            process.stdin.write(json.dumps(request).encode() + b"\n")
            process.stdin.flush()
        threading.Thread(
            target=_watch, args=(job, process), name=f"studio-run-{job.id}", daemon=True
        ).start()
        return job

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

    def last(self) -> dict[str, Any] | None:
        """The run that ended last in this work folder, as :data:`LAST_RUN_FILE`
        holds it; None before the first (FileMissingError: the file cannot be
        read)."""
        if self.record is None:
            return None
        try:
            text = self.record.read_text(encoding="utf-8")
        except FileNotFoundError:
            return None
        except (OSError, UnicodeDecodeError) as exc:
            raise FileMissingError(f"run: {LAST_RUN_FILE} cannot be read ({exc})") from None
        try:
            document = json.loads(text)
        except ValueError:
            document = None
        if not _is_record(document):
            raise FileMissingError(
                f"run: {LAST_RUN_FILE} is not a run's record ({LAST_RUN_FORMAT} expected); "
                "the next run replaces it"
            )
        assert isinstance(document, dict)
        return document

    def cancel(self, run_id: str) -> Job:
        """Cancel the run: it is ``cancelled`` at once, and its process is
        stopped (SIGTERM, SIGKILL after :data:`TERMINATE_GRACE_S`) and gone
        when this returns."""
        job = self.get(run_id)
        _stop([job])
        return job

    def cancel_all(self) -> None:
        """Cancel every run going on (the studio stops), their processes at once."""
        with self._lock:
            jobs = list(self._jobs.values())
        _stop(jobs)


def _stop(jobs: list[Job]) -> None:
    """Mark ``jobs`` cancelled where they run, and end their processes: SIGTERM
    to each group, then SIGKILL to what is left after the grace."""
    for job in jobs:
        with job.lock:
            if job.state == "running":
                job.state = "cancelled"
    going = [job for job in jobs if not job.ended.is_set()]
    left = _signal_and_wait(going, signal.SIGTERM, TERMINATE_GRACE_S)
    _signal_and_wait(left, signal.SIGKILL, KILLED_WAIT_S)


def _signal_and_wait(jobs: list[Job], number: int, seconds: float) -> list[Job]:
    """Send signal ``number`` to each job's process group and wait up to
    ``seconds`` in all for them to end; the jobs still going."""
    for job in jobs:
        job.signal(number)
    deadline = time.monotonic() + seconds
    for job in jobs:
        job.ended.wait(max(0.0, deadline - time.monotonic()))
    return [job for job in jobs if not job.ended.is_set()]


def _watch(job: Job, process: subprocess.Popen[bytes]) -> None:
    """The run's thread in the studio: read the worker's lines, and when it
    has ended, sweep its group, reap it and settle the run's state."""
    outcome: list[dict[str, Any]] = []
    assert process.stdout is not None
    reader = threading.Thread(target=_read, args=(job, process.stdout, outcome), daemon=True)
    reader.start()
    # ended, not yet reaped: its id (its group's) cannot be taken meanwhile
    with contextlib.suppress(ChildProcessError):
        os.waitid(os.P_PID, process.pid, os.WEXITED | os.WNOWAIT)
    with job.lock:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(process.pid, signal.SIGKILL)  # ffmpeg or any other leftover
        returncode = process.wait()
        job.reaped = True
    reader.join(timeout=KILLED_WAIT_S)  # the group is gone: its stdout ends
    for stream in (process.stdin, process.stdout):
        if stream is not None:
            with contextlib.suppress(OSError):
                stream.close()
    if job.video is not None:  # a worker killed before it could remove them
        from demoplan.commands.execution import remove_unfinished_video

        remove_unfinished_video(job.video)
    if outcome and "result" in outcome[0]:
        _finish(job, "done", result=outcome[0]["result"], events=outcome[0].get("events"))
    elif outcome and "error" in outcome[0]:
        _finish(job, "failed", error=" ".join(str(outcome[0]["error"]).split()))
    else:
        _finish(
            job, "failed", error=f"the run's process ended without a result ({_how(returncode)})"
        )
    _write_record(job)
    job.ended.set()


def _write_record(job: Job) -> None:
    """Write the ended ``job`` to its record, atomically (a warning in the
    studio's log where the work folder refuses it: the run itself is over)."""
    if job.record is None:
        return
    from demoplan.fileio import write_atomic

    request = job.request
    document = {
        "format": LAST_RUN_FORMAT,
        **job.to_json(),
        "model": Path(str(request.get("model", ""))).name,
        **{key: request.get(key) for key in REQUEST_FIELDS},
    }
    try:
        write_atomic(job.record, json.dumps(document) + "\n")
    except DemoplanError as exc:
        logging.getLogger(__name__).warning("the run's record was not written: %s", exc)


def _is_record(document: object) -> bool:
    """Whether ``document`` has the shape of a run's record (:func:`_write_record`)."""
    return (
        isinstance(document, dict)
        and document.get("format") == LAST_RUN_FORMAT
        and isinstance(document.get("run"), str)
        and isinstance(document.get("state"), str)
        and isinstance(document.get("events"), list)
        and all(isinstance(event, dict) for event in document["events"])
        and isinstance(document.get("scene"), dict)
        and isinstance(document.get("model"), str)
    )


def _read(job: Job, stdout: IO[bytes], outcome: list[dict[str, Any]]) -> None:
    """Events into ``job`` as they come; the final line into ``outcome``."""
    for raw in stdout:
        try:
            line = json.loads(raw)
        except ValueError:  # cut short by a kill
            continue
        if not isinstance(line, dict):
            continue
        if "event" in line:
            job.add_event(line["event"])
        elif "result" in line or "error" in line:
            outcome.append(line)


def _finish(
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
            job.events = events[:MAX_EVENTS]


def _how(returncode: int) -> str:
    """How a process ended, in words: ``killed by SIGKILL``, ``exit status 1``."""
    if returncode < 0:
        try:
            name = signal.Signals(-returncode).name
        except ValueError:
            name = f"signal {-returncode}"
        return f"killed by {name}" + (", out of memory?" if name == "SIGKILL" else "")
    return f"exit status {returncode}"


def _worker_environment() -> dict[str, str]:
    """The studio's environment, with this demoplan importable first and ffmpeg
    kept in the run's process group."""
    import demoplan

    source = Path(demoplan.__file__).resolve().parent.parent
    paths = [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]
    if source.name not in ("site-packages", "dist-packages"):  # installed: found anyway,
        paths.insert(0, str(source))  # and never put before the standard library
    return os.environ | {
        "PYTHONPATH": os.pathsep.join(dict.fromkeys(paths)),
        "IMAGEIO_FFMPEG_NO_PREVENT_SIGINT": "1",
    }


def _busy(job: Job) -> bool:
    """The run goes on (a cancelled one until its process is gone)."""
    return job.state == "running" or not job.ended.is_set()
