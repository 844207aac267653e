"""Pose streams: what a motion-capture system or an object tracker records.

A :class:`PoseStream` holds one :class:`ObjectTrack` per object: sample times
(seconds, strictly increasing), positions (metres, world frame, z up) and,
when the source has them, orientations as unit quaternions ``(x, y, z, w)``.
Tracks are sampled independently: rates may differ between objects, vary over
time, and samples may be missing.

Sources (SPEC §3 "Pose stream"):

* **CSV** with header ``t,object,x,y,z`` plus optionally ``yaw``, or
  ``roll,pitch,yaw`` (degrees, extrinsic x-y-z), or ``qx,qy,qz,qw``; one row
  per object per sample, rows in any order, columns in any order. Blank lines
  and lines starting with ``#`` are skipped. Orientation cells may be left
  empty for an object without orientation (all of its rows, all the cells).
* **ROS 2 bags** (sqlite3 or mcap, a bag folder or its storage file), read
  with ``rosbags.highlevel.AnyReader``:

  - ``tf2_msgs/msg/TFMessage`` topics: every transform is a sample of the
    object named by its ``child_frame_id``; its translation and rotation are
    taken as the object's pose in the world (the parent frame is assumed to be
    the world frame and is not composed further);
  - ``geometry_msgs/msg/PoseStamped`` topics, one per object: the object is
    named by the topic's last component, or the one before it when the last is
    ``pose`` (``/mocap/plate/pose`` and ``/plate`` both name ``plate``).

  A sample's time is its header stamp, or the bag's receive time when the
  stamp is zero. Other topics are ignored.

Every problem is one :class:`~demoplan.errors.InputError` naming the file, the
row / field / topic and what was expected.
"""

from __future__ import annotations

import csv
import io
import logging
import math
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import NDArray

from demoplan.errors import InputError
from demoplan.fileio import write_atomic

if TYPE_CHECKING:
    from rosbags.interfaces import Connection

FloatArray = NDArray[np.float64]

__all__ = [
    "BagKind",
    "BagStorage",
    "ObjectTrack",
    "PoseStream",
    "load_bag",
    "load_csv",
    "load_stream",
    "stream_from_samples",
    "write_bag",
    "write_csv",
]

logger = logging.getLogger(__name__)

BagKind = Literal["tf", "pose"]
BagStorage = Literal["sqlite3", "mcap"]

TF_TYPE = "tf2_msgs/msg/TFMessage"
POSE_TYPE = "geometry_msgs/msg/PoseStamped"
WORLD_FRAME = "world"

_BASE_COLUMNS = ("t", "object", "x", "y", "z")
_ORIENTATION_SETS: dict[frozenset[str], tuple[str, ...]] = {
    frozenset(): (),
    frozenset({"yaw"}): ("yaw",),
    frozenset({"roll", "pitch", "yaw"}): ("roll", "pitch", "yaw"),
    frozenset({"qx", "qy", "qz", "qw"}): ("qx", "qy", "qz", "qw"),
}
_EXPECTED_HEADER = "t,object,x,y,z plus optionally yaw | roll,pitch,yaw | qx,qy,qz,qw"


# --------------------------------------------------------------------------- types


@dataclass(frozen=True, slots=True, eq=False)
class ObjectTrack:
    """The samples of one object.

    Parameters
    ----------
    name : str
        The object's name (CSV ``object`` column, TF child frame, topic).
    times : ndarray, shape (n,)
        Sample times in seconds, strictly increasing.
    positions : ndarray, shape (n, 3)
        Positions in metres (world frame, z up).
    orientations : ndarray, shape (n, 4), or None
        Unit quaternions ``(x, y, z, w)``; ``None`` when the source has none.
    """

    name: str
    times: FloatArray
    positions: FloatArray
    orientations: FloatArray | None = None

    def __post_init__(self) -> None:
        n = self.times.shape[0]
        if self.times.ndim != 1 or self.positions.shape != (n, 3):
            raise ValueError(
                f"track {self.name!r}: times (n,) and positions (n, 3) expected, got "
                f"{self.times.shape} and {self.positions.shape}"
            )
        if self.orientations is not None and self.orientations.shape != (n, 4):
            raise ValueError(
                f"track {self.name!r}: orientations (n, 4) expected, got {self.orientations.shape}"
            )
        if n > 1 and not bool(np.all(np.diff(self.times) > 0)):
            raise ValueError(f"track {self.name!r}: times must be strictly increasing")

    def __len__(self) -> int:
        return int(self.times.shape[0])

    @property
    def duration(self) -> float:
        """Time from the first to the last sample (s)."""
        return float(self.times[-1] - self.times[0]) if len(self) else 0.0


@dataclass(frozen=True, slots=True, eq=False)
class PoseStream:
    """Object poses over time: one :class:`ObjectTrack` per object, in order of appearance."""

    tracks: tuple[ObjectTrack, ...]
    source: str | None = None

    @property
    def objects(self) -> tuple[str, ...]:
        """The objects' names, in the stream's order."""
        return tuple(track.name for track in self.tracks)

    @property
    def n_samples(self) -> int:
        """Number of samples over all objects."""
        return sum(len(track) for track in self.tracks)

    @property
    def start_time(self) -> float:
        return min(float(track.times[0]) for track in self.tracks if len(track))

    @property
    def end_time(self) -> float:
        return max(float(track.times[-1]) for track in self.tracks if len(track))

    def track(self, name: str) -> ObjectTrack:
        """The track of object ``name`` (``KeyError`` if absent)."""
        for track in self.tracks:
            if track.name == name:
                return track
        raise KeyError(name)

    def __iter__(self) -> Iterator[ObjectTrack]:
        return iter(self.tracks)


def stream_from_samples(
    names: Sequence[str],
    times: FloatArray,
    positions: FloatArray,
    orientations: FloatArray | None = None,
    *,
    source: str | None = None,
    where: Sequence[str] | None = None,
) -> PoseStream:
    """Group flat samples (one per row, any order) into a :class:`PoseStream`.

    ``orientations`` may hold NaN rows for samples without an orientation; an
    object must then have orientations on all of its samples or on none.
    ``where[i]`` names sample i in error messages (e.g. ``"row 12"``). Two
    samples of one object at the same time are refused.
    """
    codes, order_names = _codes(names)
    label = (lambda i: where[i]) if where is not None else (lambda i: f"sample {i}")
    has_q: NDArray[np.bool_] | None = None
    if orientations is not None:
        has_q = np.asarray(~np.isnan(orientations).any(axis=1), dtype=bool)
    tracks = []
    # One stable sort groups the samples by object, in time order within each.
    order = np.lexsort((times, codes))
    bounds = np.searchsorted(codes[order], np.arange(len(order_names) + 1))
    for k, name in enumerate(order_names):
        index = order[bounds[k] : bounds[k + 1]]
        t = times[index]
        repeated = np.flatnonzero(np.diff(t) <= 0)
        if repeated.size:
            first = int(index[repeated[0] + 1])
            raise InputError(
                f"object {name!r} has two samples at t = {float(t[repeated[0]]):g}; "
                "one sample per object per time expected",
                source=source,
                field=label(first),
            )
        quats = None
        if orientations is not None and has_q is not None:
            present = has_q[index]
            if present.any() and not present.all():
                missing = int(index[int(np.argmin(present))])
                raise InputError(
                    f"object {name!r} has orientations on some samples only; "
                    "every sample of an object needs one, or none",
                    source=source,
                    field=label(missing),
                )
            if present.all():
                quats = orientations[index]
        tracks.append(
            ObjectTrack(
                name,
                np.ascontiguousarray(t, dtype=float),
                np.ascontiguousarray(positions[index], dtype=float),
                None if quats is None else np.ascontiguousarray(quats, dtype=float),
            )
        )
    return PoseStream(tuple(tracks), source)


def _codes(names: Sequence[str]) -> tuple[NDArray[np.intp], list[str]]:
    """Integer code per sample, codes numbered in order of first appearance."""
    table: dict[str, int] = {}
    codes = np.fromiter((table.setdefault(name, len(table)) for name in names), np.intp, len(names))
    return codes, list(table)


def _normalise_quats(
    quats: FloatArray, source: str | None, where: Sequence[str] | None
) -> FloatArray:
    norms = np.linalg.norm(quats, axis=1)
    bad = np.flatnonzero(~(norms > 1e-9) & ~np.isnan(norms))
    if bad.size:
        i = int(bad[0])
        raise InputError(
            "zero quaternion; a non-zero quaternion (qx, qy, qz, qw) expected",
            source=source,
            field=where[i] if where is not None else f"sample {i}",
        )
    with np.errstate(invalid="ignore"):
        unit = quats / norms[:, None]
    return np.asarray(unit, dtype=float)


# --------------------------------------------------------------------------- loading


def load_stream(path: str | Path) -> PoseStream:
    """Read a pose stream: a CSV file, or a ROS 2 bag (folder, ``.db3`` or ``.mcap``).

    A folder, a ``.db3``, ``.mcap`` or ``metadata.yaml`` path is read as a bag;
    anything else as CSV.
    """
    path = Path(path)
    if not path.exists():
        raise InputError(
            "no such file or folder; a CSV file or a ROS 2 bag expected", source=str(path)
        )
    if path.is_dir() or path.suffix.lower() in {".db3", ".mcap"} or path.name == "metadata.yaml":
        return load_bag(path)
    return load_csv(path)


def load_csv(path: str | Path) -> PoseStream:
    """Read a CSV pose stream (module docstring); angles in degrees, lengths in metres."""
    path = Path(path)
    source = str(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read file as UTF-8 text ({exc})", source=source) from None
    lines = [
        (number, line)
        for number, line in enumerate(text.splitlines(), start=1)
        if line.strip() and not line.lstrip().startswith("#")
    ]
    if not lines:
        raise InputError(f"empty file; a CSV header {_EXPECTED_HEADER} expected", source=source)
    rows = list(csv.reader(line for _, line in lines))
    header = [cell.strip().lower() for cell in rows[0]]
    columns = _check_header(header, source, lines[0][0])
    body = rows[1:]
    numbers = [number for number, _ in lines[1:]]
    if not body:
        raise InputError("no samples; at least one row after the header expected", source=source)
    width = len(header)
    for row, number in zip(body, numbers, strict=True):
        if len(row) != width:
            raise InputError(
                f"{len(row)} cells; {width} expected ({','.join(header)})",
                source=source,
                field=f"line {number}",
            )
    where = [f"line {number}" for number in numbers]
    names = [row[columns["object"]].strip() for row in body]
    for i, name in enumerate(names):
        if not name:
            raise InputError(
                "empty object name", source=source, field=f"{where[i]}, column 'object'"
            )

    def column(name: str, *, optional: bool = False) -> FloatArray:
        """A numeric column; with ``optional``, empty cells are NaN (no orientation)."""
        cells = [row[columns[name]] for row in body]
        empty = np.array([not c.strip() for c in cells]) if optional else None
        if empty is not None and empty.any():
            cells = ["nan" if e else c for c, e in zip(cells, empty.tolist(), strict=True)]
        try:
            values = np.array(cells, dtype=float)
        except ValueError:
            i = next(i for i, c in enumerate(cells) if not _is_number(c))
            raise InputError(
                f"{cells[i].strip()!r} is not a number; a number expected",
                source=source,
                field=f"{where[i]}, column {name!r}",
            ) from None
        finite = np.isfinite(values)
        if empty is not None:
            finite |= empty
        bad_values = np.flatnonzero(~finite)
        if bad_values.size:
            i = int(bad_values[0])
            raise InputError(
                f"{cells[i].strip()!r} is not a finite number; a finite number expected",
                source=source,
                field=f"{where[i]}, column {name!r}",
            )
        return values

    def orientation_columns(names: tuple[str, ...]) -> FloatArray:
        values = np.stack([column(c, optional=True) for c in names], axis=1)
        missing = np.isnan(values)
        partial = np.flatnonzero(missing.any(axis=1) & ~missing.all(axis=1))
        if partial.size:
            i = int(partial[0])
            raise InputError(
                f"orientation cells {','.join(names)} must be all given or all empty",
                source=source,
                field=where[i],
            )
        return values

    times = column("t")
    positions = np.stack([column("x"), column("y"), column("z")], axis=1)
    kind = columns["__orientation__"]
    orientations: FloatArray | None = None
    if kind == ("yaw",):
        yaw = np.radians(orientation_columns(kind)[:, 0]) / 2.0
        zeros = np.zeros_like(yaw)
        orientations = np.stack([zeros, zeros, np.sin(yaw), np.cos(yaw)], axis=1)
    elif kind == ("roll", "pitch", "yaw"):
        orientations = quats_from_rpy_array(orientation_columns(kind))
    elif kind:
        orientations = _normalise_quats(orientation_columns(kind), source, where)
    return stream_from_samples(names, times, positions, orientations, source=source, where=where)


def _check_header(header: list[str], source: str, line: int) -> dict[str, Any]:
    field = f"line {line} (header)"
    seen: set[str] = set()
    for name in header:
        if name in seen:
            raise InputError(f"column {name!r} appears twice", source=source, field=field)
        seen.add(name)
    missing = [c for c in _BASE_COLUMNS if c not in seen]
    if missing:
        raise InputError(
            f"missing column{'s' if len(missing) > 1 else ''} {', '.join(missing)}; "
            f"expected {_EXPECTED_HEADER}",
            source=source,
            field=field,
        )
    extra = frozenset(seen - set(_BASE_COLUMNS))
    if extra not in _ORIENTATION_SETS:
        raise InputError(
            f"unknown orientation columns {','.join(sorted(extra))}; expected {_EXPECTED_HEADER}",
            source=source,
            field=field,
        )
    columns: dict[str, Any] = {name: index for index, name in enumerate(header)}
    columns["__orientation__"] = _ORIENTATION_SETS[extra]
    return columns


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def quats_from_rpy_array(angles_deg: FloatArray) -> FloatArray:
    """``(n, 3)`` extrinsic x-y-z Euler angles (degrees) → ``(n, 4)`` quaternions (x, y, z, w).

    The vectorised form of :func:`demoplan.rotations.quat_from_rpy`.
    """
    half = np.radians(np.asarray(angles_deg, dtype=float)) / 2.0
    cr, cp, cy = np.cos(half).T
    sr, sp, sy = np.sin(half).T
    quats = np.stack(
        [
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy,
        ],
        axis=1,
    )
    quats[quats[:, 3] < 0] *= -1.0
    return np.asarray(quats, dtype=float)


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
        orientations = _normalise_quats(values[:, 4:], source, self.where)
        return stream_from_samples(
            self.names, values[:, 0], values[:, 1:4], orientations, source=source, where=self.where
        )


# --------------------------------------------------------------------------- writing


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
