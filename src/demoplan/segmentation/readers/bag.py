"""ROS 2 bag pose streams (docs/formats.md "Pose stream"), read with ``rosbags``.

A bag (sqlite3 or mcap; a bag folder or its storage file) is read with
``rosbags.highlevel.AnyReader``:

- ``tf2_msgs/msg/TFMessage`` topics (any topic of that type; one whose name
  ends in ``tf_static`` holds static transforms, valid for all time): every
  transform links its ``child_frame_id`` to its parent (``header.frame_id``).
  The links form a tree (:mod:`demoplan.segmentation.tftree`), and each
  object frame's poses are composed to the world frame (``frame``, default
  the tree's root) at the frame's own sample times, its parents interpolated.
  The objects are, by default, the tree's leaves: every frame other than the
  world frame that has no children. A frame with two parents, on both
  ``/tf`` and ``/tf_static``, or in a cycle is an error; a frame not
  connected to the world frame is left out with a logged warning;
- ``geometry_msgs/msg/PoseStamped`` topics, one per object: the object is
  named by the topic's last component, or the one before it when the last is
  ``pose`` (``/mocap/plate/pose`` and ``/plate`` both name ``plate``).

A sample's time is its header stamp, or the bag's receive time when the
stamp is zero. Other topics are ignored. Every problem is one
:class:`~demoplan.errors.InputError` naming the file, the topic and what was
expected. ``rosbags`` is imported on first use.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from demoplan.errors import InputError
from demoplan.segmentation.tftree import FrameLink, TransformTree
from demoplan.segmentation.types import (
    FloatArray,
    ObjectTrack,
    PoseStream,
    check_object_count,
    normalise_quats,
    select_objects,
    stream_from_samples,
)

if TYPE_CHECKING:
    from rosbags.interfaces import Connection

__all__ = ["POSE_TYPE", "TF_TYPE", "load_bag"]

TF_TYPE = "tf2_msgs/msg/TFMessage"
POSE_TYPE = "geometry_msgs/msg/PoseStamped"


def load_bag(
    path: str | Path, *, frame: str | None = None, objects: Sequence[str] | None = None
) -> PoseStream:
    """Read a ROS 2 bag (folder, its ``.db3`` / ``.mcap`` file, or ``metadata.yaml``).

    Parameters
    ----------
    path : str or Path
        The bag.
    frame : str, optional
        The world frame TF frames are composed to; by default the TF tree's
        root (several roots are an error asking for it). Ignored without TF topics.
    objects : sequence of str, optional
        Object names or :mod:`fnmatch` patterns (TF frames, PoseStamped
        objects). By default the PoseStamped objects and the TF tree's leaves:
        every frame except the world frame and frames that have children.
    """
    from rosbags.highlevel import AnyReader, AnyReaderError

    path = Path(path)
    source = str(path)
    bag = _bag_folder(path)
    if bag.is_dir():
        _refuse_links_out_of(bag)
    samples = _Samples(source)
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
    except UnicodeDecodeError as exc:  # Python's words ("'utf-8' codec can't decode…") are not
        raise InputError(
            f"cannot read ROS 2 bag (a name or type in it is not UTF-8, byte "
            f"0x{exc.object[exc.start]:02x}: a damaged or cut file?)",
            source=source,
        ) from None
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
    return samples.stream(source, frame, objects)


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


def _refuse_links_out_of(folder: Path) -> None:
    """A bag is read from its own folder: ``metadata.yaml`` and the storage
    files it lists are opened there, so an entry that is a link leading out
    of the folder (an unpacked archive's ``bag_0.db3`` → another file) is
    refused before anything is opened (docs/limits.md, "What demoplan opens")."""
    inside = folder.resolve()
    for entry in sorted(folder.iterdir()):
        if not entry.is_symlink():
            continue
        try:
            target = str(entry.resolve())
        except (OSError, RuntimeError):  # a loop of links leads nowhere in the folder
            target = str(entry.readlink())
        if not Path(target).is_relative_to(inside):
            raise InputError(
                f"a link leading out of the bag's folder (to {target!r}); a bag's "
                "own files expected",
                source=str(entry),
            )


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
    """Accumulates decoded bag samples as flat lists, in the order they were read."""

    def __init__(self, source: str) -> None:
        self.source = source
        self.names: list[str] = []
        self.values: list[tuple[float, ...]] = []
        self.where: list[str] = []
        self.parents: list[str | None] = []  # a transform's parent frame; None for a pose
        self.static: list[bool] = []
        self.distinct: set[str] = set()  # the names read so far (frames, pose objects)

    @staticmethod
    def _time(stamp: Any, timestamp: int) -> float:
        sec, nanosec = int(stamp.sec), int(stamp.nanosec)
        if sec == 0 and nanosec == 0:
            return timestamp * 1e-9
        return sec + nanosec * 1e-9

    def add_transform(self, transform: Any, timestamp: int, topic: str) -> None:
        t = self._time(transform.header.stamp, timestamp)
        p, q = transform.transform.translation, transform.transform.rotation
        child, parent = str(transform.child_frame_id).lstrip("/"), str(transform.header.frame_id)
        self.names.append(child)
        self.values.append((t, p.x, p.y, p.z, q.x, q.y, q.z, q.w))
        self.where.append(f"topic {topic}, frame {transform.child_frame_id}, t = {t:.9f}")
        self.parents.append(parent.lstrip("/"))
        self.static.append(topic.endswith("tf_static"))
        self._count(child, topic)

    def _count(self, name: str, topic: str) -> None:
        """Refuse the bag as soon as it names more than MAX_OBJECTS frames and
        objects (a tree of thousands of frames is refused after reading a few
        of its messages, not after minutes of decoding)."""
        if name not in self.distinct:
            self.distinct.add(name)
            check_object_count(
                len(self.distinct), "TF frames and pose objects", self.source, f"topic {topic}"
            )

    def add_pose(self, name: str, message: Any, timestamp: int, topic: str) -> None:
        t = self._time(message.header.stamp, timestamp)
        p, q = message.pose.position, message.pose.orientation
        self.names.append(name)
        self.values.append((t, p.x, p.y, p.z, q.x, q.y, q.z, q.w))
        self.where.append(f"topic {topic}, t = {t:.9f}")
        self.parents.append(None)
        self.static.append(False)
        self._count(name, topic)

    def stream(self, source: str, frame: str | None, objects: Sequence[str] | None) -> PoseStream:
        """The stream of the chosen objects: pose topics as read, TF frames composed."""
        values = np.array(self.values, dtype=float).reshape(-1, 8)
        bad = np.flatnonzero(~np.isfinite(values).all(axis=1))
        if bad.size:
            i = int(bad[0])
            raise InputError(
                "pose holds NaN or infinity; finite numbers expected",
                source=source,
                field=self.where[i],
            )
        quats = normalise_quats(values[:, 4:], source, self.where)
        poses = [i for i, parent in enumerate(self.parents) if parent is None]
        tracks: dict[str, ObjectTrack] = {}
        if poses:
            tracks = {
                track.name: track
                for track in stream_from_samples(
                    [self.names[i] for i in poses],
                    values[poses, 0],
                    values[poses, 1:4],
                    quats[poses],
                    source=source,
                    where=[self.where[i] for i in poses],
                )
            }
        available, default = list(tracks), list(tracks)
        tree: TransformTree | None = None
        world = ""
        if len(poses) < len(self.names):
            tree = TransformTree(self._links(values, quats, source, set(tracks)), source)
            world = tree.world_frame(frame)
            available += [f for f in tree.frames if f != world]
            default += tree.object_frames(world)
        # Objects in order of first appearance (a root, never a child, comes last).
        rank = {name: k for k, name in enumerate(dict.fromkeys([*self.names, *available]))}
        chosen = select_objects(
            objects,
            sorted(available, key=rank.__getitem__),
            sorted(default, key=rank.__getitem__),
            source=source,
        )
        if tree is not None:
            tracks |= tree.tracks_in([f for f in chosen if f not in tracks], world)
        if not any(name in tracks for name in chosen):
            raise InputError(
                f"no object frame is connected to the world frame {world!r}; "
                "choose another with --frame",
                source=source,
                field="frame",
            )
        return PoseStream(tuple(tracks[name] for name in chosen if name in tracks), source)

    def _links(
        self, values: FloatArray, quats: FloatArray, source: str, pose_objects: set[str]
    ) -> list[FrameLink]:
        """One :class:`FrameLink` per child frame, in order of first appearance.

        A static frame keeps its latest transform; a frame has one parent, and is
        published either on ``/tf`` or on ``/tf_static``.
        """
        parents: dict[str, tuple[str, int]] = {}
        static: dict[str, int] = {}
        moving: list[int] = []
        for i, (name, parent) in enumerate(zip(self.names, self.parents, strict=True)):
            if parent is None:
                continue
            if not parent:
                raise InputError(
                    "transform without a parent frame (empty header.frame_id); "
                    "a parent frame name expected",
                    source=source,
                    field=self.where[i],
                )
            if name in pose_objects:
                raise InputError(
                    f"{name!r} is both a TF frame and a PoseStamped topic's object; "
                    "one source per object expected",
                    source=source,
                    field=self.where[i],
                )
            known, first = parents.setdefault(name, (parent, i))
            if known != parent:
                raise InputError(
                    f"frame {name!r} has parents {known!r} and {parent!r}; "
                    "one parent per frame expected",
                    source=source,
                    field=self.where[i],
                )
            if self.static[i] != self.static[first]:
                raise InputError(
                    f"frame {name!r} is published on both /tf and /tf_static; one expected",
                    source=source,
                    field=self.where[i],
                )
            if not self.static[i]:
                moving.append(i)
            elif name not in static or values[i, 0] >= values[static[name], 0]:
                static[name] = i  # static transforms: the latest holds
        links: dict[str, FrameLink] = {}
        if moving:
            for track in stream_from_samples(
                [self.names[i] for i in moving],
                values[moving, 0],
                values[moving, 1:4],
                quats[moving],
                source=source,
                where=[self.where[i] for i in moving],
            ):
                links[track.name] = FrameLink(parents[track.name][0], track)
        for name, i in static.items():
            row = slice(i, i + 1)
            track = ObjectTrack(name, values[row, 0].copy(), values[row, 1:4], quats[row])
            links[name] = FrameLink(parents[name][0], track, static=True)
        return [links[name] for name in parents]
