"""What ``demoplan learn`` reads: demonstration files and folders, and pose streams.

This module sits above the two stages it dispatches to:
:mod:`demoplan.learning.demonstrations` reads demonstration files only, and
:mod:`demoplan.segmentation` turns a pose stream (CSV, ROS 2 bag) into a
demonstration (it writes demonstration files, so it imports the former; the
former imports neither).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path

from demoplan.learning.demonstrations import check_demonstrations, demonstrations_from_path
from demoplan.model import Demonstration

__all__ = ["STREAM_SUFFIXES", "is_pose_stream", "load_inputs"]

STREAM_SUFFIXES = {".csv", ".db3", ".mcap"}


def is_pose_stream(path: Path) -> bool:
    """A pose stream (docs/formats.md): a CSV file, or a ROS 2 bag (``.db3``, ``.mcap``, or a
    folder holding ``metadata.yaml``)."""
    if path.is_dir():
        return (path / "metadata.yaml").is_file()
    return path.suffix.lower() in STREAM_SUFFIXES or path.name == "metadata.yaml"


def load_inputs(
    paths: Iterable[str | Path],
    *,
    frame: str | None = None,
    objects: Sequence[str] | None = None,
) -> list[Demonstration]:
    """Read demonstration files and folders (``*.json``, ``*.yaml``, in name order);
    a pose stream (CSV, ROS 2 bag) is segmented into a demonstration on the way
    (:mod:`demoplan.segmentation`, default settings), named after the file.

    ``frame`` and ``objects`` are passed to
    :func:`~demoplan.segmentation.load_stream` for pose streams (the world frame
    of a TF tree, the objects to keep); demonstration files ignore them."""
    demos: list[Demonstration] = []
    for path in map(Path, paths):
        if is_pose_stream(path):
            from demoplan.segmentation import load_stream, segment

            name = path.stem if path.name != "metadata.yaml" else path.parent.name
            stream = load_stream(path, frame=frame, objects=objects)
            demos.append(segment(stream).to_demonstration(name))
        else:
            demos += demonstrations_from_path(path)
    check_demonstrations(demos)
    return demos
