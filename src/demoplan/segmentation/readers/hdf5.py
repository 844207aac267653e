"""Robosuite / robomimic HDF5 recordings → object pose streams (docs/formats.md "Recording").

A recording holds, per demonstration ``data/<key>``, the simulator's states
over time (``states``: one row per sample, ``[time, qpos…, qvel…, act…]``) and
the MuJoCo model they belong to (the group attribute ``model_file``: either
the XML text itself — robomimic, robosuite ≥ 1.x — or the name of a file in
the ``models/`` folder beside the recording — robosuite 0.3 / 1.0).

The model is read as XML (``defusedxml``), not compiled: the recordings ship
without the meshes they reference. What is taken from it:

* **State layout.** qpos / qvel addresses follow MuJoCo's order — bodies
  depth-first in document order, joints in order within a body; a free joint
  takes 7 qpos (position, quaternion *w, x, y, z*) and 6 qvel, a ball joint 4
  and 3, a hinge or slide joint 1 and 1 (a joint's type comes from its
  ``type`` attribute, else its ``<default>`` class, else ``hinge``).
  Actuators with activation dynamics add to the state's width. A width other
  than ``1 + nq + nv (+ na)`` is refused.
* **Objects**: bodies with a free joint, named by the body's name without
  robosuite's instance suffix (``Milk0`` → ``Milk``) when that stays unique.
* **World frame** (docs/formats.md): z up, the table top is z = 0. The table-top
  height is the ``table_top`` site if the model has one, else the top of the
  collision boxes of a body named ``table``, else the highest static box top
  under each object's first rest (the lowest of these over the objects):
  robosuite's PickPlace has no table, its objects stand on the floor of the
  bin ``bin1`` (top at 0.82 m). It is subtracted from every z.
* **Resting points**: an object's position is the centre of its bottom face.
  For an object made of primitive geoms (box, cylinder, sphere, capsule,
  ellipsoid; with their ``pos`` and orientation) it is the point below the
  body origin at the bottom of their bounding box in the body frame, turned
  with the body's orientation at every sample: the model's own centre (a
  nut's hole, not the middle of nut and handle; for a cube the same point).
  For an object whose collision geometry is a mesh (PickPlace's milk,
  bread, cereal and can) the bottom is *estimated*
  from its first rest: the height of its body origin above the highest
  static surface under it. Such objects get no geometry (only their height
  would be known).
* **Landmarks**: top-level bodies without joints in their subtree that have
  at least one colliding geom (``contype`` / ``conaffinity`` not both 0),
  except the table, the floor and robot mounts (PickPlace's ``Visual*``
  target markers collide with nothing and are left out by that rule). A
  landmark's position is the bottom centre of its colliding geoms' bounding
  box, its orientation the body's yaw.

Samples whose time does not increase (robosuite 0.3's Baxter recordings
repeat a few) are dropped. Every problem is one
:class:`~demoplan.errors.InputError` naming the file (and the demonstration).
"""

from __future__ import annotations

import logging
import re
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from demoplan.documents.poses import check_physical
from demoplan.errors import InputError
from demoplan.fileio import read_input_text
from demoplan.model import Compartment, ObjectGeometry, Pose
from demoplan.rotations import (
    UNIT_TOLERANCE,
    matrices_from_quats,
    unit_length_expected,
)
from demoplan.segmentation.readers.hdf5_container import (
    attribute_text,
    open_recording,
    read_float_table,
)
from demoplan.segmentation.readers.mjcf import ModelLayout, model_layout
from demoplan.segmentation.readers.support import (
    body_geoms,
    geom_bounds,
    landmark_poses,
    object_geometry,
    settled_sample,
    static_surfaces,
    support_top,
    table_top,
)
from demoplan.segmentation.types import (
    ObjectTrack,
    PoseStream,
    check_object_count,
    check_stream_limits,
)

if TYPE_CHECKING:
    import h5py

FloatArray = NDArray[np.float64]
ProvenanceValue = str | int | float

__all__ = [
    "ModelLayout",
    "RecordedDemonstration",
    "demonstration_keys",
    "model_layout",
    "read_demonstration",
    "read_recording",
]

logger = logging.getLogger(__name__)


@dataclass(frozen=True, slots=True, eq=False)
class RecordedDemonstration:
    """One demonstration of a recording, in demoplan's world frame (docs/formats.md).

    Attributes
    ----------
    key : str
        The demonstration's group name in the file (``demo_1``).
    stream : PoseStream
        The free objects' resting points and orientations at the states' times.
    landmarks : tuple of (name, Pose)
        Static bodies usable as references (bins, pegs).
    geometry : tuple of (name, ObjectGeometry)
        Shape and size of objects and landmarks where the model's primitives
        give them.
    compartments : tuple of (name, compartments)
        The open interiors of landmarks that have them (a bin's compartments,
        :func:`demoplan.documents.compartments.compartments`), in the landmark's frame.
    provenance : tuple of (key, value)
        ``source``, ``demonstration``, ``samples``, ``env``,
        ``robosuite_version``, ``model`` and ``table_top_z`` (the simulator's
        height of z = 0, m) — what is known.
    """

    key: str
    stream: PoseStream
    landmarks: tuple[tuple[str, Pose], ...]
    geometry: tuple[tuple[str, ObjectGeometry], ...]
    provenance: tuple[tuple[str, ProvenanceValue], ...]
    compartments: tuple[tuple[str, tuple[Compartment, ...]], ...] = ()

    @property
    def env(self) -> str | None:
        """The robosuite environment's name, when the file records it."""
        value = dict(self.provenance).get("env")
        return value if isinstance(value, str) else None

    @property
    def samples(self) -> int:
        """Number of states read (after dropping samples whose time does not increase)."""
        return len(self.stream.tracks[0]) if self.stream.tracks else 0


def _matrices_from_wxyz(quats: FloatArray) -> FloatArray:
    """Rotation matrices (n, 3, 3) from MuJoCo's quaternions (n, 4) ordered w, x, y, z."""
    xyzw = quats[:, [1, 2, 3, 0]]
    return matrices_from_quats(xyzw / np.linalg.norm(xyzw, axis=1, keepdims=True)).reshape(-1, 3, 3)


def _object_names(layout: ModelLayout) -> list[str]:
    """Object names: body names without a trailing instance ``0`` where that stays unique."""
    raw = [layout.bodies[i].name for i in layout.free_bodies]
    taken = {b.name for b in layout.bodies}
    names = []
    for name in raw:
        short = name[:-1] if name.endswith("0") and len(name) > 1 else name
        clash = short != name and (
            short in taken or sum(1 for n in raw if (n[:-1] if n.endswith("0") else n) == short) > 1
        )
        names.append(name if clash else short)
    return names


def _natural_key(key: str) -> tuple[str, int, str]:
    match = re.match(r"^(.*?)(\d+)$", key)
    return (match.group(1), int(match.group(2)), key) if match else (key, -1, key)


@contextmanager
def _h5_errors(source: str) -> Iterator[None]:
    """A damaged file can fail at any read: one InputError naming it."""
    try:
        yield
    except InputError:
        raise
    except (OSError, RuntimeError, KeyError, ValueError, TypeError) as exc:
        detail = " ".join(str(exc).split())
        raise InputError(f"damaged HDF5 file ({detail})", source=source) from None


def _data_group(handle: h5py.File, source: str) -> Any:
    import h5py

    data = handle.get("data")
    if not isinstance(data, h5py.Group):
        raise InputError(
            "no 'data' group; a robosuite / robomimic recording (data/demo_N/states) expected",
            source=source,
            field="data",
        )
    return data


def demonstration_keys(path: str | Path) -> tuple[str, ...]:
    """The demonstrations' keys in a recording (``demo_1``, ``demo_2``, … in number order)."""
    path = Path(path)
    source = str(path)
    with open_recording(path) as handle, _h5_errors(source):
        data = _data_group(handle, source)
        keys = sorted((str(k) for k in data), key=_natural_key)
    if not keys:
        raise InputError("'data' holds no demonstrations", source=source, field="data")
    return tuple(keys)


def _model_xml(group: Any, path: Path, key: str) -> tuple[str, str]:
    """The demonstration's model XML and a name for it (the file, or "model_file attribute")."""
    source = f"{path}: {key}"
    value = attribute_text(group.attrs, "model_file", source)
    if value is None:
        raise InputError(
            "no 'model_file' attribute; the MuJoCo model (XML text or a file name) expected",
            source=source,
            field="model_file",
        )
    if value.lstrip().startswith("<"):
        return value, f"{source}: model_file"
    name = Path(value).name
    # The recording as named may be a link (to a download cache): its model is
    # the one in models/ beside the file it names, and nothing outside models/
    # (not the recording's other neighbours: a name such as "../notes.txt" or
    # a link in models/ leading to one would make demoplan read them).
    models = path.resolve().parent / "models"
    candidate = models / name
    if candidate.is_file():
        if not candidate.resolve().is_relative_to(models):
            raise InputError(
                f"model file {str(candidate)!r} leads outside the recording's models/ folder "
                f"(to {str(candidate.resolve())!r}); a model in models/ beside the recording "
                "expected",
                source=source,
                field="model_file",
            )
        return read_input_text(candidate, "a MuJoCo model (XML)"), str(candidate)
    raise InputError(
        f"model file {value!r} not found in {models}",
        source=source,
        field="model_file",
    )


def read_demonstration(path: str | Path, key: str) -> RecordedDemonstration:
    """Read demonstration ``key`` of a recording (module docstring)."""
    import h5py

    path = Path(path)
    source = f"{path}: {key}"
    with open_recording(path) as handle, _h5_errors(source):
        data = _data_group(handle, str(path))
        group = data.get(key)
        if not isinstance(group, h5py.Group):
            raise InputError(f"no demonstration group {key!r}", source=str(path), field="data")
        dataset = group.get("states")
        if not isinstance(dataset, h5py.Dataset):
            raise InputError(
                "no 'states' dataset; the simulator states (time, qpos, qvel) expected",
                source=source,
                field="states",
            )
        # The model first: its size is checked before the states it sizes are read.
        xml, model_source = _model_xml(group, path, key)
        layout = model_layout(xml, model_source)
        check_object_count(len(layout.free_bodies), "free-jointed bodies", model_source, None)
        try:
            states = read_float_table(dataset, source, "states", int(handle.id.get_filesize()))
        except (OSError, ValueError, TypeError) as exc:
            if isinstance(exc, InputError):
                raise
            raise InputError(f"cannot read states ({exc})", source=source, field="states") from None
        env = attribute_text(data.attrs, "env", str(path))
        version = attribute_text(data.attrs, "repository_version", str(path))
        if env is None:
            env = _env_from_robomimic(attribute_text(data.attrs, "env_args", str(path)))
    if states.ndim != 2 or states.shape[0] == 0:
        raise InputError(
            f"states of shape {states.shape}; a table (samples × (1 + nq + nv)) expected",
            source=source,
            field="states",
        )
    if not layout.free_bodies:
        raise InputError(
            "the model has no free-jointed body (no objects to follow)", source=model_source
        )
    if states.shape[1] not in layout.widths():
        raise InputError(
            f"states have {states.shape[1]} columns; the model expects "
            f"{' or '.join(map(str, layout.widths()))} (1 time + {layout.nq} qpos + "
            f"{layout.nv} qvel" + (f" [+ {layout.na} act]" if layout.na else "") + ")",
            source=source,
            field="states",
        )
    if not np.isfinite(states[:, : 1 + layout.nq]).all():
        raise InputError("states hold NaN or infinity", source=source, field="states")
    times = states[:, 0]
    keep = np.concatenate(([True], times[1:] > np.maximum.accumulate(times)[:-1]))
    if not keep.all():
        logger.warning("%s: %d samples whose time does not increase dropped", source, (~keep).sum())
        states, times = states[keep], times[keep]
    return _demonstration(path, key, states, times, layout, env, version, model_source)


def _env_from_robomimic(text: str | None) -> str | None:
    """robomimic's ``data`` attribute ``env_args`` is JSON with ``env_name``."""
    if text is None:
        return None
    import json

    try:
        parsed = json.loads(text)
    except ValueError:
        return None
    name = parsed.get("env_name") if isinstance(parsed, dict) else None
    return name if isinstance(name, str) else None


def _demonstration(
    path: Path,
    key: str,
    states: FloatArray,
    times: FloatArray,
    layout: ModelLayout,
    env: str | None,
    version: str | None,
    model_source: str,
) -> RecordedDemonstration:
    qpos = states[:, 1 : 1 + layout.nq]
    names = _object_names(layout)
    surfaces = static_surfaces(layout)
    body_pos: list[FloatArray] = []
    body_quat: list[FloatArray] = []
    rests: list[int] = []
    for address in layout.qpos_address:
        p = qpos[:, address : address + 3]
        q = qpos[:, address + 3 : address + 7]
        lengths = np.linalg.norm(q, axis=1)
        off = np.flatnonzero(~(np.abs(lengths - 1.0) <= UNIT_TOLERANCE))
        if off.size:
            raise InputError(
                f"the quaternion of {layout.bodies[layout.free_bodies[len(body_pos)]].name!r} at "
                f"sample {int(off[0])} ({', '.join(f'{v:g}' for v in q[off[0]])}): "
                f"{unit_length_expected(float(lengths[off[0]]))} (MuJoCo keeps it within 1e-15)",
                source=f"{path}: {key}",
                field="states",
            )
        body_pos.append(p)
        body_quat.append(q)
        rests.append(settled_sample(times, p))
    rest_points = [p[i] for p, i in zip(body_pos, rests, strict=True)]
    table_z = table_top(layout, surfaces, rest_points, str(path))
    tracks, geometry = [], []
    for k, index in enumerate(layout.free_bodies):
        geoms = body_geoms(layout, index)
        bounds = geom_bounds(geoms)
        rot = _matrices_from_wxyz(body_quat[k])
        if bounds is not None:
            low, high = bounds
            offset = np.array([0.0, 0.0, low[2]])  # below the body origin
            geometry.append((names[k], object_geometry(geoms, low, high)))
        else:
            # Mesh object: its body origin's height above the surface it first rests on.
            settled = rests[k]
            support = support_top(surfaces, rest_points[k])
            height = float(rest_points[k][2]) - (table_z if support is None else support)
            offset = rot[settled].T @ np.array([0.0, 0.0, -height])
            logger.info(
                "%s: %s is a mesh; its bottom estimated %.4f m below its origin",
                key,
                names[k],
                height,
            )
        positions = body_pos[k] + rot @ offset
        positions[:, 2] -= table_z
        quats = np.ascontiguousarray(body_quat[k][:, [1, 2, 3, 0]])
        quats /= np.linalg.norm(quats, axis=1, keepdims=True)
        tracks.append(ObjectTrack(names[k], times.copy(), np.ascontiguousarray(positions), quats))
    landmarks, landmark_geometry, compartments = landmark_poses(layout, table_z, set(names))
    _check_limits(tracks, landmarks, geometry + landmark_geometry, f"{path}: {key}")
    provenance: list[tuple[str, ProvenanceValue]] = [
        ("source", str(path)),
        ("demonstration", key),
        ("samples", int(states.shape[0])),
    ]
    if env is not None:
        provenance.append(("env", env))
    if version is not None:
        provenance.append(("robosuite_version", version))
    provenance += [("model", Path(model_source).name), ("table_top_z", round(table_z, 6))]
    return RecordedDemonstration(
        key=key,
        stream=PoseStream(tuple(tracks), f"{path}: {key}"),
        landmarks=tuple(landmarks),
        geometry=tuple(geometry + landmark_geometry),
        provenance=tuple(provenance),
        compartments=tuple(compartments),
    )


def _check_limits(
    tracks: Sequence[ObjectTrack],
    landmarks: Sequence[tuple[str, Pose]],
    geometry: Sequence[tuple[str, ObjectGeometry]],
    source: str,
) -> None:
    """The limits every demonstration file keeps (docs/limits.md), by the same
    validation (:func:`~demoplan.documents.poses.check_physical`): every
    sample's position within 1 km of the origin (:func:`check_stream_limits`),
    the landmarks' too, the extents of objects and landmarks within
    0.1 mm – 10 m; one InputError naming the object. (The spread of what is
    imported is checked on each demonstration made: ``check_measured``.)"""
    check_stream_limits(PoseStream(tuple(tracks), source))
    check_physical(
        {
            "landmarks": {name: {"position": list(pose.position)} for name, pose in landmarks},
            "objects": {name: {"size": list(shape.size)} for name, shape in geometry},
        },
        "m",
        source,
    )


def read_recording(
    path: str | Path, progress: Callable[[int, int, str], None] | None = None
) -> list[RecordedDemonstration]:
    """Read every demonstration of a recording; ``progress(done, total, key)`` after each."""
    keys = demonstration_keys(path)
    out = []
    for done, key in enumerate(keys, 1):
        out.append(read_demonstration(path, key))
        if progress is not None:
            progress(done, len(keys), key)
    return out
