"""``demoplan solve``'s options and output, shared by the lean launcher
(:mod:`demoplan.cli.launcher`) and the typer command, so that both paths print
the same plan, JSON and lines. Only the planner is imported."""

from __future__ import annotations

from collections.abc import Callable
from contextlib import AbstractContextManager, nullcontext
from dataclasses import dataclass
from pathlib import Path

from demoplan.cli.clock import command_budget

__all__ = ["SolveOptions", "solve_text"]


@dataclass(frozen=True)
class SolveOptions:
    """What ``demoplan solve`` was asked to do."""

    problem: Path
    json_output: bool = False
    search: str = "astar"
    max_nodes: int | None = None
    timeout: float | None = None  # None: the default budget
    optimal: bool = False


def solve_text(
    options: SolveOptions, spinner: Callable[[str], AbstractContextManager[object]] | None = None
) -> tuple[str, str]:
    """``demoplan solve``'s output: the plan of
    :func:`~demoplan.commands.solving.solve_problem` in the paper's format (or
    its JSON), and the line for stderr saying whether it is proved shortest;
    ``spinner(text)`` wraps the search (a terminal's status line). Both
    ``solve`` paths (this launcher's and typer's) render with this."""
    from demoplan.commands.solving import solve_problem
    from demoplan.planning.problem import format_plan, optimality_line, plan_to_json

    budget = command_budget(options.max_nodes, options.timeout)
    with spinner(f"Searching ({options.search}) for a plan…") if spinner else nullcontext():
        solved = solve_problem(
            options.problem, search=options.search, budget=budget, optimal=options.optimal
        )
    note = f"demoplan: {optimality_line(solved.plan)}\n"
    if options.json_output:
        import json

        data = plan_to_json(solved.plan, solved.read_seconds)
        return json.dumps(data, indent=2, ensure_ascii=False, allow_nan=False) + "\n", note
    return format_plan(solved.plan), note
