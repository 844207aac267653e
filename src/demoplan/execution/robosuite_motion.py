"""robosuite's Panda moved by its own OSC_POSE controller in delta mode: a
straight-line servo of the grip site to a point and a finger direction, the
gripper opened and closed, nothing else.

Measured on robosuite 1.5.2's Panda (docs/execution.md "robosuite"): the
fingers close along the grip site's x axis; with the hand pointing down,
turning it by +δ about the world's z turns the last joint by −δ, and that
joint stops at ±2.9 rad, so the finger direction is kept where the joint can
take it (:meth:`PandaHand.finger_yaws_within_reach`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from demoplan.execution.robosuite_clearance import HandShape

__all__ = ["PandaHand"]

POSITION_SCALE = 0.05
"""m per unit of the controller's position input (robosuite's default output_max)."""
ROTATION_SCALE = 0.5
"""rad per unit of its rotation input."""
STEP_LENGTH = 0.012
"""m: the farthest the goal is moved in one control step (0.24 m/s at 20 Hz)."""
STEP_TURN = math.radians(6.0)
"""The most the goal turns in one control step (120°/s at 20 Hz)."""
POSITION_TOLERANCE = 0.002  # m
TURN_TOLERANCE = math.radians(1.5)
MAX_STEPS = 400
"""Control steps a move may take (20 s at 20 Hz); a move that has not arrived
by then is reported (the arm is blocked or the point out of reach)."""
STALLED = 0.0005
"""m: a control step that moves the hand less than this, after the goal has
reached its end, did not move it."""
STALL_STEPS = 10
"""Control steps without moving after which a move stops short (0.5 s)."""
GRIPPER_STEPS = 12
"""Control steps the gripper is given to close or open (0.6 s)."""
DOWN = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
"""The grip site's frame pointing down with its fingers along the world's +y
(columns: the site's x, y, z axes in the world)."""
WRIST_LIMIT = 2.6
"""rad: how far the last joint may be sent (its range is ±2.9 rad; the
controller turns the arm away when it meets a limit)."""


def _wrap(angle: float) -> float:
    """``angle`` (deg) in [-180, 180)."""
    return (angle + 180.0) % 360.0 - 180.0


def hand_frame(finger_yaw: float) -> np.ndarray:
    """The grip site's orientation pointing down with the fingers closing along
    ``finger_yaw`` (deg from the world's x axis)."""
    turn = Rotation.from_euler("z", finger_yaw - 90.0, degrees=True).as_matrix()
    frame: np.ndarray = turn @ DOWN
    return frame


class PandaHand:
    """The grip site of robosuite's Panda, moved through ``env.step``."""

    def __init__(self, env: Any) -> None:
        self.env = env
        robot = env.robots[0]
        self.robot = robot
        self.site = int(robot.eef_site_id["right"])
        self.gripper_model = robot.gripper["right"]
        base = robot.robot_model.root_body
        self.base = np.asarray(env.sim.data.get_body_xmat(base)).reshape(3, 3).copy()
        self.base_position = np.asarray(env.sim.data.get_body_xpos(base)).copy()
        self.wrist = int(robot._ref_joint_pos_indexes[-1])
        self.grip = -1.0  # open
        self.steps = 0
        self.shape = self._housing()

    def _housing(self) -> HandShape:
        """The hand's housing (the gripper's root body's colliding geoms, its
        fingers left out) as a box in the grip site's frame, from the compiled
        model's bounding boxes (``geom_aabb``)."""
        model, data = self.env.sim.model, self.env.sim.data
        root = int(model.body_name2id(self.gripper_model.root_body))
        signs = np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)])
        corners = []
        for g in range(model.ngeom):
            if int(model.geom_bodyid[g]) != root or not (
                int(model.geom_contype[g]) or int(model.geom_conaffinity[g])
            ):
                continue
            box = np.asarray(model.geom_aabb[g])
            local = box[:3] + signs * box[3:]
            world = (
                np.asarray(data.geom_xpos[g])
                + local @ np.asarray(data.geom_xmat[g]).reshape(3, 3).T
            )
            corners.append((world - self.position) @ self.frame)  # the site's z points down
        every = np.concatenate(corners)
        low, high = every.min(axis=0), every.max(axis=0)
        return HandShape(
            half_length=float(max(-low[0], high[0])),
            half_width=float(max(-low[1], high[1])),
            bottom=float(-high[2]),
        )

    # -- reading ------------------------------------------------------------------------

    @property
    def position(self) -> np.ndarray:
        return np.asarray(self.env.sim.data.site_xpos[self.site]).copy()

    @property
    def frame(self) -> np.ndarray:
        return np.asarray(self.env.sim.data.site_xmat[self.site]).reshape(3, 3).copy()

    @property
    def finger_yaw(self) -> float:
        """deg: the direction the fingers close along, in the table's plane."""
        x_axis = self.frame[:, 0]
        return math.degrees(math.atan2(x_axis[1], x_axis[0]))

    def finger_yaws_within_reach(
        self, choices: Sequence[float], at: Sequence[float] | np.ndarray
    ) -> list[float]:
        """Of the finger directions ``choices`` (deg; each also turned by the
        hand's half turn), those the wrist reaches with the hand at ``at``
        (world x, y), each as the least turn from the current direction.

        With the hand pointing down its yaw is the first joint's angle minus
        the last one's (and a constant): going to ``at`` turns the first joint
        by the change of the hand's bearing from the robot's base, so the
        last joint ends at its angle now + that change − the turn."""
        wrist = float(self.env.sim.data.qpos[self.wrist])
        now = self.finger_yaw
        bearing = self._bearing(at) - self._bearing(self.position)
        reached = []
        for choice in choices:
            for half in (0.0, 180.0):
                turns = [_wrap(choice + half - now) + lap for lap in (-360.0, 0.0, 360.0)]
                allowed = [
                    t for t in turns if abs(wrist + bearing - math.radians(t)) <= WRIST_LIMIT
                ]
                if allowed:
                    reached.append(now + min(allowed, key=abs))
        return reached

    def _bearing(self, point: Sequence[float] | np.ndarray) -> float:
        """rad: the direction of ``point`` (x, y) from the robot's base."""
        return math.atan2(point[1] - self.base_position[1], point[0] - self.base_position[0])

    # -- moving -------------------------------------------------------------------------

    def step(self, position: np.ndarray, rotation: np.ndarray) -> None:
        """One control step towards the goal (position offset and rotation
        vector in the world, already capped)."""
        action = np.zeros(self.env.action_dim)
        action[:3] = self.base.T @ position / POSITION_SCALE
        action[3:6] = self.base.T @ rotation / ROTATION_SCALE
        action[-1] = self.grip
        self.env.step(np.clip(action, -1.0, 1.0))
        self.steps += 1

    def move(self, goal: Sequence[float] | np.ndarray, finger_yaw: float | None = None) -> bool:
        """Move the grip site along a straight line to ``goal`` (world, m),
        pointing down, the fingers turning to ``finger_yaw`` (deg, the way it
        says: 270 from 45 turns by +225°, not −135°; the current one if None);
        whether it arrived within :data:`MAX_STEPS`."""
        target = np.asarray(goal, dtype=float)
        start = self.position
        first_yaw = self.finger_yaw
        last_yaw = first_yaw if finger_yaw is None else finger_yaw
        ramp = max(
            1,
            math.ceil(float(np.linalg.norm(target - start)) / STEP_LENGTH),
            math.ceil(math.radians(abs(last_yaw - first_yaw)) / STEP_TURN),
        )
        still = 0
        for k in range(MAX_STEPS):
            t = min(1.0, (k + 1) / ramp)
            waypoint = start + t * (target - start)
            orientation = Rotation.from_matrix(hand_frame(first_yaw + t * (last_yaw - first_yaw)))
            before = self.position
            error = waypoint - before
            turn = (orientation * Rotation.from_matrix(self.frame).inv()).as_rotvec()
            arrived = np.linalg.norm(error) < POSITION_TOLERANCE
            if t >= 1.0 and arrived and np.linalg.norm(turn) < TURN_TOLERANCE:
                return True
            self.step(2.0 * error, turn)
            moved = float(np.linalg.norm(self.position - before))
            still = still + 1 if t >= 1.0 and moved < STALLED else 0
            if still == STALL_STEPS:
                return False  # held up (a peg under the nut, the table under the fingers)
        return False

    def hold(self, steps: int) -> None:
        """Stay where the hand is for ``steps`` control steps."""
        for _ in range(steps):
            self.step(np.zeros(3), np.zeros(3))

    def close(self) -> None:
        self.grip = 1.0
        self.hold(GRIPPER_STEPS)

    def open(self) -> None:
        self.grip = -1.0
        self.hold(GRIPPER_STEPS)

    def grasping(self, model: Any) -> bool:
        """robosuite's own check: both finger pads touch ``model``'s geoms."""
        return bool(self.env._check_grasp(gripper=self.gripper_model, object_geoms=model))
