"""What the commands read: demonstration files and folders, and pose streams
(:func:`load_inputs`); a task model and a scene, given as values or as the
files that hold them (:func:`task_and_scene`).

This module sits above the two stages it dispatches to:
:mod:`demoplan.documents.demonstrations` reads demonstration files only, and
:mod:`demoplan.segmentation` turns a pose stream (CSV, ROS 2 bag) into a
demonstration (it writes demonstration files, so it imports the former; the
former imports neither).
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

from demoplan.documents.demonstrations import check_demonstrations, demonstrations_from_path
from demoplan.errors import InputError
from demoplan.learning.modelfile import load_model
from demoplan.model import Demonstration, TaskModel
from demoplan.scenes.scene import Scene, load_scene

if TYPE_CHECKING:
    from demoplan.segmentation.streams import StreamOptions

__all__ = [
    "STREAM_SUFFIXES",
    "is_pose_stream",
    "load_examples",
    "load_inputs",
    "model_named",
    "task_and_scene",
]

STREAM_SUFFIXES = {".csv", ".db3", ".mcap"}


def is_pose_stream(path: Path) -> bool:
    """A pose stream (docs/formats.md): a CSV file, or a ROS 2 bag (``.db3``, ``.mcap``, or a
    folder holding ``metadata.yaml``)."""
    if path.is_dir():
        return (path / "metadata.yaml").is_file()
    return path.suffix.lower() in STREAM_SUFFIXES or path.name == "metadata.yaml"


def load_examples(names: Iterable[str]) -> list[Demonstration]:
    """The demonstrations of the shipped examples (``names`` are paths inside
    the examples folder, e.g. ``set_table/demonstration-1.json``), read as
    :func:`load_inputs` reads them."""
    from demoplan.experiments.runs import examples_dir

    return load_inputs([examples_dir() / name for name in names])


def load_inputs(
    paths: Iterable[str | Path],
    *,
    stream: StreamOptions | None = None,
) -> list[Demonstration]:
    """Read demonstration files and folders (``*.json``, ``*.yaml``, in name order);
    a pose stream (CSV, ROS 2 bag) is segmented into a demonstration on the way
    (:func:`~demoplan.segmentation.streams.demonstration_from_stream`, default
    settings), named after the file.

    ``stream`` says how pose streams are read
    (:class:`~demoplan.segmentation.streams.StreamOptions`: the world frame of
    a TF tree, the objects to keep, a CSV's unit of length, the tracked frames
    that are landmarks), as ``segment`` takes them; its objects file's geometry
    is written into each stream's demonstration — every name must be an
    object of some stream. Demonstration files ignore all of it: they carry their own
    objects and landmarks (an object's geometry must agree across all
    demonstrations, :func:`~demoplan.documents.demonstrations.check_demonstrations`)."""
    from demoplan.segmentation.streams import StreamOptions

    options = stream or StreamOptions()
    geometry = options.geometry()
    geometry_source = None if options.objects_file is None else str(options.objects_file)
    demos: list[Demonstration] = []
    tracked: dict[str, None] = {}
    streams = 0
    for path in map(Path, paths):
        if is_pose_stream(path):
            from demoplan.segmentation.streams import demonstration_from_stream

            segmented = demonstration_from_stream(path, options=options, geometry=geometry)
            tracked.update(dict.fromkeys(segmented.stream.objects))
            demos.append(segmented.demonstration)
            streams += 1
        else:
            demos += demonstrations_from_path(path)
    if geometry is not None:
        if not streams:
            raise InputError(
                "an objects file gives the geometry of pose streams' objects, and no "
                "pose stream is given (demonstration files carry their own 'objects')",
                source=geometry_source,
            )
        from demoplan.documents.demonstrations import check_geometry_names

        check_geometry_names(geometry, list(tracked), geometry_source)
    check_demonstrations(demos)
    return demos


def task_and_scene(
    model: TaskModel | str | Path, scene: Scene | str | Path
) -> tuple[TaskModel, Scene]:
    """The task model and the scene: given, or read from their files."""
    task = model if isinstance(model, TaskModel) else load_model(model)
    return task, scene if isinstance(scene, Scene) else load_scene(scene)


@contextmanager
def model_named(model: TaskModel | str | Path) -> Iterator[None]:
    """A fault in the model found only while planning (a cycle of references)
    names the model file, not "task model", where the model came from one."""
    try:
        yield
    except InputError as exc:
        if exc.source != "task model" or isinstance(model, TaskModel):
            raise
        raise InputError(exc.message, source=str(model), field=exc.field) from None
