"""The arm of ``--sim arm`` as a model: dm_control's Kinova Jaco with a
combined tool in MuJoCo (a suction cup on a stem between the two fingers of a
parallel-jaw gripper on a slide), its inverse kinematics (mink), where it
stands, and what it can take (see :mod:`demoplan.execution.arm` for the world
that moves it)."""

from __future__ import annotations

import importlib.util
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from demoplan.errors import InputError, UsageError
from demoplan.model import ObjectGeometry
from demoplan.scenes.scene import Scene

__all__ = [
    "ArmKinematics",
    "add_tool_drives",
    "arm_base",
    "arm_bodies",
    "arm_joints",
    "attach_arm",
    "check_base",
    "jaco_folder",
]

SUCTION_FORCE = 5.0
"""N: the adhesion actuator's pull at full suction (a 10 mm cup at 60 kPa of vacuum
holds 0.785 cm² × 6 N/cm² = 4.7 N)."""
PAD_HALF = 0.005  # m: half the side of the square suction pad
PAD_REACH = 0.001
"""m: the pad's contact margin (its soft face): contacts push from this far
off the face; the suction pulls on them from twice as far."""
STEM = 0.08  # m: from the wrist flange to the pad's face
JAW_STROKE = 0.085
"""m: how far the fingers open (a Robotiq 2F-85's stroke)."""
GRIP_FORCE = 40.0
"""N: each finger's squeeze at most (a Robotiq 2F-85 grips with 20–235 N)."""
FINGER_FRICTION = 1.0
"""The finger pads' friction: rubber on a dry glazed or plastic surface."""
FINGER_HALF = (0.004, 0.011, 0.025)
"""m: half the thickness, width and length of a finger (its inner face is the pad)."""
FINGER_REACH = 2 * FINGER_HALF[2]
"""m: how far the extended fingertips reach past the suction pad's face."""
JAW_SLIDE = 0.08
"""m: the slide that lowers the jaws past the pad for a finger grasp; drawn
up, the housing is level with the wrist flange and the fingertips stay 3 cm
behind the pad's face, out of the cup's way."""
JAWS_CLOSED = 0.012  # m: half the gap the drawn-up fingers leave round the stem
ARM_GROUP = 2
"""MuJoCo geom group of the arm's links: the top camera masks them out, as a
robot's perception filters out the robot's own links by its kinematics."""
BASE_RADIUS = 0.06  # m: the Jaco base's footprint
BASE_STANDOFF = 0.42  # m: default base distance from the objects' centre
REACH = (0.22, 0.6)
"""m: horizontal distances from the base where the cup, pointing down, reaches
anywhere from the table to 30 cm up (measured by inverse kinematics on a grid)."""
HOME = (-0.237, 2.743, 5.164, 2.922, 0.839, -2.027)
"""rad: the cup 35 cm in front of the base, 30 cm up, pointing down (elbow up)."""
_ARM_XML = "jaco_arm.xml"


def jaco_folder() -> Path:
    """Where dm_control keeps the Kinova Jaco's model (found without importing
    dm_control, whose Python bindings this world does not use)."""
    spec = importlib.util.find_spec("dm_control")
    if (
        spec is None
        or not spec.submodule_search_locations
        or importlib.util.find_spec("mink") is None
    ):
        raise UsageError(
            "--sim arm needs dm_control's Kinova Jaco model and mink: pip install 'demoplan[sim]'"
        )
    folder = Path(next(iter(spec.submodule_search_locations))) / "third_party" / "kinova"
    if not (folder / _ARM_XML).is_file():
        raise UsageError(f"--sim arm: {folder / _ARM_XML} is missing from dm_control")
    return folder


def _arm_spec(mujoco: Any, jaws: bool = True) -> Any:
    """The Jaco arm with the combined tool on its wrist flange, links
    gravity-compensated: a suction cup on a stem, and (``jaws``; the inverse
    kinematics does without them: they do not move the cup) a parallel-jaw
    gripper whose housing slides along the stem, its two fingers each on a
    slide joint."""
    arm = mujoco.MjSpec.from_file(str(jaco_folder() / _ARM_XML))
    flange = arm.site("wristsite")
    tool = arm.body("b_6").add_body(name="tool", pos=flange.pos, quat=flange.quat)
    tool.add_geom(
        name="stem",
        type=mujoco.mjtGeom.mjGEOM_CYLINDER,
        size=[0.008, (STEM - 0.008) / 2, 0],
        pos=[0, 0, (STEM - 0.008) / 2],
        rgba=[0.55, 0.55, 0.6, 1],
        mass=0.1,
    )
    cup = tool.add_body(name="cup", pos=[0, 0, STEM - 0.008])
    cup.add_geom(
        name="pad",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[PAD_HALF, PAD_HALF, 0.004],
        pos=[0, 0, 0.004],
        rgba=[0.15, 0.25, 0.7, 1],
        mass=0.01,
        # contacts pushing from PAD_REACH off the face, found (the suction
        # pulling on them) twice as far (_suction_reach)
        **_suction_reach(mujoco.__version__),
        # a flat pad resists turning and tilting up to about its radius times
        # the normal force: torsional and rolling friction of 5 mm (condim 6)
        friction=[1.5, 0.005, 0.005],
        condim=6,
        priority=1,  # the pad's stiff contact parameters, not a mix with the object's
        solref=[0.004, 1.0],
        solimp=[0.99, 0.999, 0.0005, 0.5, 2.0],
    )
    cup.add_site(name="tcp", pos=[0, 0, 0.008])
    if jaws:
        _add_jaws(mujoco, tool)
    for body in arm.bodies:
        body.gravcomp = 1
    for geom in arm.geoms:
        geom.group = ARM_GROUP
    return arm


def _suction_reach(version: str) -> dict[str, float]:
    """The pad's ``margin`` and ``gap`` in MuJoCo ``version``: its contacts
    push from :data:`PAD_REACH` off its face, as before, and are found
    :data:`PAD_REACH` farther out, where they push nothing but the suction
    (the adhesion actuator) still pulls on them. Without that band the
    suction holds a load where its contacts begin, at the very edge of where
    they are found: a tilt of a hundredth of a degree loses the pad's far
    corners, the whole pull goes to the corner left and the load peels off
    (a 0.225 kg box, four contacts at 1.0 mm, fell as the 5 N cup lifted it;
    the cup carried no more than 0.2 kg of any shape). MuJoCo 4 made ``gap``
    the band found beyond ``margin``; before, the part of ``margin`` in which
    a contact pushes nothing."""
    if int(version.split(".")[0]) >= 4:
        return {"margin": PAD_REACH, "gap": PAD_REACH}
    return {"margin": 2 * PAD_REACH, "gap": PAD_REACH}


def _add_jaws(mujoco: Any, tool: Any) -> None:
    """The parallel-jaw gripper round the stem: a housing on a slide along the
    tool's axis (0: drawn up, :data:`JAW_SLIDE`: lowered so the fingertips
    reach :data:`FINGER_REACH` past the pad), and two fingers on slide joints
    across it (0: closed, :data:`JAW_STROKE`/2: open), rubber pads with
    torsional friction (a pad's patch resists the load turning about the grasp)."""
    housing = tool.add_body(name="jaws")
    housing.add_joint(
        name="jaw_slide",
        type=mujoco.mjtJoint.mjJNT_SLIDE,
        axis=[0, 0, 1],
        range=[0, JAW_SLIDE],
        damping=300.0,
        solref_limit=[0.004, 1.0],
    )
    housing.add_geom(
        name="housing",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[JAW_STROKE / 2 + 2 * FINGER_HALF[0], 0.015, 0.0075],
        pos=[0, 0, -0.0075],
        rgba=[0.3, 0.3, 0.35, 1],
        mass=0.4,
    )
    for side, sign in (("left", -1.0), ("right", 1.0)):
        finger = housing.add_body(name=f"finger_{side}", pos=[0, 0, FINGER_HALF[2]])
        finger.add_joint(
            name=f"finger_{side}",
            type=mujoco.mjtJoint.mjJNT_SLIDE,
            axis=[sign, 0, 0],
            range=[0, JAW_STROKE / 2],
            damping=400.0,  # closes at 0.1 m/s under the full grip force
        )
        finger.add_geom(
            name=f"finger_{side}",
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=list(FINGER_HALF),
            pos=[sign * FINGER_HALF[0], 0, 0],
            rgba=[0.2, 0.2, 0.22, 1],
            mass=0.05,
            friction=[FINGER_FRICTION, 0.01, 0.0001],
            condim=6,
            priority=1,
            solref=[0.004, 1.0],
            solimp=[0.99, 0.999, 0.0005, 0.5, 2.0],
        )


def add_tool_drives(mujoco: Any, world: Any) -> None:
    """The tool's drives in ``world`` (the arm attached by :func:`attach_arm`):
    the suction (an adhesion actuator on the cup, :data:`SUCTION_FORCE`), the
    jaws' slide (a stiff position servo) and one position servo per finger,
    force-limited to :data:`GRIP_FORCE`, the two fingers coupled; the tool's
    parts do not collide with each other or the wrist (the fingers close round
    the stem)."""
    suction = world.add_actuator(
        name="_suction", target="arm/cup", trntype=mujoco.mjtTrn.mjTRN_BODY
    )
    suction.set_to_adhesion(gain=SUCTION_FORCE)
    suction.ctrlrange = [0.0, 1.0]
    slide = world.add_actuator(
        name="_jaw_slide", target="arm/jaw_slide", trntype=mujoco.mjtTrn.mjTRN_JOINT
    )
    slide.set_to_position(kp=5000.0)
    slide.ctrlrange = [0.0, JAW_SLIDE]
    slide.forcerange = [-100.0, 100.0]
    slide.forcelimited = True
    for side in ("left", "right"):
        finger = world.add_actuator(
            name=f"_finger_{side}", target=f"arm/finger_{side}", trntype=mujoco.mjtTrn.mjTRN_JOINT
        )
        finger.set_to_position(kp=10000.0)
        finger.ctrlrange = [0.0, JAW_STROKE / 2]
        finger.forcerange = [-GRIP_FORCE, GRIP_FORCE]
        finger.forcelimited = True
    # one mechanism moves both fingers, as a real parallel gripper's rack or
    # linkage does: held between two independent force servos, a load would shake
    world.add_equality(
        type=mujoco.mjtEq.mjEQ_JOINT,
        name1="arm/finger_left",
        name2="arm/finger_right",
        data=[0, 1, 0, 0, 0] + [0] * 7,
        solref=[0.004, 1.0],
    )
    parts = [
        "arm/b_5",
        "arm/b_6",
        "arm/tool",
        "arm/cup",
        "arm/jaws",
        "arm/finger_left",
        "arm/finger_right",
    ]
    for k, first in enumerate(parts):
        for second in parts[k + 1 :]:
            world.add_exclude(bodyname1=first, bodyname2=second)


def attach_arm(
    mujoco: Any, world: Any, base: tuple[float, float, float], jaws: bool = True
) -> None:
    """The arm (prefix ``arm/``) at ``base`` = (x, y, yaw°) in ``world`` (with
    the jaws, or without: :func:`_arm_spec`)."""
    x, y, yaw = base
    half = math.radians(yaw) / 2
    frame = world.worldbody.add_frame(pos=[x, y, 0], quat=[math.cos(half), 0, 0, math.sin(half)])
    world.attach(_arm_spec(mujoco, jaws), prefix="arm/", frame=frame)


def arm_joints(mujoco: Any, model: Any) -> list[int]:
    """The qpos addresses of the arm's six joints in ``model`` (attached by
    :func:`attach_arm`)."""
    joint = mujoco.mjtObj.mjOBJ_JOINT
    return [
        int(model.jnt_qposadr[mujoco.mj_name2id(model, joint, f"arm/joint_{k}")])
        for k in range(1, 7)
    ]


def arm_bodies(mujoco: Any, model: Any) -> set[int]:
    """The ids of the arm's bodies in ``model``: its base and everything on it."""
    root = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "arm/b_base")
    bodies = set()
    for body in range(model.nbody):
        parent = body
        while parent > 0 and parent != root:
            parent = int(model.body_parentid[parent])
        if parent == root:
            bodies.add(body)
    return bodies


def _tool_rotation(yaw: float) -> np.ndarray:
    """The cup's frame pointing straight down, its x axis at ``yaw`` degrees."""
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    return np.array([[c, s, 0.0], [s, -c, 0.0], [0.0, 0.0, -1.0]])


class ArmKinematics:
    """Inverse kinematics of the cup (mink on a model of the arm alone)."""

    def __init__(self, mujoco: Any, base: tuple[float, float, float]):
        import mink

        self.mink = mink
        world = mujoco.MjSpec()
        attach_arm(mujoco, world, base, jaws=False)
        self.model = world.compile()
        self.configuration = mink.Configuration(self.model)
        self.task = mink.FrameTask("arm/tcp", "site", position_cost=1.0, orientation_cost=0.5)
        self.limits = [mink.ConfigurationLimit(self.model)]
        low = self.model.jnt_range[:, 0].copy()
        high = self.model.jnt_range[:, 1].copy()
        free = ~self.model.jnt_limited.astype(bool)
        low[free], high[free] = -math.pi, math.pi
        self.low, self.high = low, high

    def solve(
        self, position: np.ndarray, yaw: float, seed: np.ndarray, steps: int = 200
    ) -> np.ndarray | None:
        """Joint angles putting the cup at ``position`` pointing down at ``yaw``,
        starting from ``seed``; None when the solver does not get within 0.5 mm
        and 0.3° (out of reach, or a seed that leads nowhere)."""
        mink = self.mink
        self.configuration.update(np.array(seed, dtype=float))
        target = mink.SE3.from_rotation_and_translation(
            mink.SO3.from_matrix(_tool_rotation(yaw)), np.asarray(position, dtype=float)
        )
        self.task.set_target(target)
        for _ in range(steps):
            velocity = mink.solve_ik(
                self.configuration, [self.task], 0.05, "daqp", damping=1e-3, limits=self.limits
            )
            self.configuration.integrate_inplace(velocity, 0.05)
            error = self.task.compute_error(self.configuration)
            if np.linalg.norm(error[:3]) < 5e-4 and np.linalg.norm(error[3:]) < 5e-3:
                return np.array(self.configuration.q, dtype=float)
        return None

    def solve_anywhere(
        self, position: np.ndarray, yaw: float, seed: np.ndarray
    ) -> np.ndarray | None:
        """:meth:`solve` from ``seed``, then from a few fixed restarts."""
        found = self.solve(position, yaw, seed)
        rng = np.random.default_rng(0)
        for _ in range(6):
            if found is not None:
                return found
            found = self.solve(position, yaw, rng.uniform(self.low, self.high))
        return found


def arm_base(scene: Scene, workspace: Sequence[tuple[float, float]]) -> tuple[float, float, float]:
    """Where the arm stands, (x, y, yaw°): the scene's ``robot`` when it says,
    else the spot around the points to reach (the objects and ``workspace``)
    that leaves every point best inside the cup's reach (:data:`REACH`, at
    most 30 cm up) and no object on the base; ties go to the spot in front
    (−x), facing +x. The yaw faces the points' centre."""
    if scene.robot is not None:
        return scene.robot
    points = np.array(
        [o.pose.position[:2] for o in scene.objects] + [tuple(p[:2]) for p in workspace],
        dtype=float,
    )
    centre = (points.min(axis=0) + points.max(axis=0)) / 2
    best: tuple[float, tuple[float, float, float]] | None = None
    for standoff in (0.42, 0.35, 0.5, 0.3):
        for turn in range(0, 360, 15):
            angle = math.radians(180 + turn)
            base = centre + standoff * np.array([math.cos(angle), math.sin(angle)])
            distances = np.linalg.norm(points - base, axis=1)
            margin = float(min((distances - REACH[0]).min(), (REACH[1] - distances).min()))
            clear = all(
                math.dist(o.pose.position[:2], base) >= BASE_RADIUS + footprint(o.geometry)
                for o in scene.objects
                if o.geometry is not None
            )
            if clear and (best is None or margin > best[0] + 0.01):
                facing = math.degrees(math.atan2(*(centre - base)[::-1]))
                best = (margin, (float(base[0]), float(base[1]), facing))
    if best is None:
        x, y = centre
        return (float(x) - BASE_STANDOFF, float(y), 0.0)
    return best[1]


def check_base(scene: Scene, base: tuple[float, float, float]) -> None:
    """An input error for an object standing where the arm's base stands."""
    for obj in scene.objects:
        assert obj.geometry is not None
        reach = footprint(obj.geometry)
        distance = math.hypot(obj.pose.position[0] - base[0], obj.pose.position[1] - base[1])
        if distance < BASE_RADIUS + reach:
            raise InputError(
                f"stands inside the arm's base at ({base[0]:.3f}, {base[1]:.3f}) "
                f"({distance:.3f} m from its centre; at least "
                f"{BASE_RADIUS + reach:.3f} m expected)",
                source=scene.source,
                field=f"objects.{obj.name}.position",
            )


def footprint(shape: ObjectGeometry | None) -> float:
    """The radius of the circle round an object's footprint."""
    return 0.0 if shape is None else math.hypot(shape.size[0], shape.size[1]) / 2
