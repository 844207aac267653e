"""Benchmark: how fast ``TaskModelLearner().fit`` is, and what it costs in memory.

What it measures
----------------
1. **Learning** on synthetic demonstrations generated in memory, over a grid of
   demonstrations (2 … 200) by objects (3 … 30). For each cell:

   * wall time of ``TaskModelLearner().fit(demos)`` — the median of several
     repeats (``time.perf_counter``; 5 repeats for cells under 0.1 s, 3 under
     5 s, a single run above that);
   * peak memory traced by ``tracemalloc`` during one further, separate fit
     (tracing slows Python down, so it is never timed).

   Then **state counts over placement noise**: for a placement noise sigma of
   0.2 mm … 3 cm, used as both the absolute scatter and the relative noise
   (alternatives then at least max(10 cm, 6 sigma + 5 cm) apart, the anchor
   grid widened to match: :meth:`Noise.uniform`), a few (demonstrations,
   objects) cells, each with the learned/expected states (✓ where every
   object learned the expected number) and the median time. The sanity line
   summarises both tables: the expected count per object is the number of its
   alternatives used in at least two of the demonstrations, at least 1 (a place
   demonstrated once is no evidence of a state of its own).

   Then the empirical growth exponents: the least-squares slope of log(time)
   against log(demonstrations) at a fixed number of objects, and against
   log(objects) at a fixed number of demonstrations (slope 1 = linear,
   2 = quadratic). It ends with the target line for the
   50-demonstration, 20-object cell (target: under 1 s on one core).

2. **K-means per call** on tiny data (n = 5 … 200 points, d = 3, c = 2 and 4):
   demoplan's vectorised NumPy :func:`demoplan.learning.clustering.kmeans` against
   scikit-learn's ``KMeans(n_clusters=c, n_init=4, random_state=0)``, median µs
   per call and their ratio. Skipped (with a note) when scikit-learn is missing.

Everything runs on one core: the BLAS/OpenMP thread counts are pinned to 1
before NumPy is imported. Machines are shared and noisy, so only medians and
ratios are reported.

The synthetic task
------------------
N objects; each is placed either *absolutely* (near a fixed point on the table,
~2 cm RMS scatter between demonstrations) or *relative to an earlier object*
(fixed offset, in the reference's frame when the reference is oriented, ~2 mm
RMS noise). About a quarter of the objects have two
alternative placements at least 10 cm apart, chosen at random per
demonstration. About half the objects carry a yaw orientation (absolute, or
relative to an oriented reference). Every demonstration moves every object
once; the step order is random except that a relative object always comes
after its reference. All randomness flows from one ``numpy.random.Generator``.

How to run
----------
From the repository root, with demoplan installed (``pip install -e ".[dev]"``)::

    python benchmarks/learning.py              # full grid (a few minutes)
    python benchmarks/learning.py --quick      # small grid and noise table, under 30 s
    python benchmarks/learning.py --out results.json   # also save the numbers
"""

from __future__ import annotations

import os

# One core: must happen before NumPy (and its BLAS) is imported.
for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import platform  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import tracemalloc  # noqa: E402
from collections import Counter  # noqa: E402
from collections.abc import Callable, Sequence  # noqa: E402
from dataclasses import asdict, dataclass, field  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402
from numpy.typing import NDArray  # noqa: E402
from rich.console import Console  # noqa: E402
from rich.table import Table  # noqa: E402

import demoplan  # noqa: E402
from common import package_version  # noqa: E402
from demoplan.learning import TaskModelLearner  # noqa: E402
from demoplan.learning.clustering import kmeans  # noqa: E402
from demoplan.model import Demonstration, Pose, Step, Vector3  # noqa: E402
from demoplan.rotations import quat_from_yaw  # noqa: E402

FULL_DEMOS = (2, 5, 10, 20, 50, 100, 200)
FULL_OBJECTS = (3, 5, 10, 20, 30)
QUICK_DEMOS = (2, 5, 10, 20, 50)
QUICK_OBJECTS = (3, 5, 10)  # the 50 x 20 target cell is measured on its own
TARGET_DEMOS, TARGET_OBJECTS, TARGET_SECONDS = 50, 20, 1.0
TIMES = "\u00d7"  # multiplication sign (spelled out for ruff's RUF001)

KMEANS_SIZES = (5, 20, 50, 200)
KMEANS_CLUSTERS = (2, 4)

# Generator parameters (metres, degrees).
ABSOLUTE_SCATTER = 0.02  # RMS in the table plane between demonstrations
RELATIVE_NOISE = 0.002  # RMS of a relative placement about its offset
ABSOLUTE_YAW_NOISE = 3.0
RELATIVE_YAW_NOISE = 0.3
MIN_ALTERNATIVE_GAP = 0.10
GRID_SPACING = 0.30  # absolute anchors sit on a grid this coarse
# The noise table: sigma (m) as both the absolute scatter and the relative noise.
FULL_SIGMAS = (0.0002, 0.001, 0.005, 0.01, 0.02, 0.03)
QUICK_SIGMAS = (0.0002, 0.01, 0.03)
FULL_NOISE_CELLS = ((5, 5), (10, 10), (20, 10), (50, 20))  # (demonstrations, objects)
QUICK_NOISE_CELLS = ((5, 5), (10, 10), (50, 20))
# Every cell's data is a prefix of one task of TASK_OBJECTS objects and of one
# run of TASK_DEMOS demonstrations per object count, so that along a row or a
# column of the grid only the counts change (and --quick measures the same cells).
TASK_OBJECTS = max(FULL_OBJECTS)
TASK_DEMOS = max(FULL_DEMOS)


# --------------------------------------------------------------------------- generator


@dataclass(frozen=True, slots=True)
class Noise:
    """The generator's scales (metres): the defaults are the module constants.

    ``absolute_scatter`` and ``relative_noise`` are planar RMS values;
    alternatives are at least ``min_gap`` apart; absolute anchors sit on a grid
    ``grid_spacing`` apart.
    """

    absolute_scatter: float = ABSOLUTE_SCATTER
    relative_noise: float = RELATIVE_NOISE
    min_gap: float = MIN_ALTERNATIVE_GAP
    grid_spacing: float = GRID_SPACING

    @classmethod
    def uniform(cls, sigma: float) -> Noise:
        """``sigma`` as both the absolute scatter and the relative noise, with
        alternatives at least max(10 cm, 6 sigma + 5 cm) apart and a grid coarse
        enough that two anchors' alternatives stay 6 sigma apart."""
        gap = max(MIN_ALTERNATIVE_GAP, 6.0 * sigma + 0.05)
        return cls(sigma, sigma, gap, max(GRID_SPACING, 2.0 * (gap + 0.05) + 6.0 * sigma))


@dataclass(frozen=True, slots=True)
class ObjectSpec:
    """How one object is placed in the synthetic task.

    ``reference`` is the index of an earlier object (``None``: absolute);
    ``placements`` are the alternative anchors (absolute) or offsets (relative);
    ``yaw`` is the absolute yaw or the yaw offset from an oriented reference
    (``None``: the object's orientation is not recorded).
    """

    name: str
    reference: int | None
    placements: tuple[tuple[float, float], ...]
    yaw: float | None


@dataclass(frozen=True, slots=True)
class TaskSpec:
    objects: tuple[ObjectSpec, ...]

    def prefix(self, n_objects: int) -> TaskSpec:
        """The task restricted to its first ``n_objects`` objects (references stay valid)."""
        return TaskSpec(self.objects[:n_objects])


@dataclass(frozen=True, slots=True)
class SyntheticDemonstrations:
    """Demonstrations of a task, with which alternative each object took in each."""

    demonstrations: tuple[Demonstration, ...]
    choices: tuple[tuple[int, ...], ...]  # choices[k][i]: alternative of object i in demo k
    names: tuple[str, ...]  # names[i]: object i's name

    def expected_states(self, n_demos: int) -> int:
        """States a perfect learner finds in the first ``n_demos``: the sum of
        :meth:`expected_per_object`."""
        return sum(self.expected_per_object(n_demos).values())

    def expected_per_object(self, n_demos: int) -> dict[str, int]:
        """States a perfect learner finds per object in the first ``n_demos``, under
        the method's rule.

        Per object, the number of its alternatives used in at least two of these
        demonstrations, at least 1. A place demonstrated once is no evidence of
        a separate state: learning rejects every clustering with a cluster of
        one placement (``_Scan.consider`` in ``demoplan.learning.clustering``),
        so such a placement joins a state of the object. Here an object has at
        most two alternatives, so one used once leaves a single cluster (c = 1,
        which is never rejected): one state, as counted. (With three or more,
        the single placement could join a neighbouring cluster whose spread then
        fails the precision check, collapsing the object further; the generator
        never draws that case.)
        """
        used = self.choices[:n_demos]
        expected = {}
        for i, name in enumerate(self.names):
            counts = Counter(choice[i] for choice in used)
            expected[name] = max(1, sum(1 for n in counts.values() if n >= 2))
        return expected


def _planar(rng: np.random.Generator, low: float, high: float) -> tuple[float, float]:
    """A random planar vector with length in [low, high)."""
    angle = rng.uniform(0.0, 2.0 * math.pi)
    length = rng.uniform(low, high)
    return (length * math.cos(angle), length * math.sin(angle))


def _alternative(
    rng: np.random.Generator,
    centre: tuple[float, float],
    first: tuple[float, float],
    low: float,
    high: float,
    gap: float,
) -> tuple[float, float]:
    """A second placement ``low``–``high`` from ``centre`` and at least ``gap``
    from ``first``."""
    while True:
        dx, dy = _planar(rng, low, high)
        candidate = (centre[0] + dx, centre[1] + dy)
        if math.dist(candidate, first) >= gap:
            return candidate


def make_task(
    n_objects: int,
    rng: np.random.Generator,
    *,
    relative_fraction: float = 0.5,
    alternative_fraction: float = 0.25,
    oriented_fraction: float = 0.5,
    noise: Noise = Noise(),
) -> TaskSpec:
    """A random task with ``n_objects`` objects (the first one is always absolute).

    Absolute objects sit on distinct nodes of a square grid ``noise.grid_spacing``
    apart; relative ones 6-15 cm from their reference. Alternatives are drawn
    at least ``noise.min_gap`` from the first placement (absolute: up to 5 cm
    further; relative: 6 cm to max(20 cm, gap + 10 cm) from the reference).
    """
    gap = noise.min_gap
    side = math.ceil(math.sqrt(n_objects))
    cells = rng.permutation(side * side)
    specs: list[ObjectSpec] = []
    for i in range(n_objects):
        relative = i > 0 and rng.random() < relative_fraction
        reference = int(rng.integers(i)) if relative else None
        if reference is None:
            row, col = divmod(int(cells[i]), side)
            first = (col * noise.grid_spacing, row * noise.grid_spacing)
            placements = [first]
            if rng.random() < alternative_fraction:
                # (rounded, so that the default task keeps its draws: 0.1 + 0.05 != 0.15)
                placements.append(_alternative(rng, first, first, gap, round(gap + 0.05, 6), gap))
        else:
            first = _planar(rng, 0.06, 0.15)
            placements = [first]
            if rng.random() < alternative_fraction:
                # Around the reference, and away from the first placement: the two
                # must be told apart (an alternative 2 cm from the first is one place).
                placements.append(
                    _alternative(rng, (0.0, 0.0), first, 0.06, max(0.20, gap + 0.10), gap)
                )
        yaw = float(rng.uniform(-90.0, 90.0)) if rng.random() < oriented_fraction else None
        specs.append(ObjectSpec(f"obj{i:02d}", reference, tuple(placements), yaw))
    return TaskSpec(tuple(specs))


def _step_order(task: TaskSpec, rng: np.random.Generator) -> list[int]:
    """A random order of all objects with every relative object after its reference."""
    remaining = set(range(len(task.objects)))
    order: list[int] = []
    while remaining:
        ready = sorted(
            i
            for i in remaining
            if task.objects[i].reference is None or task.objects[i].reference not in remaining
        )
        choice = ready[int(rng.integers(len(ready)))]
        order.append(choice)
        remaining.remove(choice)
    return order


def make_demonstrations(
    task: TaskSpec, n_demos: int, rng: np.random.Generator, noise: Noise = Noise()
) -> SyntheticDemonstrations:
    """``n_demos`` noisy demonstrations of ``task``, each moving every object once."""
    # Per axis, so that the planar RMS is the target.
    abs_sigma = noise.absolute_scatter / math.sqrt(2.0)
    rel_sigma = noise.relative_noise / math.sqrt(2.0)
    demos: list[Demonstration] = []
    choices: list[tuple[int, ...]] = []
    for k in range(n_demos):
        choice = [0] * len(task.objects)
        positions: dict[int, tuple[float, float]] = {}
        yaws: dict[int, float] = {}
        steps: list[Step] = []
        for i in _step_order(task, rng):
            spec = task.objects[i]
            choice[i] = int(rng.integers(len(spec.placements)))
            px, py = spec.placements[choice[i]]
            if spec.reference is None:
                nx, ny = rng.normal(0.0, abs_sigma, size=2)
                xy = (px + nx, py + ny)
            else:
                if spec.reference in yaws:  # the offset is in the oriented reference's frame
                    turn = math.radians(yaws[spec.reference])
                    px, py = (
                        math.cos(turn) * px - math.sin(turn) * py,
                        math.sin(turn) * px + math.cos(turn) * py,
                    )
                rx, ry = positions[spec.reference]
                nx, ny = rng.normal(0.0, rel_sigma, size=2)
                xy = (rx + px + nx, ry + py + ny)
            positions[i] = xy
            orientation = None
            if spec.yaw is not None:
                if spec.reference is not None and spec.reference in yaws:
                    yaw = yaws[spec.reference] + spec.yaw + rng.normal(0.0, RELATIVE_YAW_NOISE)
                else:
                    yaw = spec.yaw + rng.normal(0.0, ABSOLUTE_YAW_NOISE)
                yaws[i] = yaw
                orientation = quat_from_yaw(yaw)
            position: Vector3 = (float(xy[0]), float(xy[1]), 0.0)
            steps.append(Step(spec.name, Pose(position, orientation)))
        demos.append(Demonstration(name=f"demo{k:03d}", steps=tuple(steps)))
        choices.append(tuple(choice))
    return SyntheticDemonstrations(
        tuple(demos), tuple(choices), tuple(spec.name for spec in task.objects)
    )


def synthetic_data(
    n_objects: int, seed: int, noise: Noise = Noise(), n_demos: int = TASK_DEMOS
) -> SyntheticDemonstrations:
    """The demonstrations every cell with ``n_objects`` objects takes a prefix of.

    The task is the first ``n_objects`` objects of one ``TASK_OBJECTS``-object
    task drawn from ``seed``; the demonstrations come from a generator seeded
    with ``(seed, n_objects)``.
    """
    task = make_task(max(n_objects, TASK_OBJECTS), np.random.default_rng(seed), noise=noise)
    return make_demonstrations(
        task.prefix(n_objects), n_demos, np.random.default_rng([seed, n_objects]), noise
    )


# --------------------------------------------------------------------------- learning grid


@dataclass(slots=True)
class CellResult:
    demos: int
    objects: int
    times_s: list[float] = field(default_factory=list)
    peak_mib: float = math.nan
    states: int = 0
    expected_states: int = 0
    objects_off: int = 0  # objects whose learned state count is not the expected one

    @property
    def matches(self) -> bool:
        """Every object learned as many states as expected (so the totals agree too)."""
        return self.objects_off == 0

    @property
    def median_s(self) -> float:
        return statistics.median(self.times_s) if self.times_s else math.nan


def _repeats_after(first_seconds: float, max_repeats: int) -> int:
    """How many timed runs a cell gets in total, given how long the first one took."""
    if first_seconds < 0.1:
        repeats = 5
    elif first_seconds < 5.0:
        repeats = 3
    else:
        repeats = 1
    return min(repeats, max_repeats)


def measure_cell(
    data: SyntheticDemonstrations, n_demos: int, *, max_repeats: int = 5, trace: bool = True
) -> CellResult:
    """Time (and, with ``trace``, trace) ``TaskModelLearner().fit`` on the first
    ``n_demos`` demonstrations."""
    demos = list(data.demonstrations[:n_demos])
    result = CellResult(n_demos, len(demos[0].steps), expected_states=data.expected_states(n_demos))

    start = time.perf_counter()
    learner = TaskModelLearner().fit(demos)
    result.times_s.append(time.perf_counter() - start)
    result.states = len(learner.states_)
    learned = Counter(state.object for state in learner.states_)
    expected = data.expected_per_object(n_demos)
    result.objects_off = sum(learned[name] != count for name, count in expected.items())
    for _ in range(_repeats_after(result.times_s[0], max_repeats) - 1):
        start = time.perf_counter()
        TaskModelLearner().fit(demos)
        result.times_s.append(time.perf_counter() - start)

    if not trace:
        return result
    # Peak memory in a separate, untimed run: tracing slows allocation down.
    tracemalloc.start()
    tracemalloc.reset_peak()
    TaskModelLearner().fit(demos)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    result.peak_mib = peak / 2**20
    return result


def run_grid(
    demo_counts: Sequence[int],
    object_counts: Sequence[int],
    seed: int,
    console: Console,
    *,
    max_repeats: int = 5,
) -> dict[tuple[int, int], CellResult]:
    results: dict[tuple[int, int], CellResult] = {}
    with console.status("") as status:
        for n_objects in object_counts:
            data = synthetic_data(n_objects, seed)
            for n_demos in demo_counts:
                status.update(f"fitting {n_demos} demonstrations {TIMES} {n_objects} objects …")
                results[(n_demos, n_objects)] = measure_cell(data, n_demos, max_repeats=max_repeats)
    return results


def format_length(metres: float) -> str:
    """0.0002 → ``0.2 mm``, 0.005 → ``5 mm``, 0.03 → ``3 cm``."""
    if metres < 0.01:
        return f"{metres * 1e3:g} mm"
    return f"{metres * 1e2:g} cm"


def run_noise_grid(
    sigmas: Sequence[float],
    cells: Sequence[tuple[int, int]],
    seed: int,
    console: Console,
    *,
    max_repeats: int = 3,
) -> dict[tuple[float, int, int], CellResult]:
    """The state counts (and times) over placement noise: for every sigma, the
    task and demonstrations of :meth:`Noise.uniform` (same seeds as the grid)."""
    results: dict[tuple[float, int, int], CellResult] = {}
    with console.status("") as status:
        for sigma in sigmas:
            noise = Noise.uniform(sigma)
            for n_objects in sorted({o for _, o in cells}):
                most = max(d for d, o in cells if o == n_objects)
                data = synthetic_data(n_objects, seed, noise, n_demos=most)
                for n_demos in sorted(d for d, o in cells if o == n_objects):
                    status.update(
                        f"noise {format_length(sigma)}: fitting {n_demos} demonstrations "
                        f"{TIMES} {n_objects} objects …"
                    )
                    results[(sigma, n_demos, n_objects)] = measure_cell(
                        data, n_demos, max_repeats=max_repeats, trace=False
                    )
    return results


def noise_table(
    results: dict[tuple[float, int, int], CellResult],
    sigmas: Sequence[float],
    cells: Sequence[tuple[int, int]],
) -> Table:
    table = Table(
        title="State counts over placement noise: learned/expected (✓) | median time",
        title_justify="left",
    )
    table.add_column("noise σ", justify="right", style="bold")
    for n_demos, n_objects in cells:
        table.add_column(f"{n_demos}{TIMES}{n_objects}\nstates", justify="right")
        table.add_column(f"{n_demos}{TIMES}{n_objects}\ntime", justify="right", style="dim")
    for sigma in sigmas:
        row = [format_length(sigma)]
        for n_demos, n_objects in cells:
            cell = results[(sigma, n_demos, n_objects)]
            mark = " ✓" if cell.matches else "  "
            row += [f"{cell.states}/{cell.expected_states}{mark}", format_seconds(cell.median_s)]
        table.add_row(*row)
    return table


def sanity_line(
    results: dict[tuple[int, int], CellResult],
    noisy: dict[tuple[float, int, int], CellResult],
) -> str:
    """In how many cells of each table every object learned the expected number of
    states (:meth:`SyntheticDemonstrations.expected_per_object`) — not a timing result."""
    off = [("", c) for c in results.values() if not c.matches]
    off += [(f"{format_length(sigma)} ", c) for (sigma, _, _), c in noisy.items() if not c.matches]
    n_grid = sum(1 for prefix, _ in off if not prefix)
    line = (
        "Sanity: every object learned the expected states (the alternatives it used in at "
        f"least two demonstrations, at least 1) in {len(results) - n_grid}/{len(results)} "
        f"cells of the grid and {len(noisy) - (len(off) - n_grid)}/{len(noisy)} of the "
        "noise table."
    )
    if off:
        line += " Elsewhere, learned/expected states: " + ", ".join(
            f"{prefix}{c.demos}{TIMES}{c.objects}: {c.states}/{c.expected_states} "
            f"({c.objects_off} object{'s' if c.objects_off > 1 else ''} off)"
            for prefix, c in off
        )
    return line


def slope(xs: Sequence[float], ys: Sequence[float]) -> float:
    """Least-squares slope of log(y) against log(x): the empirical exponent."""
    if len(xs) < 2:
        return math.nan
    return float(np.polyfit(np.log(xs), np.log(ys), 1)[0])


def format_seconds(seconds: float) -> str:
    if math.isnan(seconds):
        return "-"
    if seconds < 1e-3:
        return f"{seconds * 1e6:.0f} µs"
    if seconds < 1.0:
        return f"{seconds * 1e3:.1f} ms"
    return f"{seconds:.2f} s"


def grid_table(
    results: dict[tuple[int, int], CellResult],
    demo_counts: Sequence[int],
    object_counts: Sequence[int],
) -> Table:
    table = Table(
        title="TaskModelLearner().fit: median time | tracemalloc peak",
        title_justify="left",
    )
    table.add_column("demos", justify="right", style="bold")
    for n_objects in object_counts:
        table.add_column(f"{n_objects} obj\ntime", justify="right")
        table.add_column(f"{n_objects} obj\npeak", justify="right", style="dim")
    for n_demos in demo_counts:
        row = [str(n_demos)]
        for n_objects in object_counts:
            cell = results[(n_demos, n_objects)]
            row += [format_seconds(cell.median_s), f"{cell.peak_mib:.1f} MiB"]
        table.add_row(*row)
    return table


def exponents(
    results: dict[tuple[int, int], CellResult],
    demo_counts: Sequence[int],
    object_counts: Sequence[int],
) -> dict[str, dict[int, dict[str, float]]]:
    """Growth exponents of time and peak memory along each axis of the grid."""
    by_demos = {}
    for n_objects in object_counts:
        cells = [results[(d, n_objects)] for d in demo_counts]
        by_demos[n_objects] = {
            "time": slope(demo_counts, [c.median_s for c in cells]),
            "memory": slope(demo_counts, [c.peak_mib for c in cells]),
        }
    by_objects = {}
    for n_demos in demo_counts:
        cells = [results[(n_demos, o)] for o in object_counts]
        by_objects[n_demos] = {
            "time": slope(object_counts, [c.median_s for c in cells]),
            "memory": slope(object_counts, [c.peak_mib for c in cells]),
        }
    return {"vs_demos_at_fixed_objects": by_demos, "vs_objects_at_fixed_demos": by_objects}


def exponent_table(growth: dict[str, dict[int, dict[str, float]]]) -> Table:
    table = Table(
        title="Empirical growth exponents (least-squares slope on log-log axes)",
        title_justify="left",
    )
    table.add_column("fit", style="bold")
    table.add_column("held fixed", justify="right")
    table.add_column("time exponent", justify="right")
    table.add_column("memory exponent", justify="right", style="dim")
    for label, key, unit in (
        ("log t vs log demos", "vs_demos_at_fixed_objects", "objects"),
        ("log t vs log objects", "vs_objects_at_fixed_demos", "demos"),
    ):
        for fixed, values in growth[key].items():
            table.add_row(
                label, f"{fixed} {unit}", f"{values['time']:.2f}", f"{values['memory']:.2f}"
            )
        table.add_section()
    return table


# --------------------------------------------------------------------------- k-means


@dataclass(frozen=True, slots=True)
class KMeansRow:
    n: int
    clusters: int
    demoplan_us: float
    sklearn_us: float

    @property
    def ratio(self) -> float:
        return self.sklearn_us / self.demoplan_us


def _per_call_us(call: Callable[[], object], batches: int, min_batch_s: float) -> float:
    """Median over ``batches`` of the mean µs per call, batches sized to ≥ ``min_batch_s``."""
    call()  # warm-up
    number = 1
    while True:
        start = time.perf_counter()
        for _ in range(number):
            call()
        elapsed = time.perf_counter() - start
        if elapsed >= min_batch_s:
            break
        number *= 2 if elapsed == 0 else max(2, math.ceil(min_batch_s / elapsed))
    samples = [elapsed / number]
    for _ in range(batches - 1):
        start = time.perf_counter()
        for _ in range(number):
            call()
        samples.append((time.perf_counter() - start) / number)
    return statistics.median(samples) * 1e6


def _blobs(n: int, clusters: int, rng: np.random.Generator) -> NDArray[np.float64]:
    """Placement-like data: ``clusters`` groups ~10 cm apart with ~2 mm noise, in metres."""
    centres = rng.uniform(-0.2, 0.2, size=(clusters, 3))
    labels = np.arange(n) % clusters
    return centres[labels] + rng.normal(0.0, 0.002, size=(n, 3))


def run_kmeans(seed: int, batches: int, min_batch_s: float) -> list[KMeansRow] | None:
    try:
        from sklearn.cluster import KMeans
    except ImportError:
        return None
    rows = []
    for n in KMEANS_SIZES:
        for clusters in KMEANS_CLUSTERS:
            points = _blobs(n, clusters, np.random.default_rng([seed, n, clusters]))
            model = KMeans(n_clusters=clusters, n_init=4, random_state=0)

            def ours(points: NDArray[np.float64] = points, clusters: int = clusters) -> object:
                return kmeans(points, clusters, n_init=4, rng=0)

            def theirs(points: NDArray[np.float64] = points, model: Any = model) -> object:
                return model.fit(points)

            rows.append(
                KMeansRow(
                    n,
                    clusters,
                    _per_call_us(ours, batches, min_batch_s),
                    _per_call_us(theirs, batches, min_batch_s),
                )
            )
    return rows


def kmeans_table(rows: list[KMeansRow]) -> Table:
    table = Table(
        title="K-means per call, d = 3, n_init = 4 — median µs (one core)",
        title_justify="left",
    )
    table.add_column("n", justify="right", style="bold")
    table.add_column("c", justify="right")
    table.add_column("demoplan kmeans", justify="right")
    table.add_column("sklearn KMeans", justify="right")
    table.add_column("sklearn / demoplan", justify="right")
    for row in rows:
        table.add_row(
            str(row.n),
            str(row.clusters),
            f"{row.demoplan_us:,.0f} µs",
            f"{row.sklearn_us:,.0f} µs",
            f"{row.ratio:.1f}{TIMES}",
        )
    return table


# --------------------------------------------------------------------------- main


def parse_args(argv: Sequence[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        description="Benchmark TaskModelLearner.fit (time, memory, growth) and K-means per call.",
    )
    parser.add_argument(
        "--quick", action="store_true", help="small grid that finishes in under 30 s"
    )
    parser.add_argument("--out", type=Path, help="also save the results to this JSON file")
    parser.add_argument("--seed", type=int, default=0, help="seed of the synthetic data")
    return parser.parse_args(argv)


@dataclass(slots=True)
class UnstructuredRow:
    demos: int
    objects: int
    max_clusters: int
    seconds: float
    states: int


def run_unstructured(seed: int, *, quick: bool) -> list[UnstructuredRow]:
    """The worst case: placements that follow no task (uniform on a 1 m table),
    learned with the paper's full scan of c and with ``max_clusters=5``."""
    rng = np.random.default_rng([seed, 99])
    n_demos, n_objects = (20, 10) if quick else (TARGET_DEMOS, TARGET_OBJECTS)
    demos = [
        Demonstration(
            f"random-{d + 1}",
            tuple(
                Step(f"obj{i}", Pose((float(rng.uniform(0, 1)), float(rng.uniform(0, 1)), 0.0)))
                for i in rng.permutation(n_objects)
            ),
        )
        for d in range(n_demos)
    ]
    rows = []
    for cap in (0, 5):
        start = time.perf_counter()
        learner = TaskModelLearner(max_clusters=cap).fit(demos)
        rows.append(
            UnstructuredRow(
                n_demos, n_objects, cap, time.perf_counter() - start, len(learner.states_)
            )
        )
    return rows


def unstructured_table(rows: list[UnstructuredRow]) -> Table:
    table = Table(title="Worst case: placements with no structure (uniform on a 1 m table)")
    for column in ("demos", "objects", "max_clusters", "time", "states learned"):
        table.add_column(column, justify="right")
    for row in rows:
        table.add_row(
            str(row.demos),
            str(row.objects),
            "none (paper)" if row.max_clusters == 0 else str(row.max_clusters),
            format_seconds(row.seconds),
            str(row.states),
        )
    return table


def main(argv: Sequence[str] | None = None) -> int:
    args = parse_args(argv)
    console = Console(width=None if sys.stdout.isatty() else 150)
    demo_counts = QUICK_DEMOS if args.quick else FULL_DEMOS
    object_counts = QUICK_OBJECTS if args.quick else FULL_OBJECTS
    started = time.perf_counter()

    console.print(
        f"demoplan learning benchmark — {'quick' if args.quick else 'full'} grid, "
        f"seed {args.seed}; "
        f"Python {platform.python_version()}, NumPy {np.__version__}, "
        f"scikit-learn {package_version('scikit-learn')}, {platform.machine()}, "
        f"OMP/OPENBLAS/MKL threads = 1",
        highlight=False,
    )
    console.print(f"demoplan imported from {Path(demoplan.__file__).parent}", highlight=False)
    max_repeats = 3 if args.quick else 5
    # Warm-up: imports, first-call caches.
    TaskModelLearner().fit(synthetic_data(3, args.seed).demonstrations[:3])

    results = run_grid(demo_counts, object_counts, args.seed, console, max_repeats=max_repeats)
    console.print(grid_table(results, demo_counts, object_counts))
    sigmas = QUICK_SIGMAS if args.quick else FULL_SIGMAS
    noise_cells = QUICK_NOISE_CELLS if args.quick else FULL_NOISE_CELLS
    noisy = run_noise_grid(
        sigmas, noise_cells, args.seed, console, max_repeats=1 if args.quick else 3
    )
    console.print(noise_table(noisy, sigmas, noise_cells))
    console.print(sanity_line(results, noisy), highlight=False)

    growth = exponents(results, demo_counts, object_counts)
    console.print(exponent_table(growth))

    target = results.get((TARGET_DEMOS, TARGET_OBJECTS))
    if target is None:
        target = measure_cell(
            synthetic_data(TARGET_OBJECTS, args.seed), TARGET_DEMOS, max_repeats=max_repeats
        )
    verdict = "PASS" if target.median_s < TARGET_SECONDS else "FAIL"
    console.print(
        f"{TARGET_DEMOS} demonstrations {TIMES} {TARGET_OBJECTS} objects: {target.median_s:.3f} s "
        f"(target < {TARGET_SECONDS:g} s on one core): {verdict}",
        style="bold green" if verdict == "PASS" else "bold red",
        highlight=False,
    )

    unstructured = run_unstructured(args.seed, quick=args.quick)
    console.print(unstructured_table(unstructured))

    kmeans_rows = run_kmeans(
        args.seed, batches=3 if args.quick else 7, min_batch_s=0.02 if args.quick else 0.1
    )
    if kmeans_rows is None:
        console.print("scikit-learn is not installed: K-means comparison skipped.")
    else:
        console.print(kmeans_table(kmeans_rows))
    console.print(f"Total benchmark time: {time.perf_counter() - started:.1f} s")

    if args.out is not None:
        document: dict[str, Any] = {
            "benchmark": "demoplan learning",
            "grid": "quick" if args.quick else "full",
            "seed": args.seed,
            "python": platform.python_version(),
            "numpy": np.__version__,
            "machine": platform.machine(),
            "cells": [{**asdict(cell), "median_s": cell.median_s} for cell in results.values()],
            "noise_cells": [
                {"sigma_m": sigma, **asdict(cell), "median_s": cell.median_s}
                for (sigma, _, _), cell in noisy.items()
            ],
            "exponents": growth,
            "target": {
                "demos": TARGET_DEMOS,
                "objects": TARGET_OBJECTS,
                "median_s": target.median_s,
                "limit_s": TARGET_SECONDS,
                "pass": verdict == "PASS",
            },
            "unstructured": [asdict(row) for row in unstructured],
            "kmeans": None
            if kmeans_rows is None
            else [{**asdict(row), "ratio": row.ratio} for row in kmeans_rows],
        }
        args.out.write_text(json.dumps(document, indent=2) + "\n", encoding="utf-8")
        console.print(f"Results saved to {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
