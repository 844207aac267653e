"""``run`` and ``perceive``."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.table import Table
from rich.text import Text

from demoplan.budget import PERCEPTION_TIMEOUT
from demoplan.cli.common import (
    TIMEOUT_EXPECTED,
    ClutterOption,
    CollisionsOption,
    CollisionSource,
    FreespaceOption,
    ModelArgument,
    PerceptionName,
    SimName,
    app,
    bounded_number,
    geometry_settings,
    plain_text,
    planning_timeout,
    print_json,
    reported_errors,
    stderr,
    stdout,
    working,
)
from demoplan.cli.render import print_run_report
from demoplan.errors import UsageError
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
            plain_text(
                f"step {event.step} · {event.text} · replans {event.replans} · "
                f"{plural(event.remaining, 'action')} to go"
            )
        )
        if event.kind in ("action", "failure", "replan"):
            live.console.print(f"step {event.step}: {event.text}", markup=False, highlight=False)

    with live:
        yield on_event


def _run_tree(
    tree: Path,
    model_path: Path,
    scene_path: Path,
    sim: SimName,
    faults: str | None,
    seed: int,
    json_output: bool,
) -> None:
    """``run --bt``: the tree's outcome, one line (or JSON); exit 3 where it failed."""
    from demoplan.commands.export import run_tree
    from demoplan.execution.faults import parse_faults

    with reported_errors():
        outcome = run_tree(
            tree, model_path, scene_path, sim=sim.value, faults=parse_faults(faults), seed=seed
        )
        if json_output:
            print_json(outcome.to_json())
        for fault in outcome.injected:
            stderr.print(
                f"injected at action {fault.action}: {fault.kind}: {fault.detail}",
                markup=False,
                highlight=False,
            )
        if outcome.success:
            stderr.print(f"SUCCESS after {outcome.actions} actions", markup=False, highlight=False)
            return
        where = f" (subgoal {outcome.failed_subgoal})" if outcome.failed_subgoal else ""
        stderr.print(
            f"demoplan: error: the tree failed{where}: {outcome.failure}: {outcome.failure_detail}",
            markup=False,
            highlight=False,
        )
        raise typer.Exit(3)


@app.command()
def run(
    model_path: ModelArgument,
    scene_path: Annotated[
        Path | None,
        typer.Argument(
            metavar="SCENE",
            help="The scene at run time (demoplan/scene-1); none with --sim robosuite:ENV.",
        ),
    ] = None,
    sim: Annotated[
        str,
        typer.Option(
            help="kinematic (exact, fast), mujoco (physics, a floating gripper), arm "
            "(physics, a 6-DOF Kinova Jaco with a suction cup and two fingers) or robosuite:ENV "
            "(robosuite's environment ENV, e.g. Stack, with its Panda; it judges the run too).",
        ),
    ] = SimName.kinematic.value,
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
        Path | None,
        typer.Option(
            help="Write PNG frames and a storyboard here: kinematic draws the table from "
            "above; mujoco and arm render the simulator's 3-D view from a fixed camera at an "
            "angle; robosuite:ENV its agentview camera."
        ),
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
        float | None,
        planning_timeout("Seconds for each (re)planning (the best plan found by then)"),
    ] = None,
    clutter: ClutterOption = False,
    collisions: CollisionsOption = CollisionSource.rule,
    video: Annotated[
        Path | None,
        typer.Option(
            help="Also record the run as an MP4 from a fixed camera (--sim mujoco; --sim arm "
            "at twice the speed)."
        ),
    ] = None,
    tree: Annotated[
        Path | None,
        typer.Option(
            "--bt",
            metavar="TASK.xml",
            help="Tick this behaviour tree ('export bt') in the simulation instead of planning.",
        ),
    ] = None,
) -> None:
    """Execute the task in simulation: plan, act, observe, replan on failure."""
    from demoplan.budget import Budget
    from demoplan.cli.clock import DEFAULT_TIMEOUT
    from demoplan.commands.execution import run as run_task
    from demoplan.execution.executor import ExecutionSettings
    from demoplan.execution.faults import parse_faults

    with reported_errors():
        if not sim.startswith("robosuite:") and sim not in set(SimName):
            raise UsageError(f"--sim {sim}: expected kinematic, mujoco, arm or robosuite:ENV")
        if tree is not None and sim.startswith("robosuite:"):
            raise UsageError(f"--bt: not with --sim {sim} (trees tick in demoplan's worlds)")
    if tree is not None:
        _run_tree(
            tree, model_path, _scene_given(scene_path), SimName(sim), faults, seed, json_output
        )
        return
    with reported_errors():
        live = stderr.is_terminal and not json_output
        with live_progress(live) as on_event:
            report = run_task(
                model_path,
                scene_path,
                sim=sim,
                faults=parse_faults(faults),
                seed=seed,
                frames=frames,
                perception=perception.value,
                settings=ExecutionSettings(
                    max_replans=max_replans,
                    geometry=geometry_settings(freespace, collisions),
                    budget=Budget(timeout=DEFAULT_TIMEOUT if timeout is None else timeout),
                ),
                on_event=on_event,
                clutter=clutter,
                video=video,
            )
        if json_output:
            print_json(report.to_json())
        else:
            print_run_report(report)
        if not report.success:
            stderr.print(f"demoplan: error: {report.reason}", markup=False, highlight=False)
            raise typer.Exit(report.exit_code)


def _scene_given(scene_path: Path | None) -> Path:
    """The SCENE argument, which every world but robosuite's needs."""
    if scene_path is None:
        with reported_errors():
            raise UsageError("a SCENE is needed (only --sim robosuite:ENV observes its own)")
    assert scene_path is not None
    return scene_path


@app.command()
def calibrate(
    image_path: Annotated[
        Path,
        typer.Argument(metavar="IMAGE", help="A photograph of the table with markers on it."),
    ],
    markers: Annotated[
        Path,
        typer.Option(
            help="Markers file: their dictionary, side and each id's place on the table "
            "(docs/formats.md)."
        ),
    ],
    output: Annotated[
        Path | None, typer.Option("--output", "-o", help="Write the camera file here.")
    ] = None,
    plot: Annotated[
        Path | None,
        typer.Option(help="Draw the markers found and the table's grid on the photograph (PNG)."),
    ] = None,
    intrinsics: Annotated[
        Path | None,
        typer.Option(help="The camera's matrix and distortion (JSON / YAML), when known."),
    ] = None,
    json_output: Annotated[
        bool, typer.Option("--json", help="Print the camera file's document.")
    ] = False,
) -> None:
    """Calibrate a camera from markers on the table: the image → table homography."""
    from demoplan.commands.perception import calibrate as calibrate_camera

    with reported_errors():
        done = calibrate_camera(
            image_path, markers, output=output, plot=plot, intrinsics=intrinsics
        )
        if json_output:
            print_json(done.document)
            return
        calibration = done.calibration
        stdout.print(
            f"Calibrated {image_path.name} from markers "
            f"{', '.join(map(str, calibration.markers))}: reprojection error "
            f"{calibration.error_px:.2f} px, {calibration.error_mm:.2f} mm on the table",
            markup=False,
            highlight=False,
        )
        centre = calibration.centre
        if centre is None:
            stdout.print(
                "camera centre: unknown (a view straight down; --intrinsics tells it): "
                "block heights are not corrected",
                markup=False,
                highlight=False,
            )
        else:
            x, y, z = centre.position
            how = "from --intrinsics" if centre.source == "intrinsics" else "focal length estimated"
            stdout.print(
                f"camera centre: ({x:.3f}, {y:.3f}, {z:.3f}) m "
                f"({how}, f = {centre.focal_px:.0f} px)",
                markup=False,
                highlight=False,
            )


@app.command()
def perceive(
    image_paths: Annotated[
        list[Path],
        typer.Argument(
            metavar="IMAGE",
            help="A colour image of the table: a top view, or any view with --camera / --markers"
            " (with --sequence: the frames in order, or one video file).",
        ),
    ],
    px_per_m: Annotated[
        float | None,
        typer.Option(
            "--px-per-m",
            min=1e-3,
            max=1e7,
            parser=bounded_number(1e-3, 1e7, expected="pixels per metre, 0.001 to 10,000,000,"),
            help="Pixels per metre (a top view).",
        ),
    ] = None,
    origin: Annotated[
        tuple[float, float] | None,
        typer.Option(help="World x y (m) of the image's bottom-left corner (a top view)."),
    ] = None,
    camera: Annotated[
        Path | None,
        typer.Option(help="A camera file (from calibrate): the image → table mapping."),
    ] = None,
    markers: Annotated[
        Path | None,
        typer.Option(help="A markers file: calibrate from the markers in IMAGE first."),
    ] = None,
    json_output: Annotated[bool, typer.Option("--json", help="Print the scene as JSON.")] = False,
    before: Annotated[
        Path | None,
        typer.Option(help="The picture before the last move: blocks it covers stand under it."),
    ] = None,
    output: Annotated[
        Path | None, typer.Option("--output", "-o", help="Also write the scene to this file.")
    ] = None,
    side: Annotated[
        list[float] | None,
        typer.Option(
            min=1e-4,
            parser=bounded_number(1e-4, expected="the blocks' side in metres, 0.0001 or more,"),
            help="The blocks' side (m), when known: sizes 15 % off it are not blocks; "
            "repeatable for blocks of several sizes (a top view with --px-per-m). Alone "
            "(no --px-per-m, --camera, --markers) it gives a straight-down view's scale.",
            show_default=False,
        ),
    ] = None,
    timeout: Annotated[
        float,
        typer.Option(
            min=0.0,
            parser=bounded_number(0.0, expected=TIMEOUT_EXPECTED),
            help="Seconds perception may take before it stops with exit 4 (inf: none).",
        ),
    ] = PERCEPTION_TIMEOUT,
    plot: Annotated[
        Path | None,
        typer.Option(
            help="Draw the blocks found and the regions rejected, and why, on IMAGE (PNG)."
        ),
    ] = None,
    colours: Annotated[
        Path | None,
        typer.Option(help="A palette file: colour names to add or move (docs/formats.md)."),
    ] = None,
    sequence: Annotated[
        bool,
        typer.Option(
            "--sequence", help="The images are the frames of one demonstration: write it (-o)."
        ),
    ] = False,
    name: Annotated[
        str | None, typer.Option(help="The demonstration's name (--sequence; default: its file's).")
    ] = None,
) -> None:
    """Find the blocks in an image of the table (paper §V.B: Hough transform over x, y, θ, s),
    or with --sequence the demonstration camera frames show."""
    from demoplan.cli.perceiving import print_perceived
    from demoplan.commands.perception import perceive as perceive_image

    with reported_errors():
        if sequence:
            single = [o for o, v in (("--before", before), ("--plot", plot)) if v is not None]
            if colours is not None:
                single.append("--colours")
            if single:
                raise UsageError(
                    f"{' and '.join(single)}: for one IMAGE, not a --sequence of frames"
                )
            _perceive_sequence(
                image_paths,
                px_per_m,
                origin,
                camera,
                markers,
                side,
                timeout,
                output,
                name,
                json_output,
            )
            return
        if len(image_paths) != 1:
            raise UsageError(
                f"{len(image_paths)} images; one IMAGE expected (the frames of a "
                "demonstration: --sequence)"
            )
        image_path = image_paths[0]
        with working("Finding blocks…"):
            found = perceive_image(
                image_path,
                px_per_m,
                origin,
                camera=camera,
                markers=markers,
                before=before,
                side=side,
                timeout=timeout,
                output=output,
                plot=plot,
                colours=colours,
                rejections=plot is not None,  # shown only with --plot
            )
        if json_output:
            print_json(found.document)
            return
        print_perceived(stdout, found, image_path, plot)


def _perceive_sequence(
    frames: list[Path],
    px_per_m: float | None,
    origin: tuple[float, float] | None,
    camera: Path | None,
    markers: Path | None,
    side: list[float] | None,
    timeout: float,
    output: Path | None,
    name: str | None,
    json_output: bool,
) -> None:
    """``perceive --sequence``: the demonstration, as a table of its steps."""
    from demoplan.commands.perception import perceive_sequence

    with working("Perceiving frames…"):
        found = perceive_sequence(
            frames,
            px_per_m,
            origin,
            camera=camera,
            markers=markers,
            side=side,
            timeout=timeout,
            output=output,
            name=name,
        )
    if json_output:
        print_json(found.document)
        return
    demo = found.demonstration
    table = Table(
        title=f"Demonstration {demo.name} from {plural(found.frames, 'frame')}",
        title_justify="left",
    )
    for column in ("step", "object", "x [m]", "y [m]", "z [m]", "yaw [deg]"):
        table.add_column(column, justify="left" if column == "object" else "right")
    for number, step in enumerate(demo.steps, start=1):
        x, y, z = step.pose.position
        yaw = step.pose.rpy[2] if step.pose.rpy is not None else 0.0
        table.add_row(str(number), step.object, f"{x:.4f}", f"{y:.4f}", f"{z:.3f}", f"{yaw:.1f}")
    stdout.print(table)
    if output is not None:
        stdout.print(f"wrote {output}", markup=False, highlight=False)
