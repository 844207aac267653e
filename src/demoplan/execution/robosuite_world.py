"""``--sim robosuite:ENV``: a task carried out in robosuite's own environment by
its Panda, and judged by robosuite (``env._check_success()``).

The world is the environment after ``reset(seed)`` and a few idle steps (its
objects are dropped onto the table at reset). Observing reads ``sim.data``
(:mod:`demoplan.execution.robosuite_scene`); a grasp comes down on the
object (a nut at its handle; across another of the object's grasps, noted
among the motions refused, where the hand would come down on a taller
neighbour or a bin's wall and that grasp's would not), closes, lifts, and
asks robosuite whether both finger pads touch it (``env._check_grasp``): if
not, the hand opens and the executor sees the object still standing. A
put-down carries the object at a travel height above everything, turns it to
the target's yaw (of the turns its shape allows and the wrist reaches, the
one whose hand goes lowest between the bins' walls, then the one with the
grip nearest the robot's base), corrects the hand by where the object is
seen to hang, lowers it towards 5 mm above its target until its support
stops it (or, where the hand would strike a bin's walls, no lower than it
clears them: :mod:`demoplan.execution.robosuite_clearance`), opens, and
retreats upwards: robosuite counts a placement only with the gripper away
from the object. The world acts on what it observes itself: the pose a grasp
is given (``where``) is not used.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from demoplan.execution.robosuite_clearance import Wall, lowest_grip
from demoplan.execution.robosuite_motion import PandaHand, hand_frame
from demoplan.execution.robosuite_scene import (
    EnvObject,
    bin_walls,
    env_objects,
    grasp_axes,
    landmarks,
    make_environment,
    object_pose,
    scene_objects,
    table_centre,
    table_top,
)
from demoplan.execution.world import Observation
from demoplan.model import ObjectGeometry, Pose
from demoplan.scenes.scene import Scene

__all__ = ["RobosuiteWorld"]

SETTLE_STEPS = 20
"""Control steps after reset before the world is observed (1 s: the objects land)."""
CLEARANCE = 0.06
"""m: how far above the highest thing the carried object's bottom travels."""
PLACE_ABOVE = 0.005
"""m: the object's bottom is released this far above its target."""
RETREAT = 0.1
"""m: how far the hand rises after letting go (robosuite's checks want it > 4 cm away)."""
FINGER_DEPTH = 0.012
"""m: how far above an object's bottom the grip site stays at least (the pads
reach about 1 cm below it; lower they would press on the table)."""
FREE_YAW_STEP = 30.0
"""deg: the yaws tried for an object whose turn does not matter (a round nut on its peg)."""
ALIGN_TRIES = 3
"""Corrections of the hand over the target, at most."""
REACH = 0.74
"""m: how far from its base (horizontally) the Panda puts an object down with
the hand pointing down, as the scene tells a region goal: measured in
PickPlace (bearings 20° and 35°, the grip 3–7 cm above the bins' floor), at
0.74 m it goes down and comes back; at 0.78 m the elbow straightens to its
limit and the hand cannot come back towards the base (docs/execution.md)."""
ALIGNED = 0.002
"""m: over its target, the held object is moved until it hangs this close above it."""


class RobosuiteWorld:
    """A :class:`~demoplan.execution.world.World` over a robosuite environment."""

    def __init__(self, env_name: str, seed: int) -> None:
        self.name = f"robosuite:{env_name}"
        self.env = make_environment(env_name, seed)
        self.hand = PandaHand(self.env)
        self.hand.open()
        self.hand.hold(SETTLE_STEPS)
        self.objects = {o.name: o for o in env_objects(self.env)}
        found = landmarks(self.env)
        self.landmarks, self.landmark_geometry = found.poses, found.shapes
        self.landmark_tops = found.tops
        self.walls = bin_walls(found, table_top(self.env))
        self.held: str | None = None
        self.offset = np.zeros(3)  # the held object's bottom from the grip site, hand frame
        self.turn = 0.0  # its yaw minus the fingers'
        self.motion_failures: list[str] = []
        self.grasp_problems: list[str] = []

    # -- what robosuite says --------------------------------------------------------------

    def scene(self, source: str) -> Scene:
        """The environment as a scene (the world a run starts from)."""
        table = None
        if hasattr(self.env, "table_full_size"):  # PickPlace has none
            half = np.asarray(self.env.table_full_size[:2], dtype=float) / 2
            low, high = table_centre(self.env) - half, table_centre(self.env) + half
            table = ((float(low[0]), float(low[1])), (float(high[0]), float(high[1])))
        base = self.hand.base_position
        return Scene(
            objects=scene_objects(self.env, list(self.objects.values())),
            landmarks=self.landmarks,
            landmark_geometry=self.landmark_geometry,
            table=table,
            source=source,
            robot=(float(base[0]), float(base[1]), 0.0),
            reach=REACH,
        )

    def env_success(self) -> bool:
        """robosuite's own verdict (``_check_success``)."""
        return bool(self.env._check_success())

    # -- the World protocol ---------------------------------------------------------------

    def observe(self) -> Observation:
        if self.held is not None and not self._holding(self.held):
            self.held = None
        poses = {
            name: object_pose(self.env, obj)
            for name, obj in self.objects.items()
            if name != self.held
        }
        geometry = {name: obj.geometry for name, obj in self.objects.items()}
        return Observation(poses, self.held, geometry)

    def grasp(self, obj: str, axis: float, where: Pose | None = None) -> None:
        if self.held is not None or obj not in self.objects:
            return
        target = self.objects[obj]
        pose = object_pose(self.env, target)
        point = self._grip_point(target, pose)
        struck = self._struck(obj, point, pose.yaw + axis)
        clear = [a for a in grasp_axes(target) if not self._struck(obj, point, pose.yaw + a)]
        if struck and clear:
            self.motion_failures.append(
                f"refused {obj} across {axis:g}° (the hand would strike {struck}): "
                f"took it across {clear[0]:g}°"
            )
            axis = clear[0]
        reached = self.hand.finger_yaws_within_reach([pose.yaw + axis], point)
        if not reached:
            self.motion_failures.append(f"the wrist cannot turn the fingers to grasp {obj}")
            return
        fingers = min(reached, key=lambda yaw: abs(yaw - self.hand.finger_yaw))
        travel = self._travel_height(None)
        self.hand.open()
        self._move([*self.hand.position[:2], travel])
        self._move([point[0], point[1], travel], fingers)
        self._move(point, stop_on_contact=True)
        self.hand.close()
        self._move([point[0], point[1], travel])
        if not self._holding(obj):
            self.grasp_problems.append(f"robosuite's grasp check: {obj} is not between the fingers")
            self.hand.open()
            return
        self.held = obj
        frame = self.hand.frame
        bottom = np.array(object_pose(self.env, target).position) + [0.0, 0.0, table_top(self.env)]
        self.offset = frame.T @ (bottom - self.hand.position)
        self.turn = object_pose(self.env, target).yaw - self.hand.finger_yaw

    def put_down(self, obj: str, pose: Pose) -> None:
        if self.held != obj:
            return
        x, y, z = pose.position
        bottom = np.array([x, y, z + table_top(self.env) + PLACE_ABOVE])
        placements = []
        for yaw in self._target_yaws(obj, pose):
            fingers = yaw - self.turn
            grip = bottom - hand_frame(fingers) @ self.offset
            placements += [
                (reached, bottom - hand_frame(reached) @ self.offset)
                for reached in self.hand.finger_yaws_within_reach([fingers], grip)
            ]
        if not placements:
            self.motion_failures.append(f"the wrist cannot turn {obj} to its target")
            return
        base = self.hand.base_position[:2]
        fingers, grip = min(
            placements,
            key=lambda p: (
                round(self._drop(p[0], p[1]), 3),
                float(np.linalg.norm(p[1][:2] - base)),
            ),
        )
        travel = self._travel_height(obj)
        self._move([*self.hand.position[:2], travel])
        self._move([grip[0], grip[1], travel], fingers)
        grip = self._aligned(obj, bottom, grip, travel)
        grip[2] += self._drop(fingers, grip)
        self._move(grip, stop_on_contact=True)
        self.hand.open()
        self.held = None
        self._move([grip[0], grip[1], grip[2] + RETREAT])

    def _drop(self, fingers: float, grip: np.ndarray) -> float:
        """m: how far above ``grip`` the grip site must stay for the hand, its
        fingers along ``fingers`` (deg), to keep above the bins' walls
        (:func:`~demoplan.execution.robosuite_clearance.lowest_grip`); 0 where
        it clears them."""
        lowest = lowest_grip(self.hand.shape, grip[:2], fingers, self.walls)
        return max(0.0, lowest - float(grip[2]))

    def _target_yaws(self, obj: str, pose: Pose) -> list[float]:
        """The yaws (deg) ``obj`` may take at ``pose``: the target's, turned by
        its shape's period (a square box: 90°); a nut going on a peg: the peg's
        (square) turned by 90° or (round) any yaw, in steps of
        :data:`FREE_YAW_STEP`."""
        target = self.objects[obj]
        peg = self._peg_under(pose) if target.handle is not None else None
        if peg is not None:
            peg_pose, shape = peg
            if shape.shape == "cylinder":
                return [k * FREE_YAW_STEP for k in range(round(360.0 / FREE_YAW_STEP))]
            return [peg_pose.yaw + k * 90.0 for k in range(4)]
        period = target.geometry.yaw_period or FREE_YAW_STEP
        return [pose.yaw + k * period for k in range(round(360.0 / period))]

    def _peg_under(self, pose: Pose) -> tuple[Pose, ObjectGeometry] | None:
        """The landmark whose footprint holds ``pose``'s point (a peg), with its shape."""
        shapes = dict(self.landmark_geometry)
        for name, where in self.landmarks:
            shape = shapes.get(name)
            if shape is None:
                continue  # a bin, not a peg
            dx, dy = (pose.position[k] - where.position[k] for k in (0, 1))
            if math.hypot(dx, dy) <= max(shape.size[:2]) / 2:
                return where, shape
        return None

    def _aligned(self, obj: str, bottom: np.ndarray, grip: np.ndarray, travel: float) -> np.ndarray:
        """The grip site's point over the target corrected by where the held
        object is seen to hang (it may have turned in the fingers on the way):
        up to :data:`ALIGN_TRIES` corrections at the travel height."""
        grip = grip.copy()
        for _ in range(ALIGN_TRIES):
            seen = np.array(object_pose(self.env, self.objects[obj]).position[:2])
            error = bottom[:2] - seen
            if float(np.linalg.norm(error)) < ALIGNED:
                break
            grip[:2] += error
            self._move([grip[0], grip[1], travel])
        return grip

    def between_actions(self, upcoming: Sequence[Pose] = ()) -> None:
        """robosuite's world does not change by itself between actions."""

    def close(self) -> None:
        self.env.close()

    # -- helpers --------------------------------------------------------------------------

    def _move(
        self,
        goal: Sequence[float] | np.ndarray,
        fingers: float | None = None,
        stop_on_contact: bool = False,
    ) -> None:
        """Move the hand; a move that stops short is noted (``stop_on_contact``:
        a lowering that the target's support is expected to end)."""
        if not self.hand.move(goal, fingers) and not stop_on_contact:
            where = ", ".join(f"{v:.3f}" for v in goal)
            self.motion_failures.append(f"the hand did not reach ({where}) in time")

    def _holding(self, obj: str) -> bool:
        """robosuite's grasp check: both finger pads touch ``obj``."""
        target = self.objects[obj]
        return self.hand.grasping(target.model)

    def _struck(self, obj: str, point: np.ndarray, fingers: float) -> str:
        """What the hand, lowered to grasp ``obj`` at ``point`` with the fingers
        along ``fingers`` (deg), would come down on: another object standing
        higher than the hand's bottom there (a tall box it would knock over;
        PickPlace seed 30: the cereal box, grasping the bread beside it) or a
        bin's wall, named; "" where nothing."""
        for name, other in self.objects.items():
            if name == obj:
                continue
            where = object_pose(self.env, other)
            half = (other.geometry.size[0] / 2, other.geometry.size[1] / 2)
            top = where.position[2] + other.geometry.size[2] + table_top(self.env)
            body = Wall((where.position[0], where.position[1]), half, where.yaw, top)
            if lowest_grip(self.hand.shape, point[:2], fingers, [body]) > point[2]:
                return name
        if lowest_grip(self.hand.shape, point[:2], fingers, self.walls) > point[2]:
            return "a bin's wall"
        return ""

    def _grip_point(self, obj: EnvObject, pose: Pose) -> np.ndarray:
        """Where the grip site closes on ``obj`` (world): a nut's handle, else
        the middle of its height above its bottom centre."""
        data = self.env.sim.data
        bottom = np.array(pose.position) + [0.0, 0.0, table_top(self.env)]
        if obj.handle is not None:
            point = np.asarray(data.site_xpos[obj.handle]).copy()
        else:
            point = bottom + [0.0, 0.0, obj.geometry.size[2] / 2]
        point[2] = max(point[2], bottom[2] + FINGER_DEPTH)
        return point

    def _travel_height(self, carried: str | None) -> float:
        """World z of the grip site when travelling: the carried object's bottom
        :data:`CLEARANCE` above the top of every object and landmark."""
        tops = [
            object_pose(self.env, o).position[2] + o.geometry.size[2]
            for name, o in self.objects.items()
            if name != carried
        ]
        tops += list(self.landmark_tops.values())
        below = 0.0 if carried is None else self._carried_depth()
        return table_top(self.env) + max(tops, default=0.0) + CLEARANCE + below

    def _carried_depth(self) -> float:
        """m: how far the held object's bottom hangs below the grip site."""
        return max(0.0, float(-(self.hand.frame @ self.offset)[2]))
