"""``segment`` and ``import``: recordings in — a continuous pose stream cut
into pick-and-place steps, and robot-learning recordings (robosuite,
robomimic) turned into demonstration files."""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from demoplan.budget import ProgressCallback
from demoplan.documents.demonstrations import (
    demonstration_to_dict,
    load_object_colours,
    load_object_geometry,
    load_object_types,
    with_declared_types,
    with_given_colours,
)
from demoplan.errors import InputError, UsageError
from demoplan.fileio import (
    StagedOutputs,
    check_output_folder,
    dump_json,
    file_inside,
    refuse_overwriting_inputs,
)
from demoplan.model import Demonstration
from demoplan.segmentation.detect import Segmentation
from demoplan.segmentation.importing import ImportedDemonstration, import_recording_details
from demoplan.segmentation.settings import settings_from_text
from demoplan.segmentation.streams import StreamOptions, demonstration_from_stream

__all__ = ["Imported", "Segmented", "import_recording", "segment"]


@dataclass(frozen=True, slots=True)
class Segmented:
    """A pose stream segmented: the steps found (and the pushes and nudges left
    out) and the demonstration written."""

    segmentation: Segmentation
    demonstration: Demonstration


def segment(
    stream: Path,
    output: Path,
    *,
    name: str | None = None,
    plot: Path | None = None,
    thresholds: Sequence[str] = (),
    options: StreamOptions = StreamOptions(),
) -> Segmented:
    """Segment ``stream`` (CSV, ROS 2 bag) into pick-and-place steps and write the
    demonstration to ``output`` — and with ``plot`` the segmentation figure,
    both or neither (docs/segmentation.md). ``thresholds``: ``NAME=VALUE``
    settings; ``options``: how the stream is read (its objects file: the
    geometry of the stream's objects)."""
    from demoplan.plotting.output import check_figure_path

    objects_file = options.objects_file
    inputs = [stream, *([objects_file] if objects_file is not None else [])]
    refuse_overwriting_inputs(output, inputs)
    if plot is not None:
        refuse_overwriting_inputs(plot, [*inputs, output])
        check_figure_path(plot, "--plot")
    segmented = demonstration_from_stream(
        stream,
        name=name or stream.stem,
        settings=settings_from_text(list(thresholds)),
        options=options,
        geometry_of_this_stream=True,
    )
    found, demo = segmented.segmentation, segmented.demonstration
    with StagedOutputs() as outputs:  # the demonstration and the figure, both or neither
        text = dump_json(demonstration_to_dict(demo))
        outputs.add(output, text.encode("utf-8", "backslashreplace"))  # see write_atomic
        if plot is not None:
            outputs.add(plot, _segmentation_figure(found, plot))
    return Segmented(found, demo)


def _segmentation_figure(found: Segmentation, plot: Path) -> bytes:
    """The segmentation figure, encoded for ``plot``."""
    try:
        from demoplan.plotting.backend import use_agg

        use_agg()
        import matplotlib.pyplot as plt
    except ImportError:
        raise InputError(
            "matplotlib is not installed; pip install 'demoplan[plot]'", field="--plot"
        ) from None
    from demoplan.plotting.output import figure_bytes
    from demoplan.plotting.segmentation import plot_segmentation

    axes = plot_segmentation(found)
    if not axes:
        raise InputError("nothing to draw (no object moved)", source=str(plot), field="--plot")
    figure: Any = axes[0].figure
    try:
        return figure_bytes(figure, plot)
    finally:
        plt.close(figure)


@dataclass(frozen=True, slots=True)
class Imported:
    """A recording imported: every demonstration in it (with its segmentation,
    or why it was left out) and the file each was written to."""

    items: tuple[ImportedDemonstration, ...]
    files: dict[str, Path]
    """Per recorded demonstration's key, the file written (none: left out)."""


def import_recording(
    recording: Path,
    output: Path,
    *,
    name_prefix: str | None = None,
    objects_file: Path | None = None,
    progress: ProgressCallback | None = None,
) -> Imported:
    """One demonstration file in folder ``output`` per demonstration of a
    robosuite or robomimic HDF5 ``recording`` that has a step — every file or
    none; ``progress(key, done, total)`` hears each one read. A file is named
    after its demonstration, reduced to a safe file name
    (:func:`~demoplan.fileio.safe_file_name`: no separator, ``..`` or control
    character) and kept inside ``output``."""
    geometry = None if objects_file is None else load_object_geometry(objects_file)
    types = {} if objects_file is None else load_object_types(objects_file)
    colours = {} if objects_file is None else load_object_colours(objects_file)
    if name_prefix is not None and not re.fullmatch(r"[\w.+-]+", name_prefix):
        raise UsageError(f"--name-prefix {name_prefix!r}: letters, digits and . _ + - expected")
    items = import_recording_details(
        recording,
        progress=progress,
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
        # The name comes from the recording (its environment, its keys): a file
        # name made safe, inside the folder named, one per demonstration.
        target = file_inside(output, item.demonstration.name, ".json", list(targets.values()))
        refuse_overwriting_inputs(
            target, [recording, *([objects_file] if objects_file is not None else [])]
        )
        targets[item.key] = target
        demo = with_given_colours(with_declared_types(item.demonstration, types), colours)
        files.append((target, dump_json(demonstration_to_dict(demo))))
    if not files:
        problems = "; ".join(f"{i.key}: {i.problem}" for i in items)
        raise InputError(f"no demonstration with a step ({problems})", source=str(recording))
    _write_all(files, output)
    return Imported(tuple(items), targets)


def _write_all(files: list[tuple[Path, str]], folder: Path) -> None:
    """Write every file or none (:class:`~demoplan.fileio.StagedOutputs`): on
    any failure, or Ctrl-C, the files are as they were — an earlier import's
    file replaced on the way is put back — and the folders made for them
    are removed."""
    check_output_folder(folder)
    with StagedOutputs() as outputs:
        for path, text in files:
            outputs.add(path, text.encode("utf-8", "backslashreplace"))  # as write_atomic
