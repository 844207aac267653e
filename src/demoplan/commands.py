"""What the ``demoplan`` commands share with the lean launcher
(:mod:`demoplan.launcher`), which must not import the typer application: the
command clock — a planning command's time budget counts from the start of the
process — and the ``solve`` command's work (read, solve, render).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from contextlib import AbstractContextManager, nullcontext
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from demoplan.planning.budget import PLANNING_SECONDS

__all__ = [
    "DEFAULT_TIMEOUT",
    "SolveOptions",
    "command_budget",
    "mark_command_start",
    "mark_process_start",
    "solve_text",
]

DEFAULT_TIMEOUT = PLANNING_SECONDS
"""Seconds a planning command may take by default, counted from its start (docs/cli.md)."""

_command_started = time.monotonic()
"""When the current command started: the import of this module, for the
``demoplan`` executable (so a time budget bounds the whole process, start-up
included); each invocation of the typer app in a longer-lived process (tests,
notebooks) restarts it (:func:`mark_command_start`)."""
_started_by_main = False


def mark_process_start() -> None:
    """The executable's own command: its clock runs from the process start."""
    global _started_by_main
    _started_by_main = True


def mark_command_start() -> None:
    """A command starts now — unless it is the one :func:`main` started, whose
    clock has been running since the process began."""
    global _command_started, _started_by_main
    if _started_by_main:
        _started_by_main = False
        return
    _command_started = time.monotonic()


@dataclass(frozen=True)
class SolveOptions:
    """What ``demoplan solve`` was asked to do."""

    problem: Path
    json_output: bool = False
    search: str = "astar"
    max_nodes: int | None = None
    timeout: float | None = None  # None: DEFAULT_TIMEOUT
    optimal: bool = False


def command_budget(max_nodes: int | None, timeout: float | None) -> Any:
    """The :class:`~demoplan.planning.budget.Budget` of a planning command:
    ``timeout`` seconds (default :data:`DEFAULT_TIMEOUT`) from the start of the
    process, so that the whole command answers within it."""
    from demoplan.planning.budget import Budget

    seconds = DEFAULT_TIMEOUT if timeout is None else timeout
    # The search stops a little before the end, to leave time to write the answer
    # and tear down what it built.
    margin = min(_ANSWER_SECONDS, seconds / 8)
    return Budget(max_nodes, timeout=seconds, deadline=_command_started + seconds - margin)


_ANSWER_SECONDS = 0.25


def solve_text(
    options: SolveOptions, spinner: Callable[[str], AbstractContextManager[object]] | None = None
) -> tuple[str, str]:
    """Read the problem, solve it and render the plan (the paper's format, or its
    JSON) and the line for stderr saying whether it is proved shortest;
    ``spinner(text)`` wraps the search (a terminal's status line). Raises
    :class:`~demoplan.errors.DemoplanError`. Both ``solve`` paths use this."""
    from demoplan.planning.problem import format_plan, optimality_line, plan_to_json
    from demoplan.planning.search import solve
    from demoplan.planning.xml import load_problem

    started = time.perf_counter()
    problem = load_problem(options.problem)
    read_seconds = time.perf_counter() - started
    budget = command_budget(options.max_nodes, options.timeout)
    with spinner(f"Searching ({options.search}) for a plan…") if spinner else nullcontext():
        plan = solve(problem, options.search, budget, optimal=options.optimal)
    note = f"demoplan: {optimality_line(plan)}\n"
    if options.json_output:
        import json

        data = plan_to_json(plan, read_seconds)
        return json.dumps(data, indent=2, ensure_ascii=False, allow_nan=False) + "\n", note
    return format_plan(plan), note
