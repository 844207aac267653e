"""Benchmark: ``demoplan evaluate`` here and on Ray with 1 and 2 local workers.

What it measures
----------------
Both paper experiments (Experiment 1, table setting, learned from
``examples/set_table``; Experiment 2, the pyramid, from
``examples/blocks/demonstrations.json``) evaluated over ``--scenes`` random
start layouts × ``--seeds`` seeds with faults ``drop=0.2,displace=0.1`` in the
kinematic world, three ways:

1. **serial**: :class:`~demoplan.evaluation.engine.SerialEngine`, the runs one
   after the other in this process;
2. **Ray, 1 worker** and 3. **Ray, 2 workers**:
   :class:`~demoplan.evaluation.engine.RayEngine` on a local Ray started with
   that many CPUs (its start-up timed apart).

Per way: the wall time of the evaluations (scenes drawn and written, runs,
rows written), the runs per second, and for Ray the start-up; then the
speed-up of 2 workers over 1 and over serial, and Ray's overhead per run
(Ray with 1 worker − serial, over the runs). Target: the rows of every way
equal the serial ones, timing aside (determinism).

How to run
----------
From the repository root, with demoplan[scale] installed::

    python benchmarks/evaluation.py              # 50 layouts × 2 seeds per experiment
    python benchmarks/evaluation.py --quick      # 10 layouts × 2 seeds
    python benchmarks/evaluation.py --out results.json
"""

from __future__ import annotations

import os

# One core per worker: must happen before NumPy (and its BLAS) is imported.
for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from collections.abc import Sequence  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

from rich.console import Console  # noqa: E402
from rich.table import Table  # noqa: E402

from common import Target, package_version, print_targets  # noqa: E402
from demoplan.commands.evaluation import Evaluation, evaluate, settings_from_options  # noqa: E402
from demoplan.documents.demonstrations import load_demonstrations  # noqa: E402
from demoplan.evaluation.engine import Engine, RayEngine, SerialEngine  # noqa: E402
from demoplan.fileio import dump_json  # noqa: E402
from demoplan.learning import learn  # noqa: E402
from demoplan.learning.modelfile import model_to_dict  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
EXPERIMENTS = {
    "exp1": ROOT / "examples" / "set_table",
    "exp2": ROOT / "examples" / "blocks" / "demonstrations.json",
}
FAULTS = "drop=0.2,displace=0.1"


def _evaluate_all(
    models: dict[str, Path], folder: Path, engine: Engine, scenes: int, seeds: int
) -> tuple[float, list[Evaluation]]:
    started = time.perf_counter()
    done = []
    for key, model in models.items():
        settings = settings_from_options(
            model, [], random_scenes=scenes, seeds=seeds, faults=FAULTS, sim="kinematic", clutter=0
        )
        done.append(evaluate(settings, folder / key, engine=engine))
    return time.perf_counter() - started, done


def _on_ray(
    workers: int, models: dict[str, Path], folder: Path, scenes: int, seeds: int
) -> tuple[float, float, list[Evaluation]]:
    import ray

    started = time.perf_counter()
    ray.init(address="local", num_cpus=workers, include_dashboard=False, log_to_driver=False)
    ray.get(ray.remote(lambda: None).remote())  # a worker up: start-up complete
    start_s = time.perf_counter() - started
    try:
        wall, done = _evaluate_all(models, folder, RayEngine(), scenes, seeds)
    finally:
        ray.shutdown()
    return start_s, wall, done


def _outcomes(done: list[Evaluation]) -> list[dict[str, Any]]:
    return [row.outcome() for evaluation in done for row in evaluation.rows]


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="10 layouts per experiment")
    parser.add_argument("--scenes", type=int, default=None, help="layouts per experiment")
    parser.add_argument("--seeds", type=int, default=2)
    parser.add_argument("--out", type=Path, default=None, help="also save the numbers (JSON)")
    args = parser.parse_args(argv)
    scenes = args.scenes or (10 if args.quick else 50)
    console = Console(width=None if sys.stdout.isatty() else 160)
    console.print(
        f"demoplan evaluation benchmark — {scenes} layouts × {args.seeds} seeds per experiment, "
        f"faults {FAULTS}; Python {platform.python_version()}, {os.cpu_count()} CPUs, "
        f"Ray {package_version('ray')}",
        highlight=False,
    )
    with tempfile.TemporaryDirectory() as temporary:
        folder = Path(temporary)
        models = {}
        for key, demos in EXPERIMENTS.items():
            models[key] = folder / f"{key}.json"
            models[key].write_text(dump_json(model_to_dict(learn(load_demonstrations([demos])))))
        _evaluate_all(models, folder / "warm-up", SerialEngine(), 1, 1)  # imports, caches
        serial_s, serial = _evaluate_all(
            models, folder / "serial", SerialEngine(), scenes, args.seeds
        )
        start1, ray1_s, ray1 = _on_ray(1, models, folder / "ray1", scenes, args.seeds)
        start2, ray2_s, ray2 = _on_ray(2, models, folder / "ray2", scenes, args.seeds)
    runs = len(_outcomes(serial))
    table = Table(title=f"{runs} runs (both experiments)", title_justify="left")
    for column in ("way", "Ray start-up [s]", "wall [s]", "runs / s", "ms / run"):
        table.add_column(column, justify="left" if column == "way" else "right")
    for way, start, wall in (
        ("serial", None, serial_s),
        ("Ray, 1 worker", start1, ray1_s),
        ("Ray, 2 workers", start2, ray2_s),
    ):
        table.add_row(
            way,
            "—" if start is None else f"{start:.2f}",
            f"{wall:.2f}",
            f"{runs / wall:.1f}",
            f"{1e3 * wall / runs:.1f}",
        )
    console.print(table)
    overhead_ms = 1e3 * (ray1_s - serial_s) / runs
    console.print(
        f"speed-up of 2 workers: {ray1_s / ray2_s:.2f}× over 1 worker, {serial_s / ray2_s:.2f}× "
        f"over serial; Ray's overhead per run (1 worker − serial): {overhead_ms:.1f} ms",
        highlight=False,
    )
    same = _outcomes(serial) == _outcomes(ray1) == _outcomes(ray2)
    print_targets(
        console,
        [Target("rows equal the serial run's (timing aside)", same, f"{runs} rows per way")],
    )
    if args.out is not None:
        numbers = {
            "runs": runs,
            "scenes": scenes,
            "seeds": args.seeds,
            "cpus": os.cpu_count(),
            "serial_s": serial_s,
            "ray1": {"start_s": start1, "wall_s": ray1_s},
            "ray2": {"start_s": start2, "wall_s": ray2_s},
            "overhead_ms_per_run": overhead_ms,
            "deterministic": same,
        }
        args.out.write_text(json.dumps(numbers, indent=2) + "\n", encoding="utf-8")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
