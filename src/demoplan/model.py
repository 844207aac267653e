"""Value types shared by every pipeline stage.

Frozen, slotted dataclasses with tuples inside, so that values hash and
compare. Positions are metres ``(x, y, z)`` in the world frame (z up, table
top at z = 0, the point is the centre of the object's bottom face); orientations
are unit quaternions ``(x, y, z, w)`` or ``None`` when unknown (docs/formats.md).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
import shapely
from shapely.geometry.base import BaseGeometry

from demoplan.learning.settings import LearningSettings
from demoplan.rotations import Quaternion, matrices_from_quats, rpy_from_quat

Vector3 = tuple[float, float, float]
Compartment = tuple[float, float, float, float, float, float]
"""An open interior of a landmark (a bin's compartment), in the landmark's frame
from its position: ``(x_low, y_low, z_low, x_high, y_high, z_high)`` in metres,
``z_low`` its floor, ``z_high`` its rim (docs/formats.md "Landmark")."""

WOOD_DENSITY = 600.0
"""kg/m³: an object's density where its file gives neither ``mass`` nor
``density`` (solid wood, as the paper's blocks)."""

__all__ = [
    "LEVEL_TOLERANCE",
    "REST_TOLERANCE",
    "SUPPORT_FRACTION",
    "WOOD_DENSITY",
    "Compartment",
    "Demonstration",
    "ObjectGeometry",
    "Pose",
    "Role",
    "State",
    "StateOrientation",
    "StatePosition",
    "Step",
    "TaskModel",
    "Vector3",
    "demonstrated_shapes",
    "demonstrated_types",
    "footprint",
    "lowest_point",
    "visit_label",
    "yaw_period",
]


@dataclass(frozen=True, slots=True)
class Pose:
    """An object's resting pose: position (m) and optional orientation."""

    position: Vector3
    orientation: Quaternion | None = None

    @property
    def rpy(self) -> tuple[float, float, float] | None:
        """Orientation as extrinsic x-y-z Euler angles in degrees, or ``None``."""
        return None if self.orientation is None else rpy_from_quat(self.orientation)

    @property
    def yaw(self) -> float:
        """The yaw in degrees: the rotation about z of :attr:`rpy` (0 when the
        orientation is unknown)."""
        return 0.0 if self.orientation is None else rpy_from_quat(self.orientation)[2]


@dataclass(frozen=True, slots=True)
class ObjectGeometry:
    """Shape and size (metres, x/y/z extents; a cylinder's x and y are its diameter)
    and mass (kg; None: solid wood, :data:`WOOD_DENSITY`)."""

    shape: str
    size: Vector3
    mass: float | None = None

    @property
    def volume(self) -> float:
        """m³ of the solid the physics simulates: a box, a sphere of the largest
        extent, and a cylinder (of the larger of x and y) for every other shape."""
        sx, sy, sz = self.size
        if self.shape == "box":
            return sx * sy * sz
        if self.shape == "sphere":
            return 4.0 / 3.0 * math.pi * (max(sx, sy, sz) / 2) ** 3
        return math.pi * (max(sx, sy) / 2) ** 2 * sz

    @property
    def kg(self) -> float:
        """The object's mass: :attr:`mass` where given, else solid wood of :attr:`volume`."""
        return self.mass if self.mass is not None else WOOD_DENSITY * self.volume

    @property
    def yaw_period(self) -> float:
        """The turn (deg) about its own z axis after which the object looks the same:
        90° for a square box (x and y within 1 mm), 180° for other boxes, 0 (any
        turn) for cylinders and spheres, 360° for other shapes."""
        if self.shape in {"cylinder", "sphere"}:
            return 0.0
        if self.shape == "box":
            return 90.0 if abs(self.size[0] - self.size[1]) <= 0.001 else 180.0
        return 360.0


def yaw_period(shape: ObjectGeometry | None) -> float:
    """:attr:`ObjectGeometry.yaw_period`, and 360° (no symmetry) for an unknown shape."""
    return 360.0 if shape is None else shape.yaw_period


def demonstrated_types(demonstrations: Iterable[Demonstration]) -> dict[str, str]:
    """Each moved or described object's type: as declared (``"type"``), else its
    name — an object of its own kind, as every object is unless told."""
    types: dict[str, str] = {}
    for demo in demonstrations:
        declared = dict(demo.types)
        for name in (
            *(n for n, _ in demo.objects),
            *demo.moved_objects,
            *(n for n, _ in demo.initial),
        ):
            if name not in dict(demo.landmarks):
                types.setdefault(name, declared.get(name, name))
    return types


def demonstrated_shapes(demonstrations: Iterable[Demonstration]) -> dict[str, ObjectGeometry]:
    """Each object's (and landmark's) shape as the first demonstration giving one has it."""
    shapes: dict[str, ObjectGeometry] = {}
    for demo in demonstrations:
        for name, shape in demo.objects:
            shapes.setdefault(name, shape)
    return shapes


def demonstrated_colours(demonstrations: Iterable[Demonstration]) -> dict[str, str]:
    """Each object's (and landmark's) colour as the first demonstration giving one has it."""
    colours: dict[str, str] = {}
    for demo in demonstrations:
        for name, colour in demo.colours:
            colours.setdefault(name, colour)
    return colours


@dataclass(frozen=True, slots=True)
class Step:
    """One subtask of a segmented demonstration: ``object`` moved and released at ``pose``."""

    object: str
    pose: Pose


@dataclass(frozen=True, slots=True)
class Demonstration:
    """A segmented demonstration (docs/formats.md ``demoplan/demonstration-1``)."""

    name: str
    steps: tuple[Step, ...]
    objects: tuple[tuple[str, ObjectGeometry], ...] = ()
    landmarks: tuple[tuple[str, Pose], ...] = ()
    initial: tuple[tuple[str, Pose], ...] = ()
    source: str | None = field(default=None, compare=False)
    provenance: tuple[tuple[str, str | int | float], ...] = field(default=(), compare=False)
    """Where the demonstration came from (``("source", file)``, ``("demonstration",
    "demo_1")``, ``("samples", 1252)``, …); written as the file's ``provenance``."""
    compartments: tuple[tuple[str, tuple[Compartment, ...]], ...] = ()
    """The open interiors of landmarks that have them (a bin's compartments):
    landmark name → its compartments (docs/formats.md "Landmark")."""
    types: tuple[tuple[str, str], ...] = ()
    """Declared types (object name → type) of objects that are one of several
    interchangeable instances (two plates, three red blocks); an object not
    listed is of its own type, its name (docs/formats.md)."""
    colours: tuple[tuple[str, str], ...] = ()
    """The colours the file gives its objects and landmarks (name → ``#rrggbb``,
    docs/formats.md ``colour``): every figure of the demonstration and of the
    model learned from it draws them; the others take the figures' palette."""

    def renamed(self, renaming: Mapping[str, str]) -> Demonstration:
        """This demonstration with objects renamed (``renaming``: old → new name;
        others kept): its steps, geometry, initial poses and declared types."""

        def name(old: str) -> str:
            return renaming.get(old, old)

        return replace(
            self,
            steps=tuple(Step(name(s.object), s.pose) for s in self.steps),
            objects=tuple((name(n), g) for n, g in self.objects),
            initial=tuple((name(n), p) for n, p in self.initial),
            types=tuple((name(n), t) for n, t in self.types),
            colours=tuple((name(n), c) for n, c in self.colours),
        )

    @property
    def given_colours(self) -> dict[str, str]:
        """Name → ``#rrggbb`` of the objects and landmarks the file gives a colour."""
        return dict(self.colours)

    def type_of(self, name: str) -> str:
        """``name``'s type: as declared, else its name."""
        return dict(self.types).get(name, name)

    @property
    def moved_objects(self) -> tuple[str, ...]:
        """Objects moved in this demonstration, in order of their first move."""
        return tuple(dict.fromkeys(step.object for step in self.steps))

    def landmark_poses(self) -> dict[str, Pose]:
        return dict(self.landmarks)

    def initial_poses(self) -> dict[str, Pose]:
        return dict(self.initial)

    def geometry(self) -> dict[str, ObjectGeometry]:
        return dict(self.objects)


@dataclass(frozen=True, slots=True)
class StatePosition:
    """Where a state puts its object: ``value`` (m) relative to ``reference``.

    ``reference`` is ``None`` for an absolute (world-frame) position, else the
    object or landmark whose placement is subtracted (paper eq. 1: x_i − x_j),
    expressed in the reference's frame (``R_j⁻¹·(x_i − x_j)``, docs/learning.md) when
    ``in_reference_frame``, else in world axes. ``spread`` is the trace of the
    sample covariance of the members' relative positions (m²).
    """

    reference: str | None
    value: Vector3
    spread: float
    in_reference_frame: bool = False
    """``value`` is in the reference's frame (turned with it), not in world axes."""
    anywhere: bool = False
    """Placed anywhere on its support: absolute placements that scatter far
    beyond the precision with no reference explaining them (``value`` is
    their mean, for information). At run time the object stays where it
    stands when it can (:mod:`demoplan.scenes.targets`)."""
    region: Compartment | None = None
    """Placed anywhere inside this compartment of the reference landmark (its
    frame, as :data:`Compartment`): every demonstrated placement lay inside it
    (docs/learning.md, "Region goals"); ``value`` is their mean. At run time
    the object stays where it stands when it is inside, else goes to the
    point inside nearest ``value`` that the robot reaches."""


@dataclass(frozen=True, slots=True)
class StateOrientation:
    """How a state orients its object: ``value`` relative to ``reference``.

    ``value`` is the mean rotation ``R_ref⁻¹·R_obj`` (``None`` when the object's
    orientation was never observed); ``spread`` is the trace of the sample
    covariance of the members' rotation vectors about that mean (deg²).
    """

    reference: str | None
    value: Quaternion | None
    spread: float

    @property
    def rpy(self) -> tuple[float, float, float] | None:
        return None if self.value is None else rpy_from_quat(self.value)


@dataclass(frozen=True, slots=True)
class State:
    """A quantised subtask (paper §IV.A): object, placement, and its statistics.

    ``members`` are the ``(demonstration, step)`` indices (0-based) that were
    quantised to this state.
    """

    id: str
    object: str
    position: StatePosition
    orientation: StateOrientation
    members: tuple[tuple[int, int], ...]
    margins: tuple[tuple[str, float], ...] = field(default=(), compare=False)
    """Per decision (``"position reference"``, ``"position clusters"``, …) how far
    it was from going the other way, in units of the precision (docs/learning.md; the
    smallest over the members); below 1: within the precision."""
    notes: tuple[str, ...] = field(default=(), compare=False)
    """Decisions learning took at an edge of its rules, in words a teacher reads
    (docs/learning.md, "Notes"): ``"turns with lunchbox: never seen turned"``."""


@dataclass(frozen=True, slots=True)
class Role:
    """One of several interchangeable places of a type's instances: ``plate#1``,
    ``plate#2`` (docs/learning.md, "Identical objects"). ``instances[d]`` is the
    instance that filled it in demonstration ``d`` (``None``: that demonstration
    had fewer instances of the type)."""

    name: str
    type: str
    instances: tuple[str | None, ...]


def visit_label(state_id: str, occurrence: int) -> str:
    """Label of a state's ``occurrence``-th visit in one demonstration.

    The first visit is the state id itself (so models without repeated moves
    read exactly like the paper's); later ones are ``"C#2"``, ``"C#3"``, ….
    """
    return state_id if occurrence == 1 else f"{state_id}#{occurrence}"


@dataclass(frozen=True, slots=True)
class TaskModel:
    """A learned task model (docs/formats.md ``demoplan/model-1``).

    ``constraints`` are pairs of visit labels ``(X, Y)`` meaning "X before Y";
    ``goals[k]`` is the set of states demonstration k ends in.
    ``teacher_constraints`` are the pairs a teacher required; ``violations``
    lists, per demonstration, the teacher constraints it contradicts.
    ``settings`` are those it was learned with (``require``: the teacher's texts).
    """

    states: tuple[State, ...]
    sequences: tuple[tuple[str, ...], ...]
    constraints: tuple[tuple[str, str], ...]
    goals: tuple[tuple[str, ...], ...]
    demonstrations: tuple[Demonstration, ...]
    teacher_constraints: tuple[tuple[str, str], ...] = ()
    violations: tuple[tuple[int, str, str], ...] = ()
    settings: LearningSettings = field(default_factory=LearningSettings)
    precision: tuple[float, float] | None = None
    """The placement precision decisions were measured against: RMS position (m)
    and orientation (deg) — estimated from the demonstrations unless set."""
    precision_estimated: bool = True
    roles: tuple[Role, ...] = ()
    """The roles of types with several instances, and which instance filled each
    in every demonstration; states, constraints and the demonstrations name
    roles (docs/learning.md, "Identical objects"). Empty where every object is
    of its own type."""

    def object_types(self) -> dict[str, str]:
        """Every object (role) of the model and its type."""
        return demonstrated_types(self.demonstrations)

    def state(self, state_id: str) -> State:
        for state in self.states:
            if state.id == state_id:
                return state
        raise KeyError(state_id)

    def demonstration_label(self, index: int) -> str:
        """Demonstration ``index`` (0-based, as in files and ``--json``) as a person
        reads it: numbered from 1, with its name — ``demonstration 2 (pyramid-2)``."""
        return f"demonstration {self.demonstration_number(index)}"

    def demonstration_number(self, index: int) -> str:
        """``2 (pyramid-2)`` for index 1: the number a person reads, and the name."""
        if index < len(self.demonstrations) and self.demonstrations[index].name:
            return f"{index + 1} ({self.demonstrations[index].name})"
        return str(index + 1)


LEVEL_TOLERANCE = 0.005
"""m: heights closer than this are one level (a top meets a bottom; an object
whose bottom is this close to the table stands on it)."""
REST_TOLERANCE = 0.01
"""m: an object whose bottom is within this height of the table or of a top
beneath it rests on it (a segmented rest, a demonstrated release)."""
SUPPORT_FRACTION = 0.05
"""An object stands on another when their outlines overlap by at least this
share of the upper one's (the support rule of docs/scenes.md)."""


def lowest_point(shape: ObjectGeometry | None, pose: Pose) -> float:
    """The height of the lowest corner of ``shape``'s box at ``pose`` (the pose is
    the centre of its bottom face, turned with it): a knife on its edge reaches
    half its width below its resting point, a box leaning on a wall its lower
    edge's height. The pose's height where shape or orientation is unknown."""
    z = pose.position[2]
    if shape is None or pose.orientation is None:
        return z
    sx, sy, sz = shape.size
    m = matrices_from_quats(np.asarray([pose.orientation], dtype=float))[0]
    return float(z - abs(m[6]) * sx / 2 - abs(m[7]) * sy / 2 + min(0.0, m[8] * sz))


def footprint(shape: ObjectGeometry, position: Sequence[float], yaw: float) -> BaseGeometry:
    """The object's outline on the table at ``position`` and ``yaw`` (degrees)."""
    x, y = position[0], position[1]
    if shape.shape == "box":
        hx, hy = shape.size[0] / 2, shape.size[1] / 2
        c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
        corners = [
            (x + c * px - s * py, y + s * px + c * py)
            for px, py in ((-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy))
        ]
        return shapely.Polygon(corners)
    return shapely.Point(x, y).buffer(max(shape.size[0], shape.size[1]) / 2, quad_segs=16)
