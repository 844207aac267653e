"""A MuJoCo model (MJCF) read as XML, not compiled — the recordings ship
without the meshes they reference (:mod:`~demoplan.segmentation.readers.hdf5`'s
docstring says what is taken from it): the state layout (qpos / qvel addresses
in MuJoCo's order, activations), the bodies with their frames, joints and
geoms, and the sites. Orientations (``quat``, ``axisangle``, ``euler``,
``xyaxes``, ``zaxis``) become matrices through :mod:`demoplan.rotations`."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from xml.etree.ElementTree import Element

import numpy as np
from numpy.typing import NDArray

from demoplan.documents.poses import MAX_COORDINATE
from demoplan.errors import InputError
from demoplan.rotations import (
    matrices_from_quats,
)

FloatArray = NDArray[np.float64]

__all__ = [
    "JOINT_QPOS",
    "JOINT_QVEL",
    "MAX_MODEL_BODIES",
    "MAX_MODEL_DEPTH",
    "PRIMITIVES",
    "Body",
    "Geom",
    "ModelLayout",
    "model_layout",
]

PRIMITIVES = frozenset({"box", "sphere", "cylinder", "capsule", "ellipsoid"})


JOINT_QPOS = {"free": 7, "ball": 4, "hinge": 1, "slide": 1}


JOINT_QVEL = {"free": 6, "ball": 3, "hinge": 1, "slide": 1}


MAX_MODEL_DEPTH = 100
"""The deepest nesting of elements in a model's XML (robosuite's go 12 deep)."""


MAX_MODEL_BODIES = 10_000
"""Bodies in a recording's model, at most (robosuite's have about a hundred):
reading one costs about a quarter of a millisecond, and the model's text is
read whole before its free bodies can be counted."""


@dataclass(frozen=True, slots=True)
class Geom:
    type: str
    size: tuple[float, ...]
    pos: FloatArray  # in the owning body's frame
    rot: FloatArray  # 3 × 3, geom frame → body frame
    collides: bool


@dataclass(slots=True)
class Body:
    name: str
    parent: int  # -1: the world
    top: int  # index of its top-level ancestor (itself when top-level)
    pos: FloatArray  # world
    rot: FloatArray  # world ← body
    joints: list[str] = field(default_factory=list)  # joint types, in order
    geoms: list[Geom] = field(default_factory=list)
    children: list[int] = field(default_factory=list)


@dataclass(frozen=True, slots=True, eq=False)
class ModelLayout:
    """What the importer needs from a MuJoCo model.

    ``bodies`` in MuJoCo's (depth-first) order; ``free_bodies`` the indices of
    bodies with a free joint and ``qpos_address`` the index of each one's
    free joint in qpos; ``nq``, ``nv``, ``na`` the sizes of the state parts;
    ``sites`` the world positions of named sites.
    """

    bodies: tuple[Body, ...]
    free_bodies: tuple[int, ...]
    qpos_address: tuple[int, ...]
    nq: int
    nv: int
    na: int
    sites: dict[str, FloatArray]
    world_geoms: tuple[Geom, ...]

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


def _quat_matrix(w: float, x: float, y: float, z: float) -> FloatArray:
    """The rotation matrix of an MJCF quaternion (``w, x, y, z``, any length but
    zero), by :func:`~demoplan.rotations.matrices_from_quats`."""
    quat = np.array([x, y, z, w], dtype=float)
    n = float(np.linalg.norm(quat))
    if n < 1e-12:
        raise ValueError("zero quaternion")
    return matrices_from_quats(quat / n).reshape(3, 3)


def _axis_angle_matrix(axis: Sequence[float] | FloatArray, angle: float) -> FloatArray:
    a = np.asarray(axis, dtype=float)
    n = float(np.linalg.norm(a))
    if n < 1e-12:
        raise ValueError("zero rotation axis")
    a = a / n
    half = angle / 2.0
    return _quat_matrix(math.cos(half), *(a * math.sin(half)))


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
        self.bodies: list[Body] = []
        self.sites: dict[str, FloatArray] = {}
        self.world_geoms: list[Geom] = []

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

    def geom(self, element: Element, cls: str) -> Geom:
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
        return Geom(kind, size, pos, rot, collides)

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
        body = Body(
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
