"""Benchmark: execution with failure detection and replanning, kinematic and MuJoCo.

What it measures
----------------
Monte-Carlo runs of the paper's two experiments, executed by
:func:`demoplan.execution.executor.execute` (plan, act, observe, compare,
replan) in a simulated world:

* **Experiment 1** — table setting, learned from ``examples/set_table``, run in
  ``examples/scenes/set-table-cluttered.json``;
* **Experiment 2** — the pyramid of blocks, learned from
  ``examples/blocks/demonstrations.json``, run in ``examples/scenes/pyramid-fig4.json``.

Each experiment is run in these worlds (seeds 0 … N-1, one world per seed):

1. the **kinematic** world with faults ``drop=0.2,displace=0.1`` (``--faults``):
   200 runs (``--quick``: 20);
2. the kinematic world without faults, the reference: 20 runs (5);
3. **MuJoCo** without faults: 5 runs (2);
4. MuJoCo with the same faults: 20 runs (5);
5. the **arm** (``--sim arm``: the Kinova Jaco with its suction cup) without
   faults, and with one fault kind per row (``drop``, ``displace``,
   ``misplace``, ``grasp``, ``block``, each at 0.3): Experiment 1 3 and 4 runs
   per row, Experiment 2 5 and 10 (``--quick``: 1 and 1, 2 and 3). The one-kind
   rows make a confusion table: per injected kind, what the executor detected.

MuJoCo is required for Experiment 2 only; Experiment 1 is tried in MuJoCo too,
with a few runs (2 without faults, 3 with; ``--quick``: 1 and 1), and whatever
happens is reported. ``--no-mujoco`` leaves MuJoCo (and the arm) out,
``--no-arm`` the arm.

Per row the table gives: runs, success rate, median and max replans, median and
max extra actions (actions executed − length of the first plan), faults
injected per run (mean, by kind), failures the executor detected per run (mean,
by kind), median and 95th-percentile wall time per run (building the world plus
``execute``), the median and max final position error of the goal objects in
the successful runs (mm; the executor's own success test is 1 cm) with the
number of successful runs that ended with a goal object more than 1 mm off (a
dropped object can land within the tolerance of its target and is then
accepted as placed), for MuJoCo the median simulated-seconds /
wall-seconds ratio, and for the arm its contacts with anything but its load
and the motions its checks refused. Failed runs are listed
with their seed, reason and first detected failure (the first 10 per row),
followed by a command that reproduces one. The run ends with the targets:

* kinematic runs with recoverable faults reach the goal — every one of them
  (the fault injector only makes recoverable faults);
* MuJoCo Experiment 2 with faults: every goal block within 1 cm in every
  successful run;
* the arm: every run without faults reaches the goal with every object within
  1 cm, and in no run (faults or not) does the arm touch anything but its load
  (MuJoCo's contacts, recorded every physics step).

Everything runs on one core (BLAS/OpenMP threads pinned to 1). Machines are
shared and noisy: compare medians and ratios between runs on one machine.

How to run
----------
From the repository root, with demoplan and mujoco installed::

    python benchmarks/execution.py                 # full run (a few minutes)
    python benchmarks/execution.py --quick         # ~20/5/5/2 runs per row
    python benchmarks/execution.py --out results.json   # also save every number
"""

from __future__ import annotations

import os

# One core: must happen before NumPy (and its BLAS) is imported.
for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"
os.environ.setdefault("MUJOCO_GL", "egl")

import argparse  # noqa: E402
import importlib.util  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from collections import Counter  # noqa: E402
from collections.abc import Sequence  # noqa: E402
from dataclasses import asdict, dataclass, field  # noqa: E402
from functools import partial  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

from rich.console import Console  # noqa: E402
from rich.table import Table  # noqa: E402

import demoplan  # noqa: E402
from common import Target, median, package_version, percentile, print_targets  # noqa: E402
from demoplan.commands.evaluation import run_one  # noqa: E402
from demoplan.documents.demonstrations import load_demonstrations  # noqa: E402
from demoplan.evaluation.engine import Engine, RayEngine, SerialEngine  # noqa: E402
from demoplan.evaluation.runs import RunRow, RunSpec  # noqa: E402
from demoplan.execution.faults import parse_faults  # noqa: E402
from demoplan.learning import learn  # noqa: E402
from demoplan.model import TaskModel  # noqa: E402
from demoplan.scenes.scene import Scene, complete_geometry, load_scene, scene_to_dict  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"
DEFAULT_FAULTS = "drop=0.2,displace=0.1"
KINEMATIC, MUJOCO, ARM = "kinematic", "mujoco", "arm"
ARM_FAULTS = ("drop=0.3", "displace=0.3", "misplace=0.3", "grasp=0.3", "block=0.3")
"""The arm's rows: one fault kind each, so that what was detected per kind reads
as a confusion table (injected kind → detected failure kinds)."""
TOLERANCE_MM = 10.0  # the MuJoCo target: every goal block within 1 cm
LISTED_FAILURES = 10

# Runs per row: (kinematic with faults, kinematic without, MuJoCo with, MuJoCo without).
FULL_RUNS = (200, 20, 20, 5)
QUICK_RUNS = (20, 5, 5, 2)
# Experiment 1 in MuJoCo (not required; a few runs to see what happens): without, with.
FULL_EXP1_MUJOCO = (2, 3)
QUICK_EXP1_MUJOCO = (1, 1)
# The arm, per experiment: runs without faults, runs per fault kind (Exp. 1, Exp. 2).
FULL_ARM = {"exp1": (3, 4), "exp2": (5, 10)}
QUICK_ARM = {"exp1": (1, 1), "exp2": (2, 3)}


@dataclass(frozen=True, slots=True)
class Experiment:
    key: str
    title: str
    demonstrations: Path
    scene: Path


EXPERIMENTS = (
    Experiment(
        "exp1",
        "Exp. 1 (set table)",
        EXAMPLES / "set_table",
        EXAMPLES / "scenes" / "set-table-cluttered.json",
    ),
    Experiment(
        "exp2",
        "Exp. 2 (blocks)",
        EXAMPLES / "blocks" / "demonstrations.json",
        EXAMPLES / "scenes" / "pyramid-fig4.json",
    ),
)


# --------------------------------------------------------------------------- runs


@dataclass(slots=True)
class Run:
    """One seeded run of one experiment in one world."""

    seed: int
    success: bool
    replans: int
    actions: int
    first_plan_length: int
    wall_s: float
    simulated_s: float | None  # MuJoCo only
    injected: dict[str, int]  # fault kind -> count
    detected: dict[str, int]  # failure kind -> count
    pose_errors_mm: dict[str, float]  # goal object -> final position error
    reason: str
    first_failure: str = ""
    gave_up: bool = False
    exception: str = ""  # the run raised: a defect, not a failed run
    collisions: int = 0  # the arm's contacts with anything but its load
    refused_motions: int = 0  # arm motions a check refused

    @property
    def extra_actions(self) -> int:
        return self.actions - self.first_plan_length


@dataclass(slots=True)
class Row:
    """All runs of one experiment in one world with one fault setting."""

    experiment: str
    world: str
    faults: str  # "" for none
    runs: list[Run] = field(default_factory=list)

    @property
    def label(self) -> str:
        return f"{self.experiment} {self.world} {self.faults or 'no faults'}"

    @property
    def successes(self) -> int:
        return sum(r.success for r in self.runs)

    def summary(self) -> dict[str, Any]:
        runs = self.runs
        n = len(runs)
        ok = [r for r in runs if r.success]
        errors = [e for r in ok for e in r.pose_errors_mm.values()]
        walls = [r.wall_s for r in runs]
        ratios = [
            r.simulated_s / r.wall_s for r in runs if r.simulated_s is not None and r.wall_s > 0
        ]
        injected: Counter[str] = Counter()
        detected: Counter[str] = Counter()
        for r in runs:
            injected.update(r.injected)
            detected.update(r.detected)
        return {
            "experiment": self.experiment,
            "world": self.world,
            "faults": self.faults,
            "runs": n,
            "successes": len(ok),
            "success_rate": len(ok) / n if n else None,
            "median_replans": median([r.replans for r in runs]),
            "max_replans": max((r.replans for r in runs), default=None),
            "median_extra_actions": median([r.extra_actions for r in runs]),
            "max_extra_actions": max((r.extra_actions for r in runs), default=None),
            "median_extra_actions_successful": median([r.extra_actions for r in ok]),
            "injected_per_run": {k: v / n for k, v in sorted(injected.items())} if n else {},
            "detected_per_run": {k: v / n for k, v in sorted(detected.items())} if n else {},
            "median_wall_s": median(walls),
            "p95_wall_s": percentile(walls, 95.0),
            "total_wall_s": sum(walls),
            "median_pose_error_mm": median(errors),
            "max_pose_error_mm": max(errors, default=None),
            "successes_over_1mm": sum(
                max(r.pose_errors_mm.values(), default=0.0) > 1.0 for r in ok
            ),
            "median_sim_to_wall": median(ratios),
            "exceptions": sum(bool(r.exception) for r in runs),
            "collisions": sum(r.collisions for r in runs),
            "refused_motions": sum(r.refused_motions for r in runs),
        }


def _run_of(row: RunRow) -> Run:
    """The benchmark's record of one evaluated run (its wall time: the whole
    ``demoplan run``, preparing the scene, building the world and ``execute``)."""
    crashed = row.reason.startswith("exception: ")
    return Run(
        row.seed,
        row.success,
        row.replans,
        row.actions,
        row.first_plan_length,
        row.planning_s + row.execution_s,
        row.simulated_s,
        dict(row.injected),
        dict(row.detected),
        dict(row.pose_errors_mm),
        row.reason,
        row.first_failure,
        row.gave_up,
        exception=row.reason.removeprefix("exception: ") if crashed else "",
        collisions=row.collisions,
        refused_motions=row.refused_motions,
    )


def _specs(name: str, scene: Scene, world: str, faults: str, count: int) -> list[RunSpec]:
    layout = scene_to_dict(scene)
    return [RunSpec(name, layout, seed, faults, world, clutter=True) for seed in range(count)]


def one_run(model: TaskModel, scene: Scene, world: str, faults: str, seed: int) -> Run:
    """One run, here (the warm-up)."""
    return _run_of(run_one(model, _specs("warm-up", scene, world, faults, seed + 1)[seed]))


def run_row(
    row: Row,
    model: TaskModel,
    scene: Scene,
    count: int,
    console: Console,
    engine: Engine,
) -> None:
    """The row's runs, seeds 0 … count-1, by the evaluation engine (serial or Ray)."""
    started = time.perf_counter()
    specs = _specs(row.experiment, scene, row.world, row.faults, count)
    finished = sorted(engine.rows(specs, partial(run_one, model)), key=lambda r: r.seed)
    row.runs.extend(_run_of(r) for r in finished)
    console.print(
        f"  {row.label}: {count} runs in {time.perf_counter() - started:.1f} s, "
        f"{row.successes}/{count} reached the goal",
        style="dim",
        highlight=False,
    )


# --------------------------------------------------------------------------- tables


def _seconds(value: float | None) -> str:
    if value is None:
        return "-"
    if value < 1.0:
        return f"{value * 1e3:.0f} ms"
    return f"{value:.2f} s"


def _number(value: float | None, digits: int = 1) -> str:
    if value is None:
        return "-"
    if float(value).is_integer():
        return str(int(value))
    return f"{value:.{digits}f}"


def _per_run(counts: dict[str, float]) -> str:
    if not counts:
        return "0"
    parts = ", ".join(f"{kind} {value:.2f}" for kind, value in counts.items())
    return f"{sum(counts.values()):.2f} ({parts})"


def results_table(rows: Sequence[Row], titles: dict[str, str]) -> Table:
    table = Table(
        title="Execution with failure detection and replanning (seeds 0..N-1; per-run "
        "counts are means, times medians)",
        title_justify="left",
    )
    table.add_column("experiment", style="bold")
    table.add_column("world")
    table.add_column("faults", overflow="fold")
    table.add_column("runs", justify="right")
    table.add_column("success", justify="right")
    table.add_column("replans\nmed / max", justify="right")
    table.add_column("extra actions\nmed / max", justify="right")
    table.add_column("faults injected\nper run")
    table.add_column("failures detected\nper run")
    table.add_column("wall / run\nmed / p95", justify="right")
    table.add_column("pose error mm\nmed / max (ok)", justify="right")
    table.add_column("ok runs\n> 1 mm", justify="right")
    table.add_column("sim / wall", justify="right")
    table.add_column("arm contacts\n/ refused", justify="right")
    for row in rows:
        s = row.summary()
        n, ok = s["runs"], s["successes"]
        colour = "green" if n and ok == n else "red" if ok == 0 else "yellow"
        ratio = s["median_sim_to_wall"]
        table.add_row(
            titles[row.experiment],
            row.world,
            row.faults or "none",
            str(n),
            f"[{colour}]{ok}/{n} ({100 * ok / n:.0f}%)[/{colour}]" if n else "-",
            f"{_number(s['median_replans'])} / {_number(s['max_replans'])}",
            f"{_number(s['median_extra_actions'])} / {_number(s['max_extra_actions'])}",
            _per_run(s["injected_per_run"]),
            _per_run(s["detected_per_run"]),
            f"{_seconds(s['median_wall_s'])} / {_seconds(s['p95_wall_s'])}",
            f"{_number(s['median_pose_error_mm'], 2)} / {_number(s['max_pose_error_mm'], 2)}",
            str(s["successes_over_1mm"]) if ok else "-",
            "-" if ratio is None else f"{ratio:.1f}",
            f"{s['collisions']} / {s['refused_motions']}" if row.world == ARM else "-",
        )
    return table


def confusion_table(rows: Sequence[Row], titles: dict[str, str]) -> Table | None:
    """The arm's one-kind fault rows: per injected kind, how many were injected
    and what the executor detected (failure kinds, totals over the row's runs)."""
    arm = [r for r in rows if r.world == ARM and r.faults]
    if not arm:
        return None
    kinds = sorted({k for row in arm for run in row.runs for k in run.detected})
    table = Table(
        title="The arm: faults injected → failures detected (totals over each row's runs)",
        title_justify="left",
    )
    for column in ("experiment", "injected", "runs", "count", *kinds, "success"):
        left = column in ("experiment", "injected")
        table.add_column(column, justify="left" if left else "right")
    for row in arm:
        injected: Counter[str] = Counter()
        detected: Counter[str] = Counter()
        for run in row.runs:
            injected.update(run.injected)
            detected.update(run.detected)
        kind = row.faults.split("=")[0]
        table.add_row(
            titles[row.experiment],
            kind,
            str(len(row.runs)),
            str(injected.get(kind, 0)),
            *(str(detected.get(k, 0)) for k in kinds),
            f"{row.successes}/{len(row.runs)}",
        )
    return table


def failures_table(rows: Sequence[Row], titles: dict[str, str]) -> Table | None:
    failed = [(row, r) for row in rows for r in row.runs if not r.success]
    if not failed:
        return None
    table = Table(
        title=f"Failed runs (the first {LISTED_FAILURES} of each row)", title_justify="left"
    )
    for column in ("experiment", "world", "faults", "seed", "reason", "first detected failure"):
        table.add_column(column, justify="right" if column == "seed" else "left")
    for row in rows:
        shown = [r for r in row.runs if not r.success][:LISTED_FAILURES]
        for r in shown:
            table.add_row(
                titles[row.experiment],
                row.world,
                row.faults or "none",
                str(r.seed),
                r.reason,
                r.first_failure or "-",
            )
        hidden = len(row.runs) - row.successes - len(shown)
        if hidden > 0:
            table.add_row(
                titles[row.experiment], row.world, row.faults or "none", "…", f"{hidden} more", ""
            )
    return table


def reproduction(row: Row, run: Run, experiment: Experiment) -> str:
    model = f"/tmp/demoplan-{experiment.key}-model.json"
    faults = f" --faults {row.faults}" if row.faults else ""
    return (
        f"demoplan learn {experiment.demonstrations.relative_to(ROOT)} -o {model} && "
        f"demoplan run {model} {experiment.scene.relative_to(ROOT)} --sim {row.world}"
        f"{faults} --seed {run.seed}"
    )


# --------------------------------------------------------------------------- targets


def kinematic_target(rows: Sequence[Row], faults: str) -> Target:
    name = "Kinematic runs with recoverable faults reach the goal"
    if not faults:
        return Target(name, None, "no faults given (--faults)")
    parts: list[str] = []
    failed = missing = False
    for experiment, label in (("exp1", "Experiment 1"), ("exp2", "Experiment 2")):
        row = next(
            (
                r
                for r in rows
                if r.experiment == experiment and r.world == KINEMATIC and r.faults == faults
            ),
            None,
        )
        if row is None or not row.runs:
            parts.append(f"not measured ({label})")
            missing = True
            continue
        parts.append(f"{row.successes}/{len(row.runs)} ({label})")
        failed = failed or row.successes < len(row.runs)
    return Target(name, False if failed else None if missing else True, ", ".join(parts))


def mujoco_target(rows: Sequence[Row], faults: str) -> Target:
    name = "MuJoCo Experiment 2: every block within 1 cm in every successful run"
    row = next(
        (r for r in rows if r.experiment == "exp2" and r.world == MUJOCO and r.faults == faults),
        None,
    )
    if row is None or not row.runs:
        return Target(name, None, "MuJoCo Experiment 2 with faults not run")
    s = row.summary()
    worst = s["max_pose_error_mm"]
    detail = f"success {row.successes}/{len(row.runs)}, max error " + (
        "-" if worst is None else f"{worst:.1f} mm"
    )
    if faults:
        detail += f" (faults {faults})"
    clean = next(
        (r for r in rows if r.experiment == "exp2" and r.world == MUJOCO and not r.faults), None
    )
    if clean is not None and clean.runs:
        c = clean.summary()
        worst_clean = c["max_pose_error_mm"]
        detail += f"; without faults {clean.successes}/{len(clean.runs)}, max error " + (
            "-" if worst_clean is None else f"{worst_clean:.1f} mm"
        )
    if worst is None:
        return Target(name, False, detail)
    return Target(name, worst <= TOLERANCE_MM, detail)


def arm_target(rows: Sequence[Row]) -> Target:
    name = (
        "The arm: every run without faults reaches the goal, every object within 1 cm, "
        "no contact of the arm with anything but its load in any run"
    )
    arm = [r for r in rows if r.world == ARM]
    if not arm:
        return Target(name, None, "arm not run")
    clean = [run for r in arm if not r.faults for run in r.runs]
    reached = sum(run.success for run in clean)
    worst = max((e for run in clean for e in run.pose_errors_mm.values()), default=None)
    contacts = sum(run.collisions for r in arm for run in r.runs)
    total = sum(len(r.runs) for r in arm)
    detail = (
        f"without faults {reached}/{len(clean)}, max error "
        + ("-" if worst is None else f"{worst:.1f} mm")
        + f"; contacts in {total} runs: {contacts}"
    )
    met = reached == len(clean) and worst is not None and worst <= TOLERANCE_MM and not contacts
    return Target(name, met, detail)


# --------------------------------------------------------------------------- main


def parse_args(argv: Sequence[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        description="Benchmark execution with failure detection and replanning: Monte-Carlo "
        "runs of the paper's experiments in the kinematic and MuJoCo worlds.",
    )
    parser.add_argument(
        "--quick",
        action="store_true",
        help="runs per row, kinematic with / without faults, MuJoCo with / without: "
        "{}/{}/{}/{} instead of {}/{}/{}/{}".format(*QUICK_RUNS, *FULL_RUNS),
    )
    parser.add_argument("--out", type=Path, help="also save the results to this JSON file")
    parser.add_argument(
        "--faults",
        default=DEFAULT_FAULTS,
        help=f"faults of the faulty rows (default {DEFAULT_FAULTS})",
    )
    parser.add_argument(
        "--workers",
        type=int,
        default=0,
        help="0 (default): the runs one after the other here; N: on a local Ray with N "
        "workers (demoplan[scale])",
    )
    parser.add_argument("--no-mujoco", action="store_true", help="kinematic rows only")
    parser.add_argument("--no-arm", action="store_true", help="leave out the arm's rows")
    parser.add_argument(
        "--no-mujoco-exp1",
        action="store_true",
        help="do not try Experiment 1 in MuJoCo",
    )
    args = parser.parse_args(argv)
    try:
        parse_faults(args.faults)
    except Exception as exc:
        parser.error(str(exc))
    return args


def main(argv: Sequence[str] | None = None) -> int:
    args = parse_args(argv)
    console = Console(width=None if sys.stdout.isatty() else 220)
    started = time.perf_counter()
    k_faulty, k_clean, m_faulty, m_clean = QUICK_RUNS if args.quick else FULL_RUNS
    e1_clean, e1_faulty = QUICK_EXP1_MUJOCO if args.quick else FULL_EXP1_MUJOCO
    have_mujoco = importlib.util.find_spec("mujoco") is not None
    use_mujoco = have_mujoco and not args.no_mujoco

    console.print(
        f"demoplan execution benchmark — {'quick' if args.quick else 'full'} run, faults "
        f"{args.faults!r}; Python {platform.python_version()}, {platform.machine()}, "
        f"{os.cpu_count()} CPUs, MuJoCo {package_version('mujoco')}, OMP/OPENBLAS/MKL threads = 1",
        highlight=False,
    )
    console.print(f"demoplan {demoplan.__version__} from {Path(demoplan.__file__).parent}")
    if not have_mujoco:
        console.print("mujoco is not installed: MuJoCo rows skipped.", style="yellow")

    plan: list[tuple[Experiment, str, str, int]] = []
    for experiment in EXPERIMENTS:
        plan += [
            (experiment, KINEMATIC, args.faults, k_faulty),
            (experiment, KINEMATIC, "", k_clean),
        ]
    if use_mujoco:
        exp1, exp2 = EXPERIMENTS
        plan += [(exp2, MUJOCO, "", m_clean), (exp2, MUJOCO, args.faults, m_faulty)]
        if not args.no_mujoco_exp1:
            plan += [(exp1, MUJOCO, "", e1_clean), (exp1, MUJOCO, args.faults, e1_faulty)]
    have_arm = use_mujoco and all(importlib.util.find_spec(m) for m in ("mink", "dm_control"))
    if use_mujoco and not have_arm:
        console.print("mink or dm_control is not installed: arm rows skipped.", style="yellow")
    if have_arm and not args.no_arm:
        for experiment in EXPERIMENTS:
            clean, per_kind = (QUICK_ARM if args.quick else FULL_ARM)[experiment.key]
            plan.append((experiment, ARM, "", clean))
            plan += [(experiment, ARM, kind, per_kind) for kind in ARM_FAULTS]

    models: dict[str, TaskModel] = {}
    scenes: dict[str, Scene] = {}
    learn_s: dict[str, float] = {}
    for experiment in EXPERIMENTS:
        t0 = time.perf_counter()
        models[experiment.key] = learn(load_demonstrations([experiment.demonstrations]))
        learn_s[experiment.key] = time.perf_counter() - t0
        scenes[experiment.key] = complete_geometry(
            load_scene(experiment.scene), models[experiment.key]
        )
        # Warm-up, untimed: imports and first-call caches.
        one_run(models[experiment.key], scenes[experiment.key], KINEMATIC, "", 0)
    console.print(
        "learned "
        + ", ".join(
            f"{e.title} from {e.demonstrations.relative_to(ROOT)} in {_seconds(learn_s[e.key])}"
            for e in EXPERIMENTS
        ),
        highlight=False,
    )

    engine: Engine = SerialEngine()
    if args.workers:  # one local Ray for every row
        import ray

        ray.init(
            address="local", num_cpus=args.workers, include_dashboard=False, log_to_driver=False
        )
        engine = RayEngine()
    rows: list[Row] = []
    for experiment, world, faults, count in plan:
        if count <= 0:
            continue
        row = Row(experiment.key, world, faults)
        run_row(row, models[experiment.key], scenes[experiment.key], count, console, engine)
        rows.append(row)

    titles = {e.key: e.title for e in EXPERIMENTS}
    console.print(results_table(rows, titles))
    console.print(
        "extra actions: actions executed − length of the first plan. faults injected: what "
        "the world did (drop, displace, …); failures detected: what the executor saw "
        "(dropped; misplaced: released 1–6 cm from its target; moved; grasp; …). "
        "Fewer detections than faults: a drop that lands within 1 cm of its target is no "
        "failure. wall / run: building the world + execute. pose error: final position error "
        "of every goal object, successful runs only (success itself requires < 10 mm). "
        "ok runs > 1 mm: successful runs with a goal object more than 1 mm off (a dropped "
        "object that landed within the tolerance). sim / wall: simulated seconds per "
        "wall-clock second (MuJoCo).",
        highlight=False,
        style="dim",
    )
    confusion = confusion_table(rows, titles)
    if confusion is not None:
        console.print(confusion)
    failed = failures_table(rows, titles)
    if failed is not None:
        console.print(failed)
        by_key = {e.key: e for e in EXPERIMENTS}
        for row in rows:
            first = next((r for r in row.runs if not r.success), None)
            if first is not None:
                console.print(
                    f"Reproduce ({row.label}, seed {first.seed}): "
                    + reproduction(row, first, by_key[row.experiment]),
                    highlight=False,
                    markup=False,
                    style="yellow",
                )
    crashed = [(row, r) for row in rows for r in row.runs if r.exception]
    for row, r in crashed[:LISTED_FAILURES]:
        console.print(
            f"Exception in {row.label}, seed {r.seed}: {r.exception}",
            style="bold red",
            markup=False,
            highlight=False,
        )

    goals = [kinematic_target(rows, args.faults)]
    if use_mujoco:
        goals.append(mujoco_target(rows, args.faults))
    else:
        goals.append(
            Target(
                "MuJoCo Experiment 2: every block within 1 cm in every successful run",
                None,
                "MuJoCo not run",
            )
        )
    if have_arm and not args.no_arm:
        goals.append(arm_target(rows))
    print_targets(console, goals)
    total = time.perf_counter() - started
    console.print(f"Total benchmark time: {total:.1f} s")

    if args.out is not None:
        document: dict[str, Any] = {
            "benchmark": "demoplan execution",
            "run": "quick" if args.quick else "full",
            "faults": args.faults,
            "python": platform.python_version(),
            "machine": platform.machine(),
            "cpus": os.cpu_count(),
            "mujoco": package_version("mujoco"),
            "demoplan": demoplan.__version__,
            "learn_s": learn_s,
            "experiments": [
                {
                    "key": e.key,
                    "title": e.title,
                    "demonstrations": str(e.demonstrations.relative_to(ROOT)),
                    "scene": str(e.scene.relative_to(ROOT)),
                }
                for e in EXPERIMENTS
            ],
            "rows": [
                {
                    **row.summary(),
                    "runs_detail": [
                        {**asdict(r), "extra_actions": r.extra_actions} for r in row.runs
                    ],
                }
                for row in rows
            ],
            "targets": [asdict(t) for t in goals],
            "total_s": total,
        }
        args.out.write_text(json.dumps(document, indent=2) + "\n", encoding="utf-8")
        console.print(f"Results saved to {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
