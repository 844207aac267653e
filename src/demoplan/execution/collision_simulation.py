"""Collision facts from the arm in MuJoCo (``--collisions simulation``): the
paper's §IV.C use of a path planner to decide which placements are in each
other's way, instead of the geometric finger rule of
:func:`demoplan.scenes.geometry.collision_facts`.

A fact ``(a, b, g)`` says grasp ``g`` at location ``a`` hits whatever stands at
``b``. Here every location is a static body in MuJoCo with the outlines of the
objects it is made for, the arm (:mod:`demoplan.execution.arm_model`) stands
where ``--sim arm`` puts it, and for each grasp at each location that takes its
object the cup's last approach is solved by inverse kinematics — from 10 cm
above the object's top straight down onto it, turned as the grasp turns — and
the arm (links, stem, cup) is posed at every centimetre of it. Whatever
location the arm then touches (a contact MuJoCo makes active, other than the
object being taken) is in the way: a fact. The same motion serves a put-down
with that grasp at ``a`` (the cup comes down the same way, holding the object).

The two need not agree, and the difference is the point: the finger rule
blocks a grasp whose finger discs reach a neighbour's outline; the suction cup
comes from above and is blocked only where a neighbour reaches up into the
arm's way. :class:`CollisionComparison` keeps both sets of facts.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from demoplan.errors import UsageError
from demoplan.execution.arm_model import (
    HOME,
    ArmKinematics,
    arm_base,
    arm_bodies,
    arm_joints,
    attach_arm,
)
from demoplan.execution.arm_motion import arm_contacts
from demoplan.model import ObjectGeometry
from demoplan.scenes.geometry import Location
from demoplan.scenes.scene import Scene
from demoplan.scenes.simulated_collisions import Fact

__all__ = ["simulated_collision_facts"]

APPROACH_FROM = 0.10  # m above the top where the checked approach starts
STEP = 0.01  # m between checked poses


def simulated_collision_facts(
    scene: Scene,
    locations: Sequence[Location],
    grasps: Sequence[tuple[str, str, ObjectGeometry, float]],
    pairs: set[tuple[str, str]],
) -> tuple[list[Fact], list[tuple[str, str]]]:
    """Facts ``(a, b, g)`` for grasps ``(name, object, shape, axis)``, decided by
    posing the arm along each grasp's approach (module docstring), at every
    (location, grasp) pair of ``pairs`` (:func:`checked_pairs`); and the pairs
    the arm cannot reach."""
    from demoplan.execution.physics import check_gl_setting

    check_gl_setting()  # MuJoCo reads MUJOCO_GL when it is imported
    try:
        import mink  # noqa: F401  (the arm's inverse kinematics, imported by ArmKinematics)
        import mujoco
    except ImportError:
        raise UsageError(
            "--collisions simulation needs MuJoCo, dm_control's arm model and mink: "
            "pip install 'demoplan[sim]'"
        ) from None

    base = arm_base(scene, [loc.position[:2] for loc in locations])
    world = mujoco.MjSpec()
    world.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=[3, 3, 0.05])
    for index, loc in enumerate(locations):
        half = math.radians(loc.yaw) / 2
        body = world.worldbody.add_body(
            name=f"_location{index}",
            pos=list(loc.position),
            quat=[math.cos(half), 0, 0, math.sin(half)],
        )
        for shape in loc.shapes:
            _add_outline(mujoco, body, shape)
    attach_arm(mujoco, world, base)
    model = world.compile()
    data = mujoco.MjData(model)
    kinematics = ArmKinematics(mujoco, base)
    joints = arm_joints(mujoco, model)
    arm = arm_bodies(mujoco, model)
    on_arm = np.isin(model.geom_bodyid, sorted(arm))
    location_of = {
        mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"_location{i}"): i
        for i in range(len(locations))
    }
    facts: list[Fact] = []
    unreachable: list[tuple[str, str]] = []
    home = np.array(HOME)
    for grasp, _object, shape, axis in grasps:
        for index, loc in enumerate(locations):
            if (loc.name, grasp) not in pairs:
                continue
            top = loc.bottom + shape.size[2]
            poses = _approach(kinematics, loc, axis, top, home)
            if poses is None:
                unreachable.append((loc.name, grasp))
                continue
            hit: set[int] = set()
            for q in poses:
                data.qpos[joints] = q
                mujoco.mj_forward(model, data)
                for first, second in arm_contacts(data, model, on_arm):
                    other = second if first in arm else first
                    if other in location_of and location_of[other] != index:
                        hit.add(location_of[other])
            facts += [(loc.name, locations[j].name, grasp) for j in sorted(hit)]
    return facts, unreachable


def _approach(
    kinematics: Any, loc: Location, axis: float, top: float, seed: np.ndarray
) -> list[np.ndarray] | None:
    """Joint poses of the cup every :data:`STEP` from :data:`APPROACH_FROM`
    above ``top`` down onto it, or None where one has no solution."""
    x, y = loc.position[0], loc.position[1]
    yaw = loc.yaw + axis
    poses: list[np.ndarray] = []
    q = seed
    steps = round(APPROACH_FROM / STEP)
    for k in range(steps + 1):
        point = np.array([x, y, top + APPROACH_FROM * (1 - k / steps)])
        solved = (
            kinematics.solve(point, yaw, q) if poses else kinematics.solve_anywhere(point, yaw, q)
        )
        if solved is None:
            return None
        poses.append(solved)
        q = solved
    return poses


def _add_outline(mujoco: Any, body: Any, shape: ObjectGeometry) -> None:
    sx, sy, sz = shape.size
    if shape.shape == "box":
        kind, size = mujoco.mjtGeom.mjGEOM_BOX, [sx / 2, sy / 2, sz / 2]
    elif shape.shape == "sphere":
        kind, size = mujoco.mjtGeom.mjGEOM_SPHERE, [max(sx, sy, sz) / 2, 0, 0]
    else:
        kind, size = mujoco.mjtGeom.mjGEOM_CYLINDER, [max(sx, sy) / 2, sz / 2, 0]
    body.add_geom(type=kind, size=size, pos=[0, 0, sz / 2])
