"""``segment`` and ``import``: recordings in."""

from __future__ import annotations

import re
from contextlib import suppress
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
)
from demoplan.cli.render import (
    print_steps,
    segmentation_figure,
)
from demoplan.errors import (
    InputError,
    UsageError,
)
from demoplan.fileio import (
    refuse_overwriting_inputs,
)
from demoplan.wording import plural


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
    from demoplan.fileio import StagedOutputs, dump_json
    from demoplan.learning.demonstrations import demonstration_to_dict, load_object_geometry
    from demoplan.plotting import check_figure_path
    from demoplan.segmentation.settings import settings_from_text
    from demoplan.segmentation.streams import demonstration_from_stream
    from demoplan.segmentation.types import parse_object_patterns

    with reported_errors():
        inputs = [stream_path, *([objects_file] if objects_file is not None else [])]
        refuse_overwriting_inputs(output, inputs)
        if plot is not None:
            refuse_overwriting_inputs(plot, [*inputs, output])
            check_figure_path(plot, "--plot")
        segmented = demonstration_from_stream(
            stream_path,
            name=name or stream_path.stem,
            settings=settings_from_text(thresholds or []),
            frame=frame,
            objects=parse_object_patterns(objects),
            units=None if units is None else units.value,
            landmarks=parse_object_patterns(landmarks),
            geometry=None if objects_file is None else load_object_geometry(objects_file),
            geometry_source=None if objects_file is None else str(objects_file),
            geometry_of_this_stream=True,
        )
        found, demo = segmented.segmentation, segmented.demonstration
        # The demonstration and the plot are written both or neither.
        with StagedOutputs() as outputs:
            text = dump_json(demonstration_to_dict(demo))
            outputs.add(output, text.encode("utf-8", "backslashreplace"))  # see write_atomic
            if plot is not None:
                outputs.add(plot, segmentation_figure(found, plot))
        if json_output:
            print_json(demonstration_to_dict(demo))
            return
        print_steps(f"Steps found in {stream_path.name}", found)
        stderr.print(
            f"{count_of(len(found.moves), 'step')} ({count_of(len(found.pushes), 'push')} and "
            f"{count_of(len(found.nudges), 'nudge')} left out); wrote {output}",
            markup=False,
            highlight=False,
        )


def _segmentation_defaults() -> str:
    from demoplan.segmentation.settings import settings_help

    return settings_help()


def _write_all(files: list[tuple[Path, str]], folder: Path) -> None:
    """Write every file or none (:class:`~demoplan.fileio.StagedOutputs`): on
    any failure, or Ctrl-C, the files are as they were (and ``folder`` is
    removed when this call created it)."""
    from demoplan.fileio import StagedOutputs, check_output_folder

    check_output_folder(folder)
    created = not folder.exists()
    try:
        with StagedOutputs() as outputs:
            for path, text in files:
                outputs.add(path, text.encode("utf-8", "backslashreplace"))  # as write_atomic
    except BaseException:
        if created:
            with suppress(OSError):  # not empty: someone else wrote there meanwhile
                folder.rmdir()
        raise


def _move_json(move: Any) -> dict[str, Any]:
    from demoplan.poses import pose_to_dict

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
    from demoplan.fileio import dump_json
    from demoplan.learning.demonstrations import demonstration_to_dict, load_object_geometry
    from demoplan.segmentation.importing import import_recording_details

    with reported_errors():
        geometry = None if objects_file is None else load_object_geometry(objects_file)
        if name_prefix is not None and not re.fullmatch(r"[\w.+-]+", name_prefix):
            raise UsageError(f"--name-prefix {name_prefix!r}: letters, digits and . _ + - expected")
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn

        with Progress(
            TextColumn("Importing {task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            console=stderr,
            transient=True,
            disable=not stderr.is_terminal,
        ) as bar:
            task = bar.add_task(recording.name, total=None)

            def advance(done: int, total: int, key: str) -> None:
                bar.update(task, completed=done, total=total, description=f"{recording.name} {key}")

            items = import_recording_details(
                recording,
                progress=advance,
                name_prefix=name_prefix,
                skip_empty=True,
                geometry=geometry,
                geometry_source=None if objects_file is None else str(objects_file),
            )
        files: list[tuple[Path, str]] = []
        targets: dict[str, Path] = {}
        for item in items:
            if item.demonstration is None:
                continue
            target = output / f"{item.demonstration.name}.json"
            refuse_overwriting_inputs(
                target, [recording, *([objects_file] if objects_file is not None else [])]
            )
            targets[item.key] = target
            files.append((target, dump_json(demonstration_to_dict(item.demonstration))))
        if not files:
            problems = "; ".join(f"{i.key}: {i.problem}" for i in items)
            raise InputError(f"no demonstration with a step ({problems})", source=str(recording))
        _write_all(files, output)
        for item in items:
            if item.demonstration is None:
                stderr.print(
                    f"demoplan: warning: {item.problem}; not written", markup=False, highlight=False
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
                title += f" → {targets[item.key]}"
            print_steps(title, item.segmentation)
        stderr.print(
            f"{len(files)} of {plural(len(items), 'demonstration')} imported, "
            f"{plural(sum(len(i.segmentation.moves) for i in items), 'step')}; wrote {output}",
            markup=False,
            highlight=False,
        )
