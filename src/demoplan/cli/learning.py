"""``learn`` and ``show``."""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer

from demoplan.budget import LEARNING_TIMEOUT
from demoplan.cli.common import (
    FRAME_OPTION,
    LANDMARKS_OPTION,
    OBJECTS_FILE_HELP,
    OBJECTS_OPTION,
    TIMEOUT_EXPECTED,
    UNITS_OPTION,
    Units,
    app,
    bounded_number,
    print_json,
    reported_errors,
    stderr,
    stdout,
    stream_options,
    working,
)
from demoplan.cli.render import (
    model_json,
    print_model,
    print_scene_preview,
)
from demoplan.wording import plural

DISTANCE_EXPECTED = "a distance in metres, above 0 and at most 10,"
ANGLE_EXPECTED = "an angle in degrees, above 0 and at most 360,"


class OrientationTies(StrEnum):
    """What an orientation whose reference the demonstrations cannot tell is
    taken relative to (``LearningSettings.orientation_follows_position``)."""

    follow = "follow"
    world = "world"


@app.command()
def learn(
    demos: Annotated[
        list[Path],
        typer.Argument(
            metavar="DEMO",
            help="Demonstration files or folders, or pose streams (CSV, ROS 2 bags) to "
            "segment first (with --update: the new ones). A folder's models, scenes and "
            "objects files (a studio work folder's) are skipped, named in one warning.",
            show_default=False,
        ),
    ],
    output: Annotated[
        Path | None,
        typer.Option(
            "--output",
            "-o",
            help="Model file to write (with --json, optional).",
            show_default=False,
        ),
    ] = None,
    update: Annotated[
        Path | None,
        typer.Option(
            help="Existing model to extend with DEMOS (written back unless -o).", show_default=False
        ),
    ] = None,
    require: Annotated[
        list[str] | None,
        typer.Option(
            help="Teacher constraint 'A<B' (state ids or object names); repeatable.",
            show_default=False,
        ),
    ] = None,
    require_file: Annotated[
        Path | None,
        typer.Option(help="File of teacher constraints, one 'A<B' per line.", show_default=False),
    ] = None,
    position_noise: Annotated[
        float | None,
        typer.Option(
            min=0.0,
            parser=bounded_number(0.0, expected=DISTANCE_EXPECTED),
            help="Placement precision (RMS) in m: spreads closer than this are ties "
            "(default: estimated from the demonstrations).",
            show_default=False,
        ),
    ] = None,
    orientation_noise: Annotated[
        float | None,
        typer.Option(
            min=0.0,
            parser=bounded_number(0.0, expected=ANGLE_EXPECTED),
            help="Orientation precision (RMS) in degrees (default: estimated).",
            show_default=False,
        ),
    ] = None,
    significance: Annotated[
        float | None,
        typer.Option(
            min=0.0,
            max=0.999,
            parser=bounded_number(0.0, 0.999, expected="a test's level, from 0 to 0.999,"),
            help="Level of the F test a reference or a split must pass to add states "
            "(default 0.05; 0: the paper's plain comparison).",
            show_default=False,
        ),
    ] = None,
    timeout: Annotated[
        float,
        typer.Option(
            min=0.0,
            parser=bounded_number(0.0, expected=TIMEOUT_EXPECTED),
            help="Seconds learning may take before it stops with exit 4 (inf: no limit).",
        ),
    ] = LEARNING_TIMEOUT,
    paper: Annotated[
        bool,
        typer.Option(
            "--paper",
            help="The paper's reading: fixed 3 mm / 0.5° ties and the plain comparison "
            "(what the shipped examples were drawn for); other options still apply.",
        ),
    ] = False,
    orientation_ties: Annotated[
        OrientationTies | None,
        typer.Option(
            help="An orientation whose reference the demonstrations cannot tell: "
            "'follow' its position's reference (default: a thing in a box turns with "
            "the box) or take the 'world' frame (as the paper, --paper).",
            show_default=False,
        ),
    ] = None,
    position_separation: Annotated[
        float | None,
        typer.Option(
            min=0.0,
            parser=bounded_number(0.0, expected=DISTANCE_EXPECTED),
            help="Minimum distance between clusters in m (default 0.05).",
            show_default=False,
        ),
    ] = None,
    orientation_separation: Annotated[
        float | None,
        typer.Option(
            min=0.0,
            parser=bounded_number(0.0, expected=ANGLE_EXPECTED),
            help="Minimum angle between clusters in degrees (default 15).",
            show_default=False,
        ),
    ] = None,
    max_clusters: Annotated[
        int | None,
        typer.Option(
            min=0,
            help="Cap on clusters per object and reference (default 0: none, as the paper).",
            show_default=False,
        ),
    ] = None,
    min_support: Annotated[
        int | None,
        typer.Option(
            min=1,
            help="Keep only learned constraints shown by at least K demonstrations (default "
            "1: the paper's rule, every pair no demonstration contradicts); teacher "
            "constraints are kept.",
            metavar="K",
            show_default=False,
        ),
    ] = None,
    frame: Annotated[str | None, FRAME_OPTION] = None,
    objects: Annotated[str | None, OBJECTS_OPTION] = None,
    landmarks: Annotated[str | None, LANDMARKS_OPTION] = None,
    objects_file: Annotated[
        Path | None,
        typer.Option(
            help=OBJECTS_FILE_HELP + ": the geometry of the pose streams' objects (a "
            "cylinder's yaw is not learned); demonstration files carry their own.",
            show_default=False,
        ),
    ] = None,
    units: Annotated[Units | None, UNITS_OPTION] = None,
    json_output: Annotated[
        bool, typer.Option("--json", help="Print the model as JSON on stdout.")
    ] = False,
    decimals: Annotated[
        int, typer.Option(min=0, max=6, help="Decimals of positions in the tables.")
    ] = 2,
) -> None:
    """Learn a task model (states, constraints, goals) from demonstrations (paper §IV.A–B)."""
    from demoplan.commands.learning import learn_files

    with reported_errors():
        if update is None and output is None and not json_output:
            raise typer.BadParameter(
                "give -o MODEL (or --update MODEL, or --json to print the model only)",
                param_hint="'-o'",
            )
        options = {
            "position_noise": position_noise,
            "orientation_noise": orientation_noise,
            "position_separation": position_separation,
            "orientation_separation": orientation_separation,
            "max_clusters": max_clusters,
            "significance": significance,
            "min_support": min_support,
            "orientation_follows_position": None
            if orientation_ties is None
            else orientation_ties is OrientationTies.follow,
        }
        result = learn_files(
            demos,
            output=output,
            update_path=update,
            require=require or (),
            require_file=require_file,
            paper=paper,
            overrides={k: v for k, v in options.items() if v is not None},
            stream=stream_options(frame, objects, units, landmarks, objects_file),
            timeout=timeout,
            working=lambda: working("Learning states and constraints…"),
        )
        if result.changes is not None:  # on stderr, so that --json stays pure
            for line in result.changes.lines():
                stderr.print(f"update: {line}", markup=False, highlight=False)
        if json_output:
            print_json(model_json(result.model))
        else:
            print_model(result.model, decimals)
            stdout.print(
                f"Learned from {plural(len(result.model.demonstrations), 'demonstration')}; "
                f"wrote {result.written}",
                markup=False,
                highlight=False,
            )


@app.command()
def show(
    path: Annotated[
        Path,
        typer.Argument(
            metavar="MODEL|SCENE",
            help="A model file written by 'learn', or a scene file to look at before planning.",
        ),
    ],
    json_output: Annotated[
        bool, typer.Option("--json", help="Print the model or the scene preview as JSON.")
    ] = False,
    decimals: Annotated[int, typer.Option(min=0, max=6, help="Decimals of positions.")] = 2,
    model_path: Annotated[
        Path | None,
        typer.Option("--model", help="A scene: take sizes the scene omits from this model."),
    ] = None,
    plot: Annotated[
        Path | None,
        typer.Option(
            help="A scene: draw it from above into this image (PNG, SVG); a model: its "
            "demonstrations, each step marked with its learned state, and their constraints."
        ),
    ] = None,
) -> None:
    """Print a model as the paper's tables (states, sequences, constraints), or
    preview a scene: where each object stands, which grasps its neighbours
    block, the landmarks and free space (the scene's, else spots near the objects)."""
    from demoplan.commands.learning import ShownModel
    from demoplan.commands.learning import show as show_file

    with reported_errors():
        shown = show_file(path, model=model_path, plot=plot)
        if shown.figure is not None:
            stderr.print(f"wrote {shown.figure}", markup=False, highlight=False)
        if isinstance(shown, ShownModel):
            if json_output:
                print_json(model_json(shown.model))
            else:
                print_model(shown.model, decimals)
        elif json_output:
            print_json(shown.preview.to_json())
        else:
            print_scene_preview(shown.preview, decimals)
