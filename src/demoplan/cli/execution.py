"""``run`` and ``perceive``."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager, nullcontext
from dataclasses import replace
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.table import Table
from rich.text import Text

from demoplan.cli.common import (
    FRAME_FILES,
    ClutterOption,
    CollisionsOption,
    CollisionSource,
    FreespaceOption,
    ModelArgument,
    PerceptionName,
    SceneArgument,
    SimName,
    app,
    geometry_settings,
    model_named,
    print_json,
    reported_errors,
    scene_inputs,
    stderr,
    stdout,
    working,
)
from demoplan.cli.render import (
    print_run_report,
)
from demoplan.deadline import PERCEPTION_TIMEOUT
from demoplan.fileio import (
    refuse_overwriting_inputs,
)
from demoplan.planning.budget import PLANNING_SECONDS
from demoplan.wording import plural


@contextmanager
def live_progress(show: bool) -> Iterator[Callable[[Any], None] | None]:
    """Live progress on stderr for a run's events (a terminal only): a line per
    action done, failure and replan, which stays on screen, and under them a
    status line — the step, the replans, the actions to go — that goes when
    the run ends (an arm's action takes seconds: the line shows it is alive)."""
    if not show:
        yield None
        return
    from rich.live import Live

    live = Live(Text("planning…"), console=stderr, transient=True, refresh_per_second=8)

    def on_event(event: Any) -> None:
        live.update(
            Text(
                f"step {event.step} · {event.text} · replans {event.replans} · "
                f"{plural(event.remaining, 'action')} to go"
            )
        )
        if event.kind in ("action", "failure", "replan"):
            live.console.print(f"step {event.step}: {event.text}", markup=False, highlight=False)

    with live:
        yield on_event


@app.command()
def run(
    model_path: ModelArgument,
    scene_path: SceneArgument,
    sim: Annotated[
        SimName,
        typer.Option(
            help="kinematic (exact, fast), mujoco (physics, a floating gripper) or arm "
            "(physics, a 6-DOF Kinova Jaco with a suction cup and two fingers)."
        ),
    ] = SimName.kinematic,
    faults: Annotated[
        str | None,
        typer.Option(
            help="Faults to inject, kind=probability,...: drop, displace, misplace, grasp, block."
        ),
    ] = None,
    seed: Annotated[int, typer.Option(min=0, help="Seed of the injected faults.")] = 0,
    json_output: Annotated[
        bool, typer.Option("--json", help="Print the run report as JSON.")
    ] = False,
    frames: Annotated[
        Path | None, typer.Option(help="Write top-view PNG frames and a storyboard here.")
    ] = None,
    max_replans: Annotated[int, typer.Option(min=0, help="Give up after this many replans.")] = 25,
    perception: Annotated[
        PerceptionName,
        typer.Option(
            help="state (read the simulator) or camera (perceive its top view; mujoco, arm)."
        ),
    ] = PerceptionName.state,
    freespace: FreespaceOption = None,
    timeout: Annotated[
        float,
        typer.Option(min=0.0, help="Seconds for each (re)planning (the best plan found by then)."),
    ] = PLANNING_SECONDS,
    clutter: ClutterOption = False,
    collisions: CollisionsOption = CollisionSource.rule,
    video: Annotated[
        Path | None,
        typer.Option(
            help="Also record the run as an MP4 from a fixed camera (--sim mujoco; --sim arm "
            "at twice the speed)."
        ),
    ] = None,
) -> None:
    """Execute the task in simulation: plan, act, observe, replan on failure."""
    from demoplan.execution.faults import parse_faults
    from demoplan.execution.runner import run_task
    from demoplan.fileio import staged_folder

    with reported_errors(), model_named(model_path):
        if video is not None:
            from demoplan.execution.runner import check_video_path

            check_video_path(video)
            refuse_overwriting_inputs(video, [model_path, scene_path])
        model, scene = scene_inputs(model_path, scene_path)
        fault_rates = parse_faults(faults)
        live = stderr.is_terminal and not json_output
        # The frames folder whole or not at all: built beside --frames, swapped in at the end.
        staging = (
            staged_folder(frames, lambda name: bool(FRAME_FILES.match(name)))
            if frames is not None
            else nullcontext(None)
        )
        with staging as building, live_progress(live) as on_event:
            report = run_task(
                model,
                scene,
                sim=sim.value,
                faults=fault_rates,
                seed=seed,
                frames=building,
                max_replans=max_replans,
                perception=perception.value,
                geometry=geometry_settings(freespace, collisions),
                on_event=on_event,
                planning_seconds=timeout,
                clutter=clutter,
                video=video,
            )
        if frames is not None and building is not None:  # named where they now are
            moved = tuple(str(frames / Path(f).name) for f in report.frames)
            report = replace(report, frames=moved)
        if json_output:
            print_json(report.to_json())
        else:
            print_run_report(report)
        if not report.success:
            stderr.print(f"demoplan: error: {report.reason}", markup=False, highlight=False)
            raise typer.Exit(report.exit_code)


@app.command()
def perceive(
    image_path: Annotated[
        Path, typer.Argument(metavar="IMAGE", help="A top-down orthographic colour image (PNG).")
    ],
    px_per_m: Annotated[
        float, typer.Option("--px-per-m", min=1e-3, max=1e7, help="Pixels per metre.")
    ],
    origin: Annotated[
        tuple[float, float],
        typer.Option(help="World x y (m) of the image's bottom-left corner."),
    ],
    json_output: Annotated[bool, typer.Option("--json", help="Print the scene as JSON.")] = False,
    before: Annotated[
        Path | None,
        typer.Option(help="The picture before the last move: blocks it covers stand under it."),
    ] = None,
    output: Annotated[
        Path | None, typer.Option("--output", "-o", help="Also write the scene to this file.")
    ] = None,
    side: Annotated[
        float | None,
        typer.Option(
            min=1e-4, help="The blocks' side (m), when known: sizes 15 % off it are not blocks."
        ),
    ] = None,
    timeout: Annotated[
        float,
        typer.Option(
            min=0.0, help="Seconds perception may take before it stops with exit 4 (inf: none)."
        ),
    ] = PERCEPTION_TIMEOUT,
) -> None:
    """Find the blocks in a top-view image (paper §V.B: Hough transform over x, y, θ, s)."""
    from demoplan.fileio import dump_json, write_atomic
    from demoplan.perception.images import perceive_files
    from demoplan.perception.stacking import scene_document

    with reported_errors():
        if output is not None:
            refuse_overwriting_inputs(output, [image_path, *([before] if before else [])])
        with working("Finding blocks…"):
            blocks = perceive_files(
                image_path, px_per_m, origin, before=before, side=side, timeout=timeout
            )
        document = scene_document(blocks)
        if output is not None:
            write_atomic(output, dump_json(document))
        if json_output:
            print_json(document)
            return
        table = Table(title=f"Blocks in {image_path.name}", title_justify="left")
        for column in ("name", "x [m]", "y [m]", "z [m]", "yaw [deg]", "side [m]"):
            table.add_column(column, justify="left" if column == "name" else "right")
        for name, b in blocks.items():
            table.add_row(
                name, f"{b.x:.4f}", f"{b.y:.4f}", f"{b.z:.3f}", f"{b.yaw:.1f}", f"{b.side:.4f}"
            )
        stdout.print(table)
