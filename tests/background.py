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
ended. ``python -m tests.background NAME FOLDER`` runs one job.
"""

from __future__ import annotations

import importlib
import os
import pickle
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

ROOT = Path(__file__).resolve().parents[1]


@dataclass(frozen=True)
class Job:
    function: str  # module:function, called with a folder of its own
    needed_by: tuple[str, ...]  # test files (node id prefixes) that read it


JOBS = {
    "experiments": Job(
        "tests.shared_experiments:run_experiments_once",
        ("tests/test_experiments.py", "tests/test_figure_labels.py"),
    ),
    "hard-parking": Job(
        "tests.helpers:hard_parking_problem",
        (
            "tests/test_interrupt.py",
            "tests/hostile/test_interrupt_any.py",
            "tests/test_plateau.py",
        ),
    ),
}


def _compute(name: str, folder: Path) -> Any:
    """Job ``name``'s result, computed in this process (``folder``: its own, existing)."""
    module, _, function = JOBS[name].function.partition(":")
    return getattr(importlib.import_module(module), function)(folder)


def _environment() -> dict[str, str]:
    """The job's environment: as the hostile suite runs a command (harness.run)."""
    env = dict(os.environ, PYTHONWARNINGS="default")
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


def _load(name: str, place: Path) -> Any:
    done = place / "result.pickle"
    if not done.exists():
        log = (place / "log.txt").read_text(errors="replace")
        raise RuntimeError(f"the shared job {name!r} failed:\n{log[-5000:]}")
    with done.open("rb") as file:
        return pickle.load(file)


def run_now(name: str, folder: Path) -> Any:
    """Run job ``name`` in ``folder/name`` and wait for its result."""
    place = folder / name
    place.mkdir(parents=True)
    with (place / "log.txt").open("wb") as log:
        subprocess.run(
            [sys.executable, "-m", "tests.background", name, str(place)],
            cwd=ROOT,
            stdout=log,
            stderr=subprocess.STDOUT,
            env=_environment(),
            check=False,
        )
    return _load(name, place)


def needed(ids: list[str] | tuple[str, ...]) -> list[str]:
    """The jobs some of the test ids ``ids`` read."""
    return [name for name, job in JOBS.items() if any(i.startswith(job.needed_by) for i in ids)]


def start(name: str, folder: Path) -> subprocess.Popen[bytes] | None:
    """Start job ``name`` in ``folder/name`` (None where there is no ``fcntl``)."""
    if fcntl is None:
        return None
    place = folder / name
    place.mkdir(parents=True)
    lock = os.open(place / "lock", os.O_CREAT | os.O_RDWR)
    try:
        fcntl.flock(lock, fcntl.LOCK_EX)
        with (place / "log.txt").open("wb") as log:
            process = subprocess.Popen(
                [sys.executable, "-m", "tests.background", name, str(place)],
                cwd=ROOT,
                stdout=log,
                stderr=subprocess.STDOUT,
                env=_environment(),
                pass_fds=(lock,),
            )
    finally:
        os.close(lock)  # the job holds it now
    (place / "started").touch()
    return process


def result(name: str, folder: Path) -> Any | None:
    """Job ``name``'s result once it has ended; None if it was never started."""
    place = folder / name
    if fcntl is None or not (place / "started").exists():
        return None
    lock = os.open(place / "lock", os.O_RDONLY)
    try:
        fcntl.flock(lock, fcntl.LOCK_SH)  # granted when the job has ended
    finally:
        os.close(lock)
    return _load(name, place)


def _main(name: str, place: Path) -> int:
    work = place / "work"
    work.mkdir()
    try:
        value = _compute(name, work)
    except BaseException:
        traceback.print_exc()
        return 1
    partial = place / "result.pickle.partial"
    with partial.open("wb") as file:
        pickle.dump(value, file)
    partial.rename(place / "result.pickle")
    return 0


if __name__ == "__main__":
    sys.exit(_main(sys.argv[1], Path(sys.argv[2])))
