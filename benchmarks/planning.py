"""Benchmark: ``demoplan solve`` vs Fast Downward and pyperplan, whole-process and planner time.

What it measures
----------------
Generated problems of two families — table setting
(:func:`tests.support.planning_families.table_problem`) and pyramid building with
stacked starts (:func:`~tests.support.planning_families.blocks_problem`) — with
N = 3, 5, 7, 10, 15, 20, 30 objects (``--quick``: N = 3, 5, 7 for every planner
plus N = 20 and 30 for demoplan alone, to check its targets). Each problem is
written once as the paper's XML (:func:`demoplan.planning.xml.save_problem`) and
as grounded STRIPS PDDL (:func:`demoplan.planning.pddl.save_pddl` with
``grounded=True``: pyperplan cannot read the lifted export), then solved
by, in one run:

1. **demoplan** — ``demoplan solve PROBLEM.xml --json`` (A*, the default), and
   ``--search bfs`` (the paper's breadth-first search, the reference) for
   N ≤ 5. Plan length, expanded states (A* expands *moves*: one GRASP with the
   PUT_DOWN that follows) and the in-process search time come from the JSON.
2. **Fast Downward** ``--alias seq-opt-lmcut`` (optimal: A* with LM-cut) and
   ``--alias lama-first`` (satisficing), through the driver ``fast-downward.py``
   (``--fd PATH``; by default the copy bundled with ``up_fast_downward`` in this
   interpreter, else in ``/tmp/upvenv``). Each run has its own working
   directory; the plan length is the number of actions in the ``sas_plan`` file
   it writes there (cross-checked with ``Plan length: N step(s)``), expanded
   states come from ``Expanded N state(s)``, and the translator's and the
   search's own times are kept to show where the time goes.
3. **pyperplan** ``-s astar -H lmcut`` (``hmax`` if this pyperplan has no
   LM-cut; both are admissible, so both runs are optimal), found next to this
   interpreter or in ``/tmp/upvenv/bin`` (``--pyperplan PATH``). The plan length
   is the number of lines of the ``.soln`` file it writes next to the problem
   (cross-checked with its ``Plan length:`` log line), expanded states come from
   ``N Nodes expanded``.

Every plan is checked with :func:`demoplan.planning.strips.validate` (PDDL
plan lines mapped back with :func:`demoplan.planning.pddl.action_from_pddl`):
an invalid plan is reported as ``invalid`` in red — a bug of that planner or
of the export. demoplan runs as ``python -m demoplan`` with the source folder
of the demoplan this script imported first on ``PYTHONPATH``, so the
subprocesses run the same code. A planner that cannot be found is skipped
with a message. Every run is a subprocess timed with ``time.perf_counter``
around start-to-exit (interpreter start-up, parsing, translation and search all
count); a run over the timeout
(``--timeout``, 60 s; 10 s with ``--quick``) is killed with its whole process
group and reported as ``timeout``. Once a competitor times out at some N, it is
not run at larger N of the same family (``--no-skip`` runs it anyway); demoplan
A* always runs. A run under 1 s is repeated (3 runs in all) and the median
reported; longer runs are timed once.

Beside the whole-process time, each run's *planner time* is kept: the time the
planner reports for the problem itself, without interpreter start-up and imports.
For demoplan it is ``read_seconds + seconds`` from ``--json`` (reading and
checking the XML, then the search); for Fast Downward, the translator's own
wall-clock (``Done! [..s CPU, ..s wall-clock]``) plus the search component's
``Total time`` (its ``Search time`` if there is no total). pyperplan has none.
The raw numbers of every timed run are kept in the JSON (``run_extras``,
``planner_s``, ``median_planner_s``).

Then a verdict table per family and N: demoplan's plan must never be longer than
another planner's (a shorter plan elsewhere means demoplan is not optimal), and
no optimal planner's plan may be longer than demoplan's (which would mean
demoplan's plan is too short, i.e. invalid) — both are flagged as bugs — and the
speed ratio FD-optimal / demoplan where both finished, in whole-process wall
time, CPU time and planner time. It ends with the targets, PASS or FAIL:
provably shortest plans for 20 objects in under 0.5 s whole process, for 30
objects in under 2 s, and at least 10× faster than Fast Downward's optimal
configuration wherever that finishes — judged twice, on whole-process wall time
and on planner time.

Hard families (issue 13)
------------------------
``parking``, ``parking-dense`` and ``parking-crowded``
(:func:`tests.support.planning_families.parking_problem` with the settings of
:data:`~tests.support.planning_families.PARKING_FAMILIES`): goal places on a dense
grid whose neighbours block each other's grasps, objects starting on one
another's goal places in swaps and 3-cycles (forced parking), distractors
without a goal standing on goal places, objects starting on the grid between
them. N = 5, 10, 15, 20, 30 objects with a goal (distractors come on top),
seeds 0–7 (``--quick``: N = 10, 20, seeds 0–3; ``--seeds``, ``--sizes``
choose); target (c) counts N ≥ 10, N = 5 is there for target (d), where
Fast Downward's optimal configuration still finishes.
Each problem is written as XML and as **lifted** PDDL (``save_pddl``'s
default: Fast Downward translates it much faster than the grounded export;
pyperplan is not run on these, it is far too slow). Per problem, each timed as
above (whole process; runs under 1 s repeated, median of 3):

1. **demoplan** with its defaults: ``python -m demoplan solve PROBLEM.xml --json``
   — anytime, answering within 2 s counted from its own start; the JSON says
   whether the plan is proved shortest (``optimal``) and its lower ``bound``;
2. Fast Downward ``--alias lama-first`` and ``--alias seq-opt-lmcut``, with
   the timeout (``--timeout``; 60 s, 20 s with ``--quick``). Either is no
   longer run at larger N of a family once it timed out on half or more of
   the seeds at some N (``--no-skip`` runs it anyway).

A table per family, one row per N: demoplan's coverage within 2 s whole
process; lama-first's coverage within 2 s and within its timeout; the share
demoplan proved shortest within 2 s; median / max of demoplan's length minus
lama's; demoplan's length against FD seq-opt-lmcut's where it finished; the
median whole-process times and FD-opt / demoplan. Then the bugs — an invalid
plan, a demoplan crash or "no plan" where a plan was found, a demoplan run
over 2.5 s whole process, a plan shorter than FD-optimal's, "proved shortest"
with another length than FD-optimal's, a lower bound above a valid plan's
length — and issue 13's targets: (a) every problem answered within 2 s whole
process, (b) never longer than lama-first's plan, (c) at least 90 % proved
optimal within 2 s, (d) at least 10× faster than FD seq-opt-lmcut wherever it
finishes, in whole-process time, and with demoplan's plan proved shortest (an
unproved answer does not count as beating an optimal planner). The targets
are judged on ``parking`` and ``parking-dense``, the families of the issue;
``parking-crowded``, the hardest we generate, gets a line of the same figures
beside them, to show where the planner stops.

How to run
----------
From the repository root, with demoplan installed (``pip install -e ".[dev]"``)::

    python benchmarks/planning.py                  # everything (~35 min on 2 busy cores)
    python benchmarks/planning.py --quick          # table/blocks N <= 7; parking N = 10, 20
    python benchmarks/planning.py --families table,blocks        # the easy families, ~5 min
    python benchmarks/planning.py --families parking,parking-dense --sizes 10,15
    python benchmarks/planning.py --out results.json --keep /tmp/problems
    python benchmarks/planning.py --fd /path/to/fast-downward.py --timeout 30
    python benchmarks/planning.py --limits         # only the limits below, ~1 min
    python benchmarks/planning.py --startup        # only the start-up figure, ~20 s
    python benchmarks/planning.py --proof          # only the proofs within 10 s, ~2 min

The crowded families (issue 44) run with them: ``crowded-swaps``,
``crowded-distractors`` and ``crowded-stacks``
(:data:`~tests.support.planning_families.CROWDED_FAMILIES`: parking forced by
swaps *and* distractors, caps stacked on objects), in the same table
(demoplan vs lama-first in length, vs seq-opt-lmcut in time, whole process and
planner time); ``--families crowded-swaps,crowded-distractors,crowded-stacks``
runs them alone. Their hardest draws against lama-first are checked in by
``benchmarks/crowded_set.py``.

Start-up (issue 44)
-------------------
Every run that is not ``--limits`` or ``--proof`` ends with, and ``--startup`` runs alone
(:mod:`planning_startup`): ``demoplan solve`` of the paper's example,
``table_problem(7)`` and a 10-object ``parking`` draw, whole process, against
``python -c pass``, interleaved, median of 11; the target is within 2×.

Every limit inside every loop (issue 44)
----------------------------------------
Every run but ``--startup`` and ``--proof`` ends with, and ``--limits`` runs
alone: ``demoplan solve`` of a
1,000-object ring (:func:`tests.support.planning_families.ring_problem`: each object
to its neighbour's goal place, each goal place blocking its neighbour's grasp)
with ``--timeout 0`` and with ``--max-nodes 1 --timeout inf`` — whole-process
wall time, median of 3, the exit code and the answer's line; the target is
under 1 s each (before the clock and the node limit were read inside
compilation, the reasons without search and successor generation: 14.8 s and
16 s). Beside it, what reading the limits costs: the clock reads of one
in-process ``solve`` of crowded-stacks N = 20 (seed 2, the default 2 s
budget) counted, times the cost of one read (``Clock.stop``, timed over a
million), as a share of that solve's time.

Proofs within 10 s (issue 44)
-----------------------------
``--proof`` runs alone (:mod:`planning_proof`): in-process ``solve`` with a
10 s budget on the four crowded families at N = 10 and 20, on seeds 0–3,
1000·s + N and 500–503 (the last chosen before any run on them); per
problem the plan's length, its bound, proved or not, wall and CPU time, and
the share proved shortest per seed set and in all against 95 %.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.util
import json
import os
import platform
import re
import resource
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

import demoplan
from common import Target, print_targets
from demoplan.errors import DemoplanError
from demoplan.planning.pddl import action_from_pddl, save_pddl
from demoplan.planning.problem import Action, Problem
from demoplan.planning.strips import validate
from demoplan.planning.xml import load_problem, save_problem
from planning_proof import PROOF_SECONDS, proof_benchmark
from planning_startup import startup_timings

# The repository root, for tests/support/planning_families.py (the problem families
# the tests use too).
REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:
    sys.path.insert(1, str(REPO))
from tests.support.planning_families import (  # noqa: E402
    CROWDED_FAMILIES,
    PARKING_FAMILIES,
    blocks_problem,
    parking_problem,
    ring_problem,
    table_problem,
)

FULL_SIZES = (3, 5, 7, 10, 15, 20, 30)
QUICK_SIZES = (3, 5, 7)
QUICK_DEMOPLAN_ONLY = (20, 30)  # --quick still measures demoplan's target cells
BFS_MAX_OBJECTS = 5
FAMILIES: dict[str, Callable[[int, int], Problem]] = {
    "table": table_problem,
    "blocks": blocks_problem,
}
FAMILY_TITLES = {"table": "Table setting", "blocks": "Blocks (pyramids, stacked starts)"}
DEFAULT_TIMEOUT, QUICK_TIMEOUT = 60.0, 10.0
CHEAP_SECONDS, CHEAP_REPEATS = 1.0, 3
TARGET_20 = (20, 0.5)  # objects, whole-process seconds
TARGET_30 = (30, 2.0)
TARGET_SPEEDUP = 10.0  # FD seq-opt-lmcut / demoplan
UPVENV = Path("/tmp/upvenv")
TIMES = "\u00d7"  # multiplication sign (spelled out for ruff's RUF001)

# Planner keys, in table order.
DEMOPLAN, BFS, FD_OPT, FD_LAMA, PYPERPLAN = "demoplan", "bfs", "fd-opt", "fd-lama", "pyperplan"


# --------------------------------------------------------------------------- cases


@dataclass(frozen=True, slots=True)
class Case:
    """One generated problem, written to disk as XML and as PDDL."""

    family: str
    n: int
    xml: Path
    domain: Path
    problem: Path
    locations: int
    pddl_actions: int
    generated: Problem  # what was written, to validate every plan against
    seed: int = 0


def make_case(family: str, n: int, seed: int, root: Path) -> Case:
    problem = FAMILIES[family](n, seed)
    folder = root / f"{family}-{n}"
    folder.mkdir(parents=True, exist_ok=True)
    xml = folder / "problem.xml"
    save_problem(problem, xml)
    # Grounded: pyperplan reads the same files, and it reads no quantifiers.
    domain, pddl_problem = save_pddl(problem, folder / "pddl", grounded=True)
    actions = domain.read_text(encoding="utf-8").count("(:action ")
    locations = len(problem.locations)
    return Case(family, n, xml, domain, pddl_problem, locations, actions, problem, seed)


# --------------------------------------------------------------------------- processes


@dataclass(frozen=True, slots=True)
class Finished:
    """A subprocess that exited (``returncode``) or was killed at the timeout (None)."""

    returncode: int | None
    seconds: float
    stdout: str
    stderr: str
    cpu_seconds: float | None  # user + system of the reaped processes (None when killed)


def _child_environment() -> dict[str, str]:
    env = dict(os.environ)
    for variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        env[variable] = "1"
    # ``python -m demoplan`` runs the demoplan this script imported (a checkout's
    # src/ on PYTHONPATH wins over an editable install of another one).
    source = str(Path(demoplan.__file__).resolve().parent.parent)
    paths = [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p and p != source]
    env["PYTHONPATH"] = os.pathsep.join([source, *paths])
    return env


def run_process(command: Sequence[str], cwd: Path, timeout: float) -> Finished:
    """Run ``command`` in its own process group; kill the whole group at ``timeout``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    process = subprocess.Popen(
        list(command),
        cwd=cwd,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        errors="replace",
        start_new_session=True,
        env=_child_environment(),
    )
    try:
        stdout, stderr = process.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        _kill_group(process)
        stdout, stderr = process.communicate()
        return Finished(None, time.perf_counter() - started, stdout, stderr, None)
    except BaseException:  # Ctrl-C: leave no planner running behind
        _kill_group(process)
        process.communicate()
        raise
    seconds = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return Finished(process.returncode, seconds, stdout, stderr, cpu)


def _kill_group(process: subprocess.Popen[str]) -> None:
    with contextlib.suppress(ProcessLookupError):
        os.killpg(process.pid, signal.SIGKILL)


def _last_line(text: str) -> str:
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    return lines[-1][:160] if lines else ""


def _last_int(pattern: str, text: str) -> int | None:
    found = re.findall(pattern, text)
    return int(found[-1]) if found else None


def _last_float(pattern: str, text: str) -> float | None:
    found = re.findall(pattern, text)
    return float(found[-1]) if found else None


# --------------------------------------------------------------------------- planners


@dataclass(slots=True)
class Attempt:
    """One run of one planner on one case."""

    status: str  # "ok", "timeout", "no plan", "error"
    seconds: float
    length: int | None = None
    expanded: int | None = None
    detail: str = ""
    extra: dict[str, float] = field(default_factory=dict)
    cpu_seconds: float | None = None
    planner_seconds: float | None = None  # the planner's own time, without start-up
    actions: tuple[Action, ...] | None = None  # the plan, when the planner gives it as ours
    plan_lines: list[str] = field(default_factory=list)  # the plan, as PDDL action lines
    optimal: bool | None = None  # demoplan: proved shortest
    bound: int | None = None  # demoplan: proven lower bound on the plan length


class Planner:
    """A planner run as a subprocess; subclasses build the command and read the output."""

    key: str = ""
    label: str = ""
    optimal: bool = False
    max_objects: int | None = None  # larger cases are not run

    def attempt(self, case: Case, workdir: Path, timeout: float) -> Attempt:
        """Run once in ``workdir`` (a fresh folder) and read what came out."""
        done = run_process(self.command(case, workdir), workdir, timeout)
        attempt = self.read(done, workdir)
        attempt.cpu_seconds = done.cpu_seconds
        if attempt.status == "ok":
            attempt.planner_seconds = self.planner_time(attempt.extra)
            check_plan(case.generated, attempt)
        return attempt

    def planner_time(self, extra: dict[str, float]) -> float | None:
        """The time spent on the problem itself, from the planner's own report (None: unknown)."""
        return None

    def command(self, case: Case, workdir: Path) -> list[str]:
        raise NotImplementedError

    def read(self, done: Finished, workdir: Path) -> Attempt:
        raise NotImplementedError


def check_plan(problem: Problem, attempt: Attempt) -> None:
    """Validate the plan of an ``ok`` attempt against ``problem``; an invalid one
    (a bug of that planner, or of the PDDL export) turns the attempt ``invalid``."""
    try:
        actions = attempt.actions
        if actions is None:
            actions = tuple(action_from_pddl(problem, line) for line in attempt.plan_lines)
        validate(problem, actions)
    except (DemoplanError, ValueError) as exc:
        attempt.status = "invalid"
        attempt.detail = f"INVALID PLAN ({attempt.length} actions): {exc}"


def _plan_lines(path: Path) -> list[str]:
    lines = path.read_text(encoding="utf-8").splitlines()
    return [line.strip() for line in lines if line.strip() and not line.startswith(";")]


class DemoplanPlanner(Planner):
    """``demoplan solve --json``, with ``--search`` when ``search`` is given."""

    def __init__(self, command: list[str], search: str | None) -> None:
        self.base_command = command
        self.search = search
        self.key = BFS if search == "bfs" else DEMOPLAN
        self.label = {"astar": "demoplan A*", "bfs": "demoplan BFS"}.get(search or "", "demoplan")
        self.optimal = search is not None  # by default an answer may be unproved
        self.max_objects = BFS_MAX_OBJECTS if search == "bfs" else None

    def command(self, case: Case, workdir: Path) -> list[str]:
        search = [] if self.search is None else ["--search", self.search]
        return [*self.base_command, "solve", str(case.xml), "--json", *search]

    def planner_time(self, extra: dict[str, float]) -> float | None:
        # Reading and checking the XML plus the search, both timed inside the process.
        if "read_s" not in extra or "search_s" not in extra:
            return None
        return extra["read_s"] + extra["search_s"]

    def read(self, done: Finished, workdir: Path) -> Attempt:
        if done.returncode is None:
            return Attempt("timeout", done.seconds)
        if done.returncode == 3:
            return Attempt("no plan", done.seconds, detail=_last_line(done.stderr))
        if done.returncode == 4:  # a limit stopped the search before any plan
            return Attempt("limit", done.seconds, detail=_last_line(done.stderr))
        if done.returncode != 0:
            return Attempt(
                "error", done.seconds, detail=f"exit {done.returncode}: {_last_line(done.stderr)}"
            )
        try:
            data = json.loads(done.stdout)
            length, actions = int(data["length"]), data["actions"]
            plan = tuple(Action(*map(str, action)) for action in actions)
        except (ValueError, KeyError, TypeError) as exc:
            return Attempt("error", done.seconds, detail=f"unreadable JSON ({exc})")
        if len(actions) != length:
            return Attempt(
                "error",
                done.seconds,
                length,
                detail=f"inconsistent plan: {len(actions)} actions listed, length {length}",
            )
        extra = {"search_s": float(data["seconds"]), "generated": float(data["generated"])}
        if "read_seconds" in data:
            extra["read_s"] = float(data["read_seconds"])
        return Attempt(
            "ok",
            done.seconds,
            length,
            int(data["expanded"]),
            extra=extra,
            actions=plan,
            optimal=bool(data.get("optimal", True)),
            bound=int(data["bound"]) if "bound" in data else None,
        )


class FastDownwardPlanner(Planner):
    def __init__(
        self,
        python: str,
        driver: Path,
        alias: str,
        key: str,
        label: str,
        translate_options: Sequence[str] = (),
    ) -> None:
        self.python = python
        self.driver = driver
        self.alias = alias
        self.translate_options = list(translate_options)
        self.key = key
        self.label = label
        self.optimal = alias.startswith("seq-opt")

    def planner_time(self, extra: dict[str, float]) -> float | None:
        # The translator's own wall-clock, then the search component's total time (it
        # includes reading output.sas) or, failing that, its search time.
        search = extra.get("search_total_s", extra.get("search_s"))
        if "translate_s" not in extra or search is None:
            return None
        return extra["translate_s"] + search

    def command(self, case: Case, workdir: Path) -> list[str]:
        return [
            self.python,
            str(self.driver),
            "--alias",
            self.alias,
            str(case.domain),
            str(case.problem),
            *(["--translate-options", *self.translate_options] if self.translate_options else []),
        ]

    def read(self, done: Finished, workdir: Path) -> Attempt:
        out = done.stdout + "\n" + done.stderr
        extra: dict[str, float] = {}
        translate = re.findall(r"Done! \[([\d.]+)s CPU, ([\d.]+)s wall-clock\]", out)
        if translate:
            extra["translate_s"] = float(translate[-1][1])
        search = _last_float(r"\] Search time: ([\d.]+)s", out)
        if search is not None:
            extra["search_s"] = search
        total = _last_float(r"\] Total time: ([\d.]+)s", out)
        if total is not None:
            extra["search_total_s"] = total
        if done.returncode is None:
            phase = "search" if "translate exit code" in out else "translating"
            # The last f layer an optimal search reached is a lower bound it proved.
            layer = _last_int(r"\] f = (\d+), \d+ evaluated", out)
            if layer is not None:
                extra["f_reached"] = float(layer)
                phase += f", having reached f = {layer}"
            return Attempt("timeout", done.seconds, detail=f"killed while {phase}", extra=extra)
        plan_file = workdir / "sas_plan"
        if done.returncode != 0 or not plan_file.exists():
            status = "no plan" if done.returncode in (11, 12) else "error"
            return Attempt(
                status,
                done.seconds,
                detail=f"exit {done.returncode}: {_last_line(done.stderr or done.stdout)}",
                extra=extra,
            )
        lines = _plan_lines(plan_file)
        length = len(lines)
        printed = _last_int(r"Plan length: (\d+) step", out)
        expanded = _last_int(r"\] Expanded (\d+) state\(s\)\.", out)
        if printed is not None and printed != length:
            return Attempt(
                "error",
                done.seconds,
                length,
                expanded,
                detail=f"sas_plan has {length} actions, stdout says {printed}",
                extra=extra,
            )
        return Attempt("ok", done.seconds, length, expanded, extra=extra, plan_lines=lines)


class PyperplanPlanner(Planner):
    def __init__(self, script: Path, heuristic: str) -> None:
        self.script = script
        self.heuristic = heuristic
        self.key = PYPERPLAN
        self.label = f"pyperplan A* {heuristic}"
        self.optimal = True  # lmcut and hmax are admissible

    def command(self, case: Case, workdir: Path) -> list[str]:
        # The .soln file goes next to the problem: use copies in the run's own folder.
        domain = shutil.copy(case.domain, workdir / "domain.pddl")
        problem = shutil.copy(case.problem, workdir / "problem.pddl")
        return [str(self.script), "-s", "astar", "-H", self.heuristic, str(domain), str(problem)]

    def read(self, done: Finished, workdir: Path) -> Attempt:
        out = done.stdout + "\n" + done.stderr
        expanded = _last_int(r"(\d+) Nodes expanded", out)
        if done.returncode is None:
            return Attempt("timeout", done.seconds, expanded=expanded)
        solution = workdir / "problem.pddl.soln"
        if done.returncode != 0:
            return Attempt(
                "error", done.seconds, detail=f"exit {done.returncode}: {_last_line(out)}"
            )
        if not solution.exists():
            return Attempt("no plan", done.seconds, expanded=expanded, detail=_last_line(out))
        lines = _plan_lines(solution)
        length = len(lines)
        printed = _last_int(r"Plan length: (\d+)", out)
        if printed is not None and printed != length:
            return Attempt(
                "error",
                done.seconds,
                length,
                expanded,
                detail=f".soln has {length} actions, the log says {printed}",
            )
        return Attempt("ok", done.seconds, length, expanded, plan_lines=lines)


def demoplan_command() -> list[str]:
    # Run with the child environment, whose PYTHONPATH leads to the demoplan imported here.
    return [sys.executable, "-m", "demoplan"]


def find_fast_downward(option: Path | None) -> tuple[str, Path] | str:
    """``(python, driver)`` for Fast Downward, or why it is skipped."""
    if option is not None:
        if option.is_file():
            return sys.executable, option
        return f"--fd {option}: no such file"
    spec = importlib.util.find_spec("up_fast_downward")
    if spec is not None and spec.origin is not None:
        driver = Path(spec.origin).parent / "downward" / "fast-downward.py"
        if driver.is_file():
            return sys.executable, driver
    python = UPVENV / "bin" / "python"
    for driver in sorted(UPVENV.glob("lib/python*/site-packages/up_fast_downward/downward/*.py")):
        if driver.name == "fast-downward.py" and python.exists():
            return str(python), driver
    return (
        "Fast Downward not found (no up_fast_downward in this interpreter or in "
        f"{UPVENV}; pass --fd PATH/TO/fast-downward.py)"
    )


def find_pyperplan(option: Path | None) -> tuple[Path, str] | str:
    """``(script, heuristic)`` for pyperplan, or why it is skipped."""
    if option is not None:
        candidates = [option]
    else:
        candidates = [Path(sys.executable).parent / "pyperplan", UPVENV / "bin" / "pyperplan"]
    for script in candidates:
        if script.is_file() and os.access(script, os.X_OK):
            try:
                done = run_process([str(script), "--help"], Path.cwd(), 30.0)
            except OSError as exc:
                return f"{script} does not run ({exc})"
            heuristic = "lmcut" if "lmcut" in done.stdout else "hmax"
            return script, heuristic
    where = " or ".join(str(c) for c in candidates)
    return f"pyperplan not found ({where}; pass --pyperplan PATH)"


def _distribution_version(near: Path, name: str) -> str:
    """The version of ``name`` installed in the virtual environment holding ``near``."""
    for parent in near.resolve().parents:
        for info in parent.glob(f"lib/python*/site-packages/{name}-*.dist-info"):
            return info.name.removeprefix(f"{name}-").removesuffix(".dist-info")
    return "?"


# --------------------------------------------------------------------------- measuring


@dataclass(slots=True)
class Result:
    """A planner on a case: the median over repeats, or why there is no time."""

    planner: str
    family: str
    n: int
    status: str  # "ok", "timeout", "no plan", "limit", "error", "invalid", "skipped", "not run"
    times_s: list[float] = field(default_factory=list)
    length: int | None = None
    expanded: int | None = None
    detail: str = ""
    extra: dict[str, float] = field(default_factory=dict)
    cpu_s: list[float] = field(default_factory=list)  # user + system CPU per timed run
    # Planner time per timed run (the planner's own report, without interpreter start-up)
    # and the raw numbers it came from, run by run.
    planner_s: list[float] = field(default_factory=list)
    run_extras: list[dict[str, float]] = field(default_factory=list)
    seed: int = 0
    optimal: bool | None = None  # demoplan: the plan is proved shortest
    bound: int | None = None  # demoplan: its proven lower bound

    @property
    def median_s(self) -> float | None:
        return statistics.median(self.times_s) if self.times_s else None

    @property
    def median_planner_s(self) -> float | None:
        # Only when every timed run reported it, so that it is the same runs' median.
        if not self.planner_s or len(self.planner_s) != len(self.times_s):
            return None
        return statistics.median(self.planner_s)

    @property
    def median_cpu_s(self) -> float | None:
        return statistics.median(self.cpu_s) if self.cpu_s else None

    @property
    def ok(self) -> bool:
        return self.status == "ok"


def measure(planner: Planner, case: Case, root: Path, timeout: float) -> Result:
    """Run ``planner`` on ``case``: once, and 3 times in all when a run is under 1 s."""
    runs: list[Attempt] = []
    for index in range(CHEAP_REPEATS):
        workdir = Path(tempfile.mkdtemp(prefix=f"{planner.key}-{index}-", dir=root))
        runs.append(planner.attempt(case, workdir, timeout))
        shutil.rmtree(workdir, ignore_errors=True)
        if runs[0].status != "ok" or runs[0].seconds >= CHEAP_SECONDS:
            break
    # An invalid plan in any run is the result: it must not hide behind a valid repeat.
    first = next((r for r in runs if r.status == "invalid"), runs[0])
    timed = [r for r in runs if r.status == first.status] if first.status == "ok" else [first]
    notes = [first.detail] if first.detail else []
    mismatched = [r.length for r in runs if r.status == "ok" and r.length != first.length]
    if mismatched:
        notes.append(f"plan length changed between repeats: {first.length} then {mismatched}")
    for index, run in enumerate(runs, start=1):
        if run.status != first.status:  # not timed; said, so that it is not lost
            notes.append(f"run {index} of {len(runs)}: {run.status} {run.detail}".strip())
    unproved = [r.length for r in timed if r.optimal is False]
    if first.optimal and unproved:
        notes.append(f"not proved shortest in a repeat ({len(unproved)} of {len(timed)} runs)")
    detail = "; ".join(notes)
    return Result(
        planner.key,
        case.family,
        case.n,
        first.status,
        [r.seconds for r in timed],
        first.length,
        first.expanded,
        detail,
        first.extra,
        [r.cpu_seconds for r in timed if r.cpu_seconds is not None],
        [r.planner_seconds for r in timed if r.planner_seconds is not None],
        [r.extra for r in timed],
        case.seed,
        # proved only when every timed run proved it
        None if first.optimal is None else all(r.optimal for r in timed),
        first.bound,
    )


def run_all(
    planners: Sequence[Planner],
    cases: dict[tuple[str, int], Case],
    demoplan_only: set[tuple[str, int]],
    root: Path,
    timeout: float,
    *,
    skip_after_timeout: bool,
    console: Console,
) -> dict[tuple[str, str, int], Result]:
    results: dict[tuple[str, str, int], Result] = {}
    timed_out: dict[tuple[str, str], int] = {}  # (planner, family) -> smallest N that timed out
    with console.status("") as status:
        for (family, n), case in sorted(cases.items(), key=lambda item: (item[0][0], item[0][1])):
            for planner in planners:
                key = (planner.key, family, n)
                if (family, n) in demoplan_only and planner.key != DEMOPLAN:
                    results[key] = Result(planner.key, family, n, "not run", detail="--quick")
                    continue
                if planner.max_objects is not None and n > planner.max_objects:
                    results[key] = Result(
                        planner.key, family, n, "not run", detail=f"N > {planner.max_objects}"
                    )
                    continue
                earlier = timed_out.get((planner.key, family))
                if skip_after_timeout and planner.key != DEMOPLAN and earlier is not None:
                    results[key] = Result(
                        planner.key, family, n, "skipped", detail=f"timed out at N = {earlier}"
                    )
                    continue
                status.update(f"{planner.label} on {family} N = {n} …")
                result = measure(planner, case, root, timeout)
                results[key] = result
                if result.status == "timeout":
                    timed_out.setdefault((planner.key, family), n)
                line = f"  {family:6} N={n:<3} {planner.label:22} {_time_text(result):>10}"
                if result.ok:
                    line += f"  length {result.length}  expanded {_number(result.expanded)}"
                if result.detail:
                    line += f"  ({result.detail})"
                console.print(line, highlight=False, markup=False, style="dim")
    return results


# --------------------------------------------------------------------------- verdicts


@dataclass(slots=True)
class Verdict:
    family: str
    n: int
    demoplan_length: int | None
    problems: list[str]  # plan-length bugs
    comparisons: int  # other planners' plans compared with demoplan's
    ratio_fd_opt: float | None  # FD optimal wall time / demoplan wall time
    ratio_fd_opt_cpu: float | None  # the same in CPU time (user + system)
    ratio_fd_opt_planner: float | None  # the same in planner time (no interpreter start-up)
    note: str


def verdicts(
    results: dict[tuple[str, str, int], Result],
    planners: Sequence[Planner],
    cases: Sequence[tuple[str, int]],
) -> list[Verdict]:
    labels = {p.key: p.label for p in planners}
    optimal = {p.key for p in planners if p.optimal}
    out = []
    for family, n in cases:
        ours = results[(DEMOPLAN, family, n)]
        problems = [
            f"BUG: {labels[p.key]} plan invalid ({r.detail})"
            for p in planners
            if (r := results[(p.key, family, n)]).status == "invalid"
        ]
        comparisons = 0
        finished = []
        for planner in planners:
            if planner.key == DEMOPLAN:
                continue
            theirs = results[(planner.key, family, n)]
            if not theirs.ok or theirs.length is None:
                continue
            finished.append(planner.key)
            if not ours.ok or ours.length is None:
                continue
            comparisons += 1
            if theirs.length < ours.length:
                problems.append(
                    f"BUG: {labels[planner.key]} found {theirs.length} < demoplan {ours.length}"
                )
            elif theirs.length > ours.length and planner.key in optimal:
                problems.append(
                    f"BUG: optimal {labels[planner.key]} found {theirs.length} "
                    f"> demoplan {ours.length}"
                )
        fd = results.get((FD_OPT, family, n))
        ratio = ratio_cpu = None
        if fd is not None and fd.ok and ours.ok and fd.median_s and ours.median_s:
            ratio = fd.median_s / ours.median_s
            if fd.median_cpu_s and ours.median_cpu_s:
                ratio_cpu = fd.median_cpu_s / ours.median_cpu_s
        ratio_planner = None
        if fd is not None and fd.ok and ours.ok and fd.median_planner_s and ours.median_planner_s:
            ratio_planner = fd.median_planner_s / ours.median_planner_s
        if ours.ok:
            note = f"compared with {', '.join(finished)}" if finished else "no other plan"
        else:
            note = f"demoplan {ours.status}"
            if finished:
                lengths = sorted({results[(k, family, n)].length or 0 for k in finished})
                note += f"; others found {'/'.join(map(str, lengths))}"
        out.append(
            Verdict(
                family,
                n,
                ours.length if ours.ok else None,
                problems,
                comparisons,
                ratio,
                ratio_cpu,
                ratio_planner,
                note,
            )
        )
    return out


def targets(
    results: dict[tuple[str, str, int], Result],
    planners: Sequence[Planner],
    families: Sequence[str],
    checks: Sequence[Verdict],
    timeout: float,
) -> list[Target]:
    optimal = [p for p in planners if p.optimal and p.key != DEMOPLAN]
    out = []

    bugs = [p for v in checks for p in v.problems]
    compared = sum(v.comparisons for v in checks)
    out.append(
        Target(
            "demoplan's plan never longer than another planner's; no optimal plan longer",
            (not bugs) if compared else None,
            f"{compared} comparison{'s' if compared != 1 else ''}, "
            f"{len(bugs)} disagreement{'s' if len(bugs) != 1 else ''}"
            + (": " + "; ".join(bugs) if bugs else ""),
        )
    )

    for n, limit in (TARGET_20, TARGET_30):
        parts = []
        passed = True
        measured = [f for f in families if (DEMOPLAN, f, n) in results]
        if not measured:
            out.append(
                Target(
                    f"Shortest plans for {n} objects in under {limit:g} s whole process",
                    None,
                    f"N = {n} not in this run",
                )
            )
            continue
        for family in families:
            ours = results.get((DEMOPLAN, family, n))
            if ours is None:
                parts.append(f"{family}: not measured")
                continue
            if not ours.ok or ours.median_s is None:
                shown = f"> {timeout:g} s" if ours.status == "timeout" else ours.status
                parts.append(f"{family}: {shown}")
                passed = False
                continue
            text = f"{family}: {ours.median_s:.3f} s"
            if ours.median_cpu_s is not None:
                text += f" (CPU {ours.median_cpu_s:.3f} s)"
            passed &= ours.median_s < limit
            agree = [
                p.label
                for p in optimal
                if (r := results.get((p.key, family, n))) is not None and r.ok
            ]
            lengths_agree = all(
                results[(p.key, family, n)].length == ours.length
                for p in optimal
                if results[(p.key, family, n)].ok
            )
            if not lengths_agree:
                passed = False
                text += " (an optimal planner disagrees on the length)"
            elif agree:
                text += f" (length {ours.length} = {', '.join(agree)})"
            else:
                text += f" (length {ours.length}; no optimal planner finished to confirm it)"
            parts.append(text)
        out.append(
            Target(
                f"Shortest plans for {n} objects in under {limit:g} s whole process",
                passed,
                "; ".join(parts),
            )
        )

    out.append(
        speedup_target(
            results,
            lambda r: r.median_s,
            f"At least {TARGET_SPEEDUP:g}{TIMES} faster than Fast Downward seq-opt-lmcut "
            "wherever it finishes",
            "",
        )
    )
    out.append(
        speedup_target(
            results,
            lambda r: r.median_planner_s,
            f"At least {TARGET_SPEEDUP:g}{TIMES} faster than Fast Downward seq-opt-lmcut "
            "in planner time (no interpreter start-up) wherever it finishes",
            " planner time",
        )
    )
    return out


def speedup_target(
    results: dict[tuple[str, str, int], Result],
    seconds: Callable[[Result], float | None],
    name: str,
    what: str,
) -> Target:
    """FD-optimal / demoplan in the time ``seconds`` picks, wherever FD-optimal finished."""
    ratios: list[float] = []
    failures: list[str] = []
    missing: list[str] = []
    count = 0
    for key, fd in sorted(results.items()):
        if key[0] != FD_OPT or not fd.ok or fd.median_s is None:
            continue
        count += 1
        ours = results[(DEMOPLAN, key[1], key[2])]
        if not ours.ok or ours.median_s is None:
            failures.append(f"{key[1]} N={key[2]}: FD finished, demoplan {ours.status}")
            continue
        theirs, mine = seconds(fd), seconds(ours)
        if not theirs or not mine:
            who = "FD" if not theirs else "demoplan"
            missing.append(f"{key[1]} N={key[2]} ({who}{what} not reported)")
            continue
        ratio = theirs / mine
        ratios.append(ratio)
        if ratio < TARGET_SPEEDUP:
            failures.append(f"{key[1]} N={key[2]}: {ratio:.1f}{TIMES}")
    if not count:
        detail = "Fast Downward's optimal configuration finished nowhere (or was not run)"
    else:
        detail = f"FD-optimal finished on {count} problem{'s' if count > 1 else ''}"
        if ratios:
            detail += (
                f"; FD-opt / demoplan{what} from {min(ratios):.1f}{TIMES} to "
                f"{max(ratios):.1f}{TIMES} (median {statistics.median(ratios):.1f}{TIMES})"
            )
        if failures:
            detail += "; short of 10" + TIMES + ": " + ", ".join(failures)
        if missing:
            detail += "; not measured: " + ", ".join(missing)
    passed: bool | None
    if failures:
        passed = False
    elif not count or missing:
        passed = None
    else:
        passed = True
    return Target(name, passed, detail)


# --------------------------------------------------------------------------- tables


def result_json(result: Result) -> dict[str, Any]:
    """One run's numbers as the saved JSON holds them, with its medians."""
    return {
        **asdict(result),
        "median_s": result.median_s,
        "median_cpu_s": result.median_cpu_s,
        "median_planner_s": result.median_planner_s,
    }


def format_seconds(seconds: float | None) -> str:
    if seconds is None:
        return "-"
    if seconds < 1.0:
        return f"{seconds * 1e3:.0f} ms"
    return f"{seconds:.2f} s"


def _number(value: int | None) -> str:
    return "-" if value is None else f"{value:,}"


def _time_text(result: Result) -> str:
    if result.ok:
        return format_seconds(result.median_s)
    return {"not run": "·", "skipped": "skipped"}.get(result.status, result.status)


def family_table(
    family: str,
    sizes: Sequence[int],
    cases: dict[tuple[str, int], Case],
    planners: Sequence[Planner],
    results: dict[tuple[str, str, int], Result],
    seed: int,
) -> Table:
    table = Table(
        title=f"{FAMILY_TITLES[family]} (seed {seed}): whole-process wall time (median), "
        "plan length, states expanded",
        title_justify="left",
    )
    table.add_column("N", justify="right", style="bold")
    table.add_column("PDDL\nactions", justify="right", style="dim")
    for planner in planners:
        table.add_column(f"{planner.label}\ntime", justify="right")
        table.add_column("len", justify="right")
        table.add_column("exp", justify="right", style="dim")
    for n in sizes:
        if (family, n) not in cases:
            continue
        row = [str(n), _number(cases[(family, n)].pddl_actions)]
        for planner in planners:
            result = results[(planner.key, family, n)]
            time_text = _time_text(result)
            if result.status == "timeout":
                time_text = f"[red]{time_text}[/red]"
            elif result.status in ("error", "no plan", "limit", "invalid"):
                time_text = f"[bold red]{time_text}[/bold red]"
            row += [
                time_text,
                str(result.length) if result.ok else "-",
                _number(result.expanded) if result.ok else "-",
            ]
        table.add_row(*row)
    return table


def fast_downward_table(
    results: dict[tuple[str, str, int], Result], planners: Sequence[Planner]
) -> Table | None:
    labels = {p.key: p.label for p in planners}
    rows = [
        r
        for r in results.values()
        if r.planner in (FD_OPT, FD_LAMA) and r.status in ("ok", "timeout")
    ]
    if not rows:
        return None
    table = Table(
        title="Fast Downward: where the wall time goes (one run; translator = its own "
        "wall-clock, search = the search component's)",
        title_justify="left",
    )
    for column in ("family", "N", "config", "whole process", "translator", "search", "share"):
        table.add_column(column, justify="left" if column in ("family", "config") else "right")
    for r in sorted(rows, key=lambda r: (r.family, r.n, r.planner)):
        whole = r.median_s
        translate = r.extra.get("translate_s")
        search = r.extra.get("search_s")
        share = "-"
        if r.ok and whole and translate is not None:
            share = f"{100 * translate / whole:.0f}% translating"
        elif r.status == "timeout":
            share = r.detail
        table.add_row(
            r.family,
            str(r.n),
            labels[r.planner],
            format_seconds(whole) if r.ok else "timeout",
            format_seconds(translate),
            format_seconds(search),
            share,
        )
    return table


def verdict_table(checks: Sequence[Verdict]) -> Table:
    table = Table(
        title="Verdicts: plan lengths against demoplan's, and FD-optimal / demoplan time "
        "(whole process and planner time)",
        title_justify="left",
    )
    table.add_column("family")
    table.add_column("N", justify="right")
    table.add_column("demoplan len", justify="right")
    table.add_column("plan lengths")
    table.add_column("FD-opt / demoplan\nwall", justify="right")
    table.add_column("FD-opt / demoplan\nCPU", justify="right", style="dim")
    table.add_column("FD-opt / demoplan\nplanner time", justify="right")
    table.add_column("note", style="dim")
    for v in checks:
        if v.problems:
            lengths = "[bold red]" + "; ".join(v.problems) + "[/bold red]"
        elif v.comparisons:
            lengths = "[green]OK[/green]"
        else:
            lengths = "-"
        ratio = "-" if v.ratio_fd_opt is None else f"{v.ratio_fd_opt:.1f}{TIMES}"
        ratio_cpu = "-" if v.ratio_fd_opt_cpu is None else f"{v.ratio_fd_opt_cpu:.1f}{TIMES}"
        ratio_planner = (
            "-" if v.ratio_fd_opt_planner is None else f"{v.ratio_fd_opt_planner:.1f}{TIMES}"
        )
        table.add_row(
            v.family,
            str(v.n),
            "-" if v.demoplan_length is None else str(v.demoplan_length),
            lengths,
            ratio,
            ratio_cpu,
            ratio_planner,
            v.note,
        )
    return table


# --------------------------------------------------------------------------- hard families

HARD_OPTIONS = {**PARKING_FAMILIES, **CROWDED_FAMILIES}
HARD_FAMILIES = tuple(HARD_OPTIONS)  # parking, -dense, -crowded; crowded-swaps, …
TARGET_FAMILIES = ("parking", "parking-dense")
"""The families issue 13's targets are judged on (designed, and failed by the
planner of the time, before the planner that meets them was written);
``parking-crowded`` runs beside them to show where the planner stops."""
HARD_TITLES = {
    "parking": "Parking (forced parking: swaps and 3-cycles, distractors on goal places, "
    "grasp collisions between neighbours)",
    "parking-dense": "Parking, dense (more cycles, distractors and blocking neighbours)",
    "parking-crowded": "Parking, crowded (most objects in cycles or on the grid, a grid "
    "barely larger than the objects; beyond the targets)",
    "crowded-swaps": "Crowded, swaps (nearly every object in a cycle, distractors on goal places)",
    "crowded-distractors": "Crowded, distractors (more distractors than cycles)",
    "crowded-stacks": "Crowded, stacks (parking-crowded with caps on a fifth of the objects)",
}
HARD_FULL_SIZES = (5, 10, 15, 20, 30)
PROOF_SIZES = 10
"""Target (c) counts the problems of at least this many objects (the issue's
10–30); N = 5 is run for target (d): Fast Downward's seq-opt-lmcut finishes
there (1–2 s) and nowhere from about 8 objects on within a minute."""
HARD_QUICK_SIZES = (10, 20)
HARD_FULL_SEEDS = tuple(range(8))
HARD_QUICK_SEEDS = tuple(range(4))
HARD_TIMEOUT, HARD_QUICK_TIMEOUT = 60.0, 20.0
ANSWER_LIMIT = 2.0  # s, whole process: demoplan's default budget and the targets' limit
SLOW_LIMIT = 2.5  # s, whole process: a demoplan run slower than this is reported as a bug
TARGET_PROVED = 0.9  # share of the problems proved shortest within ANSWER_LIMIT

HardKey = tuple[str, str, int, int]  # planner, family, N, seed


def make_hard_case(family: str, n: int, seed: int, root: Path) -> Case:
    """A parking problem of ``family``, as XML and as *lifted* PDDL (Fast Downward
    translates the lifted export much faster than the grounded one)."""
    problem = parking_problem(n, seed, **HARD_OPTIONS[family])
    folder = root / f"{family}-{n}-seed{seed}"
    folder.mkdir(parents=True, exist_ok=True)
    xml = folder / "problem.xml"
    save_problem(problem, xml)
    domain, pddl_problem = save_pddl(problem, folder / "pddl")
    schemas = domain.read_text(encoding="utf-8").count("(:action ")
    locations = len(problem.locations)
    return Case(family, n, xml, domain, pddl_problem, locations, schemas, problem, seed)


def hard_planners(base: Sequence[Planner]) -> list[Planner]:
    """demoplan with its defaults (anytime, 2 s from the process start), and Fast
    Downward's lama-first and seq-opt-lmcut from ``base`` where they were found."""
    fast_downward = [p for p in base if p.key in (FD_LAMA, FD_OPT)]
    return [DemoplanPlanner(demoplan_command(), None), *fast_downward]


def run_hard(
    planners: Sequence[Planner],
    cases: dict[tuple[str, int, int], Case],
    root: Path,
    timeout: float,
    *,
    skip_after_timeout: bool,
    console: Console,
) -> dict[HardKey, Result]:
    """Every planner on every case. A competitor that timed out on half or more of
    the seeds at some N is not run at larger N of that family (``skip_after_timeout``)."""
    results: dict[HardKey, Result] = {}
    seeds_at: dict[tuple[str, int], int] = {}
    for family, n, _ in cases:
        seeds_at[(family, n)] = seeds_at.get((family, n), 0) + 1
    timed_out: dict[tuple[str, str, int], int] = {}  # (planner, family, N) -> timeouts
    with console.status("") as status:
        for (family, n, seed), case in sorted(cases.items()):
            for planner in planners:
                key = (planner.key, family, n, seed)
                given_up = [
                    m
                    for (p, f, m), count in timed_out.items()
                    if p == planner.key and f == family and m < n and 2 * count >= seeds_at[(f, m)]
                ]
                if skip_after_timeout and planner.key != DEMOPLAN and given_up:
                    results[key] = Result(
                        planner.key,
                        family,
                        n,
                        "skipped",
                        detail=f"timed out on half or more of the seeds at N = {min(given_up)}",
                        seed=seed,
                    )
                    continue
                status.update(f"{planner.label} on {family} N = {n} seed {seed} …")
                result = measure(planner, case, root, timeout)
                results[key] = result
                if result.status == "timeout":
                    timed_out[(planner.key, family, n)] = (
                        timed_out.get((planner.key, family, n), 0) + 1
                    )
                line = (
                    f"  {family:13} N={n:<3} seed {seed}  {planner.label:9} "
                    f"{_time_text(result):>10}"
                )
                if result.ok:
                    line += f"  length {result.length}"
                    if result.optimal is not None:
                        line += " proved" if result.optimal else f" (bound {result.bound})"
                if result.detail:
                    line += f"  ({result.detail})"
                style = "bold red" if result.status in ("invalid", "error") else "dim"
                console.print(line, highlight=False, markup=False, style=style)
    return results


@dataclass(slots=True)
class HardRow:
    """One family and N of the hard benchmark, over its seeds."""

    family: str
    n: int
    problems: int
    answered: int  # demoplan: a plan within ANSWER_LIMIT, whole process (median of runs)
    proved: int  # ... and proved shortest
    lama_run: int
    lama_fast: int  # lama-first: a plan within ANSWER_LIMIT
    lama_finished: int  # lama-first: a plan within the timeout
    opt_run: int
    opt_finished: int  # seq-opt-lmcut: a plan within the timeout
    minus_lama: list[int] = field(default_factory=list)  # demoplan − lama length, both planned
    minus_opt: list[int] = field(default_factory=list)  # demoplan − FD-optimal length
    ratios: list[float] = field(default_factory=list)  # FD-opt / demoplan, whole process
    demoplan_s: list[float] = field(default_factory=list)  # every exit, median of its runs
    lama_s: list[float] = field(default_factory=list)  # finished runs
    opt_s: list[float] = field(default_factory=list)  # finished runs


def _ran(result: Result | None) -> bool:
    return result is not None and result.status not in ("skipped", "not run")


def _answered(result: Result, limit: float) -> bool:
    return result.ok and result.median_s is not None and result.median_s <= limit


def hard_rows(
    results: dict[HardKey, Result],
    cases: dict[tuple[str, int, int], Case],
    limit: float,
) -> list[HardRow]:
    rows: dict[tuple[str, int], HardRow] = {}
    for family, n, seed in sorted(cases):
        row = rows.setdefault((family, n), HardRow(family, n, 0, 0, 0, 0, 0, 0, 0, 0))
        row.problems += 1
        ours = results[(DEMOPLAN, family, n, seed)]
        lama = results.get((FD_LAMA, family, n, seed))
        opt = results.get((FD_OPT, family, n, seed))
        if _answered(ours, limit):
            row.answered += 1
            row.proved += bool(ours.optimal)
        if ours.median_s is not None and ours.status != "timeout":
            row.demoplan_s.append(ours.median_s)
        if lama is not None and _ran(lama):
            row.lama_run += 1
            if lama.ok and lama.median_s is not None:
                row.lama_finished += 1
                row.lama_fast += lama.median_s <= limit
                row.lama_s.append(lama.median_s)
                if ours.ok and ours.length is not None and lama.length is not None:
                    row.minus_lama.append(ours.length - lama.length)
        if opt is not None and _ran(opt):
            row.opt_run += 1
            if opt.ok and opt.median_s is not None:
                row.opt_finished += 1
                row.opt_s.append(opt.median_s)
                if ours.ok and ours.length is not None and opt.length is not None:
                    row.minus_opt.append(ours.length - opt.length)
                    if ours.median_s:
                        row.ratios.append(opt.median_s / ours.median_s)
    return list(rows.values())


def hard_bugs(
    results: dict[HardKey, Result],
    cases: dict[tuple[str, int, int], Case],
    planners: Sequence[Planner],
) -> list[str]:
    """Everything that can only be a bug: invalid plans, demoplan crashing, saying
    there is no plan where another planner found one, answering later than
    SLOW_LIMIT, a plan shorter than Fast Downward's optimal one, a wrong claim
    of optimality or a lower bound above a valid plan's length."""
    labels = {p.key: p.label for p in planners}
    bugs = []
    for family, n, seed in sorted(cases):
        where = f"{family} N={n} seed {seed}"
        mine = {p.key: results[(p.key, family, n, seed)] for p in planners}
        for key, result in mine.items():
            if result.status == "invalid":
                bugs.append(f"{where}: {labels[key]} {result.detail}")
        ours = mine[DEMOPLAN]
        if ours.status == "error":
            bugs.append(f"{where}: demoplan crashed ({ours.detail})")
        others = {k: r for k, r in mine.items() if k != DEMOPLAN and r.ok and r.length is not None}
        if ours.status == "no plan" and others:
            found = ", ".join(f"{labels[k]} {r.length}" for k, r in others.items())
            bugs.append(f"{where}: demoplan says no plan exists; {found} actions found")
        slow = [t for t in ours.times_s if t > SLOW_LIMIT]
        if slow:
            bugs.append(
                f"{where}: demoplan took {max(slow):.2f} s whole process "
                f"(over {SLOW_LIMIT:g} s; default budget {ANSWER_LIMIT:g} s)"
            )
        if not ours.ok or ours.length is None:
            continue
        if ours.bound is not None and ours.bound > ours.length:
            bugs.append(f"{where}: demoplan bound {ours.bound} > its own length {ours.length}")
        if ours.optimal and ours.bound is not None and ours.bound != ours.length:
            bugs.append(
                f"{where}: demoplan says proved shortest but bound {ours.bound} "
                f"!= length {ours.length}"
            )
        for key, theirs in others.items():
            assert theirs.length is not None
            if ours.bound is not None and ours.bound > theirs.length:
                bugs.append(
                    f"{where}: demoplan's lower bound {ours.bound} > {labels[key]}'s valid "
                    f"plan of {theirs.length}"
                )
            if key == FD_OPT:
                if ours.length < theirs.length:
                    bugs.append(
                        f"{where}: demoplan {ours.length} shorter than FD-optimal {theirs.length}"
                    )
                elif ours.optimal and ours.length != theirs.length:
                    bugs.append(
                        f"{where}: demoplan claims {ours.length} is shortest, "
                        f"FD-optimal found {theirs.length}"
                    )
        lama, opt = others.get(FD_LAMA), others.get(FD_OPT)
        if lama and opt and (lama.length or 0) < (opt.length or 0):
            bugs.append(f"{where}: lama-first {lama.length} shorter than FD-optimal {opt.length}")
    return bugs


def hard_targets(
    results: dict[HardKey, Result],
    cases: dict[tuple[str, int, int], Case],
    bugs: Sequence[str],
    limit: float,
    fd_found: bool,
) -> list[Target]:
    """Issue 13's targets for the hard families, and a line for the bugs."""
    keys = sorted(cases)
    total = len(keys)
    out = []

    def where(family: str, n: int, seed: int) -> str:
        return f"{family} N={n} seed {seed}"

    def listed(items: Sequence[str], most: int = 8) -> str:
        shown = ", ".join(items[:most])
        return shown + (f", and {len(items) - most} more" if len(items) > most else "")

    ours = {k: results[(DEMOPLAN, *k)] for k in keys}
    late = [
        f"{where(*k)} ({r.median_s:.2f} s)" if r.ok and r.median_s else f"{where(*k)} ({r.status})"
        for k, r in ours.items()
        if not _answered(r, limit)
    ]
    times = [r.median_s for r in ours.values() if r.median_s is not None]
    detail = f"{total - len(late)}/{total} answered within {limit:g} s"
    if times:
        within = sum(1 for r in ours.values() if _answered(r, SLOW_LIMIT))
        detail += (
            f" ({within}/{total} within {SLOW_LIMIT:g} s); whole-process median "
            f"{statistics.median(times):.2f} s, max {max(times):.2f} s"
        )
    if late:
        detail += "; not: " + listed(late)
    out.append(
        Target(
            f"(a) every problem answered within {limit:g} s whole process",
            not late if total else None,
            detail,
        )
    )

    longer, compared, missing = [], 0, []
    for k, r in ours.items():
        lama = results.get((FD_LAMA, *k))
        if lama is None or not lama.ok or lama.length is None:
            continue
        if not r.ok or r.length is None:
            missing.append(f"{where(*k)} (lama {lama.length}, demoplan {r.status})")
            continue
        compared += 1
        if r.length > lama.length:
            longer.append(f"{where(*k)} (+{r.length - lama.length}: {r.length} vs {lama.length})")
    detail = f"{compared} comparisons with lama-first's plan, longer on {len(longer)}"
    if longer:
        detail += ": " + listed(longer)
    if missing:
        detail += f"; lama planned, demoplan did not: {listed(missing)}"
    out.append(
        Target(
            "(b) plan never longer than lama-first's",
            (not longer and not missing) if compared or missing else None,
            detail,
        )
    )

    counted = {k: r for k, r in ours.items() if k[1] >= PROOF_SIZES}
    proved = sum(1 for r in counted.values() if _answered(r, limit) and r.optimal)
    share = proved / len(counted) if counted else 0.0
    out.append(
        Target(
            f"(c) at least {TARGET_PROVED:.0%} proved optimal within {limit:g} s "
            f"(N ≥ {PROOF_SIZES})",
            share >= TARGET_PROVED if counted else None,
            f"{proved}/{len(counted)} = {share:.0%}",
        )
    )

    for measure_name in ("whole process", "planner time"):
        out.append(_speedup_target(results, ours, limit, fd_found, measure_name))
    out.append(
        Target(
            "no planner bug (invalid plan, crash, demoplan shorter than FD-optimal, wrong "
            f"optimality claim or bound, run over {SLOW_LIMIT:g} s)",
            not bugs if total else None,
            f"{len(bugs)} found" + (": " + "; ".join(bugs) if bugs else ""),
        )
    )
    return out


def _speedup_target(
    results: dict[HardKey, Result],
    ours: dict[tuple[str, int, int], Result],
    limit: float,
    fd_found: bool,
    measure_name: str,
) -> Target:
    """Target (d) on whole-process time or on planner time (the time each
    planner reports for the problem, without interpreter start-up)."""

    def seconds(result: Result) -> float | None:
        return result.median_s if measure_name == "whole process" else result.median_planner_s

    ratios, short, finished = [], [], 0
    for (family, n, seed), r in ours.items():
        fd = results.get((FD_OPT, family, n, seed))
        if fd is None or not fd.ok or not seconds(fd):
            continue
        finished += 1
        where = f"{family} N={n} seed {seed}"
        mine, theirs = seconds(r), seconds(fd)
        if not _answered(r, limit) or not r.optimal or not mine or not theirs:
            short.append(f"{where} (demoplan did not prove it)")
            continue
        ratio = theirs / mine
        ratios.append(ratio)
        if ratio < TARGET_SPEEDUP:
            short.append(f"{where} ({ratio:.1f}{TIMES})")
    if not fd_found:
        detail = "Fast Downward not found"
    elif not finished:
        detail = "FD seq-opt-lmcut finished nowhere within its timeout (or was skipped)"
    else:
        detail = f"FD seq-opt-lmcut finished on {finished}/{len(ours)}"
        if ratios:
            detail += (
                f"; FD-opt / demoplan (proved) from {min(ratios):.1f}{TIMES} to "
                f"{max(ratios):.1f}{TIMES}, median {statistics.median(ratios):.1f}{TIMES}"
            )
        if short:
            shown = ", ".join(short[:8]) + (
                f", and {len(short) - 8} more" if len(short) > 8 else ""
            )
            detail += f"; short of {TARGET_SPEEDUP:g}{TIMES} or unproved: " + shown
    return Target(
        f"(d) at least {TARGET_SPEEDUP:g}{TIMES} faster than FD A*+LM-cut wherever it "
        f"finishes ({measure_name}; demoplan's plan proved optimal)",
        (not short) if finished else None,
        detail,
    )


def _share(count: int, total: int) -> str:
    return f"{count}/{total}" if total else "-"


def _signed(value: float) -> str:
    return f"+{value:g}" if value > 0 else f"{value:g}"


def _median_max(values: Sequence[int]) -> str:
    if not values:
        return "-"
    text = f"{_signed(statistics.median(values))} / {_signed(max(values))}"
    return f"[red]{text}[/red]" if max(values) > 0 else text


def _versus_optimal(row: HardRow) -> str:
    if not row.minus_opt:
        return "-"
    equal = sum(1 for d in row.minus_opt if d == 0)
    text = f"{equal}/{len(row.minus_opt)} equal"
    if any(d > 0 for d in row.minus_opt):
        text += f", max +{max(row.minus_opt)}"
    if any(d < 0 for d in row.minus_opt):
        text = f"[bold red]BUG: shorter ({min(row.minus_opt)}); {text}[/bold red]"
    return text


def _median_time(values: Sequence[float], finished: int, run: int) -> str:
    text = format_seconds(statistics.median(values)) if values else "-"
    return text if finished == run else f"{text} ({finished}/{run})"


def hard_table(family: str, rows: Sequence[HardRow], limit: float, timeout: float) -> Table:
    table = Table(
        title=f"{HARD_TITLES[family]}: demoplan (default, {limit:g} s budget) vs Fast Downward "
        "lama-first and seq-opt-lmcut, per N over its seeds",
        title_justify="left",
    )
    for name in (
        "N",
        "seeds",
        f"demoplan\nplan ≤ {limit:g} s",
        f"proved\nopt. ≤ {limit:g} s",
        f"lama\nplan ≤ {limit:g} s",
        f"lama\nplan ≤ {timeout:g} s",
        "demoplan − lama\nlength med / max",
        "demoplan vs\nFD-opt length",
        "demoplan time\nmedian (max)",
        "lama time\nmedian",
        "FD-opt time\nmedian",
        "FD-opt /\ndemoplan",
    ):
        table.add_column(name, justify="right")
    for row in rows:
        if row.family != family:
            continue
        demoplan_time = "-"
        if row.demoplan_s:
            demoplan_time = (
                f"{format_seconds(statistics.median(row.demoplan_s))} "
                f"({format_seconds(max(row.demoplan_s))})"
            )
        ratio = "-"
        if row.ratios:
            ratio = f"{statistics.median(row.ratios):.1f}{TIMES}"
            if len(row.ratios) > 1:
                ratio += f" ({min(row.ratios):.1f}–{max(row.ratios):.1f})"
        table.add_row(
            str(row.n),
            str(row.problems),
            _share(row.answered, row.problems),
            _share(row.proved, row.problems),
            _share(row.lama_fast, row.lama_run),
            _share(row.lama_finished, row.lama_run),
            _median_max(row.minus_lama),
            _versus_optimal(row),
            demoplan_time,
            _median_time(row.lama_s, row.lama_finished, row.lama_run),
            "skipped"
            if not row.opt_run
            else _median_time(row.opt_s, row.opt_finished, row.opt_run),
            ratio,
        )
    return table


def hard_document(
    cases: dict[tuple[str, int, int], Case],
    results: dict[HardKey, Result],
    rows: Sequence[HardRow],
    bugs: Sequence[str],
    goals: Sequence[Target],
    settings: dict[str, Any],
) -> dict[str, Any]:
    """The hard benchmark's part of the JSON file."""
    return {
        **settings,
        "cases": [
            {
                "family": c.family,
                "n": c.n,
                "seed": c.seed,
                "objects": len(c.generated.objects),
                "goal_objects": len(c.generated.goal),
                "locations": c.locations,
            }
            for c in cases.values()
        ],
        "results": [result_json(r) for r in results.values()],
        "rows": [asdict(row) for row in rows],
        "bugs": list(bugs),
        "targets": [asdict(t) for t in goals],
    }


# --------------------------------------------------------------------------- main


def _sizes(text: str) -> tuple[int, ...]:
    try:
        sizes = tuple(sorted({int(part) for part in text.split(",") if part.strip()}))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: comma-separated integers expected") from None
    if not sizes or min(sizes) < 1:
        raise argparse.ArgumentTypeError(f"{text!r}: positive integers expected")
    return sizes


def _seeds(text: str) -> tuple[int, ...]:
    """``0-7`` or ``0,3,5`` (or both: ``0-3,8``)."""
    seeds: set[int] = set()
    try:
        for part in (p.strip() for p in text.split(",")):
            if not part:
                continue
            first, _, last = part.partition("-")
            seeds.update(range(int(first), int(last or first) + 1))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: seeds like 0-7 or 0,3,5 expected") from None
    if not seeds or min(seeds) < 0:
        raise argparse.ArgumentTypeError(f"{text!r}: non-negative seeds expected")
    return tuple(sorted(seeds))


ALL_FAMILIES = (*FAMILIES, *HARD_FAMILIES)


# --------------------------------------------------------------------------- limits

LIMIT_OBJECTS = 1000
LIMIT_RUNS = (
    ("--timeout 0", ("--timeout", "0")),
    ("--max-nodes 1", ("--max-nodes", "1", "--timeout", "inf")),
)
LIMIT_TARGET_SECONDS = 1.0


LIMIT_MEMORY_MB = 500.0


def peak_memory_mb(command: list[str], folder: Path) -> float:
    """The peak resident memory of ``command``'s own process (MB), from
    ``os.wait4`` on it: ``RUSAGE_CHILDREN`` would give the largest child this
    benchmark ever waited for."""
    process = subprocess.Popen(
        command, cwd=folder, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    _, _, usage = os.wait4(process.pid, 0)
    return usage.ru_maxrss / 1024


def limit_timings(root: Path, console: Console, repeats: int = 3) -> dict[str, Any]:
    """``solve`` of the 1,000-object ring under each of :data:`LIMIT_RUNS`
    (whole process, median of ``repeats``), and the cost of reading the limits."""
    path = root / "ring-1000.xml"
    save_problem(ring_problem(LIMIT_OBJECTS), path)
    table = Table(title=f"Limits inside the work: solve of a {LIMIT_OBJECTS:,}-object ring")
    for column in ("options", "exit", "answer", "median s (whole process)", "runs s"):
        table.add_column(column)
    rows = []
    medians: list[tuple[str, float]] = []
    for name, options in LIMIT_RUNS:
        runs = [
            run_process([*demoplan_command(), "solve", str(path), *options], root, 120.0)
            for _ in range(repeats)
        ]
        seconds = [run.seconds for run in runs]
        medians.append((name, statistics.median(seconds)))
        last = runs[-1]
        rows.append(
            {
                "options": name,
                "returncode": last.returncode,
                "answer": _last_line(last.stderr),
                "median_s": statistics.median(seconds),
                "runs_s": seconds,
            }
        )
        table.add_row(
            name,
            str(last.returncode),
            _last_line(last.stderr)[:90],
            f"{statistics.median(seconds):.2f}",
            ", ".join(f"{s:.2f}" for s in seconds),
        )
    console.print(table)
    to_the_end = [*demoplan_command(), "solve", str(path), "--timeout", "inf"]
    peak_mb = [peak_memory_mb(to_the_end, root) for _ in range(repeats)]
    console.print(
        f"Peak memory of solve --timeout inf on {LIMIT_OBJECTS:,} objects (to the end, "
        f"os.wait4's ru_maxrss): {', '.join(f'{mb:.0f}' for mb in peak_mb)} MB",
        highlight=False,
    )
    cost = clock_read_cost()
    console.print(
        f"Reading the limits: {cost['reads']:,} clock reads in one solve of crowded-stacks "
        f"N = 20 ({cost['solve_s']:.2f} s), {1e9 * cost['read_s']:.0f} ns each: "
        f"{100 * cost['share']:.2f} % of the solve",
        highlight=False,
    )
    targets = [
        Target(
            f"solve {name} on {LIMIT_OBJECTS:,} objects answers in under "
            f"{LIMIT_TARGET_SECONDS:g} s (whole process, median)",
            median < LIMIT_TARGET_SECONDS,
            f"{median:.2f} s",
        )
        for name, median in medians
    ]
    targets.append(
        Target(
            f"solve --timeout inf on {LIMIT_OBJECTS:,} objects peaks under "
            f"{LIMIT_MEMORY_MB:g} MB (the largest of {repeats} runs)",
            max(peak_mb) < LIMIT_MEMORY_MB,
            f"{max(peak_mb):.0f} MB",
        )
    )
    print_targets(console, targets)
    return {"runs": rows, "clock_reads": cost, "targets": [asdict(t) for t in targets]}


def startup(root: Path, console: Console) -> dict[str, Any]:
    """The start-up figure (:mod:`planning_startup`) on three small problems."""
    problems = {
        "the paper's example": load_problem(REPO / "examples/planning/paper-example.xml"),
        "table 7": table_problem(7, 0),
        "parking 10": parking_problem(10, 0, **PARKING_FAMILIES["parking"]),
    }
    found, targets = startup_timings(
        root, console, problems, demoplan_command(), _child_environment
    )
    print_targets(console, targets)
    return {**found, "targets": [asdict(t) for t in targets]}


def proofs(console: Console) -> dict[str, Any]:
    """The share of crowded tables proved shortest within 10 s (:mod:`planning_proof`)."""

    def make(family: str, n: int, seed: int) -> Problem:
        return parking_problem(n, seed, **HARD_OPTIONS[family])

    found, targets = proof_benchmark(make, console)
    print_targets(console, targets)
    return {**found, "targets": [asdict(t) for t in targets]}


def clock_read_cost() -> dict[str, float]:
    """Clock reads (``Clock.stop``, ``Clock.expired``) counted during one solve of
    crowded-stacks N = 20, seed 2 (not proved within it), and the time of one read."""
    import timeit

    from demoplan.budget import Budget, Clock
    from demoplan.planning.search import solve

    problem = parking_problem(20, 2, **CROWDED_FAMILIES["crowded-stacks"])
    reads = 0
    stop, expired = Clock.stop, Clock.expired

    def counted_stop(self: Clock, expanded: int, states: int = 0) -> str | None:
        nonlocal reads
        reads += 1
        return stop(self, expanded, states)

    def counted_expired(self: Clock) -> bool:
        nonlocal reads
        reads += 1
        return expired(self)

    Clock.stop, Clock.expired = counted_stop, counted_expired  # type: ignore[method-assign]
    try:
        started = time.perf_counter()
        with contextlib.suppress(DemoplanError):
            solve(problem, budget=Budget(timeout=2.0))
        solve_s = time.perf_counter() - started
    finally:
        Clock.stop, Clock.expired = stop, expired  # type: ignore[method-assign]
    clock = Clock(Budget(timeout=600.0))
    read_s = timeit.timeit(lambda: clock.stop(0, 0), number=1_000_000) / 1_000_000
    return {"reads": reads, "solve_s": solve_s, "read_s": read_s, "share": reads * read_s / solve_s}


def parse_args(argv: Sequence[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        description="Benchmark demoplan solve against Fast Downward and pyperplan "
        "(whole-process wall time, plan length, expanded states), and on the hard "
        "parking families against Fast Downward alone (coverage within 2 s, proofs).",
    )
    parser.add_argument(
        "--quick",
        action="store_true",
        help=f"N <= 7 (demoplan also at N = 20, 30) with a {QUICK_TIMEOUT:g} s timeout; "
        f"hard families at N = 10, 20, seeds 0-3, {HARD_QUICK_TIMEOUT:g} s timeout",
    )
    parser.add_argument("--out", type=Path, help="also save the results to this JSON file")
    parser.add_argument(
        "--limits",
        action="store_true",
        help="only the limits inside the work: solve of a 1,000-object ring with --timeout 0 "
        "and --max-nodes 1, and the cost of reading the clock",
    )
    parser.add_argument(
        "--startup",
        action="store_true",
        help="only the start-up: demoplan solve of small problems against python -c pass",
    )
    parser.add_argument(
        "--proof",
        action="store_true",
        help=f"only the proofs: in-process solve with a {PROOF_SECONDS:g} s budget on the four "
        "crowded families at N = 10, 20 on three seed sets, the share proved shortest",
    )
    parser.add_argument(
        "--seed", type=int, default=0, help="seed of the table and blocks problems (default 0)"
    )
    parser.add_argument(
        "--seeds",
        type=_seeds,
        help="seeds of the hard families, e.g. 0-7 (default 0-7; 0-3 with --quick)",
    )
    parser.add_argument(
        "--timeout",
        type=float,
        help=f"seconds per run (default {DEFAULT_TIMEOUT:g}, {QUICK_TIMEOUT:g} with --quick; "
        f"hard families {HARD_TIMEOUT:g}, {HARD_QUICK_TIMEOUT:g} with --quick)",
    )
    parser.add_argument(
        "--sizes", type=_sizes, help="comma-separated N for every family chosen, e.g. 3,5,10"
    )
    parser.add_argument(
        "--families",
        default=",".join(ALL_FAMILIES),
        help=f"comma-separated problem families ({', '.join(ALL_FAMILIES)}; default all)",
    )
    parser.add_argument("--fd", type=Path, help="path of Fast Downward's fast-downward.py")
    parser.add_argument(
        "--fd-translate-options",
        metavar="OPTIONS",
        help="extra options for Fast Downward's translator, e.g. "
        "--fd-translate-options='--invariant-generation-max-candidates 0' (one string, "
        "split on spaces; use '=')",
    )
    parser.add_argument("--pyperplan", type=Path, help="path of the pyperplan script")
    parser.add_argument(
        "--no-skip",
        action="store_true",
        help="run a competitor at every N even after it timed out at a smaller one",
    )
    parser.add_argument(
        "--keep",
        type=Path,
        metavar="DIR",
        help="write the generated problems (XML, PDDL) into DIR and keep them",
    )
    args = parser.parse_args(argv)
    families = [f.strip() for f in args.families.split(",") if f.strip()]
    unknown = [f for f in families if f not in ALL_FAMILIES]
    if unknown or not families:
        parser.error(f"--families: {unknown or 'none'}; one or more of {', '.join(ALL_FAMILIES)}")
    alone = args.limits or args.startup or args.proof
    args.families = [f for f in families if f in FAMILIES] if not alone else []
    args.hard_families = [f for f in families if f in HARD_FAMILIES] if not alone else []
    if args.timeout is not None and args.timeout <= 0:
        parser.error("--timeout must be positive")
    args.hard_timeout = args.timeout or (HARD_QUICK_TIMEOUT if args.quick else HARD_TIMEOUT)
    args.timeout = args.timeout or (QUICK_TIMEOUT if args.quick else DEFAULT_TIMEOUT)
    args.hard_sizes = args.sizes or (HARD_QUICK_SIZES if args.quick else HARD_FULL_SIZES)
    args.seeds = args.seeds or (HARD_QUICK_SEEDS if args.quick else HARD_FULL_SEEDS)
    return args


def competitors(args: argparse.Namespace) -> tuple[list[Planner], list[str]]:
    """Fast Downward (seq-opt-lmcut, lama-first) and pyperplan where found, and
    what was found or skipped."""
    planners: list[Planner] = []
    messages = []
    fast_downward = find_fast_downward(args.fd)
    if isinstance(fast_downward, str):
        messages.append(f"Skipping Fast Downward: {fast_downward}")
    else:
        python, driver = fast_downward
        options = args.fd_translate_options.split() if args.fd_translate_options else []
        suffix = " (opts)" if options else ""
        for alias, key, label in (
            ("seq-opt-lmcut", FD_OPT, "FD opt"),
            ("lama-first", FD_LAMA, "FD lama"),
        ):
            planners.append(
                FastDownwardPlanner(python, driver, alias, key, label + suffix, options)
            )
        messages.append(
            f"Fast Downward: {driver} (run with {python}; --alias seq-opt-lmcut, lama-first"
            + (f"; --translate-options {' '.join(options)}" if options else "")
            + ")"
        )
    if args.families:  # pyperplan only runs on the table and blocks families
        pyperplan = find_pyperplan(args.pyperplan)
        if isinstance(pyperplan, str):
            messages.append(f"Skipping pyperplan: {pyperplan}")
        else:
            script, heuristic = pyperplan
            planners.append(PyperplanPlanner(script, heuristic))
            version = _distribution_version(script, "pyperplan")
            messages.append(f"pyperplan {version}: {script} (-s astar -H {heuristic})")
    return planners, messages


def main(argv: Sequence[str] | None = None) -> int:
    args = parse_args(argv)
    console = Console(width=None if sys.stdout.isatty() else 200)
    started = time.perf_counter()
    sizes: tuple[int, ...] = args.sizes or (QUICK_SIZES if args.quick else FULL_SIZES)
    demoplan_only_sizes = (
        tuple(n for n in QUICK_DEMOPLAN_ONLY if n not in sizes)
        if args.quick and not args.sizes
        else ()
    )
    all_sizes = tuple(sorted({*sizes, *demoplan_only_sizes}))

    others, messages = competitors(args)
    planners: list[Planner] = [
        DemoplanPlanner(demoplan_command(), "astar"),
        DemoplanPlanner(demoplan_command(), "bfs"),
        *others,
    ]
    runs = []
    if args.families:
        runs.append(
            f"families {', '.join(args.families)} at N = {', '.join(map(str, sizes))}"
            + (
                f" (demoplan also at {', '.join(map(str, demoplan_only_sizes))})"
                if demoplan_only_sizes
                else ""
            )
            + f", seed {args.seed}, timeout {args.timeout:g} s per run"
        )
    if args.hard_families:
        runs.append(
            f"hard families {', '.join(args.hard_families)} at N = "
            f"{', '.join(map(str, args.hard_sizes))}, seeds {_seed_text(args.seeds)}, "
            f"timeout {args.hard_timeout:g} s per run"
        )
    if args.proof:
        runs.append(
            f"proofs: in-process solve, {PROOF_SECONDS:g} s each, crowded families at "
            "N = 10, 20 on three seed sets"
        )
    console.print(
        f"demoplan planning benchmark — {'quick' if args.quick else 'full'} run: "
        + "; ".join(runs)
        + f"; Python {platform.python_version()}, {platform.machine()}, {os.cpu_count()} CPUs",
        highlight=False,
    )
    console.print(
        f"demoplan {demoplan.__version__} from {Path(demoplan.__file__).parent}, "
        f"run as: {' '.join(demoplan_command())} solve PROBLEM.xml --json",
        highlight=False,
    )
    for message in messages:
        console.print(message, highlight=False, style="yellow" if "Skipping" in message else None)

    document: dict[str, Any] = {
        "benchmark": "demoplan planning",
        "run": "quick" if args.quick else "full",
        "seed": args.seed,
        "timeout_s": args.timeout,
        "sizes": list(sizes) if args.families else [],
        "demoplan_only_sizes": list(demoplan_only_sizes) if args.families else [],
        "families": args.families,
        "python": platform.python_version(),
        "machine": platform.machine(),
        "cpus": os.cpu_count(),
        "planners": [{"key": p.key, "label": p.label, "optimal": p.optimal} for p in planners],
        "messages": messages,
        "cases": [],
        "results": [],
        "verdicts": [],
        "targets": [],
    }
    keep = contextlib.nullcontext(str(args.keep)) if args.keep is not None else None
    with keep or tempfile.TemporaryDirectory(prefix="demoplan-planning-bench-") as temporary:
        root = Path(temporary)
        root.mkdir(parents=True, exist_ok=True)
        if args.families:
            document.update(
                classic_benchmark(
                    args, planners, sizes, demoplan_only_sizes, all_sizes, root, console
                )
            )
        if args.hard_families:
            document["hard"] = hard_benchmark(args, planners, root, console)
        if args.proof:
            document["proof"] = proofs(console)
        if not args.startup and not args.proof:
            document["limits"] = limit_timings(root, console)
        if not args.limits and not args.proof:
            document["startup"] = startup(root, console)
    total = time.perf_counter() - started
    console.print(f"Total benchmark time: {total:.1f} s")
    document["total_s"] = total
    if args.out is not None:
        args.out.write_text(json.dumps(document, indent=2) + "\n", encoding="utf-8")
        console.print(f"Results saved to {args.out}")
    return 0


def _seed_text(seeds: Sequence[int]) -> str:
    if len(seeds) > 2 and list(seeds) == list(range(seeds[0], seeds[-1] + 1)):
        return f"{seeds[0]}–{seeds[-1]}"
    return ", ".join(map(str, seeds))


def classic_benchmark(
    args: argparse.Namespace,
    planners: Sequence[Planner],
    sizes: tuple[int, ...],
    demoplan_only_sizes: tuple[int, ...],
    all_sizes: tuple[int, ...],
    root: Path,
    console: Console,
) -> dict[str, Any]:
    """The table and blocks families: run, print the tables and targets, and
    return their part of the JSON file."""
    cases = {
        (family, n): make_case(family, n, args.seed, root)
        for family in args.families
        for n in all_sizes
    }
    demoplan_only = {(f, n) for f in args.families for n in demoplan_only_sizes}
    # Warm-up, untimed: byte-compiled caches, the page cache.
    run_process(
        [*demoplan_command(), "solve", str(cases[(args.families[0], all_sizes[0])].xml)],
        root,
        args.timeout,
    )
    results = run_all(
        planners,
        cases,
        demoplan_only,
        root,
        args.timeout,
        skip_after_timeout=not args.no_skip,
        console=console,
    )

    for family in args.families:
        console.print(family_table(family, all_sizes, cases, planners, results, args.seed))
    console.print(
        "time: whole process, median of 3 runs when under 1 s; 'timeout': killed at "
        f"{args.timeout:g} s; 'skipped': timed out at a smaller N; '·': not run. "
        "exp: states expanded — demoplan A* expands moves (GRASP + PUT_DOWN), the others "
        "primitive actions' states.",
        highlight=False,
        style="dim",
    )
    labels = {p.key: p.label for p in planners}
    for r in results.values():
        if r.detail and r.status not in ("not run", "skipped", "timeout"):
            console.print(
                f"Note: {labels[r.planner]} on {r.family} N = {r.n} ({r.status}): {r.detail}",
                style="bold red" if r.status in ("invalid", "error") else "yellow",
                highlight=False,
                markup=False,
            )
    fd_table = fast_downward_table(results, planners)
    if fd_table is not None:
        console.print(fd_table)

    ordered = [(f, n) for f in args.families for n in all_sizes]
    checks = verdicts(results, planners, ordered)
    console.print(verdict_table(checks))
    console.print(
        "wall / CPU: whole process (interpreter start-up included). planner time: what the "
        "planners report for the problem itself — demoplan read_seconds + seconds (reading "
        "and checking the XML, search); Fast Downward translator wall-clock + the search "
        "component's Total time (Search time if absent) — medians over the same runs.",
        highlight=False,
        style="dim",
    )
    goals = targets(results, planners, args.families, checks, args.timeout)
    print_targets(console, goals)
    return {
        "cases": [
            {
                "family": c.family,
                "n": c.n,
                "locations": c.locations,
                "pddl_actions": c.pddl_actions,
            }
            for c in cases.values()
        ],
        "results": [result_json(r) for r in results.values()],
        "verdicts": [asdict(v) for v in checks],
        "targets": [asdict(t) for t in goals],
    }


def hard_benchmark(
    args: argparse.Namespace, base: Sequence[Planner], root: Path, console: Console
) -> dict[str, Any]:
    """The hard (parking) families: generate, run, print the tables, bugs and
    targets, and return their part of the JSON file."""
    planners = hard_planners(base)
    cases: dict[tuple[str, int, int], Case] = {}
    with console.status("Generating the hard problems …"):
        for family in args.hard_families:
            for n in args.hard_sizes:
                for seed in args.seeds:
                    cases[(family, n, seed)] = make_hard_case(family, n, seed, root)
    console.print(
        f"Hard families: {len(cases)} problems written as XML and lifted PDDL; planners: "
        + ", ".join(p.label for p in planners),
        highlight=False,
    )
    first = next(iter(cases.values()))
    run_process([*demoplan_command(), "solve", str(first.xml)], root, args.hard_timeout)  # warm-up
    results = run_hard(
        planners,
        cases,
        root,
        args.hard_timeout,
        skip_after_timeout=not args.no_skip,
        console=console,
    )
    rows = hard_rows(results, cases, ANSWER_LIMIT)
    for family in args.hard_families:
        console.print(hard_table(family, rows, ANSWER_LIMIT, args.hard_timeout))
    console.print(
        f"plan ≤ {ANSWER_LIMIT:g} s: a plan within {ANSWER_LIMIT:g} s whole process (median of "
        "3 runs when under 1 s, else one run); proved opt.: and demoplan proved it shortest. "
        f"lama plan ≤ {args.hard_timeout:g} s: within the timeout. demoplan − lama: plan "
        "lengths where both planned (negative: demoplan shorter). vs FD-opt: demoplan's "
        "length equal to the optimal one found by FD seq-opt-lmcut, where it finished. "
        "Times: whole process, medians over the seeds — demoplan's over every run, "
        "Fast Downward's over the finished ones (finished/run when not all). FD-opt / "
        "demoplan: whole-process time ratio, median (min–max), where FD-opt finished. "
        "'skipped': timed out on half or more of the seeds at a smaller N.",
        highlight=False,
        style="dim",
    )
    bugs = hard_bugs(results, cases, planners)
    for bug in bugs:
        console.print(f"BUG: {bug}", style="bold red", highlight=False, markup=False)
    judged = {k: case for k, case in cases.items() if k[0] in TARGET_FAMILIES}
    fd_opt = any(p.key == FD_OPT for p in planners)
    goals = hard_targets(results, judged, bugs, ANSWER_LIMIT, fd_opt)
    print_targets(console, goals)
    beyond = [
        beyond_the_targets(family, results, cases, ANSWER_LIMIT)
        for family in args.hard_families
        if family not in TARGET_FAMILIES
    ]
    for line in beyond:
        console.print(line, highlight=False, markup=False, style="bold")
    settings = {
        "families": args.hard_families,
        "sizes": list(args.hard_sizes),
        "seeds": list(args.seeds),
        "timeout_s": args.hard_timeout,
        "answer_limit_s": ANSWER_LIMIT,
        "pddl": "lifted",
        "planners": [{"key": p.key, "label": p.label} for p in planners],
    }
    document = hard_document(cases, results, rows, bugs, goals, settings)
    document["beyond_the_targets"] = beyond
    return document


def beyond_the_targets(
    family: str,
    results: dict[HardKey, Result],
    cases: dict[tuple[str, int, int], Case],
    limit: float,
) -> str:
    """The targets' figures for a family they are not judged on."""
    keys = [k for k in sorted(cases) if k[0] == family]
    ours = [results[(DEMOPLAN, *k)] for k in keys]
    answered = sum(1 for r in ours if _answered(r, limit))
    proved = sum(1 for r in ours if _answered(r, limit) and r.optimal)
    longer = compared = 0
    for k, r in zip(keys, ours, strict=True):
        lama = results.get((FD_LAMA, *k))
        if lama is not None and lama.ok and lama.length is not None and r.length is not None:
            compared += 1
            longer += r.length > lama.length
    return (
        f"Beyond the targets, {family}: {answered}/{len(keys)} answered with a plan within "
        f"{limit:g} s, {proved}/{len(keys)} proved shortest, longer than lama-first's plan "
        f"on {longer} of {compared} comparisons"
    )


if __name__ == "__main__":
    sys.exit(main())
