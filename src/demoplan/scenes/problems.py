"""A candidate goal in a scene → the planner's problem (paper §IV.C; docs/scenes.md).

Locations are the objects' current poses (``loc1``…, in the scene's order),
the subtasks' targets (a target at a spot made for an object of the same shape
and size — an occupied spot, another target — is that location; one that
overlaps a spot of another shape is a location of its own, exclusive with it)
and free space (``freespace1``…: the scene's spots, else generated). Grasps
are named ``grasp1``… object by object, as in the paper's example; collision
facts, support, exclusion and what each location takes come from
:mod:`demoplan.scenes.geometry`. Every subtask is a subgoal with its visit
label as id, and the candidate's constraints are its precedences.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import shapely
from shapely.geometry.base import BaseGeometry

from demoplan.budget import check_time
from demoplan.errors import InputError, UsageError
from demoplan.model import ObjectGeometry, Pose, Vector3, lowest_point
from demoplan.planning.problem import Problem, Subgoal
from demoplan.rotations import quat_from_yaw
from demoplan.scenes.geometry import (
    FreeSpot,
    GeometrySettings,
    Location,
    accepted_objects,
    bounding_radius,
    collision_facts,
    exclusions,
    footprint,
    free_space,
    location_footprint,
    spot_shape,
    supports,
    yaw_difference,
)
from demoplan.scenes.naming import StableNames
from demoplan.scenes.overhang import OVERHANG_TOLERANCE, overhang, overhang_obstacles
from demoplan.scenes.scene import Scene
from demoplan.scenes.simulated_collisions import (
    CollisionComparison,
    checked_pairs,
)
from demoplan.scenes.table import Surroundings, Table, infer_table, workspace_table
from demoplan.scenes.targets import Candidate, Subtask

__all__ = ["FreeSpaceRoom", "Grasp", "SceneProblem", "build_problem", "landmark_tops"]


@dataclass(frozen=True, slots=True)
class Grasp:
    """A grasp of ``object``: fingers closing along ``axis`` degrees in its frame."""

    name: str
    object: str
    axis: float


@dataclass(frozen=True, slots=True)
class SceneProblem:
    """A candidate's planning problem, with what its names stand for.

    ``obstacles`` says why the candidate cannot be planned at all (a target
    nothing can hold up), empty when it can.
    """

    candidate: Candidate
    problem: Problem
    locations: tuple[Location, ...]
    grasps: tuple[Grasp, ...]
    obstacles: tuple[str, ...] = field(default=())
    collision_check: CollisionComparison | None = None
    """With ``--collisions simulation``: the arm's facts beside the rule's."""
    room: FreeSpaceRoom | None = None
    """Where free space was sought and which objects it has no room for."""

    def location(self, name: str) -> Location:
        for location in self.locations:
            if location.name == name:
                return location
        raise KeyError(name)

    def locations_json(self) -> dict[str, Any]:
        """Each location's pose and what it is, for ``plan --json``."""
        return {
            loc.name: {
                "position": [round(v, 6) for v in loc.position],
                "yaw": round(loc.yaw, 3),
                "kind": loc.kind,
                "objects": list(loc.objects),
            }
            for loc in self.locations
        }


@dataclass(frozen=True, slots=True)
class FreeSpaceRoom:
    """Where a problem's free space came from: the table it was generated on
    (None: the scene lists its spots), whether that table was inferred, and the
    objects no free-space spot takes (nowhere to park them)."""

    table: Table | None
    inferred: bool
    given: bool
    no_room: tuple[tuple[str, ObjectGeometry], ...]

    def shortage(self) -> str | None:
        """Why an object cannot be parked and what to add to the scene; None
        when every object has a spot."""
        if not self.no_room:
            return None
        named = ", ".join(f"{name} ({_size(shape)})" for name, shape in self.no_room)
        if self.given:
            return (
                f'no free space for {named}: the scene\'s "freespace" lists no spot; '
                "add spots there, or leave the field out to have them generated on the table"
            )
        assert self.table is not None
        (x0, y0), (x1, y1) = self.table
        extent = f"({x0:.3f}, {y0:.3f})–({x1:.3f}, {y1:.3f})"
        which = "the inferred table" if self.inferred else "the scene's table"
        return (
            f"no free space for {named}: {which} {extent} has no room to park it clear "
            'of the other objects and their grasps; add a larger "table" extent or '
            '"freespace" spots to the scene'
        )


def _size(shape: ObjectGeometry) -> str:
    return " × ".join(f"{v:g}" for v in shape.size[:2]) + " m"


def build_problem(
    scene: Scene,
    candidate: Candidate,
    settings: GeometrySettings = GeometrySettings(),
    reached: frozenset[str] = frozenset(),
    names: StableNames | None = None,
    surroundings: Surroundings = Surroundings(),
) -> SceneProblem:
    """The planning problem of ``candidate`` in ``scene`` (geometry completed);
    ``reached``: subgoal labels reached before (replanning keeps them);
    ``names``: the location and grasp names of earlier problems of the same
    run, kept for the same places (a new set numbers them from 1 in order:
    current places, then targets, then free space); ``surroundings``: the
    landmarks and the demonstrations' workspace, which the table free space is
    generated on is inferred from where the scene gives none
    (:mod:`demoplan.scenes.table`)."""
    if names is None:
        names = StableNames(settings.merge_distance)
    shapes = _object_shapes(scene)
    locations, current = _current_locations(scene, shapes, names)
    _check_scene_overlaps(scene, locations, settings)
    standing = _standing(scene, shapes)
    target_of = _add_target_locations(locations, candidate, shapes, names, settings, standing)
    axes = [(obj.name, axis) for obj in scene.objects for axis in obj.grasps]
    grasps = [Grasp(names.grasp(obj, axis), obj, axis) for obj, axis in axes]
    room = _add_free_space(
        locations, scene, candidate, shapes, grasps, names, settings, surroundings
    )
    support_pairs, obstacles = _supports_and_obstacles(
        locations, scene, candidate, target_of, settings
    )
    obstacles += _overhangs(scene, candidate, locations, target_of, shapes, standing)
    facts, comparison = _collisions(locations, scene, grasps, shapes, settings)
    accepts = []
    for loc in locations:
        check_time(f"at what each location takes ({len(locations)} locations)")
        taken = accepted_objects(loc, shapes, settings)
        if len(taken) < len(shapes):
            accepts += [(loc.name, obj) for obj in taken]
    final: dict[str, str] = {}
    for subtask in candidate.subtasks:
        final[subtask.object] = target_of[subtask.label]
    problem = Problem.create(
        objects=[obj.name for obj in scene.objects],
        locations=[loc.name for loc in locations],
        grasps=[g.name for g in grasps],
        allowed=[(g.object, g.name) for g in grasps],
        collisions=facts,
        initial=list(current.items()),
        goal=list(final.items()),
        freespace=[loc.name for loc in locations if loc.kind == "freespace"],
        supports=support_pairs,
        exclusions=exclusions(locations, support_pairs, settings),
        accepts=accepts,
        subgoals=[Subgoal(s.label, s.object, target_of[s.label]) for s in candidate.subtasks],
        precedences=candidate.precedences,
        reached=reached & {s.label for s in candidate.subtasks},
        name=f"goal-{candidate.goal}",
        source=scene.source,
    )
    return SceneProblem(
        candidate, problem, tuple(locations), tuple(grasps), tuple(obstacles), comparison, room
    )


def _object_shapes(scene: Scene) -> dict[str, ObjectGeometry]:
    """Every scene object's geometry; an object without one is an input error."""
    shapes: dict[str, ObjectGeometry] = {}
    for obj in scene.objects:
        if obj.geometry is None:
            raise InputError(
                'size unknown; expected "size": [x, y, z] (or a task model that gives it: '
                "show --model, plan, run)",
                source=scene.source,
                field=f"objects.{obj.name}",
            )
        shapes[obj.name] = obj.geometry
    return shapes


def _current_locations(
    scene: Scene, shapes: dict[str, ObjectGeometry], names: StableNames
) -> tuple[list[Location], dict[str, str]]:
    """A location at every object's current pose (``loc…``, in the scene's
    order), and each object's location name."""
    locations: list[Location] = []
    current: dict[str, str] = {}
    used: set[str] = set()
    for obj in scene.objects:
        name = names.place("loc", obj.pose.position, used, any_prefix=True)
        used.add(name)
        locations.append(
            Location(
                name,
                obj.pose.position,
                obj.pose.yaw,
                "current",
                (obj.name,),
                (shapes[obj.name],),
            )
        )
        current[obj.name] = name
    return locations, current


def _add_target_locations(
    locations: list[Location],
    candidate: Candidate,
    shapes: dict[str, ObjectGeometry],
    names: StableNames,
    settings: GeometrySettings,
    standing: ShapesInPlace | None = None,
) -> dict[str, str]:
    """The subtasks' targets added to ``locations``: a target at a location made
    for an object of the same shape and size is that location, any other a
    location of its own. Returns each subtask label's location name."""
    target_of: dict[str, str] = {}
    for subtask in _turned_to_fit(candidate.subtasks, shapes, settings, standing or {}):
        shape = shapes[subtask.object]
        index = _coinciding(locations, subtask, shape, settings)
        if index is None:
            name = names.place("loc", subtask.pose.position, {loc.name for loc in locations})
            locations.append(
                Location(
                    name,
                    subtask.pose.position,
                    subtask.pose.yaw,
                    "target",
                    (subtask.object,),
                    (shape,),
                )
            )
        else:
            old = locations[index]
            name = old.name
            kind = old.kind if "target" in old.kind else f"{old.kind}+target"
            users = old.objects if subtask.object in old.objects else (*old.objects, subtask.object)
            locations[index] = Location(
                name,
                subtask.pose.position,
                subtask.pose.yaw,
                kind,
                users,
                tuple(shapes[o] for o in users),
            )
        target_of[subtask.label] = name
    return target_of


def _add_free_space(
    locations: list[Location],
    scene: Scene,
    candidate: Candidate,
    shapes: dict[str, ObjectGeometry],
    grasps: list[Grasp],
    names: StableNames,
    settings: GeometrySettings,
    surroundings: Surroundings,
) -> FreeSpaceRoom:
    """Free-space locations (``freespace…``) added to ``locations``: the scene's
    spots, else spots generated on its table around the targets — where it
    gives none, on the demonstrations' workspace
    (:func:`~demoplan.scenes.table.workspace_table`), or on the inferred table
    where that has no room for some object. Returns where they came from and which objects none
    takes."""
    given = scene.freespace is not None
    table = scene.table
    if scene.freespace is not None:
        widest = max(bounding_radius(s) for s in shapes.values())
        spots = [FreeSpot(_vector(spot), widest) for spot in scene.freespace]
    else:
        targets = [s.pose.position for s in candidate.subtasks] or [
            o.pose.position for o in scene.objects
        ]
        focus = [
            sum(p[0] for p in targets) / len(targets),
            sum(p[1] for p in targets) / len(targets),
        ]
        tables = [table] if table is not None else []
        if table is None:  # the workspace first, the inferred table where it has no room
            workspace = workspace_table(surroundings, settings)
            tables = [] if workspace is None else [workspace]
            tables.append(
                infer_table(locations, list(shapes.values()), scene.gripper, surroundings, settings)
            )
        for table in tables:
            spots = free_space(
                locations,
                list(shapes.values()),
                [(g.object, g.axis) for g in grasps],
                scene.gripper,
                table,
                focus,
                settings,
                surroundings.landmark_outlines(),
            )
            if all(
                any(bounding_radius(s) <= spot.radius + 1e-6 for spot in spots)
                for s in shapes.values()
            ):
                break
    used = {loc.name for loc in locations}
    for spot in spots:
        check_time(f"at the free space ({len(spots)} spots)")
        fits = [s.size[2] for s in shapes.values() if bounding_radius(s) <= spot.radius + 1e-6]
        name = names.place("freespace", spot.position, used)
        used.add(name)
        shape = spot_shape(spot.radius, max(fits, default=0.0) or 0.001)
        locations.append(Location(name, spot.position, 0.0, "freespace", (), (shape,)))
    parked = [loc for loc in locations if loc.kind == "freespace"]
    check_time(f"at the free space ({len(locations)} locations)")
    no_room = tuple(
        (name, shape)
        for name, shape in shapes.items()
        if not any(name in accepted_objects(loc, {name: shape}, settings) for loc in parked)
    )
    return FreeSpaceRoom(table, scene.table is None and not given, given, no_room)


def _supports_and_obstacles(
    locations: list[Location],
    scene: Scene,
    candidate: Candidate,
    target_of: dict[str, str],
    settings: GeometrySettings,
) -> tuple[list[tuple[str, str]], list[str]]:
    """What stands on what (:func:`~demoplan.scenes.geometry.supports`), and why
    the candidate cannot be planned: a target that would stand on nothing. An
    object standing on nothing now is an input error."""
    support_pairs, floating = supports(locations, settings, landmark_tops(scene))
    obstacles = []
    for name in floating:
        loc = next(loc for loc in locations if loc.name == name)
        if "current" in loc.kind and _leaning(scene, loc.objects[0], settings):
            continue
        if "current" in loc.kind:
            raise InputError(
                f"stands at z = {loc.bottom:.3f} m but nothing is under it; an object "
                "with z > 0 must stand on another object",
                source=scene.source,
                field=f"objects.{loc.objects[0]}.position",
            )
        if loc.kind == "target":
            owners = ", ".join(
                f"{s.object}'s target {s.label}"
                for s in candidate.subtasks
                if target_of[s.label] == name
            )
            obstacles.append(f"{owners} at ({_xyz(loc.position)}) would stand on nothing")
    return support_pairs, obstacles


def _leaning(scene: Scene, name: str, settings: GeometrySettings) -> bool:
    """Whether ``name`` stands tilted with its lowest corner on the table (a box
    leaning on a bin's wall): held up by the table and what it leans on."""
    obj = next((o for o in scene.objects if o.name == name), None)
    return obj is not None and lowest_point(obj.geometry, obj.pose) <= settings.level_tolerance


def _overhangs(
    scene: Scene,
    candidate: Candidate,
    locations: list[Location],
    target_of: dict[str, str],
    shapes: dict[str, ObjectGeometry],
    standing: ShapesInPlace,
) -> list[str]:
    """Targets that hang over what held them up in the demonstrations
    (:func:`~demoplan.scenes.overhang.overhang_obstacles`), at their locations'
    poses (a free yaw as turned to fit)."""
    if not any(s.supports for s in candidate.subtasks):
        return []
    at = {loc.name: loc for loc in locations}
    placements = [
        (
            s.label,
            s.object,
            s.supports,
            shapes[s.object],
            at[target_of[s.label]].position,
            at[target_of[s.label]].yaw,
        )
        for s in candidate.subtasks
    ]
    return overhang_obstacles(placements, standing, scene.source)


ShapesInPlace = dict[str, tuple[Vector3, float, ObjectGeometry, str]]
"""Where each landmark with a size and each object stands at the start:
position, yaw, shape and the scene's field that says so."""


def _standing(scene: Scene, shapes: dict[str, ObjectGeometry]) -> ShapesInPlace:
    landmark_shapes = dict(scene.landmark_geometry)
    standing = {
        name: (pose.position, pose.yaw, landmark_shapes[name], f"landmarks.{name}")
        for name, pose in scene.landmarks
        if name in landmark_shapes
    }
    standing.update(
        (obj.name, (obj.pose.position, obj.pose.yaw, shapes[obj.name], f"objects.{obj.name}"))
        for obj in scene.objects
    )
    return standing


def _collisions(
    locations: list[Location],
    scene: Scene,
    grasps: list[Grasp],
    shapes: dict[str, ObjectGeometry],
    settings: GeometrySettings,
) -> tuple[list[tuple[str, str, str]], CollisionComparison | None]:
    """The collision facts by the rule (:func:`~demoplan.scenes.geometry.collision_facts`),
    or with ``--collisions simulation`` the arm's, with both for comparison."""
    grasp_shapes = [(g.name, g.object, shapes[g.object], g.axis) for g in grasps]
    facts = collision_facts(locations, grasp_shapes, scene.gripper, settings)
    comparison = None
    if settings.collisions == "simulation":
        if settings.simulator is None:
            raise UsageError(
                "--collisions simulation needs a collision simulator (GeometrySettings."
                "simulator: demoplan.execution.collision_simulation.simulated_collision_facts)"
            )
        pairs = checked_pairs(locations, grasp_shapes, shapes, settings)
        simulated, unreachable = settings.simulator(scene, locations, grasp_shapes, pairs)
        ruled = tuple(f for f in facts if (f[0], f[2]) in pairs)
        comparison = CollisionComparison(ruled, tuple(simulated), tuple(unreachable))
        facts = simulated
    return facts, comparison


TURNS = (0.0, 90.0, -90.0, 180.0, 45.0, -45.0, 135.0, -135.0)
"""World yaws (deg) tried, in order, for a target whose orientation is free and whose
current yaw does not fit."""


def _turned_to_fit(
    subtasks: tuple[Subtask, ...],
    shapes: dict[str, ObjectGeometry],
    settings: GeometrySettings,
    standing: ShapesInPlace,
) -> list[Subtask]:
    """Subtasks whose orientation was never learned keep the object's current yaw
    unless their outline there would overlap another target's, or hang over what
    held it up in the demonstrations (:mod:`demoplan.scenes.overhang`: a napkin
    turned 45° on a plate); then the first yaw in :data:`TURNS` (world-aligned
    first) that does neither is taken."""
    final = {s.object: s for s in subtasks}  # where each object ends
    where = dict(standing)  # the supports as the subtasks so far leave them

    def hangs(subtask: Subtask, yaw: float) -> bool:
        upper = footprint(shapes[subtask.object], subtask.pose.position, yaw)
        for support in subtask.supports:
            if support.name in where:
                at, turn, body, _ = where[support.name]
                lower = footprint(body, at, turn)
                if overhang(upper, lower) > support.overhang + OVERHANG_TOLERANCE:
                    return True
        return False

    def outline(subtask: Subtask, yaw: float) -> BaseGeometry:
        shape = shapes[subtask.object]
        return footprint(shape, subtask.pose.position, yaw).buffer(-settings.touch_tolerance)

    def clashes(subtask: Subtask, yaw: float) -> bool:
        mine = outline(subtask, yaw)
        for other in final.values():
            if other.object == subtask.object:
                continue
            if abs(other.pose.position[2] - subtask.pose.position[2]) > settings.level_tolerance:
                continue
            if mine.intersects(outline(other, other.pose.yaw)):
                return True
        return False

    turned = []
    for subtask in subtasks:
        yaw = subtask.pose.yaw
        if subtask.turnable and (clashes(subtask, yaw) or hangs(subtask, yaw)):
            for yaw in TURNS:
                if not clashes(subtask, yaw) and not hangs(subtask, yaw):
                    pose = Pose(subtask.pose.position, quat_from_yaw(yaw))
                    subtask = replace(subtask, pose=pose)
                    if final[subtask.object].label == subtask.label:
                        final[subtask.object] = subtask
                    break
        turned.append(subtask)
        previous = where.get(subtask.object)
        field = previous[3] if previous else f"objects.{subtask.object}"
        where[subtask.object] = (
            subtask.pose.position,
            subtask.pose.yaw,
            shapes[subtask.object],
            field,
        )
    return turned


def landmark_tops(scene: Scene) -> list[tuple[BaseGeometry, float]]:
    """The footprint and top height of every landmark with a known size: what
    objects may stand on besides the table and each other."""
    shapes = dict(scene.landmark_geometry)
    return [
        (
            footprint(shapes[name], pose.position, pose.yaw),
            pose.position[2] + shapes[name].size[2],
        )
        for name, pose in scene.landmarks
        if name in shapes
    ]


def _vector(point: tuple[float, ...]) -> Vector3:
    return (point[0], point[1], point[2] if len(point) > 2 else 0.0)


def _xyz(position: Vector3) -> str:
    return ", ".join(f"{v:.3f}" for v in position)


def _coinciding(
    locations: list[Location], subtask: Subtask, shape: ObjectGeometry, settings: GeometrySettings
) -> int | None:
    """The location a target at ``position`` coincides with, if any (the nearest).

    Only a spot made for objects of the target object's shape and size is the
    same spot (a block on another block's target); a spot of another shape
    overlapping the target is a separate, mutually exclusive location, so that
    each keeps its true footprint. A target whose orientation was learned is
    the spot only if the object there is turned the same way (to
    ``merge_angle``, given the shape's symmetry).
    """
    position = subtask.pose.position
    best, best_distance = None, settings.merge_distance
    for index, loc in enumerate(locations):
        if abs(loc.position[2] - position[2]) > settings.level_tolerance:
            continue
        if loc.kind == "freespace" or not all(_same_shape(s, shape) for s in loc.shapes):
            continue
        if (
            not subtask.turnable
            and yaw_difference(shape, loc.yaw, subtask.pose.yaw) > settings.merge_angle
        ):
            continue  # the object stands there but turned: it must be put down again
        distance = math.dist(loc.position[:2], position[:2])
        if distance < best_distance:
            best, best_distance = index, distance
    return best


def _same_shape(a: ObjectGeometry, b: ObjectGeometry) -> bool:
    return a.shape == b.shape and all(
        abs(x - y) <= 0.001 for x, y in zip(a.size, b.size, strict=True)
    )


def _check_scene_overlaps(
    scene: Scene, locations: list[Location], settings: GeometrySettings
) -> None:
    """Two objects of the scene cannot stand in each other's space."""
    shrunk = np.array(
        [location_footprint(loc).buffer(-settings.touch_tolerance) for loc in locations],
        dtype=object,
    )
    bottoms = np.array([loc.bottom for loc in locations])
    tops = np.array([loc.top for loc in locations])
    for i, la in enumerate(locations):
        check_time(f"at the scene's overlaps ({len(locations)} objects)")
        low = np.maximum(bottoms[i + 1 :], la.bottom)
        high = np.minimum(tops[i + 1 :], la.top)
        level = np.flatnonzero(high - low > settings.level_tolerance) + i + 1
        clashing = level[shapely.intersects(shrunk[i], shrunk[level])]
        if len(clashing):
            lb = locations[int(clashing[0])]
            raise InputError(
                f"{lb.objects[0]} overlaps {la.objects[0]} (their footprints intersect "
                "at the same height); objects that do not pass through each other expected",
                source=scene.source,
                field=f"objects.{lb.objects[0]}.position",
            )


def pose_of(location: Location) -> Pose:
    """A location's pose (for executors)."""
    return Pose(location.position, quat_from_yaw(location.yaw))
