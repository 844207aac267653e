"""Writing pose streams: CSV and ROS 2 bags (the inverse of the readers).

Used to make test and benchmark inputs and by ``experiments``; the files read
back with :func:`~demoplan.segmentation.readers.load_stream` as the same stream.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Callable, Collection, Mapping
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from demoplan.errors import InputError
from demoplan.fileio import write_atomic
from demoplan.segmentation.readers.bag import POSE_TYPE, TF_TYPE
from demoplan.segmentation.types import FloatArray, PoseStream

__all__ = ["BagKind", "BagStorage", "write_bag", "write_csv"]

BagKind = Literal["tf", "pose"]
BagStorage = Literal["sqlite3", "mcap"]

WORLD_FRAME = "world"


def _flat(stream: PoseStream) -> tuple[list[str], FloatArray, FloatArray, FloatArray | None]:
    """All samples in time order (ties by track order): names, times, positions, quats."""
    tracks = [track for track in stream.tracks if len(track)]
    if not tracks:
        raise InputError("the stream holds no samples; nothing to write", source=stream.source)
    times = np.concatenate([track.times for track in tracks])
    positions = np.concatenate([track.positions for track in tracks])
    codes = np.concatenate([np.full(len(track), k) for k, track in enumerate(tracks)])
    oriented = any(track.orientations is not None for track in tracks)
    quats = None
    if oriented:
        quats = np.concatenate(
            [
                track.orientations
                if track.orientations is not None
                else np.full((len(track), 4), np.nan)
                for track in tracks
            ]
        )
    order = np.lexsort((codes, times))
    names = [tracks[int(k)].name for k in codes[order]]
    return names, times[order], positions[order], None if quats is None else quats[order]


def write_csv(stream: PoseStream, path: str | Path) -> None:
    """Write ``stream`` as CSV (``t,object,x,y,z`` plus ``qx,qy,qz,qw`` when oriented).

    Numbers are written with ``repr`` so that :func:`load_csv` reads back the
    same floats. Objects without orientations get empty quaternion cells —
    which :func:`load_csv` reads back as "no orientation" for that object.
    The file is written atomically.
    """
    names, times, positions, quats = _flat(stream)
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    header = ["t", "object", "x", "y", "z"] + (
        ["qx", "qy", "qz", "qw"] if quats is not None else []
    )
    writer.writerow(header)
    columns = [times.tolist(), names, *positions.T.tolist()]
    if quats is not None:
        columns += [
            ["" if math.isnan(v) else repr(v) for v in column] for column in quats.T.tolist()
        ]
    writer.writerows(zip(*columns, strict=True))
    write_atomic(Path(path), buffer.getvalue())


def write_bag(
    stream: PoseStream,
    path: str | Path,
    *,
    kind: BagKind = "tf",
    storage: BagStorage = "sqlite3",
    frame: str = WORLD_FRAME,
    parents: Mapping[str, str] | None = None,
    static: Collection[str] = (),
) -> None:
    """Write ``stream`` as a ROS 2 bag folder with ``rosbags``' Writer.

    ``kind="tf"``: one ``/tf`` topic of ``tf2_msgs/msg/TFMessage``, one message
    per sample time holding a transform per object sampled then (child frame =
    object, parent = ``frame``). ``kind="pose"``: one
    ``geometry_msgs/msg/PoseStamped`` topic ``/<object>/pose`` per object.
    Header stamps and receive times are the sample times (rounded to
    nanoseconds; times must be ≥ 0). Objects without orientation are written
    with the identity quaternion (bags always carry one). ``path`` must not
    exist yet (rosbags refuses to overwrite a bag).

    A TF tree (``kind="tf"`` only): ``parents`` maps a track's name to its
    parent frame (default ``frame``), so that the track holds the frame's pose
    *relative to that parent*; the tracks named in ``static`` go to a
    ``/tf_static`` topic instead of ``/tf``. E.g. tracks ``odom`` (in ``map``),
    ``table`` (static, in ``odom``) and ``cup`` (in ``table``) with
    ``parents={"odom": "map", "table": "odom", "cup": "table"}, static={"table"}``.
    """
    if kind != "tf" and (parents or static):
        raise ValueError("parents and static frames need kind='tf'")
    parent_of = dict(parents or {})
    static_names = set(static)
    from rosbags.rosbag2 import StoragePlugin, Writer, WriterError
    from rosbags.typesys import Stores, get_typestore

    path = Path(path)
    store = get_typestore(Stores.ROS2_HUMBLE)
    msg = store.types
    names, times, positions, quats = _flat(stream)
    if times.size and float(times[0]) < 0:
        raise InputError("negative sample times cannot be bag stamps", source=str(path))
    if quats is None:
        quats = np.tile([0.0, 0.0, 0.0, 1.0], (len(names), 1))
    quats = np.where(np.isnan(quats), np.array([0.0, 0.0, 0.0, 1.0]), quats)
    stamps = np.rint(times * 1e9).astype(np.int64)
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    header_type = msg["std_msgs/msg/Header"]
    time_type = msg["builtin_interfaces/msg/Time"]

    def header(stamp: int, frame_id: str = frame) -> Any:
        return header_type(
            stamp=time_type(sec=stamp // 10**9, nanosec=stamp % 10**9), frame_id=frame_id
        )

    try:
        with Writer(path, version=9, storage_plugin=plugin) as writer:
            if kind == "tf":
                is_static = np.array([name in static_names for name in names], dtype=bool)
                _write_tf_topics(
                    writer,
                    store,
                    header,
                    names,
                    stamps,
                    (positions, quats),
                    is_static,
                    parent_of,
                    frame,
                )
            else:
                _write_pose_topics(writer, store, header, names, stamps, (positions, quats), frame)
    except WriterError as exc:
        raise InputError(f"cannot write ROS 2 bag ({exc})", source=str(path)) from None


def _write_tf_topics(
    writer: Any,
    store: Any,
    header: Callable[[int, str], Any],
    names: list[str],
    stamps: NDArray[np.int64],
    poses: tuple[FloatArray, FloatArray],
    is_static: NDArray[np.bool_],
    parent_of: Mapping[str, str],
    frame: str,
) -> None:
    """``/tf`` and, where a track is static, ``/tf_static``: one message per
    sample time holding a transform per track sampled then."""
    msg = store.types
    transform_type = msg["geometry_msgs/msg/TransformStamped"]
    transform3 = msg["geometry_msgs/msg/Transform"]
    vector, quaternion = msg["geometry_msgs/msg/Vector3"], msg["geometry_msgs/msg/Quaternion"]
    # Python floats once for all rows (a NumPy row per transform cost most of a
    # bag of thousands of frames), and each frame's parent once per message.
    position_rows: list[list[float]] = poses[0].tolist()
    quat_rows: list[list[float]] = poses[1].tolist()
    parents = [parent_of.get(name, frame) for name in names]
    for topic, chosen in (("/tf", ~is_static), ("/tf_static", is_static)):
        rows = np.flatnonzero(chosen)
        if not rows.size and topic == "/tf_static":
            continue
        connection = writer.add_connection(topic, TF_TYPE, typestore=store)
        # One message per sample time: runs of equal stamps.
        runs = np.flatnonzero(np.r_[True, stamps[rows][1:] != stamps[rows][:-1]])
        for run in np.split(rows, runs[1:]):
            stamp = int(stamps[run[0]])
            headers: dict[str, Any] = {}
            transforms = []
            for i in run.tolist():
                parent = parents[i]
                if parent not in headers:
                    headers[parent] = header(stamp, parent)
                transforms.append(
                    transform_type(
                        header=headers[parent],
                        child_frame_id=names[i],
                        transform=transform3(
                            translation=vector(*position_rows[i]),
                            rotation=quaternion(*quat_rows[i]),
                        ),
                    )
                )
            message = msg[TF_TYPE](transforms=transforms)
            writer.write(connection, stamp, store.serialize_cdr(message, TF_TYPE))


def _write_pose_topics(
    writer: Any,
    store: Any,
    header: Callable[[int, str], Any],
    names: list[str],
    stamps: NDArray[np.int64],
    poses: tuple[FloatArray, FloatArray],
    frame: str,
) -> None:
    """One ``PoseStamped`` topic ``/<object>/pose`` per object."""
    msg = store.types
    quaternion = msg["geometry_msgs/msg/Quaternion"]
    point, pose_type = msg["geometry_msgs/msg/Point"], msg["geometry_msgs/msg/Pose"]
    positions, quats = poses
    connections = {
        name: writer.add_connection(f"/{name}/pose", POSE_TYPE, typestore=store)
        for name in dict.fromkeys(names)
    }
    for i, name in enumerate(names):
        stamp = int(stamps[i])
        message = msg[POSE_TYPE](
            header=header(stamp, frame),
            pose=pose_type(
                position=point(*map(float, positions[i])),
                orientation=quaternion(*map(float, quats[i])),
            ),
        )
        writer.write(connections[name], stamp, store.serialize_cdr(message, POSE_TYPE))
