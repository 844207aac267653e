"""Shared test helpers: the shipped examples and a generator of random tasks."""

from __future__ import annotations

import json
import signal
import subprocess
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from demoplan.budget import Budget
from demoplan.execution.executor import ExecutionSettings
from demoplan.experiments.paper import PAPER_TABLE_II
from demoplan.model import Demonstration, Pose, Step, TaskModel
from demoplan.rotations import quat_from_yaw

if TYPE_CHECKING:
    from demoplan.scenes.plan import ChosenPlan
    from demoplan.scenes.prepared import PreparedScene
    from demoplan.scenes.scene import Scene

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
ONE_MOVE_SCENE = Path(__file__).resolve().parents[1] / "data" / "scenes" / "pyramid-one-move.json"
"""Fig. 4's blocks with wood and green already at demonstration 2's goal: the
blocks model plans one move (red onto them) — a run for tests that need one,
not its length (a third of Fig. 4's four moves' CPU, frames and video)."""

# Table II: state, object, relative position, (x, y) — the library's transcription.
UNTIMED = ExecutionSettings(budget=Budget())
"""A run whose plans have no time limit, for tests that are not about the
budget: with the default 2 s, a loaded machine (or a worker starved beside
others) runs out of time building plans, and the test would measure the
machine instead of the behaviour."""

TABLE_II = [(r.id, r.object, r.position_reference, r.position) for r in PAPER_TABLE_II]


def seeded_start(
    model: TaskModel, scene: Scene, settings: ExecutionSettings = ExecutionSettings()
) -> tuple[PreparedScene, ChosenPlan]:
    """What every seeded run starting in ``scene`` begins with: the scene prepared
    (objects the model never saw allowed) and the first plan, made once for a loop
    over seeds and passed to ``execute(..., first=...)``. Each run would make the
    same: the first plan depends on neither the seed nor the faults, which act only
    once the run has begun, and every replan is still made in every run."""
    from demoplan.execution.executor import first_plan
    from demoplan.scenes.prepared import prepare

    prepared = prepare(model, scene, clutter=True, settings=settings.geometry)
    return prepared, first_plan(model, prepared, settings)


def paper_model(example: str) -> TaskModel:
    """A shipped example (a path under ``examples/``) learned with the paper's
    reading, :data:`~demoplan.learning.settings.PAPER_SETTINGS`: the examples
    were drawn for its fixed 3 mm / 0.5° ties, and learned so they give the
    paper's Tables II–V (the defaults estimate the precision from the data)."""
    from demoplan.documents.demonstrations import load_demonstrations
    from demoplan.learning import learn
    from demoplan.learning.settings import PAPER_SETTINGS

    return learn(load_demonstrations([EXAMPLES / example]), settings=PAPER_SETTINGS)


def random_task_demonstrations(
    seed: int, n_demos: int, n_objects: int, *, oriented: bool = False
) -> list[Demonstration]:
    """Demonstrations of a random task: each object is placed absolutely (2 cm
    scatter) or relative to an earlier one (fixed offset, 2 mm noise); the step
    order varies between demonstrations but keeps references first."""
    rng = np.random.default_rng(seed)
    references = [None] + [
        int(rng.integers(0, i)) if rng.random() < 0.7 else None for i in range(1, n_objects)
    ]
    offsets = rng.uniform(-0.25, 0.25, (n_objects, 2))
    anchors = rng.uniform(0.2, 0.8, (n_objects, 2))
    yaws = rng.uniform(-180, 180, n_objects)
    demos = []
    for d in range(n_demos):
        order = _shuffled_order(rng, references)
        placed: dict[int, np.ndarray] = {}
        steps = []
        for i in order:
            ref = references[i]
            if ref is None:
                xy = anchors[i] + rng.normal(0, 0.01, 2)
            else:
                xy = placed[ref] + offsets[i] + rng.normal(0, 0.001, 2)
            placed[i] = xy
            yaw = float(yaws[i] + rng.normal(0, 0.2)) if oriented else None
            steps.append(
                Step(
                    f"o{i}",
                    Pose(
                        (float(xy[0]), float(xy[1]), 0.0),
                        None if yaw is None else quat_from_yaw(yaw),
                    ),
                )
            )
        demos.append(Demonstration(f"demo-{d + 1}", tuple(steps)))
    return demos


def _shuffled_order(rng: np.random.Generator, references: list[int | None]) -> list[int]:
    remaining = list(range(len(references)))
    order: list[int] = []
    while remaining:
        ready = [i for i in remaining if references[i] is None or references[i] in order]
        pick = ready[int(rng.integers(len(ready)))]
        order.append(pick)
        remaining.remove(pick)
    return order


def demo(steps: list[dict[str, Any]] | None = None, **fields: Any) -> dict[str, Any]:
    """A minimal valid demonstration document, with ``fields`` overriding."""
    data: dict[str, Any] = {
        "format": "demoplan/demonstration-1",
        "steps": steps if steps is not None else [{"object": "plate", "position": [0.5, 0.4]}],
    }
    data.update(fields)
    return data


def raw(step: str) -> str:
    """Demonstration JSON text around one step's raw JSON (for literals json.dumps refuses)."""
    return '{"format": "demoplan/demonstration-1", "steps": [' + step + "]}"


def write(path: Path, data: Any) -> Path:
    path.write_text(data if isinstance(data, str) else json.dumps(data), encoding="utf-8")
    return path


def _wait_until_stopped(process: subprocess.Popen[str]) -> None:
    """Wait until the kernel shows ``process`` stopped (``T`` in /proc's stat), or
    ended: a SIGSTOP is sent at once but takes effect when the process is next
    scheduled."""
    stat = Path(f"/proc/{process.pid}/stat")
    while process.poll() is None:
        try:
            state = stat.read_text().rpartition(")")[2].split()[0]
        except (OSError, IndexError):
            return
        if state in ("T", "t", "Z", "X"):
            return
        time.sleep(0.001)


def stopped_when(
    process: subprocess.Popen[str], ready: Callable[[], bool], limit: float = 300.0
) -> bool:
    """Let ``process`` run in short steps, stopped (SIGSTOP) between them, until
    ``ready()`` holds while it is stopped: True, and the process is left stopped
    (:func:`interrupt_stopped` goes on); False if it ended first. Where a test
    waits for a process to reach a point and then signals it, the process
    cannot run to its end meanwhile, however long the test itself is paused —
    so the process's work need not be long for the test to be sure."""
    began = time.monotonic()
    while process.poll() is None and time.monotonic() - began < limit:
        process.send_signal(signal.SIGSTOP)
        _wait_until_stopped(process)
        if process.poll() is None and ready():
            return True
        process.send_signal(signal.SIGCONT)
        time.sleep(0.02)
    return False


def interrupt_stopped(process: subprocess.Popen[str]) -> None:
    """Ctrl-C (SIGINT) to a process :func:`stopped_when` left stopped: the
    signal is pending while it is stopped and is its first event when it goes on."""
    process.send_signal(signal.SIGINT)
    process.send_signal(signal.SIGCONT)


def wait_for_signal_handlers(process: subprocess.Popen[str], limit: float = 120.0) -> None:
    """Wait until ``process`` (a demoplan command) has set its own handler for
    SIGTERM — the first thing the launcher does — so that a signal sent now is
    demoplan's to answer, not Python's start-up's, however slowly a loaded
    machine starts the process. Reads the caught-signal mask of /proc (Linux);
    where there is none, returns at once."""
    status = Path(f"/proc/{process.pid}/status")
    began = time.monotonic()
    while process.poll() is None and time.monotonic() - began < limit:
        try:
            text = status.read_text()
        except OSError:
            return
        caught = [line.split()[1] for line in text.splitlines() if line.startswith("SigCgt:")]
        if not caught or int(caught[0], 16) >> (signal.SIGTERM - 1) & 1:
            return
        time.sleep(0.005)
