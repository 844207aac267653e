"""Writing pose streams: CSV and ROS 2 bags (the inverse of the readers).

Used to make test and benchmark inputs and by ``experiments``; the files read
back with :func:`~demoplan.segmentation.readers.load_stream` as the same stream.
"""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path
from typing import Any, Literal

import numpy as np

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
    """
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
    vector, quaternion = msg["geometry_msgs/msg/Vector3"], msg["geometry_msgs/msg/Quaternion"]
    point, pose_type = msg["geometry_msgs/msg/Point"], msg["geometry_msgs/msg/Pose"]

    def header(stamp: int) -> Any:
        return header_type(
            stamp=time_type(sec=stamp // 10**9, nanosec=stamp % 10**9), frame_id=frame
        )

    try:
        with Writer(path, version=9, storage_plugin=plugin) as writer:
            if kind == "tf":
                connection = writer.add_connection("/tf", TF_TYPE, typestore=store)
                transform_type = msg["geometry_msgs/msg/TransformStamped"]
                transform3 = msg["geometry_msgs/msg/Transform"]
                starts = np.flatnonzero(np.r_[True, stamps[1:] != stamps[:-1]])
                ends = np.r_[starts[1:], len(stamps)]
                for start, end in zip(starts.tolist(), ends.tolist(), strict=True):
                    stamp = int(stamps[start])
                    transforms = [
                        transform_type(
                            header=header(stamp),
                            child_frame_id=names[i],
                            transform=transform3(
                                translation=vector(*map(float, positions[i])),
                                rotation=quaternion(*map(float, quats[i])),
                            ),
                        )
                        for i in range(start, end)
                    ]
                    message = msg[TF_TYPE](transforms=transforms)
                    writer.write(connection, stamp, store.serialize_cdr(message, TF_TYPE))
            else:
                connections = {
                    name: writer.add_connection(f"/{name}/pose", POSE_TYPE, typestore=store)
                    for name in dict.fromkeys(names)
                }
                for i, name in enumerate(names):
                    stamp = int(stamps[i])
                    message = msg[POSE_TYPE](
                        header=header(stamp),
                        pose=pose_type(
                            position=point(*map(float, positions[i])),
                            orientation=quaternion(*map(float, quats[i])),
                        ),
                    )
                    writer.write(connections[name], stamp, store.serialize_cdr(message, POSE_TYPE))
    except WriterError as exc:
        raise InputError(f"cannot write ROS 2 bag ({exc})", source=str(path)) from None
