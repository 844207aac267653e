"""Benchmark: planning with identical objects — bindings weighed, planned, and what the bound saves.

What it measures
----------------
A model learned from identical objects names roles (``plate#1``, ``plate#2``);
``plan_in_scene`` plans each candidate goal under every binding of roles to a
scene's instances, lowest lower bound first, and sets aside every binding
whose bound reaches the best plan (docs/planning.md, "Identical objects").
Per case, on this machine:

- **instances / roles** of the types with roles, the **bindings** per goal
  (``CandidatePlan.bindings_weighed``), and how many were **planned** — the
  calls of ``demoplan.scenes.plan.solve_candidate`` counted by wrapping it
  here (``src/`` is not touched) — against those set aside by their bound;
- the chosen plan's **length**, whether it is **proved** shortest, its bound;
- the median wall time of
  ``plan_in_scene(model, prepare(model, scene), clock=Clock(Budget(timeout=T)))``
  (``--timeout``, 120 s: long enough to prove every case here) over
  ``--repeats`` runs (3) for runs under 2 s, one run above; and where it goes:
  ``prepare`` (checking the scene, enumerating the bindings, resolving every
  binding's goals and bounds), ``build_problem`` (one planning problem per
  binding planned: locations, grasps, collision facts, free space) and
  ``solve_candidate`` (the search), each timed by wrapping it;
- the same with the **default budget** of the ``plan`` command
  (``default_budget()``, 2 s in all): length, proved, bindings planned —
  what a user gets who gives no ``--timeout``;
- the **oracle**: every binding's every goal built and planned alone with no
  time limit (as ``tests/scenes/test_identical_objects.py`` checks it), the least
  length, and its time; ``oracle / B&B`` is the time the bound saves. Above
  ``--oracle-max`` bindings (200) the oracle plans a random sample of
  ``--oracle-sample`` (100) and its time is extrapolated (marked ``~``); the
  least length is then the sample's, and the bound proves the rest.

The last column checks: the plan is valid (``strips.validate`` on its own
problem), no longer than the oracle's least (longer would be a bug of the
branch and bound), not shorter (an invalid plan or a wrong oracle), and its
bound is no more than the oracle's least.

The cases
---------
From ``tests/support/identical_families.py`` (the tests' generated tasks; this script
puts the repository root on ``sys.path``): the **table for two** (two plates,
forks, knives, glasses; 2!⁴ = 16 bindings) from a scrambled start and with a
plate already at a seat; the **tower** blue < red < red < green from four
scrambled starts (2 bindings); three **cups into a turned tray** (3! = 6),
three tray poses. Generated here: **a row of N identical cubes** (``cube#1`` …
``cube#N`` at absolute slots 8 cm apart, learned from three demonstrations
with the names shuffled):

- ``row-N``: the cubes apart off the row — every binding has the same bound
  2N, the first plan meets it, the other N! − 1 are set aside; N = 6
  (720 bindings) and N = 7 (5,040, the limit);
- ``row-N-turned``: every cube already in a slot but turned 45° — the bound
  counts positions only, so a binding leaving a cube in its slot promises
  fewer actions than any plan needs (each turned cube must be picked up and
  put back): every binding but the derangements is planned;
- ``row-N-lids-K``: K cubes in slots, turned 45° and covered by a lid (an
  object the model never saw; ``clutter``) — every plan needs 2N + 2K
  actions, every bound is below it, so all N! bindings are planned: the
  worst case of the enumeration (N = 6 only with ``--worst``).

How to run
----------
From the repository root, with demoplan installed (``pip install -e ".[dev]"``)::

    python benchmarks/identical.py             # all but the worst: ~4 min (135 s of CPU)
    python benchmarks/identical.py --worst     # also row-6-lids-2 (720 bindings planned): ~11 min
    python benchmarks/identical.py --quick     # none planning over 120 bindings: ~2.5 min
    python benchmarks/identical.py --cases row-6-lids-2,table-seated --repeats 5
    python benchmarks/identical.py --cases row-6-turned --oracle-max 1000   # exhaustive oracle
    python benchmarks/identical.py --out identical.json

Run times above are from the shared 2-core machine at a load average of 5 to
11. Times are wall clock on a shared machine: compare medians and ratios
between runs on one machine, not absolute numbers across machines.
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
from collections.abc import Callable, Iterator, Sequence  # noqa: E402
from contextlib import contextmanager  # noqa: E402
from dataclasses import asdict, dataclass, field, replace  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402
from rich.console import Console  # noqa: E402
from rich.table import Table  # noqa: E402

import demoplan  # noqa: E402
import demoplan.scenes.plan as scene_plan  # noqa: E402
from demoplan.budget import Clock, default_budget  # noqa: E402
from demoplan.errors import DemoplanError  # noqa: E402
from demoplan.learning.learner import learn  # noqa: E402
from demoplan.model import Demonstration, ObjectGeometry, Pose, Step, TaskModel  # noqa: E402
from demoplan.planning.search import Budget  # noqa: E402
from demoplan.planning.strips import InvalidPlanError, validate  # noqa: E402
from demoplan.rotations import quat_from_yaw  # noqa: E402
from demoplan.scenes.prepared import prepare  # noqa: E402
from demoplan.scenes.problems import build_problem  # noqa: E402
from demoplan.scenes.scene import Scene, SceneObject  # noqa: E402
from demoplan.scenes.table import surroundings_of  # noqa: E402

# The repository root, for tests/support/identical_families.py (the tasks the tests use too).
REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:
    sys.path.insert(1, str(REPO))
from tests.support.identical_families import (  # noqa: E402
    TABLE_TYPES,
    cups_into_tray,
    cups_scene,
    table_for_two,
    table_scene,
    tower_scene,
    tower_with_two_reds,
)

DEFAULT_TIMEOUT = 120.0
CHEAP_SECONDS, DEFAULT_REPEATS = 2.0, 3
ORACLE_MAX, ORACLE_SAMPLE = 200, 100
UNLIMITED = Budget(timeout=math.inf)
TIMES = "\u00d7"  # multiplication sign (spelled out for ruff's RUF001)

# --------------------------------------------------------------------------- the cases

TABLE_ORDERS: list[
    dict[str, Sequence[int]]
] = [  # per type, the instance letters in seat order (as the tests)
    {"plate": (0, 1), "fork": (1, 0), "knife": (0, 1), "glass": (1, 0)},
    {"plate": (1, 0), "fork": (0, 1), "knife": (1, 0), "glass": (1, 0)},
    {"plate": (0, 1), "fork": (0, 1), "knife": (1, 0), "glass": (0, 1)},
]
CUP_ORDERS = [(0, 1, 2), (2, 0, 1), (1, 2, 0)]
TRAYS = ((0.45, 0.0, 30.0), (0.40, 0.10, -120.0), (0.50, -0.10, 170.0))  # x, y, yaw (deg)

CUBE = ObjectGeometry("box", (0.04, 0.04, 0.04))
LID = ObjectGeometry("box", (0.05, 0.05, 0.01))
ROW_X, ROW_GAP = 0.45, 0.08  # the slots: x = 0.45 m, 8 cm apart along y
TURNED = 45.0  # degrees: a cube in a slot, turned as the model never puts it


@dataclass(frozen=True)
class Case:
    """A model and a scene to plan it in; ``clutter``: objects the model never saw."""

    name: str
    what: str
    model: TaskModel
    scene: Scene
    clutter: bool = False
    heavy: bool = False  # plans more than 120 bindings: left out by --quick
    worst: bool = False  # plans all 720 bindings: only with --worst (or --cases)


def slots(n: int) -> list[tuple[float, float]]:
    """The row's N slots (x, y), centred on y = 0."""
    return [(ROW_X, ROW_GAP * (i - (n - 1) / 2)) for i in range(n)]


def _cube_names(n: int) -> list[str]:
    return [f"cube-{chr(ord('a') + i)}" for i in range(n)]


def row_demonstrations(n: int, rng: np.random.Generator, count: int = 3) -> list[Demonstration]:
    """N identical cubes put into the row's slots, ``count`` times, slots filled in
    a random order by instances named at random (the roles must come from the
    places, not the names)."""
    names = _cube_names(n)
    demos = []
    for index in range(count):
        filler = rng.permutation(n)  # filler[slot]: the instance put there
        steps = []
        for slot in rng.permutation(n):
            x, y = slots(n)[slot]
            pose = Pose(
                (x + rng.normal(0, 0.001), y + rng.normal(0, 0.001), 0.0), quat_from_yaw(0.0)
            )
            steps.append(Step(names[filler[slot]], pose))
        initial = tuple(
            (name, Pose((0.2, ROW_GAP * (i - (n - 1) / 2), 0.0), quat_from_yaw(0.0)))
            for i, name in enumerate(names)
        )
        demos.append(
            Demonstration(
                f"row-{index + 1}",
                tuple(steps),
                tuple((name, CUBE) for name in names),
                initial=initial,
                types=tuple((name, "cube") for name in names),
            )
        )
    return demos


def row_scene(n: int, *, in_slots: int = 0, lids: int = 0) -> Scene:
    """N cubes (``cube-0`` …): the first ``in_slots`` stand in slots 0, 1, … turned
    by :data:`TURNED`, the first ``lids`` of those under a lid; the others apart
    on a line at x = 0.2 m, off the row."""
    objects = []
    for i, (x, y) in enumerate(slots(n)):
        if i < in_slots:
            objects.append(
                SceneObject(
                    f"cube-{i}", Pose((x, y, 0.0), quat_from_yaw(TURNED)), CUBE, type="cube"
                )
            )
        else:
            objects.append(
                SceneObject(f"cube-{i}", Pose((0.2, y, 0.0), quat_from_yaw(0.0)), CUBE, type="cube")
            )
    for i, (x, y) in enumerate(slots(n)[:lids]):
        objects.append(SceneObject(f"lid-{i}", Pose((x, y, CUBE.size[2]), quat_from_yaw(0.0)), LID))
    return Scene(objects=tuple(objects), source=f"row of {n} cubes")


def build_cases() -> list[Case]:
    """Every case, the models learned once."""
    cases = []
    table = learn(table_for_two(np.random.default_rng(3), TABLE_ORDERS).demonstrations)
    scrambled = table_scene(np.random.default_rng(5), {k: (1, 0) for k in TABLE_TYPES})
    cases.append(Case("table-scrambled", "table for two, pieces at the edge", table, scrambled))
    seated = table_scene(np.random.default_rng(6), {k: (0, 1) for k in TABLE_TYPES})
    target = next(s for s in table.states if s.object == "plate#2").position.value
    seated = replace(
        seated,
        objects=tuple(
            replace(o, pose=Pose(target, o.pose.orientation)) if o.name == "plate-a" else o
            for o in seated.objects
        ),
    )
    cases.append(Case("table-seated", "table for two, plate-a at a seat", table, seated))
    tower = learn(tower_with_two_reds([False, True]).demonstrations)
    for seed in range(4):
        cases.append(
            Case(
                f"tower-{seed}",
                "blue<red<red<green, scrambled",
                tower,
                tower_scene(np.random.default_rng(seed)),
            )
        )
    cups = learn(cups_into_tray(np.random.default_rng(11), CUP_ORDERS).demonstrations)
    for index, tray in enumerate(TRAYS):
        cases.append(
            Case(f"cups-{index}", f"3 cups, tray turned {tray[2]:g}°", cups, cups_scene(tray))
        )
    rows = {n: learn(row_demonstrations(n, np.random.default_rng(n))) for n in (4, 5, 6, 7)}
    cases.append(Case("row-6", "6 cubes apart", rows[6], row_scene(6)))
    cases.append(Case("row-7", "7 cubes apart (the limit)", rows[7], row_scene(7)))
    cases.append(
        Case("row-4-turned", "4 cubes in slots, turned", rows[4], row_scene(4, in_slots=4))
    )
    cases.append(
        Case(
            "row-6-turned",
            "6 cubes in slots, turned",
            rows[6],
            row_scene(6, in_slots=6),
            heavy=True,
        )
    )
    for n, lids in ((4, 2), (5, 2), (6, 2)):
        cases.append(
            Case(
                f"row-{n}-lids-{lids}",
                f"{n} cubes, {lids} turned in slots under lids",
                rows[n],
                row_scene(n, in_slots=lids, lids=lids),
                clutter=True,
                heavy=n >= 6,
                worst=n >= 6,
            )
        )
    return cases


# --------------------------------------------------------------------------- instrumentation


@dataclass(slots=True)
class Calls:
    """Calls of the wrapped functions during one ``plan_in_scene`` and their wall time."""

    prepare_s: float = 0.0
    built: int = 0
    build_s: float = 0.0
    planned: int = 0
    solve_s: float = 0.0


@contextmanager
def instrumented() -> Iterator[Calls]:
    """``demoplan.scenes.plan``'s ``prepare``, ``build_problem`` and
    ``solve_candidate`` wrapped (the names ``plan_in_scene`` and ``plan_goal``
    call them by) to count and time every call; restored on exit."""
    calls = Calls()

    def on_prepare(seconds: float) -> None:
        calls.prepare_s += seconds

    def on_build(seconds: float) -> None:
        calls.built += 1
        calls.build_s += seconds

    def on_solve(seconds: float) -> None:
        calls.planned += 1
        calls.solve_s += seconds

    counters = {"prepare": on_prepare, "build_problem": on_build, "solve_candidate": on_solve}
    originals = {name: getattr(scene_plan, name) for name in counters}
    for name, add in counters.items():
        setattr(scene_plan, name, _timed(originals[name], add))
    try:
        yield calls
    finally:
        for name, function in originals.items():
            setattr(scene_plan, name, function)


def _timed(function: Callable[..., Any], add: Callable[[float], None]) -> Callable[..., Any]:
    """``function``, handing the wall time of every call to ``add``."""

    def wrapper(*args: Any, **kwargs: Any) -> Any:
        started = time.perf_counter()
        try:
            return function(*args, **kwargs)
        finally:
            add(time.perf_counter() - started)

    return wrapper


# --------------------------------------------------------------------------- measuring


@dataclass(slots=True)
class Run:
    """One ``plan_in_scene``: its outcome and where the time went."""

    seconds: float
    calls: Calls
    length: int | None = None
    optimal: bool | None = None
    bound: int | None = None
    weighed: int = 0  # bindings weighed, summed over the candidate goals
    goals: int = 0
    binding: str = ""
    error: str | None = None
    valid: bool | None = None


def plan_once(case: Case, budget: Budget) -> Run:
    with instrumented() as calls:
        started = time.perf_counter()
        try:
            result = scene_plan.plan_in_scene(
                case.model,
                prepare(case.model, case.scene, clutter=case.clutter),
                clock=Clock(budget),
            )
        except DemoplanError as exc:
            return Run(time.perf_counter() - started, calls, error=f"{type(exc).__name__}: {exc}")
        seconds = time.perf_counter() - started
    chosen = result.chosen
    assert chosen.plan is not None
    try:
        validate(chosen.problem.problem, chosen.plan.actions)
        valid = True
    except InvalidPlanError:
        valid = False
    return Run(
        seconds,
        calls,
        len(chosen.plan),
        result.optimal,
        result.bound,
        sum(c.bindings_weighed for c in result.candidates),
        len(result.candidates),
        chosen.binding.describe(),
        valid=valid,
    )


@dataclass(slots=True)
class Oracle:
    """Every binding (or a sample) planned alone, unlimited: the least length."""

    bindings: int
    planned_bindings: int
    least: int | None
    at_least: int  # bindings whose plan has the least length
    all_optimal: bool
    seconds: float  # measured, or extrapolated to every binding when sampled
    sampled: bool


def oracle(case: Case, limit: int, sample: int, rng: np.random.Generator) -> Oracle:
    started = time.perf_counter()
    prepared = prepare(case.model, case.scene, clutter=case.clutter)
    prepare_s = time.perf_counter() - started
    around = surroundings_of(prepared.model, prepared.scene)
    tasks = list(prepared.bindings)
    sampled = len(tasks) > limit
    if sampled:
        tasks = [tasks[i] for i in sorted(rng.choice(len(tasks), size=sample, replace=False))]
    lengths, optimal = [], True
    planning_started = time.perf_counter()
    for task in tasks:
        best: int | None = None
        for candidate in task.candidates:
            problem = build_problem(prepared.scene, candidate, surroundings=around)
            outcome = scene_plan.solve_candidate(problem, Clock(UNLIMITED))
            if outcome.plan is not None:
                optimal = optimal and outcome.plan.optimal
                best = len(outcome.plan) if best is None else min(best, len(outcome.plan))
        if best is not None:
            lengths.append(best)
    planning_s = time.perf_counter() - planning_started
    if sampled:
        planning_s *= len(prepared.bindings) / len(tasks)
    least = min(lengths) if lengths else None
    return Oracle(
        len(prepared.bindings),
        len(tasks),
        least,
        sum(1 for n in lengths if n == least),
        optimal,
        prepare_s + planning_s,
        sampled,
    )


@dataclass(slots=True)
class Result:
    case: str
    what: str
    instances: str
    runs: list[Run] = field(default_factory=list)
    quick_run: Run | None = None  # the default budget's
    oracle: Oracle | None = None

    @property
    def median_s(self) -> float:
        return statistics.median(r.seconds for r in self.runs)

    @property
    def median_run(self) -> Run:
        """The run of the median time (the upper one of an even count): its parts
        add up to its total."""
        return sorted(self.runs, key=lambda r: r.seconds)[len(self.runs) // 2]


def instances_and_roles(case: Case) -> str:
    """``8 / 8`` — the scene's instances of the types with roles / the roles."""
    kinds = {role.type for role in case.model.roles}
    instances = sum(1 for o in case.scene.objects if o.kind in kinds)
    return f"{instances} / {len(case.model.roles)}"


def measure(case: Case, args: argparse.Namespace, rng: np.random.Generator) -> Result:
    result = Result(case.name, case.what, instances_and_roles(case))
    budget = Budget(timeout=args.timeout)
    result.runs.append(plan_once(case, budget))
    while result.runs[0].seconds < CHEAP_SECONDS and len(result.runs) < args.repeats:
        result.runs.append(plan_once(case, budget))
    result.quick_run = plan_once(case, default_budget())
    if not args.no_oracle:
        result.oracle = oracle(case, args.oracle_max, args.oracle_sample, rng)
    return result


# --------------------------------------------------------------------------- reporting


def _seconds(value: float) -> str:
    if value < 1.0:
        return f"{value * 1000:.0f} ms"
    return f"{value:.2f} s"


def check(result: Result) -> tuple[str, str]:
    """The verdict of a case and its style: ok, or what is wrong."""
    run = result.runs[0]
    if run.error is not None:
        return "no plan", "bold red"
    problems = []
    if run.valid is False:
        problems.append("INVALID plan")
    if any(
        (r.length, r.optimal, r.calls.planned) != (run.length, run.optimal, run.calls.planned)
        for r in result.runs
    ):
        problems.append("runs differ")
    found = result.oracle
    if found is not None and found.least is not None and run.length is not None:
        if run.length > found.least:
            problems.append(f"BUG: {run.length} > oracle {found.least}")
        elif run.length < found.least and not found.sampled:
            problems.append(f"BUG: shorter than oracle {found.least}")
        if run.bound is not None and run.bound > found.least:
            problems.append(f"BUG: bound {run.bound} > oracle")
    return ("; ".join(problems), "bold red") if problems else ("ok", "green")


def main_table(results: Sequence[Result], timeout: float) -> Table:
    table = Table(
        title=(
            f"Identical objects: branch and bound over the bindings vs every binding planned alone "
            f"(plan_in_scene with --timeout {timeout:g} s; median wall time)"
        )
    )
    for column, justify in (
        ("case", "left"),
        ("scene", "left"),
        ("inst. / roles", "right"),
        ("bindings", "right"),
        ("planned", "right"),
        ("set aside", "right"),
        ("length", "right"),
        ("proved", "center"),
        ("B&B time", "right"),
        ("default 2 s budget", "right"),
        ("oracle least", "right"),
        ("oracle time", "right"),
        ("oracle / B&B", "right"),
        ("check", "left"),
    ):
        table.add_column(column, justify=justify)  # type: ignore[arg-type]
    for result in results:
        run = result.runs[0]
        verdict, style = check(result)
        if run.error is not None:
            table.add_row(
                result.case,
                result.what,
                result.instances,
                "",
                "",
                "",
                "—",
                "",
                _seconds(result.median_s),
                "",
                "",
                "",
                "",
                f"[{style}]{run.error}[/]",
            )
            continue
        per_goal = run.weighed // max(run.goals, 1)
        bindings = f"{per_goal:,}" + (f" {TIMES} {run.goals} goals" if run.goals > 1 else "")
        quick = result.quick_run
        if quick is None:
            quick_cell = ""
        elif quick.error is not None:
            quick_cell = "[red]" + quick.error.split(":")[0] + "[/]"
        else:
            quick_cell = (
                f"{quick.length} {'✓' if quick.optimal else f'✗ (≥{quick.bound})'} "
                f"{quick.calls.planned} planned, {_seconds(quick.seconds)}"
            )
        found = result.oracle
        if found is None:
            oracle_cells = ["", "", ""]
        else:
            mark = "~" if found.sampled else ""
            least = "—" if found.least is None else str(found.least)
            if found.sampled:
                least += f" ({found.planned_bindings} sampled)"
            else:
                least += f" ({found.at_least} at it)"
            oracle_cells = [
                least,
                f"{mark}{_seconds(found.seconds)}",
                f"{mark}{found.seconds / result.median_s:.1f}{TIMES}",
            ]
        table.add_row(
            result.case,
            result.what,
            result.instances,
            bindings,
            f"{run.calls.planned:,}",
            f"{run.weighed - run.calls.planned:,}",
            str(run.length),
            "✓" if run.optimal else f"✗ (≥{run.bound})",
            _seconds(result.median_s),
            quick_cell,
            *oracle_cells,
            f"[{style}]{verdict}[/]",
        )
    return table


def time_table(results: Sequence[Result]) -> Table:
    table = Table(
        title="Where the B&B time goes (the median run; build and search per binding planned)"
    )
    for column in (
        "case",
        "total",
        "prepare",
        "build_problem",
        "search",
        "other",
        "per build",
        "per search",
    ):
        table.add_column(column, justify="left" if column == "case" else "right")
    for result in results:
        run = result.runs[0]
        if run.error is not None:
            continue
        median = result.median_run
        total = median.seconds
        prepare_s, build_s, solve_s = (
            median.calls.prepare_s,
            median.calls.build_s,
            median.calls.solve_s,
        )
        planned = max(run.calls.planned, 1)
        table.add_row(
            result.case,
            _seconds(total),
            f"{_seconds(prepare_s)} ({prepare_s / total:.0%})",
            f"{_seconds(build_s)} ({build_s / total:.0%})",
            f"{_seconds(solve_s)} ({solve_s / total:.0%})",
            _seconds(max(total - prepare_s - build_s - solve_s, 0.0)),
            _seconds(build_s / planned),
            _seconds(solve_s / planned),
        )
    return table


def parse_args(argv: Sequence[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        description="Benchmark planning with identical objects: bindings planned vs set aside, "
        "against planning every binding alone.",
    )
    parser.add_argument(
        "--quick", action="store_true", help="leave out the cases planning over 120 bindings"
    )
    parser.add_argument(
        "--worst",
        action="store_true",
        help="also row-6-lids-2, every one of 720 bindings planned (several minutes)",
    )
    parser.add_argument("--cases", help="comma-separated case names (default: all but --worst)")
    parser.add_argument(
        "--timeout", type=float, default=DEFAULT_TIMEOUT, help="plan_in_scene's budget (s)"
    )
    parser.add_argument(
        "--repeats",
        type=int,
        default=DEFAULT_REPEATS,
        help=f"runs of a case under {CHEAP_SECONDS:g} s",
    )
    parser.add_argument(
        "--oracle-max", type=int, default=ORACLE_MAX, help="above, sample the oracle"
    )
    parser.add_argument("--oracle-sample", type=int, default=ORACLE_SAMPLE)
    parser.add_argument("--no-oracle", action="store_true", help="skip the oracle")
    parser.add_argument("--seed", type=int, default=0, help="seed of the oracle's sample")
    parser.add_argument("--out", type=Path, help="also save the results to this JSON file")
    return parser.parse_args(argv)


def main(argv: Sequence[str] | None = None) -> int:
    args = parse_args(argv)
    console = Console(width=None if sys.stdout.isatty() else 250)
    started = time.perf_counter()
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    console.print(
        f"demoplan identical-objects benchmark — {'quick' if args.quick else 'full'}; "
        f"Python {platform.python_version()}, NumPy {np.__version__}, {platform.machine()}, "
        f"{os.cpu_count()} cores, load average {load:.1f}; OMP/OPENBLAS/MKL threads = 1",
        highlight=False,
    )
    console.print(f"demoplan imported from {Path(demoplan.__file__).parent}", highlight=False)
    cases = build_cases()
    if args.cases:
        wanted = args.cases.split(",")
        unknown = sorted(set(wanted) - {c.name for c in cases})
        if unknown:
            console.print(
                f"unknown cases: {', '.join(unknown)}; known: {', '.join(c.name for c in cases)}"
            )
            return 2
        cases = [c for c in cases if c.name in wanted]
    else:
        cases = [c for c in cases if args.worst or not c.worst]
        if args.quick:
            cases = [c for c in cases if not c.heavy]
    plan_once(cases[0], Budget(timeout=args.timeout))  # warm-up: imports, first-call caches
    rng = np.random.default_rng(args.seed)
    results = []
    for case in cases:
        result = measure(case, args, rng)
        run = result.runs[0]
        console.print(
            f"  {case.name}: {run.length} actions, "
            f"{run.calls.planned} of {run.weighed} bindings planned, "
            f"{_seconds(result.median_s)} ({len(result.runs)} run(s))",
            highlight=False,
        )
        results.append(result)
    console.print(main_table(results, args.timeout))
    console.print(time_table(results))
    bugs = [r for r in results if check(r)[0] != "ok"]
    for result in bugs:
        console.print(
            f"{result.case}: {check(result)[0]} — reproduce: python benchmarks/identical.py "
            f"--cases {result.case}",
            style="bold red",
            highlight=False,
        )
    console.print(f"Total benchmark time: {time.perf_counter() - started:.1f} s", highlight=False)
    if args.out is not None:
        document = {
            "benchmark": "demoplan identical objects",
            "timeout": args.timeout,
            "load_average": load,
            "results": [asdict(r) for r in results],
        }
        args.out.write_text(json.dumps(document, indent=2), encoding="utf-8")
    return 1 if bugs else 0


if __name__ == "__main__":
    raise SystemExit(main())
