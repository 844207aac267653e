"""ROS 2 bag pose streams (SPEC §3 "Pose stream"), read with ``rosbags``.

A bag (sqlite3 or mcap; a bag folder or its storage file) is read with
``rosbags.highlevel.AnyReader``:

- ``tf2_msgs/msg/TFMessage`` topics: every transform is a sample of the
  object named by its ``child_frame_id``; its translation and rotation are
  taken as the object's pose in the world (the parent frame is assumed to be
  the world frame and is not composed further);
- ``geometry_msgs/msg/PoseStamped`` topics, one per object: the object is
  named by the topic's last component, or the one before it when the last is
  ``pose`` (``/mocap/plate/pose`` and ``/plate`` both name ``plate``).

A sample's time is its header stamp, or the bag's receive time when the
stamp is zero. Other topics are ignored. Every problem is one
:class:`~demoplan.errors.InputError` naming the file, the topic and what was
expected. ``rosbags`` is imported on first use.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from demoplan.errors import InputError
from demoplan.segmentation.types import PoseStream, normalise_quats, stream_from_samples

if TYPE_CHECKING:
    from rosbags.interfaces import Connection

__all__ = ["POSE_TYPE", "TF_TYPE", "load_bag"]

TF_TYPE = "tf2_msgs/msg/TFMessage"
POSE_TYPE = "geometry_msgs/msg/PoseStamped"


def load_bag(path: str | Path) -> PoseStream:
    """Read a ROS 2 bag (folder, its ``.db3`` / ``.mcap`` file, or ``metadata.yaml``)."""
    from rosbags.highlevel import AnyReader, AnyReaderError

    path = Path(path)
    source = str(path)
    bag = _bag_folder(path)
    samples = _Samples()
    try:
        with AnyReader([bag]) as reader:
            tf = [c for c in reader.connections if c.msgtype == TF_TYPE]
            poses = [c for c in reader.connections if c.msgtype == POSE_TYPE]
            if not tf and not poses:
                found = ", ".join(f"{c.topic} ({c.msgtype})" for c in reader.connections)
                raise InputError(
                    f"no usable topic; expected {TF_TYPE} or {POSE_TYPE} topics, "
                    f"found {found or 'no topics'}",
                    source=source,
                    field="topics",
                )
            names = _pose_topic_names(poses, source)
            for connection, timestamp, raw in reader.messages(connections=[*tf, *poses]):
                try:
                    message: Any = reader.deserialize(raw, connection.msgtype)
                except Exception as exc:  # rosbags raises several unrelated types here
                    raise InputError(
                        f"cannot decode a {connection.msgtype} message ({exc})",
                        source=source,
                        field=f"topic {connection.topic}",
                    ) from None
                if connection.msgtype == TF_TYPE:
                    for transform in message.transforms:
                        samples.add_transform(transform, timestamp, connection.topic)
                else:
                    samples.add_pose(names[connection.topic], message, timestamp, connection.topic)
    except InputError:
        raise
    except (AnyReaderError, OSError, ValueError, KeyError) as exc:
        raise InputError(f"cannot read ROS 2 bag ({exc})", source=source) from None
    except Exception as exc:  # rosbags' storage plugins raise their own error types
        if type(exc).__module__.startswith("rosbags"):
            raise InputError(f"cannot read ROS 2 bag ({exc})", source=source) from None
        raise
    if not samples.names:
        raise InputError(
            "the pose topics hold no messages; at least one sample expected",
            source=source,
            field="topics",
        )
    return samples.stream(source)


def _bag_folder(path: Path) -> Path:
    """The bag folder for a bag path: the folder itself, or the folder of its files."""
    if path.is_dir():
        if (path / "metadata.yaml").exists():
            return path
        files = [p for p in path.iterdir() if p.suffix.lower() in {".db3", ".mcap"}]
        if len(files) == 1:
            return files[0]
        raise InputError(
            "folder has no metadata.yaml and "
            + ("several bag files" if files else "no .db3 or .mcap file")
            + "; a ROS 2 bag folder expected",
            source=str(path),
        )
    if path.name == "metadata.yaml" or (path.parent / "metadata.yaml").exists():
        return path.parent
    return path  # a storage file without metadata.yaml (rosbags reads mcap files alone)


def _pose_topic_names(connections: Iterable[Connection], source: str) -> dict[str, str]:
    names: dict[str, str] = {}
    for connection in connections:
        parts = [p for p in connection.topic.split("/") if p]
        if len(parts) > 1 and parts[-1] in {"pose", "pose_stamped"}:
            parts.pop()
        name = parts[-1] if parts else connection.topic
        clash = [t for t, n in names.items() if n == name]
        if clash:
            raise InputError(
                f"topics {clash[0]} and {connection.topic} both name object {name!r}; "
                "one PoseStamped topic per object expected",
                source=source,
                field=f"topic {connection.topic}",
            )
        names[connection.topic] = name
    return names


class _Samples:
    """Accumulates decoded bag samples as flat lists."""

    def __init__(self) -> None:
        self.names: list[str] = []
        self.values: list[tuple[float, ...]] = []
        self.where: list[str] = []

    @staticmethod
    def _time(stamp: Any, timestamp: int) -> float:
        sec, nanosec = int(stamp.sec), int(stamp.nanosec)
        if sec == 0 and nanosec == 0:
            return timestamp * 1e-9
        return sec + nanosec * 1e-9

    def add_transform(self, transform: Any, timestamp: int, topic: str) -> None:
        t = self._time(transform.header.stamp, timestamp)
        p, q = transform.transform.translation, transform.transform.rotation
        self.names.append(str(transform.child_frame_id).lstrip("/"))
        self.values.append((t, p.x, p.y, p.z, q.x, q.y, q.z, q.w))
        self.where.append(f"topic {topic}, frame {transform.child_frame_id}, t = {t:.9f}")

    def add_pose(self, name: str, message: Any, timestamp: int, topic: str) -> None:
        t = self._time(message.header.stamp, timestamp)
        p, q = message.pose.position, message.pose.orientation
        self.names.append(name)
        self.values.append((t, p.x, p.y, p.z, q.x, q.y, q.z, q.w))
        self.where.append(f"topic {topic}, t = {t:.9f}")

    def stream(self, source: str) -> PoseStream:
        values = np.array(self.values, dtype=float).reshape(-1, 8)
        bad = np.flatnonzero(~np.isfinite(values).all(axis=1))
        if bad.size:
            i = int(bad[0])
            raise InputError(
                "pose holds NaN or infinity; finite numbers expected",
                source=source,
                field=self.where[i],
            )
        orientations = normalise_quats(values[:, 4:], source, self.where)
        return stream_from_samples(
            self.names, values[:, 0], values[:, 1:4], orientations, source=source, where=self.where
        )
