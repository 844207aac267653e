"""A scene looked at before planning (``demoplan show SCENE``): where each
object stands, which of its grasps the neighbours block (the collision rule
of paper §IV.C / §V.B that planning uses), the landmarks, and free space:
the scene's spots, or where it lists none, spots generated near the objects
(planning generates its own near the targets of the goal it plans), on the
scene's table or, where it gives none, the one inferred around the objects and
landmarks (:mod:`demoplan.scenes.table`); objects with no room to park are named.

It builds the same planning problem as :func:`~demoplan.scenes.problems.build_problem`
with no goal, so what it shows is what the planner will see at the start.
"""

from __future__ import annotations

from dataclasses import dataclass

from demoplan.model import ObjectGeometry, Pose, Vector3, footprint
from demoplan.scenes.geometry import GeometrySettings
from demoplan.scenes.problems import SceneProblem, build_problem
from demoplan.scenes.scene import Scene
from demoplan.scenes.table import Surroundings, landmarks_of
from demoplan.scenes.targets import Candidate

__all__ = ["GraspPreview", "ObjectPreview", "ScenePreview", "preview_scene"]


@dataclass(frozen=True, slots=True)
class GraspPreview:
    """One grasp of an object where it stands: fingers closing along ``axis``
    (deg, in the object's frame), and the objects in the way (empty: free)."""

    name: str
    axis: float
    blocked_by: tuple[str, ...]


@dataclass(frozen=True, slots=True)
class ObjectPreview:
    name: str
    geometry: ObjectGeometry
    position: Vector3
    yaw: float
    location: str
    grasps: tuple[GraspPreview, ...]
    on: tuple[str, ...]  # the objects or the landmark it stands on (empty: on the table)

    @property
    def graspable(self) -> bool:
        """Some grasp is free and nothing stands on it."""
        return any(not g.blocked_by for g in self.grasps)


@dataclass(frozen=True, slots=True)
class LandmarkPreview:
    """A landmark as the scene places it: where, turned how far, and its shape
    where the scene knows it."""

    name: str
    position: Vector3
    yaw: float
    geometry: ObjectGeometry | None


@dataclass(frozen=True, slots=True)
class ScenePreview:
    """What :func:`preview_scene` found; ``problem``: the goal-less planning
    problem (for figures)."""

    source: str
    objects: tuple[ObjectPreview, ...]
    landmarks: tuple[LandmarkPreview, ...]
    freespace: tuple[Vector3, ...]
    freespace_generated: bool
    table: tuple[tuple[float, float], tuple[float, float]] | None
    """The table free space was generated on (the scene's, else inferred)."""
    problem: SceneProblem
    table_inferred: bool = False
    no_room: tuple[str, ...] = ()
    """Objects no free-space spot takes: nowhere to park them."""
    shortage: str | None = None
    """Why, and what to add to the scene (None: every object has a spot)."""

    def to_json(self) -> dict[str, object]:
        return {
            "source": self.source,
            "objects": {
                o.name: {
                    "location": o.location,
                    "position": [round(v, 6) for v in o.position],
                    "yaw": round(o.yaw, 3),
                    "shape": o.geometry.shape,
                    "size": list(o.geometry.size),
                    "on": list(o.on),
                    "grasps": [
                        {"name": g.name, "axis": g.axis, "blocked_by": list(g.blocked_by)}
                        for g in o.grasps
                    ],
                }
                for o in self.objects
            },
            "landmarks": {lm.name: list(lm.position) for lm in self.landmarks},
            "freespace": [list(spot) for spot in self.freespace],
            "freespace_generated": self.freespace_generated,
            "table": None if self.table is None else [list(corner) for corner in self.table],
            "table_inferred": self.table_inferred,
            "no_room": list(self.no_room),
        }


def preview_scene(scene: Scene, settings: GeometrySettings = GeometrySettings()) -> ScenePreview:
    """Look at ``scene`` as the planner will (every object's size known: see
    :func:`~demoplan.scenes.scene.complete_geometry`)."""
    nothing = Candidate(goal=0, demonstrations=(), subtasks=(), precedences=())
    around = Surroundings(landmarks=landmarks_of(scene))
    built = build_problem(scene, nothing, settings, surroundings=around)
    problem = built.problem
    at = dict(problem.initial)
    standing = {location: obj for obj, location in problem.initial}
    below: dict[str, list[str]] = {}
    for upper, lower in problem.supports:
        below.setdefault(upper, []).append(lower)
    blocked: dict[tuple[str, str], list[str]] = {}
    for a, b, grasp in sorted(problem.collisions):
        if b in standing and standing.get(a) is not None:
            blocked.setdefault((a, grasp), []).append(standing[b])
    objects = []
    for obj in scene.objects:
        assert obj.geometry is not None  # build_problem refused it otherwise
        here = at[obj.name]
        resting_on = tuple(sorted(standing[b] for b in below.get(here, ()) if b in standing))
        if not resting_on:
            resting_on = _landmark_under(obj.name, obj.geometry, obj.pose, scene, settings)
        on_top = [standing[u] for u, lows in below.items() if here in lows and u in standing]
        grasps = tuple(
            GraspPreview(
                g.name,
                g.axis,
                tuple(sorted(set(blocked.get((here, g.name), []) + on_top))),
            )
            for g in built.grasps
            if g.object == obj.name
        )
        objects.append(
            ObjectPreview(
                obj.name,
                obj.geometry,
                obj.pose.position,
                obj.pose.yaw,
                here,
                grasps,
                resting_on,
            )
        )
    spots = tuple(loc.position for loc in built.locations if loc.kind == "freespace")
    room = built.room
    return ScenePreview(
        scene.source,
        tuple(objects),
        tuple(
            LandmarkPreview(name, pose.position, pose.yaw, shape)
            for name, pose, shape in landmarks_of(scene)
        ),
        spots,
        scene.freespace is None,
        scene.table if room is None else room.table,
        built,
        room is not None and room.inferred,
        () if room is None else tuple(name for name, _ in room.no_room),
        None if room is None else room.shortage(),
    )


def _landmark_under(
    name: str, geometry: ObjectGeometry, pose: Pose, scene: Scene, settings: GeometrySettings
) -> tuple[str, ...]:
    """The landmark whose top holds up object ``name`` (standing at its level
    over at least ``support_fraction`` of the object's footprint, as the
    planner's support rule has it): ``()`` where none does (on the table)."""
    bottom = pose.position[2]
    if bottom <= settings.level_tolerance:
        return ()
    outline = footprint(geometry, pose.position, pose.yaw)
    for landmark, at, shape in landmarks_of(scene):
        if shape is None or abs(at.position[2] + shape.size[2] - bottom) > settings.level_tolerance:
            continue
        top = footprint(shape, at.position, at.yaw)
        if outline.intersection(top).area >= settings.support_fraction * outline.area:
            return (landmark,)
    return ()
