"""The arm's motions (:mod:`demoplan.execution.arm`): a straight line of the
cup as joint waypoints, and the check of a joint path against collisions
before it runs.

A straight line is cut into waypoints :data:`WAYPOINT` apart, each solved by
inverse kinematics warm-started from the one before; a joint that would turn
more than :data:`MAX_JUMP` between two waypoints means the arm would swing
through a new posture, and the line is refused. The check poses the arm at
every waypoint in a scratch copy of the simulation, with the held object
carried along (its frame fixed in the cup's), and reads MuJoCo's contacts:
the arm may touch nothing but its load and the object it is allowed to (the
one it is taking), the load nothing but where it lands.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from demoplan.execution.arm_model import ArmKinematics

__all__ = ["ArmMotion", "Load", "MotionError", "cup_frame", "wrapped", "xyz"]

WAYPOINT = 0.01  # m between inverse-kinematics waypoints
MAX_JUMP = 0.6  # rad a joint may turn between two waypoints 1 cm apart
WRIST_NUDGE = 0.3  # rad the wrist is bent to leave its singularity
PENETRATION = 0.002
"""m: in the check before a motion, a contact deeper than this is a collision
(the waypoints are 1 cm apart; grazing is left to the watch while it runs)."""
LANDING_WAYPOINTS = 3  # the last waypoints of a landing, where the load may touch


class MotionError(RuntimeError):
    """A motion the arm cannot make (no inverse kinematics, or a collision)."""


@dataclass(frozen=True, slots=True)
class Load:
    """What the cup holds: the object's name and body, and its frame in the cup's."""

    name: str
    body: int
    grip: np.ndarray


def cup_frame(data: Any, tcp: int) -> np.ndarray:
    """The cup's pose (4×4) in ``data``: site ``tcp``'s position and rotation."""
    frame = np.eye(4)
    frame[:3, :3] = np.array(data.site_xmat[tcp]).reshape(3, 3)
    frame[:3, 3] = data.site_xpos[tcp]
    return frame


def wrapped(delta: np.ndarray) -> np.ndarray:
    """Angle differences (rad) wrapped into [−π, π)."""
    return (np.asarray(delta) + math.pi) % (2 * math.pi) - math.pi


class ArmMotion:
    """Straight lines as joint paths, and their collision check (module docstring)."""

    def __init__(
        self,
        mujoco: Any,
        model: Any,
        kinematics: ArmKinematics,
        joints: Sequence[int],
        arm_bodies: set[int],
        tcp: int,
    ):
        self.mujoco = mujoco
        self.model = model
        self.kinematics = kinematics
        self.joints = list(joints)
        self.arm_bodies = arm_bodies
        self.arm_geoms = np.isin(model.geom_bodyid, sorted(arm_bodies))
        """Per geom of ``model``: True where it is on the arm."""
        self.tcp = tcp
        self.scratch = mujoco.MjData(model)

    def straight_line(
        self, start: np.ndarray, start_yaw: float, q: np.ndarray, goal: np.ndarray, yaw: float
    ) -> list[np.ndarray]:
        """Joint waypoints moving the cup from ``start`` (turned ``start_yaw``,
        the arm at ``q``) in a straight line to ``goal`` while it turns to
        ``yaw``; MotionError where a waypoint has no solution nearby."""
        turn = ((yaw - start_yaw + 180.0) % 360.0) - 180.0
        steps = max(
            1, math.ceil(float(np.linalg.norm(goal - start)) / WAYPOINT), math.ceil(abs(turn) / 5)
        )
        path = []
        for k in range(1, steps + 1):
            t = k / steps
            solved = self.step_to(start + t * (goal - start), start_yaw + t * turn, q)
            q = q + wrapped(solved - q)
            path.append(q)
        return path

    def step_to(self, point: np.ndarray, yaw: float, q: np.ndarray) -> np.ndarray:
        """The joint angles one waypoint on from ``q``: solved from ``q``, else
        from ``q`` with the wrist bent a little either way (a straight wrist,
        fifth joint at 0, is a singularity the solver cannot leave), else from
        anywhere — refused (MotionError) if that means a new posture."""
        nudge = np.array([0.0, 0.0, 0.0, 0.0, WRIST_NUDGE, 0.0])
        for seed in (q, q + nudge, q - nudge):
            solved = self.kinematics.solve(point, yaw, seed)
            if solved is not None and np.max(np.abs(wrapped(solved - q))) <= MAX_JUMP:
                return solved
        solved = self.kinematics.solve_anywhere(point, yaw, q)
        if solved is None:
            raise MotionError(f"the cup cannot reach {xyz(point)}")
        if np.max(np.abs(wrapped(solved - q))) > MAX_JUMP:
            raise MotionError(f"the arm would swing through a new posture near {xyz(point)}")
        return solved

    def first_collision(
        self,
        qpos: np.ndarray,
        path: Sequence[np.ndarray],
        load: Load | None,
        allowed: int | None,
        landing: bool,
        label: Callable[[int], str],
    ) -> str | None:
        """The first collision along ``path`` from the simulation's ``qpos``, as a
        sentence (``label`` names a body), or None. ``allowed``: a body the arm
        may touch; ``landing``: the load may touch what it is put on at the end."""
        mujoco, model, scratch = self.mujoco, self.model, self.scratch
        scratch.qpos[:] = qpos
        scratch.qvel[:] = 0.0
        address = 0
        if load is not None:
            address = int(model.jnt_qposadr[int(model.body_jntadr[load.body])])
        for index, q in enumerate(path):
            scratch.qpos[self.joints] = q
            if load is not None:
                mujoco.mj_kinematics(model, scratch)
                frame = cup_frame(scratch, self.tcp) @ load.grip
                quat = np.zeros(4)
                mujoco.mju_mat2Quat(quat, frame[:3, :3].flatten())
                scratch.qpos[address : address + 3] = frame[:3, 3]
                scratch.qpos[address + 3 : address + 7] = quat
            mujoco.mj_forward(model, scratch)
            lands = landing and index >= len(path) - LANDING_WAYPOINTS
            for first, second in self._arm_or_load_contacts(scratch, load):
                found = self._offending(first, second, load, allowed, lands, label)
                if found is not None:
                    return found
        return None

    def _arm_or_load_contacts(self, data: Any, load: Load | None) -> list[list[int]]:
        """The body pairs of the contacts in ``data`` deeper than
        :data:`PENETRATION`, in MuJoCo's order, that may be collisions: between
        an arm body and another, or touching the load (:meth:`_offending` finds
        nothing in the others). Read as MuJoCo's arrays: reading each contact
        as an object cost more than posing the arm."""
        contacts = data.contact
        pairs = contacts.geom[~(contacts.dist > contacts.includemargin - PENETRATION)]
        bodies = self.model.geom_bodyid[pairs]
        on_arm = self.arm_geoms[pairs]
        held = load.body if load is not None else -1
        relevant = (on_arm[:, 0] != on_arm[:, 1]) | (bodies == held).any(axis=1)
        result: list[list[int]] = bodies[relevant].tolist()
        return result

    def _offending(
        self,
        first: int,
        second: int,
        load: Load | None,
        allowed: int | None,
        lands: bool,
        label: Callable[[int], str],
    ) -> str | None:
        """A sentence when a contact between bodies ``first`` and ``second`` is a
        collision (the arm touching anything but its load or the allowed body,
        the load anything but its landing place), else None."""
        held = load.body if load is not None else -1
        for mine, other in ((first, second), (second, first)):
            if mine in self.arm_bodies and other not in self.arm_bodies:
                if other in (held, allowed):
                    return None
                return f"the arm would hit {label(other)}"
            if load is not None and mine == held and other not in self.arm_bodies and not lands:
                return f"{load.name} would hit {label(other)}"
        return None


def xyz(point: np.ndarray) -> str:
    return f"({point[0]:.3f}, {point[1]:.3f}, {point[2]:.3f})"


def arm_contacts(data: Any, model: Any, on_arm: np.ndarray) -> list[list[int]]:
    """The body pairs of the active contacts in ``data`` (closer than their
    margin) between an arm geom (``on_arm``: per geom) and another, in
    MuJoCo's order. Read as arrays: reading each contact as an object costs
    more than posing the arm."""
    contacts = data.contact
    pairs = contacts.geom[contacts.dist < contacts.includemargin]
    pairs = pairs[on_arm[pairs[:, 0]] != on_arm[pairs[:, 1]]]
    result: list[list[int]] = model.geom_bodyid[pairs].tolist()
    return result
