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
import math
import re
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any
from xml.etree.ElementTree import Element

import numpy as np
from numpy.typing import NDArray

from demoplan.documents.poses import MAX_COORDINATE, check_physical
from demoplan.errors import InputError
from demoplan.fileio import read_input_text
from demoplan.model import Compartment, ObjectGeometry, Pose
from demoplan.rotations import UNIT_TOLERANCE, quat_from_yaw, unit_length_expected
from demoplan.scenes.regions import compartments
from demoplan.segmentation.readers.hdf5_container import (
    attribute_text,
    open_recording,
    read_float_table,
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

PRIMITIVES = frozenset({"box", "sphere", "cylinder", "capsule", "ellipsoid"})
JOINT_QPOS = {"free": 7, "ball": 4, "hinge": 1, "slide": 1}
JOINT_QVEL = {"free": 6, "ball": 3, "hinge": 1, "slide": 1}
EXCLUDED_LANDMARKS = re.compile(r"^(table|floor|ground)$|mount|pedestal|^visual", re.IGNORECASE)
SETTLE_WINDOW_S = 0.25  # s: an object has settled when it stays within SETTLE_TOLERANCE this long
SETTLE_TOLERANCE = 0.001  # m
SUPPORT_SLACK = 0.005  # m: a surface counts as "under" a point up to this far above it
MAX_MODEL_DEPTH = 100
"""The deepest nesting of elements in a model's XML (robosuite's go 12 deep)."""
MAX_MODEL_BODIES = 10_000
"""Bodies in a recording's model, at most (robosuite's have about a hundred):
reading one costs about a quarter of a millisecond, and the model's text is
read whole before its free bodies can be counted."""


# --------------------------------------------------------------------------- values


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
        :func:`demoplan.scenes.regions.compartments`), in the landmark's frame.
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


@dataclass(frozen=True, slots=True)
class _Geom:
    type: str
    size: tuple[float, ...]
    pos: FloatArray  # in the owning body's frame
    rot: FloatArray  # 3 × 3, geom frame → body frame
    collides: bool


@dataclass(slots=True)
class _Body:
    name: str
    parent: int  # -1: the world
    top: int  # index of its top-level ancestor (itself when top-level)
    pos: FloatArray  # world
    rot: FloatArray  # world ← body
    joints: list[str] = field(default_factory=list)  # joint types, in order
    geoms: list[_Geom] = field(default_factory=list)
    children: list[int] = field(default_factory=list)


@dataclass(frozen=True, slots=True, eq=False)
class ModelLayout:
    """What the importer needs from a MuJoCo model.

    ``bodies`` in MuJoCo's (depth-first) order; ``free_bodies`` the indices of
    bodies with a free joint and ``qpos_address`` the index of each one's
    free joint in qpos; ``nq``, ``nv``, ``na`` the sizes of the state parts;
    ``sites`` the world positions of named sites.
    """

    bodies: tuple[_Body, ...]
    free_bodies: tuple[int, ...]
    qpos_address: tuple[int, ...]
    nq: int
    nv: int
    na: int
    sites: dict[str, FloatArray]
    world_geoms: tuple[_Geom, ...]

    def jointed_subtree(self, index: int) -> bool:
        """Whether body ``index`` or a body below it has a joint."""
        body = self.bodies[index]
        return bool(body.joints) or any(self.jointed_subtree(c) for c in body.children)

    def moves(self, index: int) -> bool:
        """Whether body ``index`` can move (it or an ancestor has a joint)."""
        while index >= 0:
            if self.bodies[index].joints:
                return True
            index = self.bodies[index].parent
        return False

    def widths(self) -> tuple[int, ...]:
        """State widths that fit this model: ``1 + nq + nv (+ na)``."""
        base = 1 + self.nq + self.nv
        return (base, base + self.na) if self.na else (base,)


# --------------------------------------------------------------------------- rotations


def _quat_matrix(w: float, x: float, y: float, z: float) -> FloatArray:
    n = math.sqrt(w * w + x * x + y * y + z * z)
    if n < 1e-12:
        raise ValueError("zero quaternion")
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def _matrices_from_wxyz(quats: FloatArray) -> FloatArray:
    """Rotation matrices (n, 3, 3) from quaternions (n, 4) ordered w, x, y, z."""
    q = quats / np.linalg.norm(quats, axis=1, keepdims=True)
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    out = np.empty((q.shape[0], 3, 3))
    out[:, 0, 0] = 1 - 2 * (y * y + z * z)
    out[:, 0, 1] = 2 * (x * y - z * w)
    out[:, 0, 2] = 2 * (x * z + y * w)
    out[:, 1, 0] = 2 * (x * y + z * w)
    out[:, 1, 1] = 1 - 2 * (x * x + z * z)
    out[:, 1, 2] = 2 * (y * z - x * w)
    out[:, 2, 0] = 2 * (x * z - y * w)
    out[:, 2, 1] = 2 * (y * z + x * w)
    out[:, 2, 2] = 1 - 2 * (x * x + y * y)
    return out


def _axis_angle_matrix(axis: Sequence[float] | FloatArray, angle: float) -> FloatArray:
    a = np.asarray(axis, dtype=float)
    n = float(np.linalg.norm(a))
    if n < 1e-12:
        raise ValueError("zero rotation axis")
    a = a / n
    half = angle / 2.0
    return _quat_matrix(math.cos(half), *(a * math.sin(half)))


# --------------------------------------------------------------------------- model XML


class _Defaults:
    """MuJoCo ``<default>`` classes: class name → element tag → attributes (inherited)."""

    def __init__(self, root: Element) -> None:
        self.classes: dict[str, dict[str, dict[str, str]]] = {"main": {}}
        for default in root.findall("default"):
            self._read(default, {}, top=True)

    def _read(self, element: Element, inherited: dict[str, dict[str, str]], *, top: bool) -> None:
        name = element.get("class") or ("main" if top else "")
        table = {tag: dict(attrs) for tag, attrs in inherited.items()}
        if top and "main" in self.classes:
            table = {tag: dict(attrs) for tag, attrs in self.classes["main"].items()}
        for child in element:
            if child.tag == "default":
                continue
            table.setdefault(child.tag, {}).update(child.attrib)
        if name:
            self.classes[name] = table
        for child in element.findall("default"):
            self._read(child, table, top=False)

    def get(self, element: Element, key: str, cls: str, default: str | None = None) -> str | None:
        """``element``'s attribute ``key``, else its class's (``class`` or the inherited one)."""
        value = element.get(key)
        if value is not None:
            return value
        table = self.classes.get(element.get("class") or cls) or self.classes["main"]
        return table.get(element.tag, {}).get(key, default)


class _ModelReader:
    """Reads bodies, joints, geoms and sites from a MuJoCo XML tree."""

    def __init__(self, root: Element, source: str) -> None:
        self.source = source
        self.defaults = _Defaults(root)
        compiler = root.find("compiler")
        angle = compiler.get("angle", "degree") if compiler is not None else "degree"
        self.radians = angle.startswith("rad")
        self.eulerseq = compiler.get("eulerseq", "xyz") if compiler is not None else "xyz"
        self.bodies: list[_Body] = []
        self.sites: dict[str, FloatArray] = {}
        self.world_geoms: list[_Geom] = []

    def floats(self, element: Element, key: str, cls: str, count: int | None = None) -> list[float]:
        text = self.defaults.get(element, key, cls)
        if text is None:
            return []
        try:
            values = [float(v) for v in text.split()]
        except ValueError:
            raise InputError(
                f"<{element.tag} {key}={text!r}> is not a list of numbers", source=self.source
            ) from None
        if count is not None and len(values) < count:
            raise InputError(
                f"<{element.tag} {key}={text!r}>: {count} numbers expected", source=self.source
            )
        if not all(abs(v) <= MAX_COORDINATE for v in values):  # NaN fails too
            raise InputError(
                f"<{element.tag} name={element.get('name')!r} {key}={text!r}>: finite numbers "
                f"within ±{MAX_COORDINATE:g} expected (a documented limit: docs/limits.md)",
                source=self.source,
            )
        return values

    def frame(self, element: Element, cls: str) -> tuple[FloatArray, FloatArray]:
        """Local position and rotation of a body / geom / site (MuJoCo's orientation forms)."""
        pos = np.array((self.floats(element, "pos", cls, 3) or [0.0, 0.0, 0.0])[:3])
        try:
            rot = self._rotation(element, cls)
        except ValueError as exc:
            raise InputError(
                f"<{element.tag} name={element.get('name')!r}>: bad orientation ({exc})",
                source=self.source,
            ) from None
        return pos, rot

    def _rotation(self, element: Element, cls: str) -> FloatArray:
        to_rad = 1.0 if self.radians else math.pi / 180.0
        if element.get("quat") is not None:
            return _quat_matrix(*self.floats(element, "quat", cls, 4)[:4])
        if element.get("axisangle") is not None:
            x, y, z, a = self.floats(element, "axisangle", cls, 4)[:4]
            return _axis_angle_matrix((x, y, z), a * to_rad)
        if element.get("euler") is not None:
            angles = self.floats(element, "euler", cls, 3)[:3]
            rot = np.eye(3)
            for axis_name, angle in zip(self.eulerseq, angles, strict=True):
                axis = np.eye(3)["xyz".index(axis_name.lower())]
                step = _axis_angle_matrix(axis, angle * to_rad)
                # Lower case: axes that turn with the frame; upper case: fixed axes.
                rot = rot @ step if axis_name.islower() else step @ rot
            return rot
        if element.get("xyaxes") is not None:
            v = np.array(self.floats(element, "xyaxes", cls, 6)[:6])
            if float(np.linalg.norm(v[:3])) < 1e-9:
                raise ValueError("xyaxes: a zero x axis")
            x_axis = v[:3] / np.linalg.norm(v[:3])
            y_axis = v[3:] - x_axis * float(x_axis @ v[3:])
            if float(np.linalg.norm(y_axis)) < 1e-9:
                raise ValueError("xyaxes: a y axis zero or parallel to the x axis")
            y_axis /= np.linalg.norm(y_axis)
            return np.column_stack((x_axis, y_axis, np.cross(x_axis, y_axis)))
        if element.get("zaxis") is not None:
            z_axis = np.array(self.floats(element, "zaxis", cls, 3)[:3])
            if float(np.linalg.norm(z_axis)) < 1e-9:
                raise ValueError("zaxis: a zero axis")
            z_axis /= np.linalg.norm(z_axis)
            axis = np.cross([0.0, 0.0, 1.0], z_axis)
            if float(np.linalg.norm(axis)) < 1e-12:
                return np.eye(3) if z_axis[2] > 0 else np.diag([1.0, -1.0, -1.0])
            return _axis_angle_matrix(axis, math.acos(max(-1.0, min(1.0, float(z_axis[2])))))
        return np.eye(3)

    def geom(self, element: Element, cls: str) -> _Geom:
        kind = self.defaults.get(element, "type", cls, "sphere") or "sphere"
        size = tuple(self.floats(element, "size", cls))
        if any(v < 0 for v in size):
            raise InputError(
                f"<geom name={element.get('name')!r} size={' '.join(map(str, size))!r}>: "
                "sizes of at least 0 expected",
                source=self.source,
            )
        fromto = self.floats(element, "fromto", cls)
        if len(fromto) == 6 and kind in {"capsule", "cylinder", "box", "ellipsoid"}:
            start, end = np.array(fromto[:3]), np.array(fromto[3:])
            pos = (start + end) / 2.0
            half = float(np.linalg.norm(end - start)) / 2.0
            direction = (end - start) / (2.0 * half) if half > 0 else np.array([0.0, 0.0, 1.0])
            axis = np.cross([0.0, 0.0, 1.0], direction)
            angle = math.acos(max(-1.0, min(1.0, float(direction[2]))))
            rot = _axis_angle_matrix(axis, angle) if np.linalg.norm(axis) > 1e-12 else np.eye(3)
            radius = size[0] if size else 0.0
            size = (radius, radius, half) if kind in {"box", "ellipsoid"} else (radius, half)
        else:
            pos, rot = self.frame(element, cls)
        contype = self.defaults.get(element, "contype", cls, "1") or "1"
        conaffinity = self.defaults.get(element, "conaffinity", cls, "1") or "1"
        try:
            collides = int(contype) != 0 or int(conaffinity) != 0
        except ValueError:
            raise InputError(
                f"<geom contype={contype!r} conaffinity={conaffinity!r}>: integers expected",
                source=self.source,
            ) from None
        return _Geom(kind, size, pos, rot, collides)

    def read_body(
        self,
        element: Element,
        parent: int,
        top: int,
        world_pos: FloatArray,
        world_rot: FloatArray,
        cls: str,
    ) -> None:
        """Add ``element`` (a ``<body>``) and its subtree, depth-first in document order."""
        cls = element.get("childclass") or cls
        pos, rot = self.frame(element, cls)
        index = len(self.bodies)
        body = _Body(
            name=element.get("name") or f"body{index}",
            parent=parent,
            top=index if top < 0 else top,
            pos=world_pos + world_rot @ pos,
            rot=world_rot @ rot,
        )
        self.bodies.append(body)
        if parent >= 0:
            self.bodies[parent].children.append(index)
        for child in element:
            if child.tag == "freejoint":
                body.joints.append("free")
            elif child.tag == "joint":
                kind = self.defaults.get(child, "type", cls, "hinge") or "hinge"
                if kind not in JOINT_QPOS:
                    raise InputError(
                        f"joint {child.get('name')!r} has unknown type {kind!r}; "
                        "free, ball, slide or hinge expected",
                        source=self.source,
                    )
                body.joints.append(kind)
            elif child.tag == "geom":
                body.geoms.append(self.geom(child, cls))
            elif child.tag == "site" and child.get("name"):
                site_pos, _ = self.frame(child, cls)
                self.sites[child.get("name", "")] = body.pos + body.rot @ site_pos
        for child in element.findall("body"):
            self.read_body(child, index, body.top, body.pos, body.rot, cls)


def _activations(root: Element, defaults: _Defaults) -> int:
    """Number of actuator activations (``na``): actuators with dynamics."""
    actuators = root.find("actuator")
    if actuators is None:
        return 0
    na = 0
    for element in actuators:
        cls = "main"
        if element.tag == "general":
            dyntype = defaults.get(element, "dyntype", cls, "none")
            if dyntype and dyntype != "none":
                actdim = int(defaults.get(element, "actdim", cls, "-1") or "-1")
                na += actdim if actdim > 0 else 1
        elif element.tag in {"muscle", "intvelocity"}:
            na += 1
        elif element.tag in {"cylinder", "position"}:
            default = "1" if element.tag == "cylinder" else "0"
            timeconst = defaults.get(element, "timeconst", cls, default) or default
            if float(timeconst) > 0:  # NaN: none
                na += 1
    return na


def _check_depth(root: Element, source: str) -> None:
    """Refuse elements nested deeper than :data:`MAX_MODEL_DEPTH` (the reader
    recurses through bodies and default classes), walking without recursion."""
    stack = [(root, 1)]
    while stack:
        element, depth = stack.pop()
        if depth > MAX_MODEL_DEPTH:
            raise InputError(
                f"<{element.tag}> nested {depth} elements deep; a MuJoCo model nesting at most "
                f"{MAX_MODEL_DEPTH} expected (a documented limit: docs/limits.md)",
                source=source,
            )
        stack.extend((child, depth + 1) for child in element)


def model_layout(xml: str, source: str) -> ModelLayout:
    """Parse a MuJoCo model (XML text) into the importer's :class:`ModelLayout`.

    ``source`` names the model in error messages.
    """
    from defusedxml import ElementTree
    from defusedxml.common import DefusedXmlException

    try:
        root = ElementTree.fromstring(xml)
    except ElementTree.ParseError as exc:
        raise InputError(f"malformed model XML ({exc})", source=source) from None
    except DefusedXmlException as exc:
        raise InputError(f"model XML refused ({exc})", source=source) from None
    _check_depth(root, source)
    bodies = sum(1 for _ in root.iter("body"))
    if bodies > MAX_MODEL_BODIES:
        raise InputError(
            f"{bodies:,} <body> elements; a MuJoCo model of at most {MAX_MODEL_BODIES:,} "
            "expected (a documented limit: docs/limits.md)",
            source=source,
        )
    if root.tag != "mujoco":
        raise InputError(
            f"root element <{root.tag}>; a MuJoCo model (<mujoco>) expected", source=source
        )
    worldbody = root.find("worldbody")
    if worldbody is None:
        raise InputError("model has no <worldbody>", source=source)
    reader = _ModelReader(root, source)
    for child in worldbody:
        if child.tag == "body":
            reader.read_body(child, -1, -1, np.zeros(3), np.eye(3), "main")
        elif child.tag == "geom":
            reader.world_geoms.append(reader.geom(child, "main"))
        elif child.tag == "site" and child.get("name"):
            site_pos, _ = reader.frame(child, "main")
            reader.sites[child.get("name", "")] = site_pos
    free, address = [], []
    nq = nv = 0
    for index, body in enumerate(reader.bodies):
        for kind in body.joints:
            if kind == "free":
                free.append(index)
                address.append(nq)
            nq += JOINT_QPOS[kind]
            nv += JOINT_QVEL[kind]
    try:
        na = _activations(root, reader.defaults)
    except ValueError:
        raise InputError(
            "an actuator's actdim is not an integer or its timeconst not a number", source=source
        ) from None
    return ModelLayout(
        bodies=tuple(reader.bodies),
        free_bodies=tuple(free),
        qpos_address=tuple(address),
        nq=nq,
        nv=nv,
        na=na,
        sites=reader.sites,
        world_geoms=tuple(reader.world_geoms),
    )


# --------------------------------------------------------------------------- geometry


def _corners(geom: _Geom) -> FloatArray | None:
    """The 8 corners of a primitive geom's box (or its bounding box) in its body's frame."""
    if geom.type not in PRIMITIVES or not geom.size:
        return None
    s = geom.size
    if geom.type in {"box", "ellipsoid"} and len(s) >= 3:
        half = np.array(s[:3])
    elif geom.type == "sphere":
        half = np.full(3, s[0])
    elif geom.type == "cylinder" and len(s) >= 2:
        half = np.array([s[0], s[0], s[1]])
    elif geom.type == "capsule" and len(s) >= 2:
        half = np.array([s[0], s[0], s[1] + s[0]])
    else:
        return None
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    return np.asarray(geom.pos + (signs * half) @ geom.rot.T, dtype=float)


def _body_geoms(layout: ModelLayout, index: int) -> list[_Geom]:
    """Geoms of body ``index`` and of the bodies rigidly attached below it, in its frame."""
    body = layout.bodies[index]
    out = list(body.geoms)
    for child_index in body.children:
        child = layout.bodies[child_index]
        if child.joints:
            continue
        to_body = body.rot.T
        for geom in _body_geoms(layout, child_index):
            pos = to_body @ (child.pos - body.pos) + to_body @ child.rot @ geom.pos
            rot = to_body @ child.rot @ geom.rot
            out.append(_Geom(geom.type, geom.size, pos, rot, geom.collides))
    return out


def _bounds(geoms: Sequence[_Geom]) -> tuple[FloatArray, FloatArray] | None:
    """Body-frame bounding box (low, high) of colliding primitive geoms; None if any is not one."""
    colliding = [g for g in geoms if g.collides]
    if not colliding:
        return None
    corners = [_corners(g) for g in colliding]
    if any(c is None for c in corners):
        return None
    points = np.concatenate([c for c in corners if c is not None])
    return points.min(axis=0), points.max(axis=0)


def _geometry(geoms: Sequence[_Geom], low: FloatArray, high: FloatArray) -> ObjectGeometry:
    colliding = [g for g in geoms if g.collides]
    x, y, z = (float(v) for v in high - low)
    if (
        len(colliding) == 1
        and colliding[0].type == "cylinder"
        and np.allclose(colliding[0].rot[:, 2], [0.0, 0.0, 1.0])
    ):
        return ObjectGeometry("cylinder", (x, y, z))
    return ObjectGeometry("box", (x, y, z))


@dataclass(frozen=True, slots=True)
class _Surface:
    """A static colliding geom's world axis-aligned bounding box."""

    low: FloatArray
    high: FloatArray


def _static_surfaces(layout: ModelLayout) -> list[_Surface]:
    """World boxes of static colliding primitives (bodies that cannot move, world geoms)."""
    out = []
    placed: list[tuple[FloatArray, FloatArray, _Geom]] = [
        (np.zeros(3), np.eye(3), g) for g in layout.world_geoms
    ]
    for index, body in enumerate(layout.bodies):
        if not layout.moves(index):
            placed += [(body.pos, body.rot, g) for g in body.geoms]
    for pos, rot, geom in placed:
        corners = _corners(geom) if geom.collides else None
        if corners is None:
            continue
        world = pos + corners @ rot.T
        out.append(_Surface(world.min(axis=0), world.max(axis=0)))
    return out


def _support_top(surfaces: Sequence[_Surface], point: FloatArray) -> float | None:
    """Height of the highest static surface under ``point`` (its top at most slightly above)."""
    tops = [
        float(s.high[2])
        for s in surfaces
        if s.low[0] <= point[0] <= s.high[0]
        and s.low[1] <= point[1] <= s.high[1]
        and s.high[2] <= point[2] + SUPPORT_SLACK
    ]
    return max(tops) if tops else None


def _settled(times: FloatArray, positions: FloatArray) -> int:
    """Index of the first sample after which the object stays put for SETTLE_WINDOW_S."""
    n = len(times)
    ends = np.searchsorted(times, times + SETTLE_WINDOW_S, side="right")
    for i in range(n):
        if ends[i] >= n and i > 0:
            break
        window = positions[i : ends[i]]
        if float(np.max(np.linalg.norm(window - positions[i], axis=1))) <= SETTLE_TOLERANCE:
            return i
    return 0


def _table_top(
    layout: ModelLayout,
    surfaces: Sequence[_Surface],
    rests: Sequence[FloatArray],
    source: str,
) -> float:
    """World z of the table top (module docstring: site, table body, supports)."""
    if "table_top" in layout.sites:
        return float(layout.sites["table_top"][2])
    for body in layout.bodies:
        if body.name == "table":
            tops = []
            for geom in body.geoms:
                corners = _corners(geom) if geom.collides and geom.type == "box" else None
                if corners is not None:
                    tops.append(float((body.pos + corners @ body.rot.T)[:, 2].max()))
            if tops:
                return max(tops)
    supports = [top for p in rests if (top := _support_top(surfaces, p)) is not None]
    if supports:
        return min(supports)
    logger.warning("%s: no table or support found under the objects; z is kept as is", source)
    return 0.0


# --------------------------------------------------------------------------- reading


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
    surfaces = _static_surfaces(layout)
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
        rests.append(_settled(times, p))
    rest_points = [p[i] for p, i in zip(body_pos, rests, strict=True)]
    table_z = _table_top(layout, surfaces, rest_points, str(path))
    tracks, geometry = [], []
    for k, index in enumerate(layout.free_bodies):
        geoms = _body_geoms(layout, index)
        bounds = _bounds(geoms)
        rot = _matrices_from_wxyz(body_quat[k])
        if bounds is not None:
            low, high = bounds
            offset = np.array([0.0, 0.0, low[2]])  # below the body origin
            geometry.append((names[k], _geometry(geoms, low, high)))
        else:
            # Mesh object: its body origin's height above the surface it first rests on.
            settled = rests[k]
            support = _support_top(surfaces, rest_points[k])
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
    landmarks, landmark_geometry, compartments = _landmarks(layout, table_z, set(names))
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


def _landmarks(
    layout: ModelLayout, table_z: float, objects: set[str]
) -> tuple[
    list[tuple[str, Pose]],
    list[tuple[str, ObjectGeometry]],
    list[tuple[str, tuple[Compartment, ...]]],
]:
    """The static top-level bodies that collide: their poses, their sizes, and
    the compartments of those that have some (a bin's, its frame)."""
    poses, geometry, found = [], [], []
    for index, body in enumerate(layout.bodies):
        if body.parent != -1 or layout.jointed_subtree(index):
            continue
        if EXCLUDED_LANDMARKS.search(body.name) or body.name in objects:
            continue
        geoms = [g for g in _body_geoms(layout, index) if g.collides]
        if not geoms:
            continue
        yaw = math.degrees(math.atan2(body.rot[1, 0], body.rot[0, 0]))
        bounds = _bounds(geoms)
        point = body.pos.copy()
        if bounds is not None:
            low, high = bounds
            local = np.array([(low[0] + high[0]) / 2, (low[1] + high[1]) / 2, low[2]])
            point = body.pos + body.rot @ local
            geometry.append((body.name, _geometry(geoms, low, high)))
            parts = [_bounds([g]) for g in geoms]
            boxes = compartments([(p[0] - local, p[1] - local) for p in parts if p is not None])
            if boxes:
                found.append((body.name, boxes))
        x, y, z = (float(v) for v in point)
        poses.append((body.name, Pose((x, y, z - table_z), quat_from_yaw(yaw))))
    return poses, geometry, found


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


def iter_recording(path: str | Path) -> Iterator[RecordedDemonstration]:
    """The demonstrations of a recording, read one at a time."""
    for key in demonstration_keys(path):
        yield read_demonstration(path, key)
