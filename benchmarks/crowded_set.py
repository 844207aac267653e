"""The lama-first comparison set (issue 44): crowded tables, hardest cases checked in.

What it does
------------
Draws crowded tables — :func:`tests.support.planning_families.parking_problem`
with the settings of ``PARKING_FAMILIES`` (``parking``, ``parking-dense``,
``parking-crowded``) and ``CROWDED_FAMILIES`` (``crowded-swaps``,
``crowded-distractors``, ``crowded-stacks``: parking forced by swaps *and*
distractors, caps stacked on objects) — of 10–40 objects, and for each:

1. demoplan's first plan, in-process: the greedy phase
   (:func:`demoplan.planning.greedy.greedy_moves`, shortened) with a count of
   expansions, ``GREEDY_NODES``, and no time limit, so that the answer is the
   same on any machine — the anytime search never returns a plan longer than
   its first one, whatever its budget (a later phase only keeps a shorter
   plan), so this is the longest plan ``demoplan solve`` can answer once the
   greedy phase has finished;
2. Fast Downward's ``--alias lama-first`` on the lifted PDDL export (whole
   run, ``--lama-timeout``, 120 s), its plan checked with
   :func:`demoplan.planning.strips.validate`. Its results are cached in
   ``--cache`` (a JSON-lines file: lama-first takes tens of seconds on 20
   crowded objects under load) and reused on the next run.

Then it keeps the hardest: the draws where demoplan's plan is longest
relative to lama-first's (the ratio of the lengths, highest first; a draw
lama-first did not plan within its timeout ranks last), ``--keep`` per family,
and writes them to ``tests/data/planning/crowded/`` (``--out``): per case
``NAME.xml`` (the paper's XML, which demoplan reads), ``NAME.domain.pddl`` and
``NAME.problem.pddl`` (the lifted export, which Fast Downward reads), and one
``cases.json`` with, per case, the family, size and seed, lama-first's plan
length and time, and demoplan's length and bound under the counted budget
when the set was made (lama-first's length is run afresh for the cases
kept). ``tests/planning/test_crowded_set.py`` checks that demoplan's first
plan is never longer than the stored lama-first length.

How to run
----------
From the repository root, Fast Downward in ``/tmp/upvenv``
(``python -m venv /tmp/upvenv && /tmp/upvenv/bin/pip install up-fast-downward``)::

    python benchmarks/crowded_set.py                       # the checked-in set
    python benchmarks/crowded_set.py --sizes 10,20 --seeds 0:3 --out /tmp/set
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:
    sys.path.insert(1, str(REPO))

from tests.support.planning_families import (  # noqa: E402
    CROWDED_FAMILIES,
    PARKING_FAMILIES,
    parking_problem,
)

from demoplan.budget import Budget, Clock  # noqa: E402
from demoplan.planning.bounds import LowerBounds  # noqa: E402
from demoplan.planning.compiled import compile_problem  # noqa: E402
from demoplan.planning.greedy import greedy_moves  # noqa: E402
from demoplan.planning.pddl import action_from_pddl, problem_to_pddl  # noqa: E402
from demoplan.planning.problem import Problem  # noqa: E402
from demoplan.planning.strips import validate  # noqa: E402
from demoplan.planning.xml import problem_to_xml  # noqa: E402

FAMILIES = {**PARKING_FAMILIES, **CROWDED_FAMILIES}
GREEDY_NODES = 5_000
"""Expansions the greedy search may make (tests/planning/test_crowded_set.py
uses the same): a hang guard, far above what a plan of these sizes needs (the
search expands about one state per move of its plan, at most a few hundred
here); reaching it would leave no plan and fail the test."""
UPVENV = Path("/tmp/upvenv")


@dataclass(frozen=True, slots=True)
class Case:
    """One draw, planned by both."""

    name: str
    family: str
    n: int
    seed: int
    lama: int | None  # lama-first's plan length; None: no plan within its timeout
    lama_seconds: float
    demoplan: int  # its first plan's length (the greedy phase's)
    root_bound: int  # the start's lower bound


def draw(family: str, n: int, seed: int) -> Problem | None:
    """The draw of ``family`` with ``n`` objects and ``seed`` — the same as
    ``benchmarks/planning.py``'s, so that its hard-family run includes the
    set — None where the family draws none."""
    try:
        return parking_problem(n, seed, **FAMILIES[family])
    except ValueError:
        return None


def first_plan(problem: Problem) -> tuple[int, int]:
    """demoplan's first plan's length (the greedy phase's, counted) and the
    start's lower bound, in actions."""
    compiled = compile_problem(problem)
    bounds = LowerBounds(compiled)
    moves = greedy_moves(compiled, bounds, Clock(Budget(max_nodes=GREEDY_NODES)))
    if moves is None:
        raise SystemExit(f"{problem.name}: no greedy plan within {GREEDY_NODES} expansions")
    return 2 * len(moves), 2 * bounds.estimate(compiled.start, compiled.start_reached)


def lama_first(problem: Problem, timeout: float) -> tuple[int | None, float]:
    """lama-first's plan length on the lifted export (None: no plan in time)
    and its whole run's seconds."""
    drivers = sorted(UPVENV.glob("lib/python*/site-packages/up_fast_downward/downward/*.py"))
    driver = next((d for d in drivers if d.name == "fast-downward.py"), None)
    if driver is None:
        raise SystemExit(f"Fast Downward not found in {UPVENV} (pip install up-fast-downward)")
    domain, task = problem_to_pddl(problem)
    with tempfile.TemporaryDirectory() as folder:
        Path(folder, "domain.pddl").write_text(domain)
        Path(folder, "problem.pddl").write_text(task)
        started = time.perf_counter()
        command = [str(UPVENV / "bin" / "python"), str(driver), "--alias", "lama-first"]
        # Its own process group: the driver's search process is killed with it.
        run = subprocess.Popen(
            [*command, "domain.pddl", "problem.pddl"],
            cwd=folder,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,
        )
        try:
            run.wait(timeout)
        except subprocess.TimeoutExpired:
            os.killpg(run.pid, signal.SIGKILL)
            run.wait()
            return None, time.perf_counter() - started
        seconds = time.perf_counter() - started
        plan = Path(folder, "sas_plan")
        if not plan.exists():
            return None, seconds
        lines = [line.strip() for line in plan.read_text().splitlines()]
        actions = [action_from_pddl(problem, line) for line in lines if line and line[0] != ";"]
    validate(problem, actions)
    return len(actions), seconds


def cached_lama(cache: Path) -> dict[tuple[str, int, int], tuple[int | None, float]]:
    """lama-first's results kept from earlier runs."""
    found: dict[tuple[str, int, int], tuple[int | None, float]] = {}
    if cache.exists():
        for line in cache.read_text().splitlines():
            row = json.loads(line)
            if row.get("alias", "lama-first") == "lama-first":
                length = row["length"] if isinstance(row["length"], int) else None
                found[row["family"], row["n"], row["seed"]] = (length, row["seconds"])
    return found


def plan_case(
    family: str, n: int, seed: int, cache: Path, timeout: float
) -> tuple[Case, Problem] | None:
    """Both planners on one draw (lama-first from the cache where it is there)."""
    problem = draw(family, n, seed)
    if problem is None:
        return None
    known = cached_lama(cache).get((family, n, seed))
    if known is None:
        known = lama_first(problem, timeout)
        with cache.open("a") as stream:
            row = {"family": family, "n": n, "seed": seed, "alias": "lama-first"}
            stream.write(json.dumps({**row, "length": known[0], "seconds": known[1]}) + "\n")
    name = f"{family}-{n}-s{seed}"
    return Case(name, family, n, seed, *known, *first_plan(problem)), problem


def hardness(case: Case) -> float:
    """demoplan's length over lama-first's (0 where lama-first has no plan)."""
    return 0.0 if case.lama is None else case.demoplan / case.lama


def write_set(chosen: list[tuple[Case, Problem]], out: Path) -> None:
    """The cases' files and ``cases.json`` in ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    for case, problem in chosen:
        domain, task = problem_to_pddl(problem)
        Path(out, f"{case.name}.xml").write_text(problem_to_xml(problem))
        Path(out, f"{case.name}.domain.pddl").write_text(domain)
        Path(out, f"{case.name}.problem.pddl").write_text(task)
    index = {"greedy_nodes": GREEDY_NODES, "cases": [asdict(case) for case, _ in chosen]}
    Path(out, "cases.json").write_text(json.dumps(index, indent=1) + "\n")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--families", default=",".join(FAMILIES))
    parser.add_argument("--sizes", default="10,15,20,25,30,40")
    parser.add_argument("--seeds", default="0:6", help="first:last+1")
    parser.add_argument("--keep", type=int, default=3, help="hardest cases kept per family")
    parser.add_argument("--cache", type=Path, default=Path("/tmp/demoplan-lama-first.jsonl"))
    parser.add_argument("--lama-timeout", type=float, default=120.0)
    parser.add_argument("--out", type=Path, default=REPO / "tests/data/planning/crowded")
    args = parser.parse_args()
    first, last = (int(part) for part in args.seeds.split(":"))
    chosen: list[tuple[Case, Problem]] = []
    for family in args.families.split(","):
        planned = []
        for n in (int(size) for size in args.sizes.split(",")):
            for seed in range(first, last):
                result = plan_case(family, n, seed, args.cache, args.lama_timeout)
                if result is not None:
                    planned.append(result)
                    print(asdict(result[0]), flush=True)
        planned.sort(key=lambda pair: -hardness(pair[0]))
        for case, problem in planned[: args.keep]:  # lama-first afresh: not a stale cache
            length, seconds = lama_first(problem, args.lama_timeout)
            if length is not None:
                fresh = replace(case, lama=length, lama_seconds=round(seconds, 2))
                chosen.append((fresh, problem))
    write_set(chosen, args.out)
    longer = [case.name for case, _ in chosen if hardness(case) > 1]
    print(f"{len(chosen)} cases written to {args.out}; demoplan longer on: {longer or 'none'}")


if __name__ == "__main__":
    main()
