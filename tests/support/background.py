"""Slow results several tests read, computed once per test session in a
process of their own, while the tests run.

Each :data:`JOBS` entry names a function ``f(folder) -> result`` (its result
is pickled) and the test files that read it. Under pytest-xdist the
controller (tests/conftest.py) starts a job as soon as the workers' collection
holds one of those files, so it runs beside the tests instead of holding up
one worker while the other waits for it; the fixture
:func:`tests.conftest.shared_result` waits for the job where a test needs it.
Without xdist (or without ``fcntl``) the fixture runs the job itself, once
per session, and waits for it (:func:`run_now`). A job runs in a process of
its own in either case: it may change its working folder, environment and
signal handlers (the experiments run through the command's entry point).

The job holds an exclusive ``flock`` on ``FOLDER/NAME/lock`` for its whole
life (taken by the controller before the job starts, inherited by it): a
worker's shared lock on the file is granted when the job has ended, however it
ended. ``python -m tests.support.background NAME FOLDER`` runs one job in an existing
folder, as it is (:func:`run_now` runs it as the tests do: prepared, and
audited where the job says so).

An audited job (``Job.audited``: the experiments) runs under ``strace -f``
where strace works (tests/hostile/file_audit.py's options), its log in
``FOLDER/NAME/strace.log``, in the environment of an audited command: ``HOME``,
``TMPDIR`` and the libraries' caches fresh folders in ``FOLDER/NAME`` (whether
traced or not: the same run). A test reads the log afterwards and checks the
command's accesses (tests/hostile/test_open_audit.py): the suite audits the
run it shares instead of running the experiments a second time.
"""

from __future__ import annotations

import importlib
import os
import pickle
import signal
import subprocess
import sys
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Any

try:
    import fcntl
except ImportError:  # not POSIX: each session computes in its own process
    fcntl = None  # type: ignore[assignment]

ROOT = Path(__file__).resolve().parents[2]


@dataclass(frozen=True)
class Job:
    function: str  # module:function, called with a folder of its own
    needed_by: tuple[str, ...]  # test files (node id prefixes) that read it
    prepare: str | None = None  # module:function called with the working folder, before the run
    audited: bool = False  # under strace where it works, in an audited command's environment


JOBS = {
    "experiments": Job(
        "tests.support.shared_experiments:run_experiments_once",
        (
            "tests/experiments/test_experiments.py",
            "tests/experiments/test_figure_labels.py",
            "tests/hostile/test_open_audit.py::test_experiments_",
        ),
        prepare="tests.support.shared_experiments:plant_the_users_file",
        audited=True,
    ),
}


@dataclass(frozen=True)
class JobFolder:
    """A job's folder ``FOLDER/NAME`` and what its harness (this module) keeps
    there: the lock, the job's output (``log.txt``), its result pickle, the
    working folder the job's function is given, and the strace log of an
    audited job."""

    path: Path

    @property
    def work(self) -> Path:
        return self.path / "work"

    @property
    def lock(self) -> Path:
        return self.path / "lock"

    @property
    def log(self) -> Path:
        return self.path / "log.txt"

    @property
    def result(self) -> Path:
        return self.path / "result.pickle"

    @property
    def partial_result(self) -> Path:
        """The pickle as it is written, renamed to :attr:`result` when whole."""
        return self.path / "result.pickle.partial"

    @property
    def trace(self) -> Path:
        return self.path / "strace.log"

    def traced(self) -> Path | None:
        """The strace log, where the job ran under strace (strace made it)."""
        return self.trace if self.trace.exists() else None


def _call(function: str, folder: Path) -> Any:
    module, _, name = function.partition(":")
    return getattr(importlib.import_module(module), name)(folder)


def _compute(name: str, folder: Path) -> Any:
    """Job ``name``'s result, computed in this process (``folder``: its own, existing)."""
    return _call(JOBS[name].function, folder)


def _environment(job: JobFolder, audited: bool) -> dict[str, str]:
    """The job's environment: as the hostile suite runs a command (harness.run),
    or as it runs an audited one (HOME, TMPDIR and the caches in the job's folder)."""
    if audited:
        from tests.hostile.file_audit import audit_environment

        (job.path / "caches").mkdir()  # the libraries make their folders in it
        return audit_environment(job.path, job.path / "caches")
    env = dict(os.environ, PYTHONWARNINGS="default")
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


def _prepare(name: str, folder: Path) -> tuple[JobFolder, list[str], dict[str, str]]:
    """Job ``name``'s folder made (its working folder prepared), and the
    command and environment it runs in: under strace if it is audited and
    strace works."""
    job, spec = JobFolder(folder / name), JOBS[name]
    job.work.mkdir(parents=True)
    if spec.prepare is not None:
        _call(spec.prepare, job.work)  # before the trace: the job's own writes only
    command = [sys.executable, "-m", "tests.support.background", name, str(job.path)]
    if spec.audited:
        from tests.hostile.file_audit import STRACE, strace_command

        if STRACE:
            command = [*strace_command(job.trace), *command]
    return job, command, _environment(job, spec.audited)


def _load(name: str, job: JobFolder) -> Any:
    if not job.result.exists():
        log = job.log.read_text(errors="replace")
        raise RuntimeError(f"the shared job {name!r} failed:\n{log[-5000:]}")
    with job.result.open("rb") as file:
        return pickle.load(file)


def run_now(name: str, folder: Path) -> Any:
    """Run job ``name`` in ``folder/name`` and wait for its result."""
    job, command, env = _prepare(name, folder)
    with job.log.open("wb") as log:
        subprocess.run(
            command, cwd=ROOT, stdout=log, stderr=subprocess.STDOUT, env=env, check=False
        )
    return _load(name, job)


def needed(ids: list[str] | tuple[str, ...]) -> list[str]:
    """The jobs some of the test ids ``ids`` read."""
    return [name for name, job in JOBS.items() if any(i.startswith(job.needed_by) for i in ids)]


def start(name: str, folder: Path) -> subprocess.Popen[bytes] | None:
    """Start job ``name`` in ``folder/name`` (None where there is no ``fcntl``),
    in a process group of its own (:func:`stop` ends the job, strace with it)."""
    if fcntl is None:
        return None
    job, command, env = _prepare(name, folder)
    lock = os.open(job.lock, os.O_CREAT | os.O_RDWR)
    try:
        fcntl.flock(lock, fcntl.LOCK_EX)
        with job.log.open("wb") as log:
            process = subprocess.Popen(
                command,
                cwd=ROOT,
                stdout=log,
                stderr=subprocess.STDOUT,
                env=env,
                pass_fds=(lock,),
                start_new_session=True,
            )
    finally:
        os.close(lock)  # the job holds it now
    (job.path / "started").touch()
    return process


def stop(process: subprocess.Popen[bytes]) -> None:
    """End a job :func:`start` started, if it still runs: its process group
    (the job, and strace tracing it)."""
    if process.poll() is None:
        os.killpg(process.pid, signal.SIGKILL)
        process.wait()


def result(name: str, folder: Path) -> Any | None:
    """Job ``name``'s result once it has ended; None if it was never started."""
    job = JobFolder(folder / name)
    if fcntl is None or not (job.path / "started").exists():
        return None
    lock = os.open(job.lock, os.O_RDONLY)
    try:
        fcntl.flock(lock, fcntl.LOCK_SH)  # granted when the job (and strace) has ended
    finally:
        os.close(lock)
    return _load(name, job)


def _main(name: str, place: Path) -> int:
    job = JobFolder(place)
    if not job.work.exists():  # made by _prepare, unless run by hand (no attempt traced)
        job.work.mkdir()
    try:
        value = _compute(name, job.work)
    except BaseException:
        traceback.print_exc()
        return 1
    with job.partial_result.open("wb") as file:
        pickle.dump(value, file)
    job.partial_result.rename(job.result)
    return 0


if __name__ == "__main__":
    sys.exit(_main(sys.argv[1], Path(sys.argv[2])))
