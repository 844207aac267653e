"""``solve``, ``pddl``, ``plan`` and ``problem``."""

from __future__ import annotations

import sys
from contextlib import nullcontext
from pathlib import Path
from typing import Annotated

import typer

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
    model_named,
    print_json,
    reported_errors,
    scene_inputs,
    stderr,
)
from demoplan.cli.render import (
    plot_no_plan,
    plot_scene_plan,
    print_scene_plan,
)
from demoplan.errors import (
    LimitReachedError,
    NoPlanError,
    UsageError,
)
from demoplan.fileio import (
    refuse_overwriting_inputs,
)


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
        typer.Option(
            min=0.0,
            help="Seconds for the whole command [default: 2]; the best plan found by then is "
            "printed, with its proven lower bound if not proved shortest ('inf': no limit).",
        ),
    ] = None,
    optimal: Annotated[
        bool,
        typer.Option("--optimal", help="Only a plan proved shortest; exit 4 without one."),
    ] = False,
) -> None:
    """Solve a planning problem: a GRASP / PUT_DOWN plan (paper §IV.C), shortest where
    proved within the time budget. stderr says which, and the proven lower bound."""
    from demoplan.commands import SolveOptions, solve_text

    with reported_errors():
        options = SolveOptions(problem_path, json_output, search.value, max_nodes, timeout, optimal)
        # a spinner while a long search runs on a terminal; nothing when piped
        spinner = stderr.status if stderr.is_terminal else None
        text, note = solve_text(options, spinner)
        sys.stdout.write(text)
        sys.stderr.write(note)


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
    from demoplan.planning.pddl import save_pddl
    from demoplan.planning.xml import load_problem

    with reported_errors():
        for name in ("domain.pddl", "problem.pddl"):  # the files save_pddl writes
            refuse_overwriting_inputs(output / name, [problem_path])
        domain, problem = save_pddl(load_problem(problem_path), output, grounded=grounded)
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
        typer.Option(
            min=0.0,
            help="Seconds for the whole command, shared by the candidate goals [default: 2].",
        ),
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
    from demoplan.commands import command_budget
    from demoplan.planning.problem import optimality_line
    from demoplan.scenes.plan import plan_in_scene
    from demoplan.scenes.prepared import prepare

    with reported_errors(), model_named(model_path):
        if plot is not None:
            from demoplan.plotting import check_figure_path

            check_figure_path(plot, "--plot")
        model, raw_scene = scene_inputs(model_path, scene_path)
        scene = prepare(model, raw_scene, clutter=clutter)
        budget = command_budget(max_nodes, timeout)
        settings = geometry_settings(freespace, collisions)
        try:
            with (
                stderr.status("Planning every candidate goal…")
                if stderr.is_terminal
                else (nullcontext())
            ):
                result = plan_in_scene(
                    model, scene, budget=budget, settings=settings, clutter=clutter
                )
        except (NoPlanError, LimitReachedError) as exc:
            if plot is not None:  # a picture of the targets is what is needed now
                plot_no_plan(model, scene, settings, str(exc), plot)
            raise
        if optimal and not result.optimal:
            raise LimitReachedError(
                f"{optimality_line(result.as_plan())}; no plan proved shortest (--optimal)"
            )
        if plot is not None:
            plot_scene_plan(model, result, plot)
        if json_output:
            print_json(result.to_json())
        else:
            print_scene_plan(result, model)
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
    from demoplan.planning.pddl import pddl_domain_path, save_pddl_problem
    from demoplan.planning.xml import save_problem
    from demoplan.scenes.plan import goal_problem

    with reported_errors(), model_named(model_path):
        if grounded and not pddl_output:
            raise UsageError("--grounded chooses the PDDL form: it needs --pddl")
        inputs = [model_path, scene_path]
        refuse_overwriting_inputs(output, inputs)
        if pddl_output:
            refuse_overwriting_inputs(pddl_domain_path(output), inputs)
        model, scene = scene_inputs(model_path, scene_path)
        chosen = goal_problem(model, scene, goal, geometry_settings(freespace, collisions))
        if chosen.collision_check is not None:
            stderr.print(
                f"demoplan: {chosen.collision_check.summary()}", markup=False, highlight=False
            )
        if pddl_output:
            domain_path = save_pddl_problem(chosen.problem, output, grounded=grounded)
            stderr.print(f"wrote {output} and {domain_path}", markup=False, highlight=False)
        else:
            save_problem(chosen.problem, output)
            stderr.print(f"wrote {output}", markup=False, highlight=False)
        for obstacle in chosen.obstacles:
            stderr.print(f"demoplan: warning: {obstacle}", markup=False, highlight=False)
