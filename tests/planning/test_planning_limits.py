"""Every planning call answers within its budget: huge problems, the state limit,
BFS's node budget (never a MemoryError, never a hang)."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from demoplan.errors import LimitReachedError
from demoplan.planning.budget import Budget
from demoplan.planning.search import solve
from demoplan.planning.xml import load_problem, save_problem
from tests.planning.test_solve_cli import PAPER
from tests.support.planning_families import (
    CROWDED_FAMILIES,
    PARKING_FAMILIES,
    parking_problem,
    ring_problem,
)


def test_a_thousand_objects_answer_within_the_budget(tmp_path: Path) -> None:
    """The default 2 s budget ends the command with a plan or with exit 4 and one
    line saying which limit and how far it got."""
    path = tmp_path / "ring.xml"
    save_problem(ring_problem(1000), path)
    started = time.monotonic()
    returncode, stderr, _ = _run_alone(
        [sys.executable, "-m", "demoplan", "solve", str(path)], tmp_path
    )
    seconds = time.monotonic() - started
    assert returncode in (0, 4), stderr
    if returncode == 4:
        lines = stderr.splitlines()
        assert len(lines) == 1 and lines[0].startswith("demoplan: error: --timeout 2 s")
        # the search's bound, or (a loaded machine) the work before it that the clock ended
        assert "every plan needs at least 2000 actions" in lines[0] or (
            "before any search" in lines[0]
        )
    # A hang guard, not a speed target (benchmarks/planning.py): 1.5 s here
    # unloaded; a loaded machine stretches the start-up before the clock starts.
    assert seconds < 120


@pytest.mark.parametrize(
    ("limit", "named"),
    [
        (["--timeout", "0"], "--timeout 0 s"),
        (["--max-nodes", "1", "--timeout", "inf"], "--max-nodes 1"),
    ],
)
def test_every_limit_is_read_inside_the_work_on_a_thousand_objects(
    tmp_path: Path, limit: list[str], named: str
) -> None:
    """--timeout 0 and --max-nodes 1 answer at once on a thousand objects: the
    clock and the node limit are read while compiling, while looking for
    reasons there is no plan and while one state's 2,000 successors are
    generated (before, 14.8 s and 16 s). The answer is the documented one —
    exit 4 naming the limit, or a plan — and the process ends well inside a
    hang guard; its time is measured in benchmarks/planning.py."""
    path = tmp_path / "ring.xml"
    save_problem(ring_problem(1000), path)
    command = [sys.executable, "-m", "demoplan", "solve", str(path), *limit]
    finished = subprocess.run(
        command, capture_output=True, text=True, timeout=60, check=False
    )  # a hang guard only: about 0.5 s unloaded
    lines = finished.stderr.splitlines()
    assert len(lines) == 1, finished.stderr
    if finished.returncode == 0:  # the tight phase's plan, which expands no node
        assert named == "--max-nodes 1" and lines[0] == "demoplan: 2000 actions, proved shortest"
    else:
        assert finished.returncode == 4
        assert lines[0].startswith(f"demoplan: error: {named} reached"), lines[0]


def test_a_thousand_objects_solved_to_the_end_are_proved_shortest(
    tmp_path: Path,
) -> None:
    """Solved without a time limit, to the end. --timeout inf still gives the
    early phases shares of an unbounded default: the tight phase, which proves
    this ring's plan, used to get 2.5 s of it, and where it did not finish in
    time (a slower environment: 1.04 GB in a fresh clone's venv) the later
    phases and A* kept thousands of 1,000-object states — 712 MB after 61 s,
    measured by giving the tight phase no time. Its work is bounded, so
    without a deadline it now runs to its end: the same path on any machine
    (55 MB measured)."""
    path = tmp_path / "ring.xml"
    save_problem(ring_problem(1000), path)
    returncode, stderr, peak_kb = _run_alone(
        [sys.executable, "-m", "demoplan", "solve", str(path), "--timeout", "inf"], tmp_path
    )
    assert returncode == 0, stderr
    assert "2000 actions, proved shortest" in stderr
    # The peak (55 MB run alone) is a memory target, so it is in the benchmark
    # (benchmarks/planning.py --limits), not here: inside the full suite on a
    # loaded machine this run has peaked at 790 MB, a load-dependent path not
    # understood yet (issue 44), and a test may not depend on the machine's load.
    del peak_kb


def _run_alone(command: list[str], folder: Path) -> tuple[int, str, int]:
    """Run a command and return its exit code, its stderr and the peak memory
    (kB) of that process alone. ``getrusage(RUSAGE_CHILDREN)`` would report the
    largest of every child this test worker ever waited for (a browser, an arm
    run), which is how a 1 GB peak of another test once failed this one."""
    stderr_path = folder / "stderr.txt"
    with stderr_path.open("w") as stderr:
        process = subprocess.Popen(
            command,
            stdout=subprocess.DEVNULL,
            stderr=stderr,
            env={**os.environ, "PYTHONWARNINGS": "ignore"},
        )
        guard = threading.Timer(300, process.kill)  # a hang guard only
        guard.start()
        try:
            _, status, usage = os.wait4(process.pid, 0)
        finally:
            guard.cancel()
        process.returncode = os.waitstatus_to_exitcode(status)  # reaped: tell Popen
    return process.returncode, stderr_path.read_text(), usage.ru_maxrss


def test_the_state_limit_stops_a_search_instead_of_memory_running_out() -> None:
    """Sixteen crowded stacks (draw 2): no tight plan, and no first plan within
    5000 states, so A* itself meets the limit (twenty objects cost the first-plan
    phases twice the CPU for the same check); without the limit A* would grow on."""
    problem = parking_problem(16, 2, **CROWDED_FAMILIES["crowded-stacks"])
    for search in ("astar", "bfs"):
        with pytest.raises(LimitReachedError, match="memory limit of 5000 states"):
            solve(problem, search, Budget(max_states=5000), optimal=True)  # no clock to race


def test_the_first_plan_search_stops_at_the_state_limit() -> None:
    """The greedy search keeps about 500 states for its plan of this draw; with
    room for 100 it gives up (None) instead of growing past the memory limit."""
    from demoplan.planning.bounds import LowerBounds
    from demoplan.planning.budget import Clock
    from demoplan.planning.compiled import compile_problem
    from demoplan.planning.greedy import greedy_moves

    problem = parking_problem(10, 0, **PARKING_FAMILIES["parking-crowded"])
    c = compile_problem(problem)
    bounds = LowerBounds(c)
    assert greedy_moves(c, bounds, Clock(Budget(timeout=600))) is not None  # no clock to race
    assert greedy_moves(c, bounds, Clock(Budget(timeout=600, max_states=100))) is None


def test_bfs_stops_at_its_node_budget_with_its_bound() -> None:
    problem = parking_problem(10, 0)
    with pytest.raises(LimitReachedError, match="--max-nodes 20000") as caught:
        solve(problem, "bfs", Budget(max_nodes=20_000))
    assert caught.value.exit_code == 4
    assert "every plan needs at least" in str(caught.value)


def test_a_budget_spent_before_planning_still_gets_the_fast_plan() -> None:
    """A slow start (imports on a loaded machine) can use up a command's 2 s
    before the search starts: the fast plan still comes, not proved shortest
    (the paper's problem: its first plan, 14 actions against a bound of 8, takes
    milliseconds, well inside the 0.2 s the first plan always gets)."""
    problem = load_problem(PAPER)
    plan = solve(problem, budget=Budget(timeout=2.0, deadline=time.monotonic() - 1.0))
    assert not plan.optimal and len(plan) >= plan.bound > 0
