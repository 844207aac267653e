"""Demonstrated goals as subtasks with target poses in a new scene (docs/scenes.md "Planning").

Each demonstration's goal is a candidate (paper §IV.C). Every state the
demonstration visits is a subtask — its visit label (``C``, ``C#2``) is the
subgoal's id — and constraint (Y, X) among this demonstration's visits says X
may only be reached after Y. A subtask's target pose is resolved through its
references:

- position: absolute → the state's value; relative to object j → j's target
  at that point of this demonstration (its latest subtask before this one),
  else j's final target in this goal, else j's current pose in the scene
  (j does not move); relative to a landmark → the landmark's pose from the
  scene (from the demonstrations only where it stood still in all of them:
  :func:`landmark_poses`); placed anywhere → where the object stands, or a
  clear place nearest the demonstrations' mean (:func:`_anywhere_places`).
  Offsets are in world axes (eq. 1).
- orientation: the same chain through its own reference,
  ``R_target = R_reference · value``; a state without a learned orientation
  keeps the object's current orientation.

Candidates with the same subtasks and constraints are one candidate, named by
their earliest demonstration.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from shapely.geometry.base import BaseGeometry

from demoplan.errors import InputError
from demoplan.learning.constraints import visit_sequence
from demoplan.model import (
    ObjectGeometry,
    Pose,
    State,
    TaskModel,
    demonstrated_shapes,
    yaw_period,
)
from demoplan.rotations import (
    Quaternion,
    canonical_quat,
    quat_multiply,
    reduce_yaw,
    rotate_vectors,
)
from demoplan.scenes.geometry import footprint
from demoplan.scenes.landmarks import landmark_poses
from demoplan.scenes.overhang import Support, demonstrated_supports
from demoplan.scenes.regions import region_target
from demoplan.scenes.scene import Scene
from demoplan.scenes.table import (
    Surroundings,
    demonstrated_workspace,
    landmarks_of,
    workspace_table,
)
from demoplan.wording import did_you_mean

__all__ = [
    "Candidate",
    "Subtask",
    "candidate_goals",
    "check_scene_objects",
    "resolve_goals",
]


@dataclass(frozen=True, slots=True)
class Subtask:
    """One visit of a demonstration: put ``object`` down at ``pose`` (state ``state``)."""

    label: str
    state: str
    object: str
    pose: Pose
    turnable: bool = False
    """The state has no learned orientation: any yaw will do (the pose keeps the
    object's current one unless it would not fit, see ``scenes.problems``)."""
    supports: tuple[Support, ...] = ()
    """What the object stood on in every demonstration of the state (an object, a
    landmark), which must hold the target up too (:mod:`demoplan.scenes.overhang`)."""


@dataclass(frozen=True, slots=True)
class Candidate:
    """A demonstrated goal in this scene: subtasks in demonstrated order, precedences
    (pairs of labels) and the demonstrations (0-based) that share it."""

    goal: int
    demonstrations: tuple[int, ...]
    subtasks: tuple[Subtask, ...]
    precedences: tuple[tuple[str, str], ...]

    def final_poses(self) -> dict[str, Pose]:
        """Each moved object's pose at the end (its last subtask)."""
        return {subtask.object: subtask.pose for subtask in self.subtasks}


def check_scene_objects(model: TaskModel, scene: Scene, *, clutter: bool = False) -> None:
    """Exit-1 errors for objects the model needs but the scene lacks, and (unless
    ``clutter`` allows them, as objects with no goal) for objects the scene has
    but the model never saw. A scene name near a name the model needs is named
    as the field, with the model's name as "did you mean" (``sandwhich`` →
    ``sandwich``); a model's landmark among the scene's objects is refused, and
    the objects listed as expected are objects, the landmarks said apart. An
    instance of a type the model knows is no stranger: it fills one of the
    type's roles, or stands with no goal (:mod:`demoplan.scenes.binding`
    counts the instances)."""
    recorded = {name for demo in model.demonstrations for name, _ in demo.landmarks}
    landmarks = recorded | set(scene.landmark_names)
    for name in scene.names:
        if name in recorded:
            raise InputError(
                f"{name!r} is a landmark of the task model (it stands still in the "
                f'demonstrations); expected under "landmarks", not "objects"',
                source=scene.source,
                field=f"objects.{name}",
            )
    types = model.object_types()
    needed = {state.object for state in model.states}
    for state in model.states:
        for reference in (state.position.reference, state.orientation.reference):
            if reference is not None and reference not in landmarks:
                needed.add(reference)
    seen = needed | {
        name for demo in model.demonstrations for name, _ in demo.objects if name not in landmarks
    }
    known_types = {types.get(name, name) for name in seen}
    kinds = {obj.name: obj.type or types.get(obj.name, obj.name) for obj in scene.objects}
    present = set(scene.names) | set(kinds.values())
    missing = sorted(name for name in needed if types.get(name, name) not in present)
    unknown = sorted(
        name for name in scene.names if name not in seen and kinds[name] not in known_types
    )
    besides = f" (landmarks: {', '.join(sorted(recorded))})" if recorded else ""
    if missing:
        misspelt = next((name for name in unknown if did_you_mean(name, missing)), None)
        hint = (
            ""
            if misspelt is None
            else (
                f"; the scene's {misspelt!r} is not one of them" + did_you_mean(misspelt, missing)
            )
        )
        raise InputError(
            f"the task model needs {', '.join(missing)}, which the scene lacks; "
            f"expected objects {sorted(needed)}{besides}{hint}",
            source=scene.source,
            field="objects" if misspelt is None else f"objects.{misspelt}",
        )
    if unknown and not clutter:
        raise InputError(
            f"the task model never saw {', '.join(unknown)}; expected only objects of "
            f"the demonstrations {sorted(seen)}{besides} (--clutter plans around them)"
            + did_you_mean(unknown[0], seen | landmarks),
            source=scene.source,
            field="objects",
        )


class _Resolver:
    """Target poses of one demonstration's visits, resolved in demonstrated order."""

    def __init__(
        self,
        index: int,
        sequence: tuple[str, ...],
        states: dict[str, State],
        current: dict[str, Pose],
        landmarks: dict[str, Pose],
        geometry: dict[str, ObjectGeometry] | None = None,
        reach: tuple[float, float, float] | None = None,
        sizes: dict[str, ObjectGeometry] | None = None,
    ):
        self.index = index
        self.reach = reach
        self.sizes = sizes or {}
        """The scene's objects' shapes (a region goal keeps them clear of the
        walls; the demonstrations may give none: robosuite's meshes)."""
        self.states = states
        self.current = current
        self.landmarks = landmarks
        self.geometry = geometry or {}
        self.final_state = {states[s].object: states[s] for s in sequence}
        self.targets: dict[str, Pose] = {}  # latest target of each object so far
        self.resolving: list[str] = []
        self.placed: dict[str, tuple[float, float, float]] = {}
        """Where the objects whose states are placed anywhere go: where they
        stand, or a clear place on the table (:func:`_anywhere_places`)."""

    def visit(self, state: State) -> Pose:
        pose = self.resolve(state)
        self.targets[state.object] = pose
        return pose

    def resolve(self, state: State) -> Pose:
        if state.object in self.placed:  # placed anywhere: where it stands, or a clear place
            return Pose(self.placed[state.object], self.orientation(state))
        position = np.asarray(state.position.value, dtype=float)
        if state.position.reference is not None:
            reference = self.reference_pose(state.position.reference)
            if state.position.in_reference_frame and reference.orientation is not None:
                frame = self.frame(state.position.reference, reference)
                position = rotate_vectors(frame[None, :], position[None, :])[0]
            position = position + reference.position
            if state.position.region is not None and state.position.reference in self.landmarks:
                x, y, z = (float(v) for v in position)
                position = np.asarray(
                    region_target(
                        state.position.region,
                        reference,
                        (x, y, z),
                        self.current.get(state.object),
                        self.sizes.get(state.object) or self.geometry.get(state.object),
                        Pose((0.0, 0.0, 0.0), self.orientation(state)).yaw,
                        self.reach,
                    )
                )
        return Pose(
            (float(position[0]), float(position[1]), float(position[2])),
            self.orientation(state),
        )

    def orientation(self, state: State) -> Quaternion | None:
        value = state.orientation.value
        if value is None:
            return self.current[state.object].orientation
        if state.orientation.reference is None:
            return canonical_quat(value)
        base = self.reference_pose(state.orientation.reference).orientation
        if base is None:
            return canonical_quat(value)
        reference = state.orientation.reference
        frame = self.frame(reference, Pose((0.0, 0.0, 0.0), base))
        return canonical_quat(quat_multiply(frame, np.asarray(value)).tolist())

    def frame(self, name: str, pose: Pose) -> np.ndarray:
        """The frame relative values of ``name`` are taken in (docs/scenes.md). A target this
        demonstration resolves turns with its own reference, so its orientation is
        already the copy learning used; an object or landmark as it stands in the
        scene is one of its symmetric copies, reduced as learning reduced them
        (its turn about its own axis within half a period of none)."""
        assert pose.orientation is not None
        quat = np.asarray(pose.orientation, dtype=float)
        if name in self.targets or name in self.final_state:
            return quat
        reduced: np.ndarray = reduce_yaw(quat[None, :], self.yaw_period(name))[0]
        return reduced

    def yaw_period(self, name: str) -> float:
        """``name``'s symmetry about its z axis (deg), as learning used it (360: none)."""
        return yaw_period(self.geometry.get(name))

    def reference_pose(self, reference: str) -> Pose:
        if reference in self.targets:
            return self.targets[reference]
        if reference in self.final_state:  # placed later in this demonstration
            if reference in self.resolving:
                chain = " → ".join([*self.resolving, reference])
                raise InputError(
                    f"states refer to each other in a cycle ({chain}); a chain ending in "
                    "an absolute state, a landmark or an unmoved object expected",
                    source="task model",
                    field=f"sequences[{self.index}]",
                )
            self.resolving.append(reference)
            try:
                return self.resolve(self.final_state[reference])
            finally:
                self.resolving.pop()
        if reference in self.current:
            return self.current[reference]
        if reference in self.landmarks:
            return self.landmarks[reference]
        raise InputError(  # check_scene_objects makes this unreachable for objects
            f"reference {reference!r} is neither in the scene nor a landmark",
            source="task model",
            field=f"sequences[{self.index}]",
        )


def candidate_goals(model: TaskModel, scene: Scene, *, clutter: bool = False) -> list[Candidate]:
    """Every demonstrated goal, resolved in ``scene`` (deduplicated, in demonstration
    order), after :func:`check_scene_objects`; ``clutter``: objects the model
    never saw are allowed (they have no goal)."""
    check_scene_objects(model, scene, clutter=clutter)
    return resolve_goals(model, scene)


def resolve_goals(model: TaskModel, scene: Scene) -> list[Candidate]:
    """Every demonstrated goal, resolved in ``scene`` (deduplicated, in
    demonstration order); the scene checked already (a prepared scene, or the
    observed world of a replan)."""
    states = {state.id: state for state in model.states}
    current = {obj.name: obj.pose for obj in scene.objects}
    landmarks = landmark_poses(model, scene)
    # Symmetries as learning took them: an object's shape's; a landmark's frame as given.
    geometry = {
        name: shape
        for name, shape in demonstrated_shapes(model.demonstrations).items()
        if name not in landmarks
    }
    sizes = {obj.name: obj.geometry for obj in scene.objects if obj.geometry is not None}
    constraints = set(model.constraints)
    supported = demonstrated_supports(model)
    candidates: list[Candidate] = []
    by_key: dict[tuple[object, ...], int] = {}
    for index, sequence in enumerate(model.sequences):
        labels = visit_sequence(sequence)
        resolver = _Resolver(
            index, tuple(sequence), states, current, landmarks, geometry, _reach(scene), sizes
        )
        resolver.placed = _anywhere_places(model, scene, sequence, resolver)
        resolver.targets.clear()
        subtasks = tuple(
            Subtask(
                label,
                state_id,
                states[state_id].object,
                resolver.visit(states[state_id]),
                turnable=states[state_id].orientation.value is None,
                supports=supported.get(state_id, ()),
            )
            for label, state_id in zip(labels, sequence, strict=True)
        )
        label_set = set(labels)
        precedences = tuple(
            sorted((x, y) for x, y in constraints if x in label_set and y in label_set)
        )
        key = (tuple(sorted(zip(labels, sequence, strict=True))), precedences)
        if key in by_key:
            first = candidates[by_key[key]]
            candidates[by_key[key]] = Candidate(
                first.goal, (*first.demonstrations, index), first.subtasks, first.precedences
            )
            continue
        by_key[key] = len(candidates)
        candidates.append(Candidate(index, (index,), subtasks, precedences))
    return candidates


def _reach(scene: Scene) -> tuple[float, float, float] | None:
    """The robot's base (x, y) and how far it reaches, where the scene says."""
    if scene.robot is None or scene.reach is None:
        return None
    return (scene.robot[0], scene.robot[1], scene.reach)


def _anywhere_places(
    model: TaskModel, scene: Scene, sequence: tuple[str, ...], resolver: _Resolver
) -> dict[str, tuple[float, float, float]]:
    """Where each object of ``sequence`` placed anywhere (``StatePosition.anywhere``,
    in the sequence once) goes. It stays where it stands when it stands on the
    table (not on another object) and clear of every target that does not move
    with it (its own contents follow it). Otherwise it goes to free space: the
    place nearest the demonstrations' mean where its outline, at the yaw it
    will have, is clear of those targets and of what stays in the scene, on the
    scene's table or else the demonstrations' workspace
    (:func:`_nearest_clear_place`) — the mean itself when that is clear."""
    states = {state.id: state for state in model.states}
    visits = [states[s] for s in sequence]
    anywhere = [
        s
        for s in visits
        if s.position.anywhere
        and sum(v.object == s.object for v in visits) == 1
        and s.object in resolver.current
    ]
    if not anywhere:
        return {}
    follows = _followers(model)
    # every target with each anywhere object where it stands: the others' targets
    # do not depend on where it goes, and its followers' are not counted against it
    resolver.placed = {s.object: resolver.current[s.object].position for s in anywhere}
    targets = [(s.object, resolver.visit(s)) for s in visits]
    resolver.targets.clear()
    moved = {s.object for s in visits}
    landmark_outlines = [
        footprint(shape, pose.position, pose.yaw)
        for _, pose, shape in landmarks_of(scene)
        if shape is not None
    ]
    # on the scene's table, else on the demonstrations' workspace (as free space)
    table = scene.table or workspace_table(Surroundings(workspace=demonstrated_workspace(model)))
    places: dict[str, tuple[float, float, float]] = {}
    for state in anywhere:
        name = state.object
        shape = scene.object(name).geometry
        here = resolver.current[name]
        if shape is None:
            places[name] = here.position
            continue
        blocked = [
            footprint(other_shape, pose.position, pose.yaw)
            for other, pose in targets
            if other != name
            and name not in follows.get(other, set())
            and (other_shape := _shape(scene, other)) is not None
        ]
        yaw = Pose(here.position, resolver.orientation(state)).yaw
        if here.position[2] <= STANDING_ON_TABLE and _clear(shape, here.position, yaw, blocked):
            places[name] = here.position
            continue
        mean = tuple(float(v) for v in state.position.value)
        if mean[2] > STANDING_ON_TABLE:  # put down on something: its mean
            places[name] = (mean[0], mean[1], mean[2])
            continue
        staying = [
            footprint(obj.geometry, obj.pose.position, obj.pose.yaw)
            for obj in scene.objects
            if obj.name not in moved and obj.geometry is not None
        ]
        places[name] = _nearest_clear_place(
            shape, (mean[0], mean[1]), yaw, [*blocked, *staying, *landmark_outlines], table
        )
    return places


def _shape(scene: Scene, name: str) -> ObjectGeometry | None:
    return scene.object(name).geometry if name in scene.names else None


def _clear(
    shape: ObjectGeometry, position: Sequence[float], yaw: float, blocked: list[BaseGeometry]
) -> bool:
    """Whether ``shape``'s outline at ``position`` and ``yaw`` only touches ``blocked``."""
    outline = footprint(shape, position, yaw).buffer(-TOUCH)
    return not any(outline.intersects(other.buffer(-TOUCH)) for other in blocked)


def _nearest_clear_place(
    shape: ObjectGeometry,
    start: tuple[float, float],
    yaw: float,
    blocked: list[BaseGeometry],
    table: tuple[tuple[float, float], tuple[float, float]] | None,
) -> tuple[float, float, float]:
    """The place on the table nearest ``start`` (on rings :data:`PLACE_STEP`
    apart, out to :data:`PLACE_REACH`) where ``shape`` at ``yaw`` is clear of
    ``blocked`` and inside ``table`` when the scene gives one; ``start`` itself
    when none is (the planner then says what is in the way)."""
    for ring in range(round(PLACE_REACH / PLACE_STEP) + 1):
        radius = ring * PLACE_STEP
        count = max(1, round(2 * math.pi * radius / PLACE_STEP))
        for k in range(count):
            angle = 2 * math.pi * k / count
            point = (start[0] + radius * math.cos(angle), start[1] + radius * math.sin(angle), 0.0)
            if table is not None and not _inside(shape, point, yaw, table):
                continue
            if _clear(shape, point, yaw, blocked):
                return (round(point[0], 6), round(point[1], 6), 0.0)
    return (start[0], start[1], 0.0)


def _inside(
    shape: ObjectGeometry,
    point: tuple[float, float, float],
    yaw: float,
    table: tuple[tuple[float, float], tuple[float, float]],
) -> bool:
    (x0, y0), (x1, y1) = table
    bx0, by0, bx1, by1 = footprint(shape, point, yaw).bounds
    return bool(bx0 >= x0 and by0 >= y0 and bx1 <= x1 and by1 <= y1)


PLACE_STEP = 0.01
"""m: the rings on which a clear place for an anywhere object is looked for."""
PLACE_REACH = 1.0
"""m: how far from the demonstrations' mean a clear place is looked for."""
STANDING_ON_TABLE = 0.005
"""m: an object this low stands on the table (an anywhere object on another stays not)."""
TOUCH = 0.001
"""m: footprints that only touch are clear of each other."""


def _followers(model: TaskModel) -> dict[str, set[str]]:
    """Per object, what it is placed relative to, directly or through others."""
    direct: dict[str, set[str]] = {}
    for state in model.states:
        if state.position.reference is not None:
            direct.setdefault(state.object, set()).add(state.position.reference)
    closed = {name: set(refs) for name, refs in direct.items()}
    changed = True
    while changed:
        changed = False
        for refs in closed.values():
            more = set().union(*(direct.get(r, set()) for r in refs)) - refs
            if more:
                refs |= more
                changed = True
    return closed
