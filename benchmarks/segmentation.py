"""Benchmark: how well and how fast ``demoplan.segmentation.segment`` finds steps in pose streams.

What it measures
----------------
1. **Accuracy** over a grid of sensor noise (σ per axis, 0.5 … 5 mm) by
   sampling rate (15 … 240 Hz). Each cell segments the same random
   demonstrations, played back by
   :func:`demoplan.segmentation.stream_from_demonstration` with realistic
   disturbances: uneven clocks (±30 % per interval), 5 % of samples dropped in
   bursts, consecutive moves overlapping by 30 % (two hands) and one 1 cm nudge
   per demonstration (not a step). Per cell:

   * step **precision** and **recall**: found steps aligned in order with the
     true ones (:func:`~demoplan.segmentation.compare_steps`: same object, within
     2 cm), pooled over the cell's demonstrations;
   * **exact**: the fraction of demonstrations whose steps all came back, in
     order, nothing else, each within 5 mm (the acceptance bound);
   * **pose error**: median and 95th percentile of the matched steps' position
     errors (mm).

2. **robosuite's teleoperated demonstrations**: the nine human
   demonstrations in the six ``demo.hdf5`` files of robosuite 0.3 and 1.0
   (PickPlace, NutAssembly, Stack; ``tests/support/robosuite_data.py`` fetches and
   caches them), imported as ``demoplan import`` does, then the same
   trajectories resampled to 20 Hz, written as CSV and read back (segmented
   without geometry). Per demonstration: the hand-read steps
   (``tests/support/robosuite_data.py: EXPECTED``, which the tests check too) and the
   found ones, step precision / recall (``compare_steps``, each expected step
   placed where its object rests at the end of the recording, within 2 cm),
   the position error of the matched steps against that resting place
   (median / max, mm), the pushes reported and the time of ``segment``
   (median of repeats). Without the files (no network) the section is skipped.

3. **Throughput** in samples per second (all objects' samples together) of
   ``segment``, and of reading and writing the stream as CSV and as ROS 2
   bags (``tf`` / ``sqlite3`` and ``pose`` / ``mcap``), on one long stream
   (20 objects × 100 steps at 120 Hz, ~0.6 M samples; ``--quick``: 8 × 20).
   Times are the median of repeats (``time.perf_counter``).

Everything runs on one core: the BLAS/OpenMP thread counts are pinned to 1
before NumPy is imported. Machines are shared and noisy, so only medians are
reported.

The random demonstrations
-------------------------
4–8 objects on a 1 m × 1 m table, 3–10 steps; each step moves a random
object to a random spot at least 5 cm from where it rests. All randomness
flows from ``--seed``.

How to run
----------
From the repository root, with demoplan installed (``pip install -e ".[dev]"``)::

    python benchmarks/segmentation.py              # full grid (about a minute)
    python benchmarks/segmentation.py --quick      # small grid, a few seconds
    python benchmarks/segmentation.py --out results.json   # also save the numbers
    python benchmarks/segmentation.py --no-recordings      # without robosuite's demonstrations
"""

from __future__ import annotations

import os

# One core: must happen before NumPy (and its BLAS) is imported.
for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import shutil  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable, Sequence  # noqa: E402
from dataclasses import asdict, dataclass  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402
from rich.console import Console  # noqa: E402
from rich.table import Table  # noqa: E402

import demoplan  # noqa: E402
from common import package_version  # noqa: E402

# The repository root, for tests/support/robosuite_data.py (the demonstrations and
# their hand-read steps).
REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:
    sys.path.insert(1, str(REPO))
from demoplan.model import Demonstration, Pose, Step  # noqa: E402
from demoplan.segmentation import (  # noqa: E402
    PoseStream,
    Segmentation,
    compare_steps,
    load_stream,
    segment,
    stream_from_demonstration,
    write_bag,
    write_csv,
)
from demoplan.segmentation.importing import import_recording_details  # noqa: E402

FULL_NOISE_MM = (0.5, 1.0, 2.0, 3.0, 5.0)
FULL_RATES = (15, 30, 60, 120, 240)
QUICK_NOISE_MM = (1.0, 3.0)
QUICK_RATES = (30, 120)
FULL_DEMOS, QUICK_DEMOS = 20, 6
MATCH_TOLERANCE = 0.02  # m: a found step matches a true one within this
ACCEPT_TOLERANCE = 0.005  # m: the acceptance bound on step poses
DISTURBANCES: dict[str, float | int] = {
    "rate_jitter": 0.3,
    "drop_fraction": 0.05,
    "overlap": 0.3,
    "nudges": 1,
    "nudge_m": 0.01,
}
TIMES = "\u00d7"  # multiplication sign (spelled out for ruff's RUF001)


# --------------------------------------------------------------------------- data


def random_demonstration(
    rng: np.random.Generator, name: str, n_objects: int, n_steps: int
) -> Demonstration:
    """Random objects on a 1 m table and steps that each move one at least 5 cm."""
    names = [f"obj{i}" for i in range(n_objects)]
    current = {n: rng.uniform(0.05, 0.95, 2) for n in names}
    initial = tuple((n, Pose((float(p[0]), float(p[1]), 0.0))) for n, p in current.items())
    steps = []
    for _ in range(n_steps):
        obj = names[int(rng.integers(n_objects))]
        target = rng.uniform(0.05, 0.95, 2)
        while np.linalg.norm(target - current[obj]) < 0.05:
            target = rng.uniform(0.05, 0.95, 2)
        current[obj] = target
        steps.append(Step(obj, Pose((float(target[0]), float(target[1]), 0.0))))
    return Demonstration(name, tuple(steps), initial=initial)


def demonstrations(seed: int, count: int) -> list[Demonstration]:
    rng = np.random.default_rng([seed, 1])
    return [
        random_demonstration(
            rng, f"random-{k + 1}", int(rng.integers(4, 9)), int(rng.integers(3, 11))
        )
        for k in range(count)
    ]


# --------------------------------------------------------------------------- accuracy


@dataclass(slots=True)
class Cell:
    noise_mm: float
    rate_hz: int
    demos: int
    expected: int
    found: int
    matched: int
    exact: int
    median_error_mm: float
    p95_error_mm: float
    max_error_mm: float
    samples: int
    seconds: float

    @property
    def precision(self) -> float:
        return self.matched / self.found if self.found else 1.0

    @property
    def recall(self) -> float:
        return self.matched / self.expected if self.expected else 1.0


def measure_cell(demos: Sequence[Demonstration], noise_mm: float, rate_hz: int, seed: int) -> Cell:
    expected = found = matched = exact = samples = 0
    errors: list[float] = []
    seconds = 0.0
    for k, demo in enumerate(demos):
        stream = stream_from_demonstration(
            demo,
            rate_hz=rate_hz,
            noise_m=noise_mm / 1000,
            rng=[seed, k, rate_hz, int(noise_mm * 10)],
            **DISTURBANCES,  # type: ignore[arg-type]
        )
        start = time.perf_counter()
        result = segment(stream)
        seconds += time.perf_counter() - start
        samples += stream.n_samples
        score = compare_steps(demo.steps, result.steps, MATCH_TOLERANCE)
        expected += score.expected
        found += score.found
        matched += score.matched
        errors += score.errors
        exact += score.exact and max(score.errors, default=0.0) < ACCEPT_TOLERANCE
    mm = np.array(errors) * 1000 if errors else np.array([np.nan])
    return Cell(
        noise_mm,
        rate_hz,
        len(demos),
        expected,
        found,
        matched,
        int(exact),
        float(np.median(mm)),
        float(np.percentile(mm, 95)),
        float(np.max(mm)),
        samples,
        seconds,
    )


def accuracy_table(
    cells: dict[tuple[float, int], Cell], noises: Sequence[float], rates: Sequence[int], demos: int
) -> Table:
    table = Table(
        title=f"Step precision / recall and exact demonstrations ({demos} random "
        "demonstrations per cell; jitter ±30 %, 5 % dropped, 30 % overlap, one 1 cm nudge)"
    )
    table.add_column("noise σ \\ rate", justify="right")
    for rate in rates:
        table.add_column(f"{rate} Hz", justify="right")
    for noise in noises:
        row = [f"{noise:g} mm"]
        for rate in rates:
            cell = cells[(noise, rate)]
            row.append(
                f"P {cell.precision:.3f} R {cell.recall:.3f} exact {cell.exact}/{cell.demos}"
            )
        table.add_row(*row)
    return table


def error_table(
    cells: dict[tuple[float, int], Cell], noises: Sequence[float], rates: Sequence[int]
) -> Table:
    table = Table(title="Step pose error, median / 95th percentile / max (mm), matched steps")
    table.add_column("noise σ \\ rate", justify="right")
    for rate in rates:
        table.add_column(f"{rate} Hz", justify="right")
    for noise in noises:
        row = [f"{noise:g} mm"]
        for rate in rates:
            cell = cells[(noise, rate)]
            row.append(
                f"{cell.median_error_mm:.2f} / {cell.p95_error_mm:.2f} / {cell.max_error_mm:.2f}"
            )
        table.add_row(*row)
    return table


# --------------------------------------------------------------------------- real recordings


@dataclass(slots=True)
class Recording:
    """One robosuite demonstration segmented from one source (HDF5, or 20 Hz CSV)."""

    recording: str
    key: str
    source: str
    samples: int
    expected: list[str]
    found: list[str]
    matched: int
    errors_mm: list[float]
    pushes: list[str]  # "object distance at time (s from the start)"
    nudges: int
    seconds: float

    @property
    def precision(self) -> float:
        return self.matched / len(self.found) if self.found else 1.0

    @property
    def recall(self) -> float:
        return self.matched / len(self.expected) if self.expected else 1.0


def score_recording(
    case: tuple[str, str],
    source: str,
    stream: PoseStream,
    final: PoseStream,
    run: Callable[[], Segmentation],
    repeats: int,
) -> Recording:
    """Segment with ``run`` (timed, median of ``repeats``) and score against the hand-read
    steps, each placed where its object rests at the end of ``final``."""
    from tests.support.robosuite_data import EXPECTED

    seconds = timed(run, repeats)
    result = run()
    expected = [
        Step(name, Pose(tuple(float(v) for v in final.track(name).positions[-1])))  # type: ignore[arg-type]
        for name in EXPECTED[case]
    ]
    score = compare_steps(expected, result.steps, MATCH_TOLERANCE)
    origin = min(float(track.times[0]) for track in stream.tracks)
    return Recording(
        case[0],
        case[1],
        source,
        stream.n_samples,
        EXPECTED[case],
        [move.object for move in result.moves],
        score.matched,
        [error * 1000 for error in score.errors],
        [
            f"{move.object} {move.distance * 100:.0f} cm at {move.start - origin:.0f} s"
            for move in result.pushes
        ],
        len(result.nudges),
        seconds,
    )


def run_recordings(*, quick: bool) -> list[Recording] | str:
    """Every robosuite demonstration, from its HDF5 file and as 20 Hz CSV; or why not."""
    from tests.support.robosuite_data import (
        EXPECTED,
        RobosuiteDataError,
        resampled,
        robosuite_demonstrations,
    )

    try:
        files = robosuite_demonstrations()
    except RobosuiteDataError as exc:
        return str(exc)
    repeats = 3 if quick else 7
    rows: list[Recording] = []
    folder = Path(tempfile.mkdtemp(prefix="demoplan-seg-bench-"))
    try:
        for name in dict.fromkeys(n for n, _ in EXPECTED):
            for item in import_recording_details(files[name]):
                case = (name, item.key)
                if case not in EXPECTED:
                    continue
                recorded = item.recorded
                stream = recorded.stream

                def direct(stream: PoseStream = stream, recorded: Any = recorded) -> Segmentation:
                    return segment(
                        stream,
                        geometry=dict(recorded.geometry),
                        landmarks=dict(recorded.landmarks),
                    )

                rows.append(score_recording(case, "HDF5", stream, stream, direct, repeats))
                path = folder / f"{name}-{item.key}.csv"
                write_csv(resampled(stream, 20.0), path)
                loaded = load_stream(path)
                rows.append(
                    score_recording(
                        case,
                        "CSV 20 Hz",
                        loaded,
                        stream,
                        lambda loaded=loaded: segment(loaded),
                        repeats,
                    )
                )
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return rows


def recordings_table(rows: Sequence[Recording], source: str) -> Table:
    chosen = [row for row in rows if row.source == source]
    table = Table(
        title=f"robosuite's teleoperated demonstrations ({source}): steps found, "
        "position error against where each object rests at the end"
    )
    for column in (
        "demonstration",
        "samples",
        "expected steps",
        "found steps",
        "P",
        "R",
        "error med / max (mm)",
        "pushes",
        "segment",
    ):
        left = "steps" in column or column in {"demonstration", "pushes"}
        table.add_column(column, justify="left" if left else "right")
    for row in chosen:
        errors = (
            f"{statistics.median(row.errors_mm):.1f} / {max(row.errors_mm):.1f}"
            if row.errors_mm
            else "—"
        )
        table.add_row(
            f"{row.recording} {row.key}",
            f"{row.samples:,}",
            " ".join(row.expected),
            "= expected" if row.found == row.expected else " ".join(row.found) or "none",
            f"{row.precision:.2f}",
            f"{row.recall:.2f}",
            errors,
            ", ".join(row.pushes) or "—",
            f"{row.seconds * 1000:.1f} ms",
        )
    table.add_section()
    errors = [e for row in chosen for e in row.errors_mm]
    found = sum(len(row.found) for row in chosen)
    expected = sum(len(row.expected) for row in chosen)
    matched = sum(row.matched for row in chosen)
    table.add_row(
        "all",
        f"{sum(row.samples for row in chosen):,}",
        f"{expected} steps",
        f"{found} steps",
        f"{matched / found if found else 1.0:.2f}",
        f"{matched / expected if expected else 1.0:.2f}",
        f"{statistics.median(errors):.1f} / {max(errors):.1f}" if errors else "—",
        f"{sum(len(row.pushes) for row in chosen)} reported",
        f"{sum(row.seconds for row in chosen) * 1000:.1f} ms",
    )
    return table


# --------------------------------------------------------------------------- throughput


@dataclass(slots=True)
class Throughput:
    operation: str
    samples: int
    median_s: float

    @property
    def samples_per_s(self) -> float:
        return self.samples / self.median_s


def timed(function: Callable[[], Any], repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def run_throughput(seed: int, *, quick: bool) -> tuple[list[Throughput], int, int]:
    rng = np.random.default_rng([seed, 2])
    n_objects, n_steps = (8, 20) if quick else (20, 100)
    demo = random_demonstration(rng, "long", n_objects, n_steps)
    stream = stream_from_demonstration(demo, rate_hz=120, noise_m=0.002, rng=rng, rate_jitter=0.3)
    n = stream.n_samples
    repeats = 3 if quick else 5
    rows = [Throughput("segment", n, timed(lambda: segment(stream), repeats))]
    folder = Path(tempfile.mkdtemp(prefix="demoplan-seg-bench-"))
    try:
        csv_path = folder / "stream.csv"
        rows.append(
            Throughput(
                "write_csv", n, timed(lambda: write_csv(stream, csv_path), 1 if not quick else 2)
            )
        )
        rows.append(
            Throughput("load_stream (CSV)", n, timed(lambda: load_stream(csv_path), repeats))
        )
        for kind, storage in (("tf", "sqlite3"), ("pose", "mcap")):
            bag = folder / f"{kind}-{storage}"

            def write(bag: Path = bag, kind: str = kind, storage: str = storage) -> None:
                shutil.rmtree(bag, ignore_errors=True)
                write_bag(stream, bag, kind=kind, storage=storage)  # type: ignore[arg-type]

            rows.append(Throughput(f"write_bag ({kind}, {storage})", n, timed(write, 1)))
            rows.append(
                Throughput(
                    f"load_stream (bag: {kind}, {storage})",
                    n,
                    timed(lambda bag=bag: load_stream(bag), 1 if not quick else 2),
                )
            )
        check = load_stream(csv_path)
        assert isinstance(check, PoseStream) and check.n_samples == n
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return rows, n, n_objects


def throughput_table(rows: list[Throughput], samples: int, objects: int) -> Table:
    table = Table(
        title=f"Throughput on one stream: {samples:,} samples ({objects} objects at 120 Hz)"
    )
    for column in ("operation", "median time", "samples / s"):
        table.add_column(column, justify="right")
    for row in rows:
        table.add_row(row.operation, f"{row.median_s:.3f} s", f"{row.samples_per_s:,.0f}")
    return table


# --------------------------------------------------------------------------- main


def parse_args(argv: Sequence[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        description="Benchmark demoplan.segmentation: step precision/recall and pose error "
        "against noise and rate, and throughput."
    )
    parser.add_argument("--quick", action="store_true", help="small grid that finishes in seconds")
    parser.add_argument("--out", type=Path, help="also save the results to this JSON file")
    parser.add_argument("--seed", type=int, default=0, help="seed of the synthetic data")
    parser.add_argument(
        "--no-recordings",
        action="store_true",
        help="skip robosuite's demonstrations (fetched from PyPI when not cached)",
    )
    return parser.parse_args(argv)


def main(argv: Sequence[str] | None = None) -> int:
    args = parse_args(argv)
    console = Console(width=None if sys.stdout.isatty() else 160)
    noises = QUICK_NOISE_MM if args.quick else FULL_NOISE_MM
    rates = QUICK_RATES if args.quick else FULL_RATES
    n_demos = QUICK_DEMOS if args.quick else FULL_DEMOS
    started = time.perf_counter()
    console.print(
        f"demoplan segmentation benchmark — {'quick' if args.quick else 'full'} grid, "
        f"seed {args.seed}; Python {platform.python_version()}, NumPy {np.__version__}, "
        f"rosbags {package_version('rosbags')}, {platform.machine()}, OMP/OPENBLAS/MKL threads = 1",
        highlight=False,
    )
    console.print(f"demoplan imported from {Path(demoplan.__file__).parent}", highlight=False)
    demos = demonstrations(args.seed, n_demos)
    cells = {
        (noise, rate): measure_cell(demos, noise, rate, args.seed)
        for noise in noises
        for rate in rates
    }
    console.print(accuracy_table(cells, noises, rates, n_demos))
    console.print(error_table(cells, noises, rates))
    total = sum(c.samples for c in cells.values()) / sum(c.seconds for c in cells.values())
    console.print(f"segment() over the grid: {total:,.0f} samples/s", highlight=False)
    recordings: list[Recording] = []
    if not args.no_recordings:
        outcome = run_recordings(quick=args.quick)
        if isinstance(outcome, str):
            console.print(f"robosuite's demonstrations skipped: {outcome}", highlight=False)
        else:
            recordings = outcome
            console.print(recordings_table(recordings, "HDF5"))
            console.print(recordings_table(recordings, "CSV 20 Hz"))
    rows, samples, objects = run_throughput(args.seed, quick=args.quick)
    console.print(throughput_table(rows, samples, objects))
    console.print(f"Total benchmark time: {time.perf_counter() - started:.1f} s")
    if args.out is not None:
        document: dict[str, Any] = {
            "benchmark": "demoplan segmentation",
            "grid": "quick" if args.quick else "full",
            "seed": args.seed,
            "python": platform.python_version(),
            "numpy": np.__version__,
            "machine": platform.machine(),
            "disturbances": DISTURBANCES,
            "cells": [
                {**asdict(cell), "precision": cell.precision, "recall": cell.recall}
                for cell in cells.values()
            ],
            "recordings": [
                {**asdict(row), "precision": row.precision, "recall": row.recall}
                for row in recordings
            ],
            "throughput": [{**asdict(row), "samples_per_s": row.samples_per_s} for row in rows],
        }
        args.out.write_text(json.dumps(document, indent=2) + "\n", encoding="utf-8")
        console.print(f"Results saved to {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
