"""The arm's moves in the simulation (:mod:`demoplan.execution.arm`): the
cup's straight lines and travels, run by the joint servos after the check
against collisions (:class:`~demoplan.execution.arm_motion.ArmMotion`), the
joint-space moves, and the contacts recorded on the way. :class:`ArmMoves` is
the part of :class:`~demoplan.execution.arm.ArmWorld` that moves the arm;
the world adds its tool, its grasps and its put-downs."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from demoplan.execution.arm_model import FINGER_REACH, HOME, ArmKinematics
from demoplan.execution.arm_motion import (
    ArmMotion,
    Load,
    MotionError,
    arm_contacts,
    wrapped,
    xyz,
)
from demoplan.execution.arm_tools import Tool
from demoplan.execution.physics import MujocoWorld

__all__ = ["ArmMoves"]

SPEED = 0.25  # m/s of the cup along a straight line
TURN_SPEED = 120.0  # deg/s of the cup about the vertical
PARK_SECONDS = 2.5  # s for the half turn behind the base (a load creeps on the pad if faster)
RAISES = (0.0, 0.06, 0.15)  # m: travel heights tried above the tallest object


class ArmMoves(MujocoWorld):
    """The arm's moves; what they read of the arm is set up by
    :class:`~demoplan.execution.arm.ArmWorld`."""

    base: tuple[float, float, float]  # where the arm stands: x, y, yaw°
    kinematics: ArmKinematics
    motion: ArmMotion
    joints: list[int]  # qpos addresses of the six joints
    servos: list[int]  # their position servos
    arm_bodies: set[int]
    arm_geoms: np.ndarray  # per geom of the model: True where it is on the arm
    tcp: int  # the cup's site
    q: np.ndarray  # the joint angles the servos hold
    cup_yaw: float
    grip: np.ndarray  # the held object's frame in the cup's frame
    allowed: str | None  # the object the cup may touch now
    parked: bool
    tool: Tool
    collisions: list[str]

    # -- reading ---------------------------------------------------------------------------

    def _cup(self, data: Any = None) -> tuple[np.ndarray, np.ndarray]:
        data = self.data if data is None else data
        return np.array(data.site_xpos[self.tcp]), np.array(data.site_xmat[self.tcp]).reshape(3, 3)

    def _cup_yaw(self) -> float:
        _, rotation = self._cup()
        return math.degrees(math.atan2(rotation[1, 0], rotation[0, 0]))

    # -- motions ---------------------------------------------------------------------------

    def _path(self, goal: np.ndarray, yaw: float) -> list[np.ndarray]:
        """Joint waypoints moving the cup in a straight line from where it is to
        ``goal`` while it turns to ``yaw``; MotionError where one has no solution."""
        start, _ = self._cup()
        return self.motion.straight_line(start, self.cup_yaw, self.q, goal, yaw)

    def _step_to(self, point: np.ndarray, yaw: float, q: np.ndarray) -> np.ndarray:
        return self.motion.step_to(point, yaw, q)

    def _collision(self, path: list[np.ndarray], landing: bool) -> str | None:
        """The first collision along ``path`` (:meth:`ArmMotion.first_collision`)."""
        return self.motion.first_collision(
            self.data.qpos,
            path,
            Load(self.held, self._body(self.held), self.grip) if self.held is not None else None,
            self._body(self.allowed) if self.allowed is not None else None,
            landing,
            self._body_label,
        )

    def _body_label(self, body: int) -> str:
        if body == 0:
            return "the table"
        internal = self.mujoco.mj_id2name(self.model, self.mujoco.mjtObj.mjOBJ_BODY, body)
        for name, inner in self.body_names.items():
            if inner == internal:
                return name
        return str(internal)

    def _run(self, path: list[np.ndarray], seconds: float) -> None:
        """Track ``path`` with the joint servos over ``seconds`` (smooth start and stop)."""
        steps = max(1, math.ceil(seconds / 0.002))
        points = [self.q, *path]
        for k in range(1, steps + 1):
            t = k / steps
            t = t * t * (3.0 - 2.0 * t)
            position = t * (len(points) - 1)
            index = min(int(position), len(points) - 2)
            frac = position - index
            self.data.ctrl[self.servos] = points[index] + frac * (points[index + 1] - points[index])
            self.mujoco.mj_step(self.model, self.data)
            self._watch()
            self._tick()
        self.q = path[-1]
        for _ in range(150):  # let the servos settle on the last waypoint
            if np.max(np.abs(self.data.qpos[self.joints] - self.q)) < 2e-3:
                break
            self.mujoco.mj_step(self.model, self.data)
            self._watch()
            self._tick()

    def _watch(self) -> None:
        """Record the arm's contacts with anything but its load (a test reads them).

        Called after every physics step: the contacts are read as MuJoCo's
        arrays and only those between an arm geom and another geom are looked
        at one by one (reading each contact as an object cost more than the
        step itself)."""
        pairs = arm_contacts(self.data, self.model, self.arm_geoms)
        if not pairs:
            return
        held = self._body(self.held) if self.held is not None else -1
        allowed = self._body(self.allowed) if self.allowed is not None else -2
        for first, second in pairs:
            other = second if first in self.arm_bodies else first
            if other not in (held, allowed):
                label = f"the arm touched {self._body_label(other)} at {self.simulated:.2f} s"
                if not self.collisions or self.collisions[-1] != label:
                    self.collisions.append(label)

    def _go(
        self, goal: np.ndarray | list[float], yaw: float | None = None, landing: bool = False
    ) -> None:
        """Move the cup in a straight line to ``goal`` (turning to ``yaw``),
        after checking the path against collisions."""
        if self.parked:
            self._unpark()
        goal = np.asarray(goal, dtype=float)
        yaw = self.cup_yaw if yaw is None else yaw
        start, _ = self._cup()
        path = self._path(goal, yaw)
        problem = self._collision(path, landing)
        if problem is not None:
            raise MotionError(problem)
        turn = abs(((yaw - self.cup_yaw + 180.0) % 360.0) - 180.0)
        distance = float(np.linalg.norm(goal - start))
        self._run(path, max(1.5 * distance / SPEED, turn / TURN_SPEED, 0.1))
        self.cup_yaw = yaw

    def _travel(self, goal_xy: tuple[float, float], yaw: float, low: float) -> None:
        """Up, across at the travel height, and down to ``low`` above ``goal_xy``:
        straight moves above what stands along the way, raised when a check
        finds a collision."""
        if self.parked:
            self._unpark()
        here, _ = self._cup()
        problem = ""
        for raise_by in RAISES:
            height = max(
                self._travel_height((float(here[0]), float(here[1])), goal_xy) + raise_by, low
            )
            try:
                self._go([here[0], here[1], max(height, here[2])])
                self._go([goal_xy[0], goal_xy[1], height], yaw)
                return
            except MotionError as exc:
                problem = str(exc)
        # No straight line across (the arm would swing through a new posture on
        # the way, from close to its base): up, then a joint-space move (checked)
        # to a posture solved over the goal.
        height = max(self._travel_height((float(here[0]), float(here[1])), goal_xy), low)
        try:
            here, _ = self._cup()
            up = np.array([here[0], here[1], max(height, here[2])])
            try:
                self._go(up)
            except MotionError:  # not even straight up: a new posture right above
                self._swing_to(up, self.cup_yaw)
            self._swing_to(np.array([goal_xy[0], goal_xy[1], height]), yaw)
        except MotionError:
            raise MotionError(problem) from None

    def _swing_to(self, point: np.ndarray, yaw: float) -> None:
        """To ``point`` turned ``yaw`` by a joint-space move from where the arm
        is, to a posture solved afresh (facing the point, elbow up)."""
        seed = np.array(HOME)
        seed[0] += math.atan2(point[1] - self.base[1], point[0] - self.base[0]) - math.radians(
            self.base[2]
        )
        q = self.kinematics.solve_anywhere(point, yaw, seed)
        if q is None:
            raise MotionError(f"the cup cannot reach {xyz(point)}")
        self._joint_move(self.q + wrapped(q - self.q), 30, 2.0)

    def _travel_height(
        self, start: tuple[float, float] | None = None, goal: tuple[float, float] | None = None
    ) -> float:
        """A height for the cup to cross from ``start`` to ``goal`` (x, y): 3 cm
        over the load, or the lowered fingertips, above the tallest object near
        that line (every object without one)."""
        carried = FINGER_REACH if self.tool == "fingers" else 0.0
        sweep = 0.05
        if self.held is not None:
            shape = self.geometry[self.held]
            carried = max(carried, float(self.grip[2, 3]) + shape.size[2] / 2)
            sweep += math.hypot(shape.size[0], shape.size[1]) / 2
        tops = []
        for name in self._active():
            if name == self.held:
                continue
            pose = self._pose(name)
            shape = self.geometry[name]
            if start is not None and goal is not None:
                near = sweep + math.hypot(shape.size[0], shape.size[1]) / 2
                if _distance_to_segment(pose.position[:2], start, goal) > near:
                    continue
            tops.append(pose.position[2] + shape.size[2])
        return max(tops, default=0.0) + carried + 0.03

    def _unpark(self) -> None:
        """Back from behind the base: the half turn of :meth:`park` undone."""
        self.parked = False
        self._turn_base(-math.pi)

    def _turn_base(self, angle: float) -> None:
        """Turn the first joint alone by ``angle`` (rad)."""
        self._joint_move(self.q + np.array([angle, 0, 0, 0, 0, 0]), 36, PARK_SECONDS)

    def _joint_move(self, target: np.ndarray, steps: int, seconds: float) -> None:
        """From the arm's joint angles straight to ``target`` in joint space, in
        ``steps`` waypoints checked against collisions, then run over ``seconds``."""
        path = [self.q + (target - self.q) * k / steps for k in range(1, steps + 1)]
        problem = self._collision(path, False)
        if problem is not None:
            raise MotionError(problem)
        self._run(path, seconds)
        self.cup_yaw = self._cup_yaw()


def _distance_to_segment(
    point: tuple[float, ...], start: tuple[float, float], goal: tuple[float, float]
) -> float:
    p, a, b = np.asarray(point[:2]), np.asarray(start), np.asarray(goal)
    span = b - a
    t = 0.0 if not span.any() else float(np.clip(np.dot(p - a, span) / np.dot(span, span), 0, 1))
    return float(np.linalg.norm(p - (a + t * span)))
