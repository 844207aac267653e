"""``export``: a planned task in another runtime's format (``bt``: BehaviorTree.CPP v4)."""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer

from demoplan.cli.clock import command_budget
from demoplan.cli.common import (
    FreespaceOption,
    ModelArgument,
    SceneArgument,
    app,
    geometry_settings,
    planning_timeout,
    reported_errors,
    stderr,
)


class ExportFormat(StrEnum):
    """What ``export`` writes."""

    bt = "bt"


@app.command()
def export(
    export_format: Annotated[
        ExportFormat,
        typer.Argument(metavar="FORMAT", help="bt: a BehaviorTree.CPP v4 XML tree."),
    ],
    model_path: ModelArgument,
    scene_path: SceneArgument,
    output: Annotated[Path, typer.Option("--output", "-o", help="The tree's XML file.")],
    goal: Annotated[
        int | None,
        typer.Option(min=1, help="The goal of this demonstration (from 1), not the shortest."),
    ] = None,
    plan_only: Annotated[
        bool,
        typer.Option("--plan-only", help="The plan's flat sequence: no checks, no retries."),
    ] = False,
    attempts: Annotated[
        int, typer.Option(min=1, max=1000, help="Tries of each subgoal before the tree fails.")
    ] = 3,  # demoplan.execution.behaviour_tree.ATTEMPTS
    freespace: FreespaceOption = None,
    timeout: Annotated[
        float | None, planning_timeout("Seconds for planning, shared by the candidate goals")
    ] = None,
    plot: Annotated[
        Path | None, typer.Option(help="Also draw the tree into this image (PNG, SVG).")
    ] = None,
) -> None:
    """Export the plan chosen in a scene as a behaviour tree a robot's runtime loads and
    ticks: per subgoal, in the plan's order, a check that the object is at its target, else
    the moves that put it there, retried, then the reason on the blackboard (exit 3 and no
    file where there is no plan)."""
    from demoplan.commands.export import export_behaviour_tree

    with reported_errors():
        written = export_behaviour_tree(
            model_path,
            scene_path,
            output,
            goal=goal,
            plan_only=plan_only,
            attempts=attempts,
            budget=command_budget(None, timeout),
            settings=geometry_settings(freespace),
            plot=plot,
        )
        stderr.print(
            f"wrote {written.path}: {written.summary}"
            + (f"; drew it in {plot}" if plot is not None else ""),
            markup=False,
            highlight=False,
        )
