"""Benchmark: tasks learned from robosuite's recordings, carried out in robosuite
and judged by robosuite.

What it measures
----------------
For each environment: its task model is learned at default settings from the
recordings in robosuite's source distributions (tests/support/robosuite_tasks.py: the
Panda's and the Sawyer's, three demonstrations), then ``demoplan run MODEL
--sim robosuite:ENV --seed S`` for seeds 0 … N−1 (robosuite's Panda, its
OSC_POSE controller; docs/execution.md "robosuite"). Printed per environment:
the rate of runs robosuite's ``_check_success()`` passes (``env_success``),
the rate demoplan itself reports a success (never above robosuite's: a run
robosuite fails is not reported as a success), the mean control steps and
wall seconds per run — beside the success rate of robomimic's BC-RNN policy
trained on 200 proficient-human demonstrations of the same task, where one
was published: the low-dimensional agents of the robomimic v0.1 model zoo
(Mandlekar et al., "What Matters in Learning from Offline Human
Demonstrations for Robot Manipulation", CoRL 2021; rates as listed, "approximate",
at https://robomimic.github.io/docs/model_zoo/robomimic_v0.1.html: Can (PH)
~100 %, Square (PH) ~84 %). robomimic has no Stack or two-nut task: "—".

Needs the ``robosuite`` extra in its own environment (docs/execution.md).
Run: ``MUJOCO_GL=egl python benchmarks/robosuite_tasks.py --seeds 50``
(``--env Stack`` for one environment; every environment of
tests/support/robosuite_tasks.py by default, the full PickPlace and NutAssemblyRound
included; 2–11 s per run on a quiet core, PickPlace 30–100 s). A seed whose
scene demoplan refuses (a one-line error) counts as a failed run.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:  # tests/support/robosuite_tasks.py: the recordings and the models
    sys.path.insert(1, str(REPO))

from tests.support.robosuite_tasks import RECORDINGS, task_model  # noqa: E402

from demoplan.errors import DemoplanError  # noqa: E402
from demoplan.execution.robosuite_run import run_in_robosuite  # noqa: E402

ROBOMIMIC_BC_RNN = {"NutAssemblySquare": "~84 %", "PickPlaceCan": "~100 %"}
"""robomimic v0.1 model zoo, BC-RNN low-dim agents on the proficient-human data
(Square = NutAssemblySquare, Can = PickPlaceCan)."""


def measure(env: str, seeds: int, folder: Path) -> tuple[int, int, float, float]:
    """(robosuite's successes, demoplan's successes, mean control steps, mean seconds)."""
    model = task_model(env, folder / env)
    judged = reported = steps = 0
    started = time.perf_counter()
    for seed in range(seeds):
        began = time.perf_counter()
        try:
            report = run_in_robosuite(model, f"robosuite:{env}", seed=seed)
        except DemoplanError as exc:  # a scene demoplan refuses: a failed run, not the end
            print(f"  {env} seed {seed}: refused, {time.perf_counter() - began:.1f} s, {exc}")
            continue
        judged += report.env_success
        reported += report.success
        steps += report.control_steps
        print(
            f"  {env} seed {seed}: env_success {report.env_success}, demoplan "
            f"{report.demoplan_success}, {report.control_steps} steps, "
            f"{time.perf_counter() - began:.1f} s, {report.reason}",
            flush=True,
        )
    return judged, reported, steps / seeds, (time.perf_counter() - started) / seeds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--env", action="append", choices=sorted(RECORDINGS))
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for env in args.env or list(RECORDINGS):
            judged, reported, steps, seconds = measure(env, args.seeds, Path(folder))
            rows.append((env, judged, reported, steps, seconds))
    print(
        f"{'environment':<20} {'env_success':>12} {'demoplan':>9} {'steps':>7} {'s/run':>6}"
        f"  robomimic BC-RNN (200 PH demos)"
    )
    for env, judged, reported, steps, seconds in rows:
        print(
            f"{env:<20} {judged:>5}/{args.seeds:<3} {100 * judged / args.seeds:>3.0f}% "
            f"{reported:>5}/{args.seeds:<3} {steps:>7.0f} {seconds:>6.1f}  "
            f"{ROBOMIMIC_BC_RNN.get(env, '—')}"
        )


if __name__ == "__main__":
    main()
