"""A pose stream file → a demonstration, as ``segment``, ``learn`` and ``import`` read one.

One function (:func:`demonstration_from_stream`) reads the stream
(:func:`~demoplan.segmentation.readers.load_stream`: its objects, frame and
length unit), segments it (:func:`~demoplan.segmentation.detect.segment`)
with the objects' geometry, and writes the demonstration: the tracked frames
named as landmarks are references, not objects — their rest pose is the
demonstration's landmark — and the geometry of an objects file
(``--objects-file``, :func:`~demoplan.documents.demonstrations.load_object_geometry`)
is written into it, so that learning knows which objects are round
(a cylinder's yaw is not learned, docs/learning.md).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from demoplan.documents.demonstrations import (
    check_geometry_names,
    check_measured_demonstration,
    with_declared_types,
    with_given_colours,
)
from demoplan.errors import InputError
from demoplan.model import Demonstration, ObjectGeometry
from demoplan.segmentation.detect import Segmentation, segment
from demoplan.segmentation.readers import load_stream
from demoplan.segmentation.settings import SegmentationSettings
from demoplan.segmentation.types import PoseStream, select_objects

__all__ = [
    "SegmentedStream",
    "StreamOptions",
    "demonstration_from_stream",
    "stream_name",
]


@dataclass(frozen=True, slots=True)
class StreamOptions:
    """How a pose stream is read, as ``segment``, ``learn`` and ``import`` take it.

    ``frame``: the world frame of a TF tree; ``objects``: names or globs of
    the tracked frames to keep (None: all); ``units``: a CSV's unit of
    length; ``landmarks``: names or globs of tracked frames that are
    landmarks (a tray, a box), not objects; ``objects_file``: an objects
    file giving the geometry of the stream's objects."""

    frame: str | None = None
    objects: Sequence[str] | None = None
    units: str | None = None
    landmarks: Sequence[str] = ()
    objects_file: Path | None = None

    def geometry(self) -> dict[str, ObjectGeometry] | None:
        """The objects file's geometry (None: no file given)."""
        from demoplan.documents.demonstrations import load_object_geometry

        return None if self.objects_file is None else load_object_geometry(self.objects_file)

    def types(self) -> dict[str, str]:
        """The types the objects file declares (identical objects; none without a file)."""
        from demoplan.documents.demonstrations import load_object_types

        return {} if self.objects_file is None else load_object_types(self.objects_file)

    def colours(self) -> dict[str, str]:
        """The colours the objects file gives (none without a file)."""
        from demoplan.documents.demonstrations import load_object_colours

        return {} if self.objects_file is None else load_object_colours(self.objects_file)


@dataclass(frozen=True, slots=True, eq=False)
class SegmentedStream:
    """What :func:`demonstration_from_stream` read and found: the stream, its
    segmentation and the demonstration written from it."""

    stream: PoseStream
    segmentation: Segmentation
    demonstration: Demonstration


def stream_name(path: Path) -> str:
    """A stream's demonstration name: the file's stem, or a bag folder's name
    for its ``metadata.yaml``."""
    return path.parent.name if path.name == "metadata.yaml" else path.stem


def demonstration_from_stream(
    path: str | Path,
    *,
    name: str | None = None,
    settings: SegmentationSettings | None = None,
    options: StreamOptions = StreamOptions(),
    geometry: Mapping[str, ObjectGeometry] | None = None,
    geometry_of_this_stream: bool = False,
) -> SegmentedStream:
    """Read, segment and write the demonstration of one pose stream.

    Parameters
    ----------
    path : the stream (CSV, ROS 2 bag).
    name : the demonstration's name (default: :func:`stream_name`).
    settings : the segmentation's thresholds (default: the documented ones).
    options : how the stream is read (:class:`StreamOptions`): ``frame``,
        ``objects`` and ``units`` go to :func:`~demoplan.segmentation.readers.load_stream`
        (the landmarks are kept along with ``objects``); each landmark's first
        rest pose is the demonstration's landmark — a pattern matching no
        tracked frame, or a landmark that moved (a step), is an
        :class:`InputError`.
    geometry : object (and landmark) geometry, already read from
        ``options.objects_file`` (None: read here when a file is given): it
        checks placements against their supports and is written into the
        demonstration for the stream's objects; every object that moves must
        then have one (a demonstration's ``objects`` list them all), else an
        :class:`InputError` naming the objects file. Names outside this
        stream are ignored, unless ``geometry_of_this_stream`` (one stream,
        ``segment``): then each must be one of its objects
        (:func:`check_geometry_names`); several streams are checked together.
    """
    path = Path(path)
    if geometry is None:
        geometry = options.geometry()
    geometry_source = None if options.objects_file is None else str(options.objects_file)
    patterns = list(options.landmarks)
    keep = None if options.objects is None else [*options.objects, *patterns]
    stream = load_stream(path, frame=options.frame, objects=keep, units=options.units)
    chosen = (
        select_objects(patterns, stream.objects, (), source=str(path), field="landmarks")
        if patterns
        else []
    )
    if geometry is not None and geometry_of_this_stream:
        check_geometry_names(geometry, stream.objects, geometry_source)
    shapes = {n: g for n, g in (geometry or {}).items() if n in stream.objects}
    found = segment(stream, settings, geometry=shapes)
    if geometry is not None:
        without = sorted({m.object for m in found.moves} - set(shapes) - set(chosen))
        if without:
            raise InputError(
                f"no geometry for {', '.join(map(repr, without))} (moved in {path}); every "
                "object that moves needs one (a demonstration's objects list them all)",
                source=geometry_source,
                field="objects",
            )
    demo = found.to_demonstration(name or stream_name(path), objects=shapes, landmarks=chosen)
    demo = with_given_colours(with_declared_types(demo, options.types()), options.colours())
    check_measured_demonstration(demo, str(path))
    return SegmentedStream(stream, found, demo)
