"""Readers of pose streams: one module per file kind.

- :func:`load_stream` — any supported file, dispatched by its kind;
- :func:`~demoplan.segmentation.readers.csv.load_csv` — CSV;
- :func:`~demoplan.segmentation.readers.bag.load_bag` — ROS 2 bags (sqlite3 / mcap).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from demoplan.errors import InputError
from demoplan.fileio import require_regular_file
from demoplan.segmentation.readers.bag import load_bag
from demoplan.segmentation.readers.csv import load_csv
from demoplan.segmentation.types import PoseStream, check_stream_limits

__all__ = ["load_bag", "load_csv", "load_stream"]


def load_stream(
    path: str | Path,
    *,
    frame: str | None = None,
    objects: Sequence[str] | None = None,
    units: str | None = None,
) -> PoseStream:
    """Read a pose stream: a CSV file, or a ROS 2 bag (folder, ``.db3`` or ``.mcap``).

    A folder, a ``.db3``, ``.mcap`` or ``metadata.yaml`` path is read as a bag;
    anything else as CSV.

    Parameters
    ----------
    path : str or Path
        The stream.
    frame : str, optional
        The world frame a bag's TF tree is composed to (default: the tree's
        root). Only TF topics have frames: ignored for CSV and PoseStamped topics.
    objects : sequence of str, optional
        The objects to keep: names or :mod:`fnmatch` patterns. By default
        every object (CSV, PoseStamped topics) and every TF frame other than
        the world frame that has no children (the tree's leaves).
    units : str, optional
        The unit of a CSV stream's positions (``m``, ``cm``, ``mm``; see
        :func:`~demoplan.segmentation.readers.csv.load_csv`). A ROS 2 bag is in
        metres (REP 103): another unit is refused.
    """
    path = Path(path)
    if not path.is_dir():
        require_regular_file(path, "a CSV file or a ROS 2 bag")
    if path.is_dir() or path.suffix.lower() in {".db3", ".mcap"} or path.name == "metadata.yaml":
        if units not in (None, "m"):
            raise InputError(
                f"a ROS 2 bag is in metres (REP 103); --units {units} is for CSV streams",
                source=str(path),
                field="units",
            )
        stream = load_bag(path, frame=frame, objects=objects)
    else:
        stream = load_csv(path, objects=objects, units=units)
    check_stream_limits(stream)
    return stream
