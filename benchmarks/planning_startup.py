"""Start-up of ``demoplan solve`` against the interpreter's own (issue 44).

``python benchmarks/planning.py --startup`` (and every full run, at its end):
``demoplan solve`` of small problems — the paper's example (4 objects),
``table_problem(7)`` and a ``parking`` draw of 10 objects — as a whole
process, against ``python -c pass`` with the same interpreter and
environment, interleaved run by run (so that a change of the machine's load
falls on both), median of ``STARTUP_RUNS``. The target: within 2× the
interpreter's start.

The modules are byte-compiled first (:mod:`compileall`, as an installed
package is): where ``PYTHONDONTWRITEBYTECODE`` is set, every run would
otherwise compile demoplan's sources anew, and that is not start-up.
"""

from __future__ import annotations

import compileall
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

import demoplan
from common import Target
from demoplan.planning.problem import Problem
from demoplan.planning.xml import save_problem

STARTUP_RUNS = 11
STARTUP_TARGET = 2.0  # demoplan solve / python -c pass, whole process, median


def time_process(command: Sequence[str], env: dict[str, str], cwd: Path) -> float:
    """Seconds from start to exit of ``command`` (its output dropped)."""
    started = time.perf_counter()
    subprocess.run(
        list(command),
        cwd=cwd,
        env=env,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        check=False,
    )
    return time.perf_counter() - started


def startup_timings(
    root: Path,
    console: Console,
    problems: dict[str, Problem],
    demoplan_command: Sequence[str],
    environment: Callable[[], dict[str, str]],
    runs: int = STARTUP_RUNS,
) -> tuple[dict[str, Any], list[Target]]:
    """Whole-process medians of ``python -c pass`` and of ``demoplan solve`` on
    each of ``problems``, and the target's verdict per problem."""
    compileall.compile_dir(Path(demoplan.__file__).parent, quiet=1)
    env = environment()
    table = Table(
        title=f"Start-up: demoplan solve against python -c pass (whole process, median of {runs})"
    )
    for column in ("problem", "python -c pass", "demoplan solve", "ratio", "target"):
        table.add_column(column)
    rows, targets = [], []
    for name, problem in problems.items():
        path = root / f"startup-{name}.xml"
        save_problem(problem, path)
        bare, solving = [], []
        for _ in range(runs):
            bare.append(time_process([sys.executable, "-c", "pass"], env, root))
            solving.append(time_process([*demoplan_command, "solve", str(path)], env, root))
        ratio = statistics.median(solving) / statistics.median(bare)
        rows.append(
            {
                "problem": name,
                "objects": len(problem.objects),
                "python_s": bare,
                "demoplan_s": solving,
                "ratio": ratio,
            }
        )
        passed = ratio <= STARTUP_TARGET
        table.add_row(
            f"{name} ({len(problem.objects)} objects)",
            f"{1000 * statistics.median(bare):.0f} ms",
            f"{1000 * statistics.median(solving):.0f} ms",
            f"{ratio:.2f}",
            "PASS" if passed else "FAIL",
        )
        targets.append(
            Target(
                f"demoplan solve on {name} within {STARTUP_TARGET:g}× python -c pass "
                "(whole process, median)",
                passed,
                f"{ratio:.2f}×",
            )
        )
    console.print(table)
    return {"runs": runs, "rows": rows}, targets
