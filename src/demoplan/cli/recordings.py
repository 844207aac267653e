"""``segment`` and ``import``: recordings in."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from demoplan.cli.common import (
    FRAME_OPTION,
    LANDMARKS_OPTION,
    OBJECTS_FILE_HELP,
    OBJECTS_OPTION,
    UNITS_OPTION,
    Units,
    app,
    count_of,
    print_json,
    reported_errors,
    stderr,
    stream_options,
)
from demoplan.cli.render import print_steps
from demoplan.fileio import display_path
from demoplan.wording import plural, printable


@app.command()
def segment(
    stream_path: Annotated[
        Path,
        typer.Argument(
            metavar="STREAM", help="A pose stream: CSV, or a ROS 2 bag (sqlite3, mcap)."
        ),
    ],
    output: Annotated[
        Path, typer.Option("--output", "-o", help="The demonstration file to write.")
    ],
    plot: Annotated[
        Path | None, typer.Option(help="Also draw speed over time with the moves shaded.")
    ] = None,
    name: Annotated[str | None, typer.Option(help="The demonstration's name.")] = None,
    frame: Annotated[str | None, FRAME_OPTION] = None,
    objects: Annotated[str | None, OBJECTS_OPTION] = None,
    landmarks: Annotated[str | None, LANDMARKS_OPTION] = None,
    objects_file: Annotated[
        Path | None,
        typer.Option(
            help=OBJECTS_FILE_HELP + ": geometry written into the demonstration.",
            show_default=False,
        ),
    ] = None,
    units: Annotated[Units | None, UNITS_OPTION] = None,
    thresholds: Annotated[
        list[str] | None,
        typer.Option(
            "--set",
            metavar="NAME=VALUE",
            help="Change a threshold (repeatable; lengths m, times s, speeds m/s, "
            "angles degrees). Defaults: " + _segmentation_defaults() + ".",
            show_default=False,
        ),
    ] = None,
    json_output: Annotated[
        bool, typer.Option("--json", help="Print the demonstration as JSON.")
    ] = False,
) -> None:
    """Segment a continuous pose stream into pick-and-place steps (a demonstration).

    A step is a move that lifts an object off its support and releases it at
    rest on a support (docs/segmentation.md); a push along the support is
    reported, not a step; a pause in the air is not a placement.
    """
    from demoplan.commands.recordings import segment as segment_stream
    from demoplan.documents.demonstrations import demonstration_to_dict

    with reported_errors():
        done = segment_stream(
            stream_path,
            output,
            name=name,
            plot=plot,
            thresholds=thresholds or (),
            options=stream_options(frame, objects, units, landmarks, objects_file),
        )
        found, demo = done.segmentation, done.demonstration
        if json_output:
            print_json(demonstration_to_dict(demo))
            return
        print_steps(f"Steps found in {stream_path.name}", found)
        stderr.print(
            f"{count_of(len(found.moves), 'step')} ({count_of(len(found.pushes), 'push')} and "
            f"{count_of(len(found.nudges), 'nudge')} left out); wrote {display_path(output)}",
            markup=False,
            highlight=False,
        )


def _segmentation_defaults() -> str:
    from demoplan.segmentation.settings import settings_help

    return settings_help()


def _move_json(move: Any) -> dict[str, Any]:
    from demoplan.documents.poses import pose_to_dict

    return {
        "object": move.object,
        "start": round(move.start, 4),
        "end": round(move.end, 4),
        **pose_to_dict(move.pose),
    }


@app.command("import")
def import_(
    recording: Annotated[
        Path,
        typer.Argument(
            metavar="RECORDING", help="A robosuite (0.3, 1.x) or robomimic HDF5 recording."
        ),
    ],
    output: Annotated[
        Path,
        typer.Option(
            "--output", "-o", help="Folder for the demonstration files (created if missing)."
        ),
    ],
    json_output: Annotated[
        bool, typer.Option("--json", help="Print a summary as JSON on stdout.")
    ] = False,
    name_prefix: Annotated[
        str | None,
        typer.Option(
            help="Names are PREFIX-<demo key> (default: the file's stem, or the environment "
            "for robosuite's demo.hdf5).",
            show_default=False,
        ),
    ] = None,
    objects_file: Annotated[
        Path | None,
        typer.Option(
            help=OBJECTS_FILE_HELP + ": gives or replaces the geometry of the recording's "
            "objects and landmarks (a mesh has no primitive shape).",
            show_default=False,
        ),
    ] = None,
) -> None:
    """Import a robot-learning recording: one demonstration file per demonstration in it."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn

    from demoplan.commands.recordings import import_recording

    with reported_errors():
        with Progress(
            TextColumn("Importing {task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            console=stderr,
            transient=True,
            disable=not stderr.is_terminal,
        ) as bar:
            task = bar.add_task(printable(recording.name), total=None)

            def advance(key: str, done: int, total: int) -> None:
                description = printable(f"{recording.name} {key}")
                bar.update(task, completed=done, total=total, description=description)

            imported = import_recording(
                recording,
                output,
                name_prefix=name_prefix,
                objects_file=objects_file,
                progress=advance,
            )
        items, targets = imported.items, imported.files
        for item in items:
            if item.demonstration is None:
                stderr.print(
                    f"demoplan: WARNING: {printable(item.problem or '')}; not written",
                    markup=False,
                    highlight=False,
                )
        if json_output:
            print_json(
                {
                    "source": str(recording),
                    "output": str(output),
                    "demonstrations": [
                        {
                            "key": item.key,
                            "name": None if item.demonstration is None else item.demonstration.name,
                            "file": str(targets[item.key]) if item.key in targets else None,
                            "samples": item.recorded.samples,
                            "objects": list(item.recorded.stream.objects),
                            "landmarks": [name for name, _ in item.recorded.landmarks],
                            "steps": [_move_json(m) for m in item.segmentation.moves],
                            "provenance": dict(item.recorded.provenance),
                            **({"problem": item.problem} if item.problem else {}),
                        }
                        for item in items
                    ],
                }
            )
            return
        for item in items:
            title = f"{item.key}: {item.recorded.samples} samples"
            if item.key in targets:
                title += f" → {display_path(targets[item.key])}"
            print_steps(title, item.segmentation)
        stderr.print(
            f"{len(targets)} of {plural(len(items), 'demonstration')} imported, "
            f"{plural(sum(len(i.segmentation.moves) for i in items), 'step')}; wrote "
            f"{display_path(output)}",
            markup=False,
            highlight=False,
        )
