"""``solve``, ``pddl``, ``plan`` and ``problem``."""

from __future__ import annotations

import sys
from contextlib import nullcontext
from pathlib import Path
from typing import Annotated

import typer

from demoplan.cli.clock import command_budget
from demoplan.cli.common import (
    ClutterOption,
    CollisionsOption,
    CollisionSource,
    FreespaceOption,
    GroundedOption,
    ModelArgument,
    SceneArgument,
    SearchName,
    app,
    geometry_settings,
    planning_timeout,
    print_json,
    reported_errors,
    stderr,
)
from demoplan.cli.render import plot_no_plan, plot_scene_plan, print_scene_plan
from demoplan.cli.solving import SolveOptions, solve_text
from demoplan.commands.solving import export_pddl
from demoplan.planning.problem import optimality_line
from demoplan.wording import printable_lines


@app.command()
def solve(
    problem_path: Annotated[
        Path, typer.Argument(metavar="PROBLEM.xml", help="A problem in the paper's XML format.")
    ],
    json_output: Annotated[bool, typer.Option("--json", help="Print the plan as JSON.")] = False,
    search: Annotated[
        SearchName,
        typer.Option(
            help="astar (default: a fast plan, then A* to prove it) or bfs (the paper's)."
        ),
    ] = SearchName.astar,
    max_nodes: Annotated[
        int | None, typer.Option(min=1, help="A* / BFS expand at most this many states.")
    ] = None,
    timeout: Annotated[
        float | None,
        planning_timeout(
            "Seconds for the whole command; the best plan found by then is printed, with its "
            "proven lower bound if not proved shortest"
        ),
    ] = None,
    optimal: Annotated[
        bool,
        typer.Option("--optimal", help="Only a plan proved shortest; exit 4 without one."),
    ] = False,
) -> None:
    """Solve a planning problem: a GRASP / PUT_DOWN plan (paper §IV.C), shortest where
    proved within the time budget. stderr says which, and the proven lower bound."""
    with reported_errors():
        options = SolveOptions(problem_path, json_output, search.value, max_nodes, timeout, optimal)
        # a spinner while a long search runs on a terminal; nothing when piped
        spinner = stderr.status if stderr.is_terminal else None
        text, note = solve_text(options, spinner)
        sys.stdout.write(printable_lines(text))
        sys.stderr.write(printable_lines(note))


@app.command()
def pddl(
    problem_path: Annotated[
        Path, typer.Argument(metavar="PROBLEM.xml", help="A problem in the paper's XML format.")
    ],
    output: Annotated[
        Path, typer.Option("--output", "-o", help="Folder for domain.pddl and problem.pddl.")
    ],
    grounded: GroundedOption = False,
) -> None:
    """Export a problem as PDDL: a lifted domain and problem (--grounded: plain STRIPS)."""
    with reported_errors():
        domain, problem = export_pddl(problem_path, output, grounded=grounded)
        stderr.print(f"wrote {domain} and {problem}", markup=False, highlight=False)


@app.command()
def plan(
    model_path: ModelArgument,
    scene_path: SceneArgument,
    json_output: Annotated[bool, typer.Option("--json", help="Print the plan as JSON.")] = False,
    freespace: FreespaceOption = None,
    max_nodes: Annotated[
        int | None, typer.Option(min=1, help="Per candidate: A* expands at most this many states.")
    ] = None,
    timeout: Annotated[
        float | None,
        planning_timeout("Seconds for the whole command, shared by the candidate goals"),
    ] = None,
    optimal: Annotated[
        bool,
        typer.Option("--optimal", help="Only a plan proved shortest; exit 4 without one."),
    ] = False,
    plot: Annotated[
        Path | None, typer.Option(help="Also draw the plan from above into this image (PNG, SVG).")
    ] = None,
    clutter: ClutterOption = False,
    collisions: CollisionsOption = CollisionSource.rule,
) -> None:
    """Plan the task in a scene: every demonstrated goal, the shortest plan chosen (§IV.C)."""
    from demoplan.commands.planning import plan as plan_task
    from demoplan.plotting.output import check_figure_path
    from demoplan.scenes.plan import SceneLimitReachedError, SceneNoPlanError

    with reported_errors():
        if plot is not None:
            check_figure_path(plot, "--plot")
        try:
            with (
                stderr.status("Planning every candidate goal…")
                if stderr.is_terminal
                else (nullcontext())
            ):
                result = plan_task(
                    model_path,
                    scene_path,
                    budget=command_budget(max_nodes, timeout),
                    settings=geometry_settings(freespace, collisions),
                    clutter=clutter,
                    optimal=optimal,
                )
        except (SceneNoPlanError, SceneLimitReachedError) as exc:
            if plot is not None:  # a picture of the targets is what is needed now
                plot_no_plan(exc, plot)
            raise
        if plot is not None:
            plot_scene_plan(result, plot)
        if json_output:
            print_json(result.to_json())
        else:
            print_scene_plan(result)
        check = result.chosen.problem.collision_check
        if check is not None and not json_output:
            stderr.print(f"demoplan: {check.summary()}", markup=False, highlight=False)
        stderr.print(f"demoplan: {optimality_line(result.as_plan())}", markup=False)


@app.command()
def problem(
    model_path: ModelArgument,
    scene_path: SceneArgument,
    output: Annotated[
        Path,
        typer.Option(
            "--output", "-o", help="The problem file (XML; with --pddl the PDDL problem)."
        ),
    ],
    goal: Annotated[
        int,
        typer.Option(
            min=1,
            help="The demonstration whose goal to plan for, numbered from 1 as 'learn' and "
            "'plan' print them.",
        ),
    ] = 1,
    pddl_output: Annotated[
        bool,
        typer.Option(
            "--pddl", help="Write PDDL: the problem to FILE, the domain to FILE-domain.pddl."
        ),
    ] = False,
    freespace: FreespaceOption = None,
    grounded: GroundedOption = False,
    collisions: CollisionsOption = CollisionSource.rule,
) -> None:
    """Write the planning problem of one candidate goal (for 'solve' or a PDDL planner)."""
    from demoplan.commands.planning import write_problem

    with reported_errors():
        written = write_problem(
            model_path,
            scene_path,
            output,
            goal=goal,
            settings=geometry_settings(freespace, collisions),
            pddl=pddl_output,
            grounded=grounded,
        )
        check = written.problem.collision_check
        if check is not None:
            stderr.print(f"demoplan: {check.summary()}", markup=False, highlight=False)
        files = " and ".join(str(f) for f in written.files)
        stderr.print(f"wrote {files}", markup=False, highlight=False)
        for obstacle in written.problem.obstacles:
            stderr.print(f"demoplan: warning: {obstacle}", markup=False, highlight=False)
