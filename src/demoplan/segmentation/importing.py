"""``demoplan import``: robot-learning recordings → segmented demonstrations.

A recording (docs/formats.md "Recording": robosuite 0.3 / 1.x or robomimic HDF5) is
read with :mod:`demoplan.segmentation.readers.hdf5`; each of its
demonstrations' object tracks is segmented like any pose stream
(:func:`~demoplan.segmentation.detect.segment`) and the result gets the
recording's landmarks, geometry and provenance.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path

from demoplan.budget import ProgressCallback
from demoplan.documents.demonstrations import check_measured_demonstration
from demoplan.errors import InputError
from demoplan.model import Demonstration, ObjectGeometry
from demoplan.segmentation.detect import Segmentation, SegmentationSettings, segment
from demoplan.segmentation.readers.hdf5 import (
    RecordedDemonstration,
    demonstration_keys,
    read_demonstration,
)

logger = logging.getLogger(__name__)

__all__ = ["ImportedDemonstration", "import_recording", "import_recording_details"]


GENERIC_STEMS = frozenset({"demo", "demos", "low_dim", "image", "depth", "data"})


@dataclass(frozen=True, slots=True, eq=False)
class ImportedDemonstration:
    """One imported demonstration with what it was made from.

    ``demonstration`` is ``None`` when no step was found in it (only with
    ``skip_empty``); ``problem`` then says why.
    """

    key: str
    demonstration: Demonstration | None
    recorded: RecordedDemonstration
    segmentation: Segmentation
    problem: str | None = None


def recording_name(path: Path, env: str | None) -> str:
    """Name prefix of a recording's demonstrations: the file's stem, or the
    environment's name when the stem says nothing (robosuite's ``demo.hdf5``)."""
    if path.stem.lower() in GENERIC_STEMS and env:
        return env
    return path.stem


def import_recording_details(
    path: str | Path,
    settings: SegmentationSettings | None = None,
    progress: ProgressCallback | None = None,
    *,
    name_prefix: str | None = None,
    skip_empty: bool = False,
    geometry: Mapping[str, ObjectGeometry] | None = None,
    geometry_source: str | None = None,
) -> list[ImportedDemonstration]:
    """:func:`import_recording`, keeping each demonstration's recording and segmentation.

    ``name_prefix`` replaces the file stem / environment in the names. With
    ``skip_empty``, a demonstration in which no step is found is returned
    without a demonstration (and the reason) instead of raising.
    ``geometry`` (an objects file, ``import --objects-file``, read from
    ``geometry_source``) gives or replaces the geometry of the recording's
    objects and landmarks (a mesh has no primitive shape); every name must be
    an object or landmark of some demonstration of the recording.
    """
    path = Path(path)
    keys = demonstration_keys(path)
    out = []
    named: dict[str, None] = {}
    for done, key in enumerate(keys, 1):
        recorded = read_demonstration(path, key)
        own = [*recorded.stream.objects, *(n for n, _ in recorded.landmarks)]
        named.update(dict.fromkeys(own))
        shapes = {
            **dict(recorded.geometry),
            **{n: g for n, g in (geometry or {}).items() if n in own},
        }
        found = segment(
            recorded.stream,
            settings,
            geometry=shapes,
            landmarks=dict(recorded.landmarks),
        )
        prefix = name_prefix if name_prefix is not None else recording_name(path, recorded.env)
        try:
            demo = found.to_demonstration(f"{prefix}-{key}")
        except InputError as exc:
            if not skip_empty:
                raise
            out.append(ImportedDemonstration(key, None, recorded, found, str(exc)))
            if progress is not None:
                progress(key, done, len(keys))
            continue
        # A demonstration file's objects, when given, name every object it moves:
        # where the model has no primitive shape for one (PickPlace's meshes), no
        # geometry is written (it served the segmentation's support check).
        complete = all(step.object in shapes for step in demo.steps)
        if not complete:
            logger.info(
                "%s: no geometry for %s; the demonstration is written without objects",
                key,
                ", ".join(sorted({s.object for s in demo.steps} - set(shapes))),
            )
        demo = replace(
            demo,
            objects=tuple(shapes.items()) if complete else (),
            landmarks=recorded.landmarks,
            compartments=recorded.compartments,
            provenance=(
                *recorded.provenance,
                *((k, v) for k, v in demo.provenance if k != "source"),
            ),
        )
        check_measured_demonstration(demo, f"{path}: {key}")
        out.append(ImportedDemonstration(key, demo, recorded, found))
        if progress is not None:
            progress(key, done, len(keys))
    if geometry is not None:
        from demoplan.documents.demonstrations import check_geometry_names

        check_geometry_names(geometry, list(named), geometry_source)
    return out


def import_recording(
    path: str | Path,
    settings: SegmentationSettings | None = None,
    progress: ProgressCallback | None = None,
) -> list[Demonstration]:
    """The demonstrations of a robosuite / robomimic recording, segmented.

    Each is named ``<file stem or env>-<demonstration key>`` (e.g.
    ``SawyerStack-demo_1``) and carries the recording's landmarks, the
    geometry of its objects and landmarks, and its provenance (source file,
    demonstration key, samples, environment, robosuite version).
    ``progress(key, done, total)`` is called after each demonstration.
    Raises :class:`~demoplan.errors.InputError` for an unreadable recording
    or a demonstration in which no step is found.
    """
    items = import_recording_details(path, settings, progress)
    return [item.demonstration for item in items if item.demonstration is not None]
