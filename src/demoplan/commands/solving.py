"""``solve`` and ``pddl``: a problem in the paper's XML format, planned or
exported. Only the planner is imported, so that the lean ``demoplan solve``
path (:mod:`demoplan.cli.launcher`) does not pay for NumPy."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

from demoplan.budget import Budget
from demoplan.planning.problem import Plan

__all__ = ["Solved", "export_pddl", "solve_problem"]


@dataclass(frozen=True, slots=True)
class Solved:
    """A solved problem file: the plan (with its proven lower bound) and how
    long reading the file took (the plan's JSON reports it)."""

    plan: Plan
    read_seconds: float


def solve_problem(
    path: Path, *, search: str = "astar", budget: Budget | None = None, optimal: bool = False
) -> Solved:
    """Read the problem at ``path`` and solve it (paper §IV.C) within ``budget``
    (default :func:`~demoplan.budget.default_budget`); ``optimal``:
    only a plan proved shortest. Raises :class:`~demoplan.errors.DemoplanError`."""
    from demoplan.budget import default_budget
    from demoplan.planning.search import solve
    from demoplan.planning.xml import load_problem

    started = time.perf_counter()
    problem = load_problem(path)
    read_seconds = time.perf_counter() - started
    plan = solve(problem, search, budget or default_budget(), optimal=optimal)
    return Solved(plan, read_seconds)


def export_pddl(path: Path, output: Path, *, grounded: bool = False) -> tuple[Path, Path]:
    """The problem at ``path`` as PDDL in folder ``output``: the domain and the
    problem files written (``grounded``: plain STRIPS, no variables)."""
    from demoplan.fileio import refuse_overwriting_inputs
    from demoplan.planning.pddl import save_pddl
    from demoplan.planning.xml import load_problem

    for name in ("domain.pddl", "problem.pddl"):  # the files save_pddl writes
        refuse_overwriting_inputs(output / name, [path])
    return save_pddl(load_problem(path), output, grounded=grounded)
