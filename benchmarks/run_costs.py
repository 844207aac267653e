"""What a run costs beside its plan: the arm's physics and the frames.

``python benchmarks/run_costs.py`` (``--repeats N``, default 3; ``--no-arm``:
the frames only) measures, as
CPU seconds of this process (``time.process_time``), median of the repeats:

* **the arm** — the paper's two experiments (:data:`ARM_RUNS`) with
  ``--sim arm``: a run's CPU against the seconds its physics simulated
  (every 2 ms step is followed by the watch of the arm's contacts, every
  motion by its collision check);
* **the frames** — the tutorial's run (``examples/kitting``, scene
  ``scene-manual-on-motor.json``, ``--faults drop=0.3 --seed 0``) in the
  kinematic world, without and with ``--frames``: the frames' CPU is the
  difference, per frame and in all (the storyboard included).

Every run is checked to reach its goal (a cost of a failed run would mean
nothing). It needs the ``sim`` and ``plot`` extras (MuJoCo, mink, dm_control,
matplotlib); MUJOCO_GL is set to egl where unset.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

from rich.console import Console
from rich.table import Table

os.environ.setdefault("MUJOCO_GL", "egl")

from demoplan.budget import Budget
from demoplan.documents.demonstrations import load_demonstrations
from demoplan.execution.executor import ExecutionSettings
from demoplan.execution.faults import parse_faults
from demoplan.execution.report import RunReport
from demoplan.execution.runner import run_task
from demoplan.learning import learn
from demoplan.learning.settings import PAPER_SETTINGS
from demoplan.model import TaskModel
from demoplan.scenes.prepared import prepare
from demoplan.scenes.scene import Scene, load_scene

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"


def timed_run(
    model: TaskModel,
    scene: Scene,
    sim: str = "kinematic",
    faults: str = "",
    frames: Path | None = None,
) -> tuple[float, RunReport]:
    """The CPU seconds of this process that one run took (plans without a
    time limit), and its report; exits where the run fails (the cost of a
    failed run would mean nothing)."""
    untimed = ExecutionSettings(budget=Budget())
    started = time.process_time()
    report = run_task(
        model,
        prepare(model, scene),
        sim=sim,
        faults=parse_faults(faults),
        frames=frames,
        settings=untimed,
    )
    seconds = time.process_time() - started
    if not report.success:
        sys.exit(f"the {sim} run failed: {report.reason}")
    return seconds, report


ARM_RUNS = {
    "Experiment 1 (set table)": ("set_table", "scenes/set-table-cluttered.json"),
    "Experiment 2 (pyramid)": ("blocks/demonstrations.json", "scenes/pyramid-fig4.json"),
}
"""The arm's runs: demonstrations and scene under ``examples/``, learned with the
paper's settings (as ``learn --paper``)."""


def arm_rows(repeats: int) -> list[list[str]]:
    rows = []
    for name, (demonstrations, scene_file) in ARM_RUNS.items():
        model = learn(load_demonstrations([EXAMPLES / demonstrations]), settings=PAPER_SETTINGS)
        scene = load_scene(EXAMPLES / scene_file)
        costs: list[float] = []
        simulated = 0.0
        for _ in range(repeats):
            seconds, report = timed_run(model, scene, sim="arm")
            costs.append(seconds)
            simulated = report.simulated_seconds or 0.0
        cost = statistics.median(costs)
        rows.append([name, f"{cost:.1f}", f"{simulated:.1f}", f"{cost / simulated:.3f}"])
    return rows


def frames_row(repeats: int, scratch: Path) -> list[str]:
    model = learn(load_demonstrations([EXAMPLES / "kitting" / "demonstrations.json"]))
    scene = load_scene(EXAMPLES / "kitting" / "scene-manual-on-motor.json")
    bare: list[float] = []
    framed: list[float] = []
    files = 0
    for k in range(repeats):
        bare.append(timed_run(model, scene, faults="drop=0.3")[0])
        seconds, report = timed_run(model, scene, faults="drop=0.3", frames=scratch / str(k))
        framed.append(seconds)
        files = len(report.frames)
    extra = statistics.median(framed) - statistics.median(bare)
    return [
        "the tutorial's run, kinematic",
        f"{statistics.median(bare):.2f}",
        f"{statistics.median(framed):.2f}",
        str(files),
        f"{1000 * extra / max(files, 1):.0f}",
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="runs per row (median)")
    parser.add_argument("--no-arm", action="store_true", help="the frames only")
    options = parser.parse_args()
    console = Console()
    if not options.no_arm:
        arm = Table(title=f"The arm's physics (CPU s, median of {options.repeats})")
        for column in ("run", "CPU s", "simulated s", "CPU s per simulated s"):
            arm.add_column(column)
        for row in arm_rows(options.repeats):
            arm.add_row(*row)
        console.print(arm)
    frames = Table(title=f"Frames (CPU s, median of {options.repeats})")
    for column in ("run", "without --frames", "with --frames", "files", "ms per file"):
        frames.add_column(column)
    with tempfile.TemporaryDirectory() as scratch:
        frames.add_row(*frames_row(options.repeats, Path(scratch)))
    console.print(frames)


if __name__ == "__main__":
    main()
