"""Segmentation: continuous pose streams → pick-and-place demonstrations.

The paper's first building block (§III, "a largely open research problem"):
a tracker or motion capture records object poses over time; this package
finds when each object was picked up and put down again and turns the
placements into the steps of a :class:`~demoplan.model.Demonstration`.

Public API::

    from demoplan.segmentation import load_stream, segment, write_demonstration

    stream = load_stream("demo.csv")           # CSV, or a ROS 2 bag folder / .db3 / .mcap
    found = segment(stream)                    # SegmentationSettings() by default
    demo = found.to_demonstration("set-table-1")
    write_demonstration(demo, "set-table-1.json")

    from demoplan.plotting.segmentation import plot_segmentation

    plot_segmentation(found, "speed.png")     # speed per object, moves shaded

Reading and writing streams (:mod:`demoplan.segmentation.readers` — one
module per file kind: ``readers.csv``, ``readers.bag`` —,
:mod:`demoplan.segmentation.writers`, and the types in
:mod:`demoplan.segmentation.types`):

- ``load_stream(path, *, frame=None, objects=None) -> PoseStream`` — CSV
  (``t,object,x,y,z`` [+ ``yaw`` | ``roll,pitch,yaw`` | ``qx,qy,qz,qw``]) or a
  ROS 2 bag (sqlite3 / mcap) with ``tf2_msgs/msg/TFMessage`` topics (``/tf``,
  ``/tf_static``: a TF tree whose frames are composed to the world frame
  ``frame``, default its root; :mod:`demoplan.segmentation.tftree`) or
  ``geometry_msgs/msg/PoseStamped`` topics (one per object). ``objects``
  keeps the named objects (names or fnmatch patterns); by default every
  object, and of a TF tree its leaves (frames other than the world frame
  without children). Errors are :class:`~demoplan.errors.InputError` naming
  the file, line / column, topic or frame, and what was expected.
  ``load_csv`` / ``load_bag`` read one kind.
- ``write_csv(stream, path)``; ``write_bag(stream, path, kind="tf"|"pose",
  storage="sqlite3"|"mcap", frame="world", parents=None, static=())``
  (rosbags' Writer; ``parents`` / ``static`` write a TF tree).
- ``PoseStream(tracks, source)`` of ``ObjectTrack(name, times (n,),
  positions (n, 3), orientations (n, 4) | None)``.

Detection (:mod:`demoplan.segmentation.detect`, the method and its
thresholds are described there):

- ``segment(stream, settings=None) -> Segmentation`` with ``moves`` (each a
  ``Move(object, start, end, pose, before)``, ordered by the time the object
  comes to rest), ``nudges`` (moves below ``min_distance``), ``initial``
  (first rest pose per object), ``traces`` (speed per object), and
  ``to_demonstration(name=None, *, objects=(), landmarks=()) -> Demonstration``.
- ``SegmentationSettings`` (frozen): ``speed_window_s=0.4`` s,
  ``start_speed=0.10`` m/s, ``stop_speed=0.04`` m/s, ``min_rest_s=0.5`` s,
  ``min_distance=0.02`` m (the nudge threshold), ``min_angle_deg=20``,
  ``pose_window_s=1.0`` s, ``max_gap_s=0.25`` s.
- ``write_demonstration(demo, path)`` — a ``demoplan/demonstration-1`` file, atomically.

Recordings (:mod:`demoplan.segmentation.importing`, read by
:mod:`demoplan.segmentation.readers.hdf5`): ``import_recording(path,
settings=None, progress=None) -> list[Demonstration]`` segments each
demonstration of a robosuite / robomimic HDF5 file.

Plot (:mod:`demoplan.plotting.segmentation`, a floor above this package;
matplotlib imported lazily):
``plot_segmentation(segmentation, path=None, *, axes=None, title=None,
heights=False, dpi=110) -> list[Axes]`` (speed per object; with ``heights`` a
last row of every object's height); ``plot_heights(segmentation, ax=None) -> Axes``.

Synthetic streams (:mod:`demoplan.segmentation.synthetic`):
``stream_from_demonstration(demo, *, rate_hz=60, noise_m=0.002, rng=None,
rate_jitter=0, drop_fraction=0, overlap=0, nudges=0, nudge_m=0.01, ...)`` plays a
demonstration back as lift–carry–place trajectories with noise;
``compare_steps(expected, found, tolerance_m=0.02) -> StepComparison``
(precision, recall, pose errors).

Names are imported on first use, so importing this package loads neither
rosbags nor matplotlib.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

_EXPORTS = {
    "ObjectTrack": "demoplan.segmentation.types",
    "PoseStream": "demoplan.segmentation.types",
    "load_bag": "demoplan.segmentation.readers",
    "load_csv": "demoplan.segmentation.readers",
    "load_stream": "demoplan.segmentation.readers",
    "write_bag": "demoplan.segmentation.writers",
    "write_csv": "demoplan.segmentation.writers",
    "Move": "demoplan.segmentation.detect",
    "Segmentation": "demoplan.segmentation.detect",
    "SegmentationSettings": "demoplan.segmentation.settings",
    "SpeedTrace": "demoplan.segmentation.detect",
    "segment": "demoplan.segmentation.detect",
    "write_demonstration": "demoplan.segmentation.detect",
    "import_recording": "demoplan.segmentation.importing",
    "StepComparison": "demoplan.segmentation.synthetic",
    "compare_steps": "demoplan.segmentation.synthetic",
    "stream_from_demonstration": "demoplan.segmentation.synthetic",
}

__all__ = [
    "Move",
    "ObjectTrack",
    "PoseStream",
    "Segmentation",
    "SegmentationSettings",
    "SpeedTrace",
    "StepComparison",
    "compare_steps",
    "import_recording",
    "load_bag",
    "load_csv",
    "load_stream",
    "segment",
    "stream_from_demonstration",
    "write_bag",
    "write_csv",
    "write_demonstration",
]

if TYPE_CHECKING:
    from demoplan.segmentation.detect import (
        Move,
        Segmentation,
        SpeedTrace,
        segment,
        write_demonstration,
    )
    from demoplan.segmentation.importing import import_recording
    from demoplan.segmentation.readers import load_bag, load_csv, load_stream
    from demoplan.segmentation.settings import SegmentationSettings
    from demoplan.segmentation.synthetic import (
        StepComparison,
        compare_steps,
        stream_from_demonstration,
    )
    from demoplan.segmentation.types import ObjectTrack, PoseStream
    from demoplan.segmentation.writers import write_bag, write_csv


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *_EXPORTS])
