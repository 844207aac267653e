"""A 6-DOF arm in MuJoCo (``--sim arm``): dm_control's Kinova Jaco with a
suction cup and two fingers, inverse kinematics by mink, joint-space motions
checked against collisions before they run.

**The arm.** The Jaco model (``dm_control/third_party/kinova/jaco_arm.xml``,
shipped in dm_control's wheel: six hinge joints, two of them limited, real link
masses and joint friction) stands on the table at :attr:`ArmWorld.base`. Each
joint is driven by a position servo, as a robot controller drives it; the
links are gravity-compensated, as the Jaco's own controller does.

**The tool.** A combined tool in place of the Jaco's three-finger hand: a
suction cup on an 8 cm stem between the two fingers of a parallel-jaw
gripper (a Robotiq 2F-85's 85 mm stroke, 40 N of grip, rubber pads) whose
housing slides along the stem. The paper's cutlery is 5–8 mm thin, the napkin
3 mm, the kit's pcb 1 cm: the cup takes them from the top, the jaws drawn up
out of its way. The cup holds by force, not by a weld: MuJoCo's *adhesion*
actuator pulls the cup's contacts together with up to :data:`SUCTION_FORCE`
newtons, so a held object is carried by that force and the pad's friction.
What the 10 mm cup does not carry (a mug) the fingers take from the sides,
the jaws lowered past the pad: the fingers' servos squeeze with up to
:data:`~demoplan.execution.arm_model.GRIP_FORCE` newtons and the load hangs on
the pads' friction. Each object goes by the cup where the cup carries it, else
by the fingers, else it is refused before the run, saying why
(:func:`choose_tool`: trial carries in this same simulation).

**Motions.** Every move of the cup is a straight line (up to the travel height,
across, straight down), cut into waypoints 1 cm apart; each waypoint is solved
by inverse kinematics (mink, warm-started from the one before, joint limits
respected), so the arm's motion is a joint-space path. Before a path runs,
every waypoint is checked in a copy of the simulation: the arm may touch
nothing but the object it holds or is about to take, the held object nothing
but where it is put down. A path that would collide is raised and tried again
higher; one that still collides is not run. While it runs, the servos track
the path and every contact the arm makes is recorded (:attr:`ArmWorld.collisions`).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from demoplan.execution.arm_model import (
    ARM_GROUP,
    FINGER_HALF,
    FINGER_REACH,
    HOME,
    JAW_SLIDE,
    JAW_STROKE,
    JAWS_CLOSED,
    REACH,
    ArmKinematics,
    add_tool_drives,
    arm_base,
    arm_bodies,
    arm_joints,
    attach_arm,
    check_base,
    jaco_folder,
)
from demoplan.execution.arm_motion import (
    WAYPOINT,
    ArmMotion,
    MotionError,
    cup_frame,
    wrapped,
    xyz,
)
from demoplan.execution.arm_moves import ArmMoves
from demoplan.execution.arm_tools import (
    FINGERTIP_GAP,
    MIN_JAW_CLEARANCE,
    TOOL_NAMES,
    TRIAL_MARGIN,
    TRIAL_PICK,
    TRIAL_PLACE,
    Tool,
    ToolChoice,
    carry_in_trial,
    tool_by_trial,
)
from demoplan.execution.faults import Faults
from demoplan.execution.physics import scene_xml
from demoplan.model import ObjectGeometry, Pose
from demoplan.scenes.geometry import half_extent
from demoplan.scenes.scene import DEFAULT_GRASPS, Scene

logger = logging.getLogger(__name__)

__all__ = [
    "TRIAL_MARGIN",
    "TRIAL_PICK",
    "TRIAL_PLACE",
    "ArmWorld",
    "MotionError",
    "Tool",
    "ToolChoice",
    "carries",
    "choose_tool",
    "why_not_carried",
]

APPROACH = 0.03  # m above the contact height where the straight approach starts
JAW_CLEARANCE = 0.01  # m: between an open finger and the object's side, where there is room
TOP_GAP = 0.005  # m: between the object's top and the pad when the fingers take it


class ArmWorld(ArmMoves):
    """The scene in MuJoCo with the Jaco arm and its tool; see the module docstring."""

    name = "arm"
    video_speed = 2.0  # the arm moves carefully: its videos play at twice the speed

    def __init__(
        self,
        scene: Scene,
        faults: Faults = Faults(),
        seed: int | None = 0,
        schedule: Mapping[int, str] | None = None,
        workspace: Sequence[tuple[float, float]] = (),
    ):
        jaco_folder()  # a one-line usage error where the arm's packages are missing
        self.base = arm_base(scene, workspace)
        check_base(scene, self.base)
        self.motion_failures: list[str] = []  # motions not made, and why
        self.grasp_problems: list[str] = []  # grasps the tool felt fail, and how
        self.collisions: list[str] = []  # arm contacts with anything but its load, as they happened
        self.grip = np.eye(4)  # the held object's frame in the cup's frame
        self.grip_yaw = 0.0
        self.allowed: str | None = None  # the object the cup may touch now
        self.parked = False  # turned round behind the base (park)
        self.tool: Tool = "suction"  # the tool in use: the jaws drawn up, or lowered
        self.tools: dict[str, Tool] = {}  # each object's tool, chosen when first taken
        super().__init__(scene, faults, seed, schedule)
        self.hidden_from_top = (ARM_GROUP,)
        self.oracle.reachable = self._comfortably_reached
        # The overview looks across the arm, from its side: the arm in profile,
        # the objects beyond its base in view.
        points = [o.pose.position[:2] for o in scene.objects] + [p[:2] for p in workspace]
        xs = [p[0] for p in points] + [self.base[0]]
        ys = [p[1] for p in points] + [self.base[1]]
        span = max(max(xs) - min(xs), max(ys) - min(ys)) + 0.25
        distance = 0.75 * span / math.tan(math.radians(22.5))
        centre = [(min(xs) + max(xs)) / 2, (min(ys) + max(ys)) / 2, 0.1]
        self.overview = (centre, distance)
        self.overview_azimuth = self.base[2] + 90.0

    def _comfortably_reached(self, x: float, y: float) -> bool:
        """(x, y) lies 5 cm inside the cup's reach (where faults may put things)."""
        distance = math.hypot(x - self.base[0], y - self.base[1])
        return REACH[0] + 0.05 <= distance <= REACH[1] - 0.05

    def _start_robot(self) -> None:
        """The arm at its home pose, servos holding it there, suction off."""
        mujoco = self.mujoco
        self.kinematics = ArmKinematics(mujoco, self.base)
        self.joints = arm_joints(mujoco, self.model)
        self.servos = [
            mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_ACTUATOR, f"_joint{k}")
            for k in range(1, 7)
        ]
        actuator = mujoco.mjtObj.mjOBJ_ACTUATOR
        self.suction = mujoco.mj_name2id(self.model, actuator, "_suction")
        self.jaw_slide = mujoco.mj_name2id(self.model, actuator, "_jaw_slide")
        self.jaw_servos = [
            mujoco.mj_name2id(self.model, actuator, f"_finger_{side}") for side in ("left", "right")
        ]
        self.finger_geoms = {
            mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, f"arm/finger_{side}")
            for side in ("left", "right")
        }
        self.tcp = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_SITE, "arm/tcp")
        self.pad = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, "arm/pad")
        self.arm_bodies = arm_bodies(mujoco, self.model)
        self.motion = ArmMotion(
            mujoco, self.model, self.kinematics, self.joints, self.arm_bodies, self.tcp
        )
        self.arm_geoms = self.motion.arm_geoms
        home = np.array(HOME)
        self.data.qpos[self.joints] = home
        self.data.ctrl[self.servos] = home
        self.finger_joints = [
            int(
                self.model.jnt_qposadr[
                    mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_JOINT, f"arm/finger_{side}")
                ]
            )
            for side in ("left", "right")
        ]
        self.data.qpos[self.finger_joints] = JAWS_CLOSED
        self.data.ctrl[self.jaw_servos] = JAWS_CLOSED
        mujoco.mj_forward(self.model, self.data)
        self.q = home
        self.cup_yaw = self._cup_yaw()

    # -- building --------------------------------------------------------------------------

    def _compile(self, top_view: tuple[float, float, float], offscreen: tuple[int, int]) -> Any:
        mujoco = self.mujoco
        world = mujoco.MjSpec.from_string(scene_xml(self.scene, top_view, offscreen, hand=False))
        attach_arm(mujoco, world, self.base)
        for k in range(1, 7):
            servo = world.add_actuator(
                name=f"_joint{k}", target=f"arm/joint_{k}", trntype=mujoco.mjtTrn.mjTRN_JOINT
            )
            # stiff enough that joint friction (frictionloss 2 and 1 N·m) leaves
            # under 1.5 mrad of error: under 1 mm at the cup
            servo.set_to_position(kp=2000.0 if k <= 3 else 800.0, dampratio=1.0)
            servo.forcerange = [-60.0, 60.0] if k <= 3 else [-25.0, 25.0]
            servo.forcelimited = True
        add_tool_drives(mujoco, world)
        return world.compile()

    # -- reading ---------------------------------------------------------------------------

    def _hand(self) -> np.ndarray:
        return self._cup()[0]

    def _hand_body(self) -> np.ndarray:
        return self._cup()[0]

    def _touching(self, obj: str, data: Any = None) -> bool:
        """The tool in use touches ``obj``: the suction pad, or the fingers with
        ``obj`` between them (a finger touches it and they stopped short of
        closing, as a gripper senses an object by where its fingers stall:
        MuJoCo's contact between a flat pad and a curved side comes and goes)."""
        data = self.data if data is None else data
        body = self._body(obj)
        mine = {self.pad} if self.tool == "suction" else self.finger_geoms
        if self.tool == "fingers" and float(np.min(data.qpos[self.finger_joints])) < 0.001:
            return False
        contacts = data.contact  # as arrays: reading each contact as an object costs more
        # pushing: not the pad's outer band
        pairs = contacts.geom[contacts.dist < contacts.includemargin]
        by_tool = np.isin(pairs, sorted(mine))
        on_obj = self.model.geom_bodyid[pairs] == body
        return bool((by_tool & on_obj[:, ::-1]).any())

    def _lifted(self, name: str) -> bool:
        """Held by the tool (sealed on the cup, or in the jaws) and off whatever
        it stood on."""
        centre = self.data.xpos[self._body(name)]
        held = self._in_the_jaws(name) if self.tool == "fingers" else self._on_the_cup(name)
        return bool(held and centre[2] > 0.004 + self.geometry[name].size[2] / 2)

    def _on_the_cup(self, name: str) -> bool:
        """``name`` hangs on the suction cup, as its vacuum sensor tells: suction
        on and the pad touching it, or its top at the pad's face (within 4 mm,
        under the cup) — the pad's contact, like the fingers', may be missing
        for a step while the load hangs on."""
        if self.data.ctrl[self.suction] <= 0.0:
            return False
        if self._touching(name):
            return True
        centre = np.asarray(self.data.xpos[self._body(name)])
        cup, _ = self._cup()
        shape = self.geometry[name]
        under = math.dist(centre[:2], cup[:2]) < min(shape.size[0], shape.size[1]) / 2
        return bool(under and abs(cup[2] - (centre[2] + shape.size[2] / 2)) < 0.004)

    def _in_the_jaws(self, name: str) -> bool:
        """``name`` is in the jaws as a gripper senses it: the fingers stalled
        short of closing, with the object between them — its centre under the
        tool and within the fingers' reach below the pad. Not by the pads'
        contacts: between a pad and a load tilted in the grip they come and go
        from one step to the next while the load is held (a 0.34 kg box was
        let go, held, because one step had none)."""
        if float(np.min(self.data.qpos[self.finger_joints])) < 0.001:
            return False
        centre = np.asarray(self.data.xpos[self._body(name)])
        cup, _ = self._cup()
        shape = self.geometry[name]
        under = math.dist(centre[:2], cup[:2]) < max(shape.size[0], shape.size[1]) / 2
        depth = cup[2] - centre[2]
        return bool(under and 0.0 < depth < FINGER_REACH + shape.size[2] / 2 + 0.01)

    def _object_frame(self, name: str, data: Any = None) -> np.ndarray:
        data = self.data if data is None else data
        body = self._body(name)
        frame = np.eye(4)
        frame[:3, :3] = np.array(data.xmat[body]).reshape(3, 3)
        frame[:3, 3] = data.xpos[body]
        return frame

    def _cup_frame(self, data: Any = None) -> np.ndarray:
        return cup_frame(self.data if data is None else data, self.tcp)

    # -- the World protocol ------------------------------------------------------------

    def grasp(self, obj: str, axis: float, where: Pose | None = None) -> None:
        self.oracle.actions += 1
        if self.held is not None or obj not in self._active():
            return
        pose = where if where is not None else self._pose(obj)
        tool = self._tool_for(obj)
        if tool == "fingers" and not self._fits(obj, axis):
            # The plan's grasp is wider than the jaws open: the fingers take the
            # object across the axis the check tried (they carry it across that one).
            logger.info(
                "arm: %s is too wide for the jaws across %g°; taken across another", obj, axis
            )
            axis = choose_tool(self.geometry[obj], self._axes(obj)).axis
        missed = self.oracle._chance(self.faults.grasp, "grasp")
        if missed:
            self.oracle.record_fault("grasp", obj, None, f"the grasp of {obj} missed")
        refused = len(self.motion_failures)
        try:
            self.allowed = obj
            if tool == "suction":
                self._grasp_by_suction(obj, pose, axis, missed)
            else:
                self._grasp_by_fingers(obj, pose, axis, missed)
        except MotionError as exc:
            self._give_up(str(exc))
        finally:
            self.allowed = None
        named = TOOL_NAMES[tool]
        if self.held is not None and not self._lifted(self.held):
            self.grasp_problems.append(f"{obj} slipped from the {named} as it lifted")
            self._let_go()
            self.held = None
            self._settle(0.2)
        elif self.held is None and len(self.motion_failures) == refused:
            took = "did not seal on" if tool == "suction" else "closed without holding"
            self.grasp_problems.append(f"the {named} {took} {obj}")

    def _grasp_by_suction(self, obj: str, pose: Pose, axis: float, missed: bool) -> None:
        """Down onto ``obj``'s top, suction on, and up (``missed``: the cup comes
        down 3 cm beside it and seals on air)."""
        top = pose.position[2] + self.geometry[obj].size[2]
        x, y = pose.position[0], pose.position[1]
        if missed:
            angle = math.radians(pose.yaw + axis + 90.0)
            x, y = x + 0.03 * math.cos(angle), y + 0.03 * math.sin(angle)
        self._switch_tool("suction")
        logger.info("arm: over %s at (%.3f, %.3f) and down onto its top", obj, x, y)

        def onto_top() -> None:
            if not missed:
                self._go([x, y, top + 0.002], landing=True)
                self._press(obj, x, y, top)

        self._come_down(x, y, top, (0.0, 90.0, -90.0, 180.0), onto_top)
        self.data.ctrl[self.suction] = 1.0
        self._settle(0.3)
        self._hold_if_touching(obj)
        logger.info("arm: suction on, lifting %s (%s)", obj, "sealed" if self.held else "no seal")
        self._go([x, y, top + APPROACH])
        self._settle(0.2)

    def _grasp_by_fingers(self, obj: str, pose: Pose, axis: float, missed: bool) -> None:
        """The jaws lowered and open round ``obj`` across ``axis`` (deg, in its
        frame), down beside it until the pad is just over its top (or the
        fingertips just over what it stands on), closed with the grip force,
        and up (``missed``: they come down beside it and close on air)."""
        shape = self.geometry[obj]
        half = half_extent(shape, axis)
        if half + MIN_JAW_CLEARANCE > JAW_STROKE / 2:
            raise MotionError(
                f"{obj} is {200 * half:.1f} cm across grasp {axis:g}°; "
                f"the jaws open to {100 * JAW_STROKE:.1f} cm"
            )
        across = pose.yaw + axis
        yaw = self.cup_yaw + ((across - self.cup_yaw + 90.0) % 180.0) - 90.0
        x, y = pose.position[0], pose.position[1]
        if missed:
            angle = math.radians(across + 90.0)
            off = half_extent(shape, axis + 90.0) + FINGER_HALF[1] + 0.01
            x, y = x + off * math.cos(angle), y + off * math.sin(angle)
        low = pose.position[2] + max(shape.size[2] + TOP_GAP, FINGER_REACH + FINGERTIP_GAP)
        self._switch_tool("fingers", min(half + JAW_CLEARANCE, JAW_STROKE / 2))
        logger.info("arm: over %s at (%.3f, %.3f), the fingers down round it", obj, x, y)
        self._come_down(x, y, low, (0.0, 180.0), lambda: self._go([x, y, low], landing=True), yaw)
        self.grip_axis = axis
        self._jaws(0.0)  # the servos close until the grip force stops them
        self._settle(0.5)
        self._hold_if_touching(obj)
        logger.info("arm: fingers closed, lifting %s (%s)", obj, "held" if self.held else "empty")
        self._go([x, y, low + APPROACH])
        self._settle(0.2)

    def _fits(self, obj: str, axis: float) -> bool:
        """The open jaws go round ``obj`` across ``axis`` (deg, in its frame)."""
        return half_extent(self.geometry[obj], axis) + MIN_JAW_CLEARANCE <= JAW_STROKE / 2

    def _hold_if_touching(self, obj: str) -> None:
        """``obj`` is held when the tool touches it, or (the fingers) when they
        stalled with it between them (:meth:`_in_the_jaws`: the pads' contact
        may be missing at that step): its frame in the cup's is kept."""
        if self._touching(obj) or (self.tool == "fingers" and self._in_the_jaws(obj)):
            self.held = obj
            self.grip = np.linalg.inv(self._cup_frame()) @ self._object_frame(obj)
            self.grip_yaw = self._pose(obj).yaw - self.cup_yaw

    def _tool_for(self, obj: str) -> Tool:
        """The tool that takes ``obj`` (:func:`choose_tool`; the suction cup for
        one the check refused, as before a second tool existed)."""
        if obj not in self.tools:
            choice = choose_tool(self.geometry[obj], self._axes(obj))
            self.tools[obj] = choice.tool or "suction"
            logger.info("arm: %s goes by the %s", obj, TOOL_NAMES[self.tools[obj]])
        return self.tools[obj]

    def _axes(self, obj: str) -> tuple[float, ...]:
        """The finger axes (deg) ``obj``'s scene entry allows."""
        return next((o.grasps for o in self.scene.objects if o.name == obj), DEFAULT_GRASPS)

    def _switch_tool(self, tool: Tool, opening: float = JAWS_CLOSED) -> None:
        """The jaws lowered past the pad and opened to ``opening`` (half the gap,
        m) for the fingers, or drawn up and closed round the stem for the
        suction cup: high enough first that the fingertips clear everything."""
        if tool == self.tool and abs(float(self.data.ctrl[self.jaw_servos[0]]) - opening) < 1e-4:
            return
        here, _ = self._cup()
        lowered = tool == "fingers" and self.tool == "suction"
        height = self._travel_height() + (FINGER_REACH if lowered else 0.0)
        if here[2] < height:
            try:
                self._go([here[0], here[1], height])
            except MotionError:  # straight up passes a singularity: a new posture up there
                self._swing_to(np.array([here[0], here[1], height]), self.cup_yaw)
        if tool != self.tool:
            logger.info("arm: the jaws %s", "lowered" if tool == "fingers" else "drawn up")
        self.tool = tool
        self.data.ctrl[self.jaw_slide] = JAW_SLIDE if tool == "fingers" else 0.0
        self._jaws(opening)
        self._settle(0.5)

    def _jaws(self, opening: float) -> None:
        """Command the fingers to ``opening`` (half the gap between them, m)."""
        self.data.ctrl[self.jaw_servos] = min(max(opening, 0.0), JAW_STROKE / 2)

    def _open(self) -> None:
        """At the start: the suction cup's posture, the jaws drawn up and closed."""
        self._jaws(JAWS_CLOSED)

    def _let_go(self) -> None:
        """Suction off, or the fingers opened a little (not wide: the
        neighbours are close)."""
        if self.tool == "suction":
            self.data.ctrl[self.suction] = 0.0
            return
        half = JAWS_CLOSED
        if self.held is not None:
            half = half_extent(self.geometry[self.held], self.grip_axis)
        self._jaws(min(half + JAW_CLEARANCE, JAW_STROKE / 2))

    def put_down(self, obj: str, pose: Pose) -> None:
        self.oracle.actions += 1
        if self.held != obj:
            return
        self._sync_oracle()
        here = self._hand()
        if self.oracle._chance(self.faults.drop, "drop"):
            x, y = pose.position[0], pose.position[1]
            t = float(self.oracle.rng.uniform(0.2, 0.8))
            spot = self.oracle._land(obj, here[0] + t * (x - here[0]), here[1] + t * (y - here[1]))
            self._release_at(spot, 0.012, "drop", f"{obj} fell at {_xy(spot)} while carried")
            return
        if self.oracle._chance(self.faults.misplace, "misplace"):
            off = self.oracle.misplaced_spot(obj, pose)
            if off is not None:
                detail = f"{obj} released at {_xy(off)}, off its target"
                self._release_at(off, 0.002, "misplace", detail)
                return
        logger.info("arm: carrying %s to (%.3f, %.3f) and setting it down", obj, *pose.position[:2])
        self._release_at(pose, 0.002, None, "")

    def _come_down(
        self,
        x: float,
        y: float,
        low: float,
        turns: Sequence[float],
        last: Callable[[], None],
        across: float | None = None,
    ) -> None:
        """Over (x, y), down to :data:`APPROACH` above ``low`` and the ``last``
        straight descent, turned to ``across`` (deg; None: as the cup is) plus
        the first of ``turns`` that works: where a straight descent would take
        the wrist through a singularity (its fifth joint straight) the cup
        tries the next turn (the cup is round: any; the fingers: either way
        across the grasp), and last a new posture made up over there."""
        problem = ""
        for turn, new_posture in [(turn, False) for turn in turns] + [(0.0, True)]:
            yaw = (self.cup_yaw if across is None else across) + turn
            try:
                self._travel((x, y), yaw, low + APPROACH)
                if new_posture:
                    self._repose(np.array([x, y, low + 0.002]), yaw)
                self._go([x, y, low + APPROACH], yaw)
                last()
                return
            except MotionError as exc:
                problem = str(exc)
        raise MotionError(problem)

    def _repose(self, low: np.ndarray, yaw: float) -> None:
        """Where the posture the arm has cannot go straight down to ``low`` (a
        singularity on the way): solve ``low`` afresh, walk the straight line
        up from it to where the cup is, and change posture up here by a
        joint-space move (checked) to the start of that line."""
        here, _ = self._cup()
        seed = np.array(HOME)
        seed[0] += math.atan2(low[1] - self.base[1], low[0] - self.base[0]) - math.radians(
            self.base[2]
        )
        q = self.kinematics.solve_anywhere(low, yaw, seed)
        if q is None:
            raise MotionError(f"the cup cannot reach {xyz(low)}")
        steps = max(1, math.ceil(float(np.linalg.norm(here - low)) / WAYPOINT))
        for k in range(1, steps + 1):
            q = q + wrapped(self._step_to(low + k / steps * (here - low), yaw, q) - q)
        self._joint_move(self.q + wrapped(q - self.q), 30, 2.0)

    def _press(self, obj: str, x: float, y: float, top: float) -> None:
        """Lower the cup 1 mm at a time until its pad touches ``obj`` (as a
        compliant suction gripper senses contact), at most 6 mm below where the
        top was expected."""
        for depth in np.arange(0.001, -0.0065, -0.001):
            if self._touching(obj):
                return
            self._go([x, y, top + depth], landing=True)

    def _release_at(self, pose: Pose, gap: float, fault: str | None, detail: str) -> None:
        """Carry the held object over ``pose``, lower it to ``gap`` above it and let go."""
        assert self.held is not None
        obj = self.held
        shape = self.geometry[obj]
        target = np.eye(4)
        target[:3, :3] = _yaw_matrix(pose.yaw)
        target[:3, 3] = [
            pose.position[0],
            pose.position[1],
            pose.position[2] + shape.size[2] / 2 + gap,
        ]
        cup = target @ np.linalg.inv(self.grip)
        yaw = math.degrees(math.atan2(cup[1, 0], cup[0, 0]))
        yaw = self.cup_yaw + ((yaw - self.cup_yaw + 180.0) % 360.0) - 180.0
        above = cup[:3, 3] + [0.0, 0.0, APPROACH]
        try:
            # as a grasp comes down: where the posture the arm has cannot go
            # straight down there, a new one made up over the spot
            self._come_down(
                float(cup[0, 3]),
                float(cup[1, 3]),
                float(cup[2, 3]),
                (0.0,),
                lambda: self._go(cup[:3, 3], yaw, landing=True),
                yaw,
            )
        except MotionError as exc:
            self._give_up(str(exc))
            return
        self._let_go()
        self._settle(0.3)
        self.held = None
        try:
            self.allowed = obj  # the cup leaves it: touching it on the way up is no collision
            self._go(above)
        except MotionError as exc:
            self._give_up(str(exc))
        finally:
            self.allowed = None
        self._settle(0.2)
        if fault is not None:
            self.oracle.record_fault(fault, obj, pose, detail)

    def _give_up(self, reason: str) -> None:
        """A motion that cannot be made is not made: the action fails, and the
        executor, observing, replans."""
        self.motion_failures.append(reason)

    def park(self) -> None:
        """Turn the arm (and what it holds) round behind its base, out of the top
        camera's view: straight up, then half a turn of the first joint alone
        (its axis is vertical, so the cup stays pointing down and a load does
        not tilt), every step checked against collisions; the next motion
        turns it back first (:meth:`_unpark`)."""
        if self.parked:
            return
        here, _ = self._cup()
        try:
            self._go([here[0], here[1], max(here[2], self._travel_height() + 0.1)])
            self._turn_base(math.pi)
            self.parked = True
        except MotionError as exc:
            self._give_up(f"parking: {exc}")

    # -- checks before the run -----------------------------------------------------------

    def why_not_graspable(self, obj: str) -> str | None:
        """Why neither tool can take ``obj`` and carry it (:func:`choose_tool`), or None."""
        return why_not_carried(self.geometry[obj], self._axes(obj))

    def why_not_reachable(self, obj: str, pose: Pose) -> str | None:
        """Why the cup cannot come down on ``obj`` standing at ``pose`` (out of the
        arm's reach), or None: farther from the base, or nearer, than the cup
        reaches anywhere (:data:`~demoplan.execution.arm_model.REACH`: closer to
        the base than that, inverse kinematics may find a posture from which
        the motions of a run do not hold a load — a 0.12 kg box 19 cm from the
        base came off the cup it stayed on 20 cm out), or no posture over it."""
        shape = self.geometry[obj]
        top = pose.position[2] + shape.size[2]
        point = np.array([pose.position[0], pose.position[1], top])
        bx, by, _ = self.base
        distance = math.hypot(point[0] - bx, point[1] - by)
        low, high = REACH
        out = (
            f"at {_xy(pose)} is out of the arm's reach ({distance:.2f} m from its "
            f"base at ({bx:.3f}, {by:.3f}); the suction cup reaches {low:.2f}–{high:.2f} m)"
        )
        if not low <= distance <= high:
            return out
        for height in (0.0, APPROACH):
            if self.kinematics.solve_anywhere(point + [0, 0, height], 0.0, np.array(HOME)) is None:
                return out
        return None

    def why_not_reachable_together(self, places: Sequence[tuple[str, Pose]]) -> str | None:
        """Why no base of the arm reaches all of ``places`` (what each is, its
        pose): the two farthest apart lie more than the cup reaches across
        (twice :data:`~demoplan.execution.arm_model.REACH`'s outer bound); else None."""
        far: tuple[float, str, str] = (0.0, "", "")
        for k, (first, a) in enumerate(places):
            for second, b in places[k + 1 :]:
                apart = math.dist(a.position[:2], b.position[:2])
                if apart > far[0]:
                    far = (apart, first, second)
        apart, first, second = far
        low, high = REACH
        if apart <= 2 * high:
            return None
        return (
            f"{first} and {second} are {apart:.2f} m apart; the suction cup reaches "
            f"{low:.2f}–{high:.2f} m from the arm's base, so no place for the base "
            "reaches both"
        )


def choose_tool(shape: ObjectGeometry, axes: tuple[float, ...] = DEFAULT_GRASPS) -> ToolChoice:
    """The tool that carries an object of ``shape`` (its size and mass) whose
    scene allows finger ``axes``: the suction cup where it carries it, else the
    fingers, else neither, with why — each tried in a trial carry in an
    :class:`ArmWorld` (:func:`~demoplan.execution.arm_tools.tool_by_trial`).
    The check is the physics itself, not a model of it (docs/execution.md)."""
    return tool_by_trial(shape, axes, ArmWorld)


def why_not_carried(shape: ObjectGeometry, axes: tuple[float, ...] = DEFAULT_GRASPS) -> str | None:
    """Why neither the suction cup nor the fingers carry an object of ``shape``
    (:func:`choose_tool`), or None."""
    return choose_tool(shape, axes).why


def carries(
    shape: ObjectGeometry, pick: Pose, place: Pose, tool: Tool | None = None, axis: float = 0.0
) -> tuple[bool, bool]:
    """Whether the arm, alone on a table with an object of ``shape`` standing at
    ``pick`` (the base at the origin facing +x), lifts it and puts it down at
    ``place`` within 1 cm: (lifted, placed). ``tool``: the one it uses (None:
    the one :func:`choose_tool` chooses, as in a run); ``axis``: the fingers'."""
    trial = carry_in_trial(shape, pick, place, tool, axis, ArmWorld)
    return trial.lifted, trial.carried


def _yaw_matrix(yaw: float) -> np.ndarray:
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _xy(pose: Pose) -> str:
    return f"({pose.position[0]:.3f}, {pose.position[1]:.3f})"
