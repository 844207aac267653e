"""A robosuite environment as demoplan sees it (``--sim robosuite:ENV``): the
environment made, and its objects and landmarks read from ``sim.data`` in
demoplan's frame.

The frame is the one the recordings are imported in
(:mod:`demoplan.segmentation.readers.hdf5`, docs/formats.md): z up, the table
top at z = 0 (robosuite's ``table_offset``), an object's position the centre
of the bottom of its colliding geoms' bounding box below its body origin (a
nut's hole, a cube's centre), so that a model learned from robosuite's
recordings applies to the environment as it is. The bounding boxes are the
compiled model's (``geom_aabb``), so mesh objects get their true bottom;
robosuite's own ``bottom_offset`` is wrong for them. Landmarks are the static
top-level bodies that collide (the pegs, the bins), a peg with the size of
its colliding geoms, a bin with its compartments and its walls and dividers
as box landmarks of their own; the table, the floor and the robot are not
landmarks.
"""

from __future__ import annotations

import importlib.util
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from demoplan.documents.compartments import WALL_HEIGHT, compartments
from demoplan.errors import UsageError
from demoplan.execution.robosuite_clearance import Wall
from demoplan.model import Compartment, ObjectGeometry, Pose
from demoplan.scenes.scene import DEFAULT_GRASPS, SceneObject
from demoplan.segmentation.readers.support import EXCLUDED_LANDMARKS

__all__ = [
    "CONTROL_FREQUENCY",
    "ENVIRONMENTS",
    "EnvLandmarks",
    "EnvObject",
    "bin_walls",
    "check_installed",
    "environment_name",
    "grasp_axes",
    "landmarks",
    "make_environment",
    "object_pose",
    "scene_objects",
    "table_centre",
    "table_top",
]

ENVIRONMENTS = (
    "Stack",
    "NutAssembly",
    "NutAssemblySquare",
    "NutAssemblyRound",
    "PickPlace",
    "PickPlaceCan",
    "PickPlaceMilk",
    "PickPlaceBread",
    "PickPlaceCereal",
)
"""robosuite's pick-and-place environments whose recordings demoplan imports."""

CONTROL_FREQUENCY = 20
"""Hz: robosuite's default control rate (its recordings' too)."""

INSTALL = "pip install 'demoplan[robosuite]' in an environment of its own (docs/execution.md)"

OFF_TABLE = 2.0
"""m: an object farther than this from the table's centre is parked out of the
task (NutAssemblySquare keeps its round nut at (10, 10, 10))."""

BIN_FLOOR = 0.02
"""m: how far the floor of a PickPlace bin rises above its body (robosuite 1.5)."""

HANDLE_GRASPS = (90.0,)
"""A nut is taken at its handle, the fingers across it (the handle runs along
the nut's x axis)."""

GRIPPER_OPENING = 0.078
"""m: the gap between the Panda's finger pads when open (its pads' collision
boxes stand 3.9 cm either side of the grip site): an object is grasped only
across a side narrower than this (PickPlace's cereal box, 10 cm by 3 cm, only
across its 3 cm)."""


def environment_name(sim: str) -> str:
    """``robosuite:ENV`` → ``ENV``, one of :data:`ENVIRONMENTS`, else a usage error."""
    name = sim.removeprefix("robosuite:")
    if name not in ENVIRONMENTS:
        raise UsageError(
            f"--sim {sim}: expected robosuite:ENV with ENV one of {', '.join(ENVIRONMENTS)}"
        )
    return name


def check_installed(sim: str) -> None:
    """A usage error naming what to install when robosuite is not there."""
    if importlib.util.find_spec("robosuite") is None:
        raise UsageError(f"--sim {sim} needs robosuite: {INSTALL}")


def make_environment(name: str, seed: int) -> Any:
    """robosuite's ``name`` with its Panda under its default OSC_POSE controller
    (delta mode), headless, without a horizon (``ignore_done``: a run takes as
    many steps as it needs), reset with ``seed``."""
    import logging

    # robosuite warns at import and setup about what it is not asked for (a macro
    # file, other robots, a GR1 controller): silenced, its errors still shown.
    log = logging.getLogger("robosuite_logs")
    log.disabled = True
    import robosuite
    from robosuite.controllers import load_composite_controller_config

    config = load_composite_controller_config(controller="BASIC", robot="Panda")
    env = robosuite.make(
        name,
        robots="Panda",
        controller_configs=config,
        has_renderer=False,
        has_offscreen_renderer=False,
        use_camera_obs=False,
        ignore_done=True,
        control_freq=CONTROL_FREQUENCY,
        seed=seed,
    )
    log.setLevel(logging.ERROR)
    log.disabled = False
    env.reset()
    return env


def table_top(env: Any) -> float:
    """World z (m) of the table top: demoplan's z = 0. PickPlace has no table:
    there, as in its imported recordings, the top of the floor of the bin its
    objects start in (``bin1``)."""
    if hasattr(env, "table_offset"):
        return float(env.table_offset[2])
    return float(env.bin1_pos[2]) + BIN_FLOOR


def table_centre(env: Any) -> np.ndarray:
    """World (x, y) of the table's centre (PickPlace: of the first bin's)."""
    centre = env.table_offset if hasattr(env, "table_offset") else env.bin1_pos
    return np.asarray(centre[:2], dtype=float)


@dataclass(frozen=True, slots=True)
class EnvObject:
    """One of the environment's movable objects: demoplan's name, its body, the
    geoms robosuite checks grasps with, its handle site (nuts), and the bottom
    of its bounding box below its body origin (m, body frame)."""

    name: str
    body: int
    model: Any
    handle: int | None
    bottom: float
    geometry: ObjectGeometry


def _colliding_geoms(model: Any, bodies: set[int]) -> list[int]:
    return [
        g
        for g in range(model.ngeom)
        if int(model.geom_bodyid[g]) in bodies
        and (int(model.geom_contype[g]) or int(model.geom_conaffinity[g]))
    ]


def _subtree(model: Any, root: int) -> set[int]:
    out = {root}
    for body in range(root + 1, model.nbody):
        if int(model.body_parentid[body]) in out:
            out.add(body)
    return out


def _bounds(env: Any, body: int, geoms: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """The bounding box (low, high corners, body frame) of ``geoms``' own
    bounding boxes (``geom_aabb``: centre and half sizes in the geom's frame)."""
    data, model = env.sim.data, env.sim.model
    origin = np.asarray(data.body_xpos[body])
    frame = np.asarray(data.body_xmat[body]).reshape(3, 3)
    corners = []
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    for g in geoms:
        box = np.asarray(model.geom_aabb[g])
        local = box[:3] + signs * box[3:]
        world = (
            np.asarray(data.geom_xpos[g]) + local @ np.asarray(data.geom_xmat[g]).reshape(3, 3).T
        )
        corners.append((world - origin) @ frame)
    every = np.concatenate(corners)
    return every.min(axis=0), every.max(axis=0)


ROUND = 1.05
"""A mesh whose points lie no farther from its box's vertical axis than this
times the box's half width is round (PickPlace's can: a cylinder, not a box
whose corners would overlap its neighbours)."""

MESH = 7
"""mjGEOM_MESH."""


def _round_meshes(env: Any, body: int, geoms: list[int], low: np.ndarray, high: np.ndarray) -> bool:
    """Whether ``geoms`` are meshes with a square footprint (``low``,
    ``high``: their box, body frame) whose vertices stay within :data:`ROUND`
    times its half width from its vertical axis: a round object (a square
    box's corners lie √2 times as far)."""
    model, data = env.sim.model, env.sim.data
    width, depth = (float(v) for v in high[:2] - low[:2])
    if not all(int(model.geom_type[g]) == MESH for g in geoms) or max(width, depth) > ROUND * min(
        width, depth
    ):
        return False  # not meshes, or a footprint longer than it is wide
    origin = np.asarray(data.body_xpos[body])
    frame = np.asarray(data.body_xmat[body]).reshape(3, 3)
    centre = (low[:2] + high[:2]) / 2
    half = float(max(high[:2] - low[:2])) / 2
    for g in geoms:
        mesh = int(model.geom_dataid[g])
        first, count = int(model.mesh_vertadr[mesh]), int(model.mesh_vertnum[mesh])
        local = np.asarray(model.mesh_vert[first : first + count])
        world = (
            np.asarray(data.geom_xpos[g]) + local @ np.asarray(data.geom_xmat[g]).reshape(3, 3).T
        )
        points = (world - origin) @ frame
        if float(np.linalg.norm(points[:, :2] - centre, axis=1).max()) > ROUND * half:
            return False
    return True


def _geometry(
    model: Any,
    geoms: list[int],
    low: np.ndarray,
    high: np.ndarray,
    mass: float | None,
    round_mesh: bool = False,
) -> ObjectGeometry:
    """A box of the bounding box's size, or a cylinder where the geoms are
    cylinders or ``round_mesh``."""
    cylinders = round_mesh or all(int(model.geom_type[g]) == 5 for g in geoms)  # mjGEOM_CYLINDER
    size = tuple(round(float(v), 6) for v in high - low)
    return ObjectGeometry("cylinder" if cylinders else "box", (size[0], size[1], size[2]), mass)


def env_objects(env: Any) -> list[EnvObject]:
    """The environment's objects on the table (:data:`OFF_TABLE`) that collide."""
    model, data = env.sim.model, env.sim.data
    centre = table_centre(env)
    out = []
    for obj in env.model.mujoco_objects:
        body = int(model.body_name2id(obj.root_body))
        if np.linalg.norm(np.asarray(data.body_xpos[body][:2]) - centre) > OFF_TABLE:
            continue
        geoms = _colliding_geoms(model, _subtree(model, body))
        if not geoms:
            continue  # a marker (PickPlace's Visual* targets collide with nothing)
        low, high = _bounds(env, body, geoms)
        mass = float(sum(model.body_mass[b] for b in _subtree(model, body)))
        handle_site = obj.important_sites.get("handle")
        handle = None if handle_site is None else int(model.site_name2id(handle_site))
        rounded = _round_meshes(env, body, geoms, low, high)
        geometry = _geometry(model, geoms, low, high, mass, rounded)
        out.append(EnvObject(obj.name, body, obj, handle, float(low[2]), geometry))
    return out


def object_pose(env: Any, obj: EnvObject) -> Pose:
    """``obj``'s pose in demoplan's frame: the bottom below its body origin
    (turned with the body), the table top at z = 0; orientation x, y, z, w."""
    data = env.sim.data
    frame = np.asarray(data.body_xmat[obj.body]).reshape(3, 3)
    point = np.asarray(data.body_xpos[obj.body]) + frame @ np.array([0.0, 0.0, obj.bottom])
    w, x, y, z = (float(v) for v in data.body_xquat[obj.body])
    return Pose((float(point[0]), float(point[1]), float(point[2]) - table_top(env)), (x, y, z, w))


def grasp_axes(obj: EnvObject) -> tuple[float, ...]:
    """The finger axes (deg, the object's frame) ``obj`` is taken with: a nut's
    across its handle; else those of the default two (0°, 90°) across a side
    the open gripper spans (:data:`GRIPPER_OPENING`), both where neither is."""
    if obj.handle is not None:
        return HANDLE_GRASPS
    spanned = tuple(
        axis for axis in DEFAULT_GRASPS if obj.geometry.size[round(axis) // 90] < GRIPPER_OPENING
    )
    return spanned or DEFAULT_GRASPS


def scene_objects(env: Any, objects: list[EnvObject]) -> tuple[SceneObject, ...]:
    """The objects as a scene's: pose, geometry, and the grasps :func:`grasp_axes` allows."""
    return tuple(
        SceneObject(o.name, object_pose(env, o), o.geometry, grasps=grasp_axes(o)) for o in objects
    )


@dataclass(frozen=True, slots=True)
class EnvLandmarks:
    """The environment's landmarks as demoplan sees them: every static
    top-level body that collides (a peg, a bin) by its pose (bottom centre of
    its colliding geoms' box, the body's yaw); the solid ones' shapes (a peg);
    a container's (a bin's) compartments, and its walls and dividers as solid
    box landmarks of their own (``bin2_wall3``: obstacles things stand beside,
    and supports); and every landmark's top (z), which the hand passes above."""

    poses: tuple[tuple[str, Pose], ...]
    shapes: tuple[tuple[str, ObjectGeometry], ...]
    compartments: tuple[tuple[str, tuple[Compartment, ...]], ...]
    tops: dict[str, float]


def landmarks(env: Any) -> EnvLandmarks:
    """The static top-level bodies that collide (pegs, bins): :class:`EnvLandmarks`."""
    model = env.sim.model
    poses: list[tuple[str, Pose]] = []
    shapes: list[tuple[str, ObjectGeometry]] = []
    found: list[tuple[str, tuple[Compartment, ...]]] = []
    tops: dict[str, float] = {}
    robot_bodies = {
        b
        for robot in env.robots
        for b in _subtree(model, int(model.body_name2id(robot.robot_model.root_body)))
    }
    for body in range(1, model.nbody):
        name = model.body_id2name(body)
        if int(model.body_parentid[body]) != 0 or body in robot_bodies or not name:
            continue
        tree = _subtree(model, body)
        if any(int(model.body_jntnum[b]) for b in tree) or EXCLUDED_LANDMARKS.search(name):
            continue
        geoms = _colliding_geoms(model, tree)
        if not geoms:
            continue
        low, high = _bounds(env, body, geoms)
        local = np.array([(low[0] + high[0]) / 2, (low[1] + high[1]) / 2, low[2]])
        pose = _landmark_pose(env, body, local)
        poses.append((name, pose))
        tops[name] = pose.position[2] + float(high[2] - low[2])
        parts = [(g, *_bounds(env, body, [g])) for g in geoms]
        boxes = compartments([(lo - local, hi - local) for _, lo, hi in parts])
        if not boxes:
            shapes.append((name, _geometry(model, geoms, low, high, None)))
            continue
        found.append((name, boxes))
        tall = WALL_HEIGHT * (high[2] - low[2])
        walls = [(lo, hi) for _, lo, hi in parts if hi[2] - low[2] > tall]
        for k, (lo, hi) in enumerate(sorted(walls, key=lambda w: (w[0][0], w[0][1])), 1):
            bottom = np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]])
            part = f"{name}_wall{k}"
            poses.append((part, _landmark_pose(env, body, bottom)))
            size = tuple(round(float(v), 6) for v in hi - lo)
            shapes.append((part, ObjectGeometry("box", (size[0], size[1], size[2]))))
    return EnvLandmarks(tuple(poses), tuple(shapes), tuple(found), tops)


def bin_walls(found: EnvLandmarks, table_top: float) -> tuple[Wall, ...]:
    """The walls and dividers of ``found``'s bins (``bin2_wall3``…) as the
    hand must keep clear of them, in the world (``table_top``: world z of
    demoplan's z = 0)."""
    shapes = dict(found.shapes)
    containers = tuple(f"{name}_wall" for name, _ in found.compartments)
    walls = []
    for name, pose in found.poses:
        if not name.startswith(containers):
            continue
        size = shapes[name].size
        walls.append(
            Wall(
                (pose.position[0], pose.position[1]),
                (size[0] / 2, size[1] / 2),
                pose.yaw,
                pose.position[2] + size[2] + table_top,
            )
        )
    return tuple(walls)


def _landmark_pose(env: Any, body: int, local: np.ndarray) -> Pose:
    """The pose (demoplan's frame) of ``local`` (``body``'s frame) with the body's yaw."""
    data = env.sim.data
    frame = np.asarray(data.body_xmat[body]).reshape(3, 3)
    x, y, z = (float(v) for v in np.asarray(data.body_xpos[body]) + frame @ local)
    yaw = math.atan2(frame[1, 0], frame[0, 0])
    quat = (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
    return Pose((x, y, z - table_top(env)), quat)
