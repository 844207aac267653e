"""MuJoCo physics (``--sim mujoco``): the scene's objects as rigid bodies on a
table and a parallel-jaw gripper that really grasps, carries and releases.

The gripper is a hand welded to a mocap target (so it is a dynamic body with a
real velocity that friction can act on) with two finger pads on slide joints,
closed by position actuators: an object is held by the fingers' squeeze and
friction alone, so a poor grasp slips and a released stack has to stand by
itself. The hand moves along straight lines at ``SPEED`` (the mocap body is
stepped a little every physics step), rising to a travel height above every
object before it moves sideways. What the executor observes is read back from
the simulated bodies: resting point (bottom-face centre) and orientation of
every object standing on something, and which object, if any, is lifted
between the fingers.

Faults (:mod:`demoplan.execution.faults`) are injected physically where they
can be: ``drop`` opens the fingers low over a clear spot on the way, ``misplace``
releases 2–4 cm off target, ``grasp`` closes the hand beside the object,
``displace`` and ``block`` move an object (or a parked obstacle) as a person
would, by setting its pose.
"""

from __future__ import annotations

import logging
import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from demoplan.errors import InputError, UsageError
from demoplan.execution.faults import Faults, InjectedFault
from demoplan.execution.kinematic import OBSTACLE, KinematicWorld
from demoplan.execution.world import Observation
from demoplan.model import WOOD_DENSITY, ObjectGeometry, Pose
from demoplan.perception.camera import Camera
from demoplan.plotting.colours import NAMED, assign_colours, object_colour, rgba
from demoplan.scenes.geometry import half_extent
from demoplan.scenes.scene import Scene

__all__ = ["MujocoWorld", "scene_xml"]

logger = logging.getLogger(__name__)
os.environ.setdefault("MUJOCO_GL", "egl")  # headless rendering, before mujoco is imported

GL_SETTINGS = ("egl", "osmesa", "glx", "glfw", "disable")
"""The values of ``MUJOCO_GL`` MuJoCo takes on Linux (and their spellings
``enable``/``disabled``/``off``…, which it takes too)."""


def check_gl_setting() -> None:
    """A UsageError in one line where ``MUJOCO_GL`` holds what MuJoCo refuses (it
    raises at import, deep in its rendering module)."""
    value = os.environ.get("MUJOCO_GL", "").lower().strip()
    spellings = {"", "enable", "enabled", "on", "true", "1", "disabled", "off", "false", "0"}
    if value not in spellings | set(GL_SETTINGS):
        raise UsageError(
            f"MUJOCO_GL={value[:40]!r}: one of {', '.join(GL_SETTINGS)} expected "
            "(egl renders without a display)"
        )

TIMESTEP = 0.002  # s
SPEED = 0.4  # m/s of the hand
TURN_SPEED = 180.0  # deg/s
FINGER_HALF = (0.005, 0.012, 0.015)  # half extents of a finger pad (m)
FINGER_TRAVEL = 0.08  # how far each finger opens from the centre (m)
SQUEEZE = 0.006  # m: how far past the object's side the fingers are told to close
CLEARANCE = 0.01  # m: gap between an open finger and the object's side
OBSTACLES = 2
TOP_PX_PER_M = 1000.0  # the top camera: 1 px = 1 mm
PARK = (5.0, 5.0)  # where unused obstacles wait (off the table)
MIN_PHYSICS_EXTENT = 0.002  # m: smaller objects get no mass or inertia MuJoCo accepts
DENSITY = WOOD_DENSITY  # kg/m³ of the parked obstacles (an object has its own mass)
VIDEO_FPS = 20.0  # video frames per simulated second
VIDEO_SIZE = (480, 360)  # video width, height (px)
MIN_GRASP_HEIGHT = 0.013
"""m: the lowest object the finger pads lift (measured on a clear table: 12 mm
slips out, 13 mm and up are lifted and placed; the pads are 3 cm tall and
close at mid-height, so under that they touch the table first)."""
MAX_GRASP_WIDTH = 2 * (FINGER_TRAVEL - FINGER_HALF[0] - CLEARANCE)
"""m: the widest extent across the fingers that leaves them room to come down
beside the object (the fingers open 8 cm from the centre)."""


LANDMARK_RGBA = "0.85 0.79 0.66 1"
"""A landmark's colour in renders where its scene gives none: the figures'
sandy landmark colour."""


def _quat_wxyz(yaw_deg: float) -> list[float]:
    half = math.radians(yaw_deg) / 2
    return [math.cos(half), 0.0, 0.0, math.sin(half)]


def _geom(shape: ObjectGeometry) -> str:
    sx, sy, sz = shape.size
    if shape.shape == "box":
        return f'type="box" size="{sx / 2} {sy / 2} {sz / 2}"'
    if shape.shape == "sphere":
        return f'type="sphere" size="{max(sx, sy, sz) / 2}"'
    return f'type="cylinder" size="{max(sx, sy) / 2} {sz / 2}"'


def scene_xml(
    scene: Scene,
    top_view: tuple[float, float, float] | None = None,
    offscreen: tuple[int, int] = (1200, 1200),
    hand: bool = True,
) -> str:
    """The MJCF model of ``scene``: table, its landmarks that have a size (static
    bodies objects stand on), objects (free bodies), obstacles parked
    off the table, the floating gripper (``hand=False``: none, for a world that
    adds its own robot), and — with ``top_view = (x, y, height_m)`` — an
    orthographic camera ``top`` looking straight down at (x, y) whose picture is
    ``height_m`` metres high."""
    bodies = []
    assign_colours(scene.names, scene.given_colours)  # the figures' colours
    # Bodies get internal names (``_object3``): a scene's names can be anything.
    for index, obj in enumerate(scene.objects):
        assert obj.geometry is not None
        x, y, z = obj.pose.position
        half = obj.geometry.size[2] / 2
        w, qx, qy, qz = _wxyz(obj.pose)
        colour = rgba(rendered_colour(scene, obj.name))
        bodies.append(
            f'<body name="_object{index}" pos="{x} {y} {z + half}" quat="{w} {qx} {qy} {qz}">'
            f'<freejoint/><geom {_geom(obj.geometry)} mass="{obj.geometry.kg}" rgba="{colour}" '
            'friction="0.8 0.01 0.0005" condim="4"/></body>'
        )
    shapes = dict(scene.landmark_geometry)
    given = scene.given_colours
    for index, (name, pose) in enumerate(scene.landmarks):
        if name not in shapes:
            continue  # a landmark with no size is only a reference, nothing to stand on
        x, y, z = pose.position
        w, qx, qy, qz = _wxyz(pose)
        # Static (no joint): a tray things stand on, drawn in every render.
        colour = rgba(given[name]) if name in given else LANDMARK_RGBA
        bodies.append(
            f'<body name="_landmark{index}" pos="{x} {y} {z + shapes[name].size[2] / 2}" '
            f'quat="{w} {qx} {qy} {qz}"><geom {_geom(shapes[name])} '
            f'rgba="{colour}" friction="0.8 0.01 0.0005" condim="4"/></body>'
        )
    for k in range(OBSTACLES):
        s = OBSTACLE.size[0] / 2
        bodies.append(
            f'<body name="_obstacle{k + 1}" pos="{PARK[0] + k} {PARK[1]} {s}"><freejoint/>'
            f'<geom type="box" size="{s} {s} {s}" density="{DENSITY}" rgba="0.3 0.3 0.3 1" '
            'friction="0.8 0.01 0.0005" condim="4"/></body>'
        )
    camera = ""
    if top_view is not None:
        cx, cy, view_height = top_view
        camera = (
            f'<camera name="_top" pos="{cx} {cy} 1.5" quat="1 0 0 0" '
            f'projection="orthographic" fovy="{view_height}"/>'
        )
    header = f"""<mujoco model="demoplan">
  <option timestep="{TIMESTEP}" integrator="implicitfast" cone="elliptic" impratio="10"/>
  <visual>
    <global offwidth="{offscreen[0]}" offheight="{offscreen[1]}"/>
    <headlight ambient="0.35 0.35 0.35" diffuse="0.25 0.25 0.25" specular="0 0 0"/>
  </visual>
  <worldbody>
    <light pos="0.4 0.2 2" dir="0 0 -1" directional="true" castshadow="false"
           diffuse="0.45 0.45 0.45" specular="0 0 0"/>
    {camera}
    <geom name="table" type="plane" size="3 3 0.05" rgba="0.92 0.92 0.88 1"
          friction="0.8 0.01 0.0005"/>
    {"".join(bodies)}
"""
    if not hand:
        return header + "  </worldbody>\n</mujoco>\n"
    return header + _floating_hand()


def _floating_hand() -> str:
    """The floating parallel-jaw hand (a mocap weld) and its finger actuators,
    closing the MJCF document :func:`scene_xml` began."""
    fx, fy, fz = FINGER_HALF
    finger = (
        f'type="box" size="{fx} {fy} {fz}" mass="0.05" friction="1.5 0.02 0.001" condim="4" '
        'rgba="0.25 0.25 0.3 1"'
    )
    return f"""    <body name="_target" mocap="true" pos="0.3 0 0.4"/>
    <body name="_hand" pos="0.3 0 0.4" gravcomp="1">
      <freejoint/>
      <geom type="box" size="0.012 0.03 0.01" pos="0 0 {fz + 0.03}" contype="0" conaffinity="0"
            mass="0.5" rgba="0.4 0.4 0.45 0.5"/>
      <body name="_finger_left" gravcomp="1">
        <joint name="_left" type="slide" axis="1 0 0" range="-{FINGER_TRAVEL} 0" damping="20"/>
        <geom {finger}/>
      </body>
      <body name="_finger_right" gravcomp="1">
        <joint name="_right" type="slide" axis="1 0 0" range="0 {FINGER_TRAVEL}" damping="20"/>
        <geom {finger}/>
      </body>
    </body>
  </worldbody>
  <equality>
    <weld body1="_target" body2="_hand" solref="0.004 1"/>
  </equality>
  <contact>
    <exclude body1="_finger_left" body2="_finger_right"/>
  </contact>
  <actuator>
    <position name="_left" joint="_left" kp="800" ctrlrange="-{FINGER_TRAVEL} 0"
              forcerange="-8 8"/>
    <position name="_right" joint="_right" kp="800" ctrlrange="0 {FINGER_TRAVEL}"
              forcerange="-8 8"/>
  </actuator>
</mujoco>
"""


def _wxyz(pose: Pose) -> tuple[float, float, float, float]:
    if pose.orientation is None:
        return (1.0, 0.0, 0.0, 0.0)
    x, y, z, w = pose.orientation
    return (w, x, y, z)


def rendered_colour(scene: Scene, name: str) -> str:
    """An object's colour in renders (``#rrggbb``): the one its scene file gives
    (the colour a user chose in the studio); else its type's where that names
    a colour (``red`` and ``red2``, both of type ``red``, are both red — the top
    camera tells blocks apart by colour); else the figures' colour of its name."""
    given = scene.given_colours.get(name)
    if given is not None:
        return given
    kind = next((o.kind for o in scene.objects if o.name == name), name)
    return object_colour(kind if kind in NAMED else name)


class MujocoWorld:
    """The scene simulated by MuJoCo; see the module docstring."""

    name = "mujoco"
    video_speed = 1.0  # a video plays this many times faster than simulated time

    def __init__(
        self,
        scene: Scene,
        faults: Faults = Faults(),
        seed: int | None = 0,
        schedule: Mapping[int, str] | None = None,
    ):
        os.environ.setdefault("MUJOCO_GL", "egl")
        check_gl_setting()
        import mujoco

        self.mujoco = mujoco
        self.scene = scene
        # The kinematic world decides faults and finds clear spots (same rules, same seed).
        self.oracle = KinematicWorld(scene, faults, seed, schedule)
        (x0, y0), (x1, y1) = self.oracle.region
        self.top_camera = Camera(TOP_PX_PER_M, (x0, y0))
        self.top_size = (round((x1 - x0) * TOP_PX_PER_M), round((y1 - y0) * TOP_PX_PER_M))
        offscreen = (max(1200, self.top_size[0]), max(1200, self.top_size[1]))
        for obj in scene.objects:
            if obj.geometry is not None and min(obj.geometry.size) < MIN_PHYSICS_EXTENT:
                raise InputError(
                    f"extent {min(obj.geometry.size) * 1000:g} mm is below the "
                    f"{MIN_PHYSICS_EXTENT * 1000:g} mm the physics world simulates; "
                    "--sim kinematic takes it",
                    source=f"--sim {self.name}",
                    field=f"objects.{obj.name}.size",
                )
        try:
            self.model = self._compile(((x0 + x1) / 2, (y0 + y1) / 2, y1 - y0), offscreen)
        except ValueError as exc:  # MuJoCo's compiler refused the scene
            raise InputError(
                f"MuJoCo cannot build the scene ({str(exc).splitlines()[0]})",
                source=f"--sim {self.name}",
            ) from None
        self.data = mujoco.MjData(self.model)
        self._start_robot()
        self.geometry = {o.name: o.geometry for o in scene.objects if o.geometry is not None}
        self.names = [o.name for o in scene.objects]
        self.body_names = {name: f"_object{k}" for k, name in enumerate(self.names)}
        self.faults = faults
        self.held: str | None = None
        self.grip_offset = np.zeros(3)  # object centre relative to the hand when grasped
        self.grip_yaw = 0.0  # object yaw relative to the hand when grasped
        self.grip_axis = 0.0
        self.obstacles_used = 0
        self.simulated = 0.0
        self.left = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_ACTUATOR, "_left")
        self.right = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_ACTUATOR, "_right")
        self.hand_yaw = 0.0
        self.renderer: Any = None
        self.top_renderer: Any = None
        # A fixed camera over the workspace — the objects with room around them for
        # free space and targets — so that a video does not follow the objects.
        xs = [o.pose.position[0] for o in scene.objects]
        ys = [o.pose.position[1] for o in scene.objects]
        span = max(max(xs) - min(xs), max(ys) - min(ys)) + 0.3
        distance = 0.6 * span / math.tan(math.radians(22.5))  # MuJoCo's 45° field of view
        centre = [(min(xs) + max(xs)) / 2, (min(ys) + max(ys)) / 2, 0.02]
        self.overview = (centre, distance)
        self.overview_azimuth = 120.0  # deg: the direction the overview camera looks in
        self.targets: dict[str, Pose] = {}  # drawn in renders (show_targets)
        self.hidden_from_top: tuple[int, ...] = ()  # geom groups the top camera masks out
        self.video: Any = None  # a FrameEncoder while a video is recorded
        self.video_failed: str | None = None  # why ffmpeg stopped taking frames
        self.video_every = 0.0  # simulated seconds between video frames
        self.video_due = 0.0
        self._open()
        self._settle(0.5)

    def _compile(self, top_view: tuple[float, float, float], offscreen: tuple[int, int]) -> Any:
        """The MuJoCo model of the scene with this world's robot (here the floating hand)."""
        return self.mujoco.MjModel.from_xml_string(scene_xml(self.scene, top_view, offscreen))

    def _start_robot(self) -> None:
        """Put the robot in its starting pose before the scene settles (the hand
        starts where the model puts it)."""

    # -- reading the simulation ----------------------------------------------------------

    def _body(self, name: str) -> int:
        """The body id of an object (or of an internal body, ``_hand``…)."""
        internal = self.body_names.get(name, name)
        return int(self.mujoco.mj_name2id(self.model, self.mujoco.mjtObj.mjOBJ_BODY, internal))

    def _pose(self, name: str) -> Pose:
        body = self._body(name)
        centre = self.data.xpos[body]
        w, x, y, z = (float(v) for v in self.data.xquat[body])
        shape = self.geometry[name]
        # bottom-face centre: the centre minus the body's z axis times half the height
        axis = np.array([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)])
        bottom = centre - axis * shape.size[2] / 2
        return Pose((float(bottom[0]), float(bottom[1]), float(bottom[2])), (x, y, z, w))

    def _active(self) -> list[str]:
        return self.names + self.oracle.injected_objects[: self.obstacles_used]

    def observe(self) -> Observation:
        poses = {name: self._pose(name) for name in self._active() if name != self.held}
        if self.held is not None and not self._lifted(self.held):
            self.held = None
            poses = {name: self._pose(name) for name in self._active()}
        geometry = dict(self.geometry)
        return Observation(poses, self.held, geometry)

    def _hand(self) -> np.ndarray:
        """Where the hand is commanded to be (the mocap target)."""
        return np.array(self.data.mocap_pos[0])

    def _hand_body(self) -> np.ndarray:
        """Where the hand really is."""
        return np.array(self.data.xpos[self._body("_hand")])

    def _lifted(self, name: str) -> bool:
        """Between the fingers and off whatever it stood on."""
        centre = self.data.xpos[self._body(name)]
        hand = self._hand_body()
        return bool(
            np.linalg.norm(centre[:2] - hand[:2]) < 0.03
            and centre[2] > 0.005 + self.geometry[name].size[2] / 2
            and abs(centre[2] - hand[2]) < 0.04
        )

    # -- moving ------------------------------------------------------------------------

    def _step(self, seconds: float) -> None:
        steps = max(1, round(seconds / TIMESTEP))
        for _ in range(steps):
            self.mujoco.mj_step(self.model, self.data)
            self._tick()

    def _tick(self) -> None:
        """One physics step done: the clock, and a video frame when one is due."""
        self.simulated += TIMESTEP
        if self.video is not None and self.simulated >= self.video_due:
            self.video_due += self.video_every
            image = self.render(*VIDEO_SIZE)
            if image is not None:
                try:
                    self.video.send(image)
                except OSError as exc:  # ffmpeg is gone (a full disk): the run goes on
                    gone, self.video = self.video, None
                    gone.kill()
                    self.video_failed = _ffmpeg_problem(exc)

    def _settle(self, seconds: float = 0.3) -> None:
        self._step(seconds)

    def _set_hand_yaw(self, yaw: float) -> None:
        self.hand_yaw = yaw
        self.data.mocap_quat[0] = _quat_wxyz(yaw)

    def _move(self, target: Sequence[float] | np.ndarray, yaw: float | None = None) -> None:
        start = self._hand()
        goal = np.asarray(target, dtype=float)
        distance = float(np.linalg.norm(goal - start))
        turn = 0.0 if yaw is None else ((yaw - self.hand_yaw + 180.0) % 360.0) - 180.0
        duration = max(1.5 * distance / SPEED, abs(turn) / TURN_SPEED, TIMESTEP)
        steps = math.ceil(duration / TIMESTEP)
        first_yaw = self.hand_yaw
        for k in range(1, steps + 1):
            t = k / steps
            t = t * t * (3.0 - 2.0 * t)  # smooth start and stop: no jerk that shakes a grasp loose
            self.data.mocap_pos[0] = start + t * (goal - start)
            if yaw is not None:
                self._set_hand_yaw(first_yaw + t * turn)
            self.mujoco.mj_step(self.model, self.data)
            self._tick()

    def _fingers(self, half_width: float) -> None:
        width = min(max(half_width, 0.0), FINGER_TRAVEL)
        self.data.ctrl[self.left] = -width
        self.data.ctrl[self.right] = width

    def _open(self) -> None:
        self._fingers(FINGER_TRAVEL)

    def _release(self) -> None:
        """Open the fingers a little (not wide: the neighbours are close) and let go."""
        assert self.held is not None
        self._fingers(
            half_extent(self.geometry[self.held], self.grip_axis) + FINGER_HALF[0] + CLEARANCE
        )
        self._settle(0.4)
        self.held = None

    def _travel_height(self) -> float:
        tops = [
            self._pose(n).position[2] + self.geometry[n].size[2]
            for n in self._active()
            if n != self.held
        ]
        carried = self.geometry[self.held].size[2] if self.held else 0.0
        return max(tops, default=0.0) + carried + FINGER_HALF[2] + 0.05

    # -- the World protocol ------------------------------------------------------------

    def grasp(self, obj: str, axis: float, where: Pose | None = None) -> None:
        self.oracle.actions += 1
        if self.held is not None or obj not in self._active():
            return
        pose = where if where is not None else self._pose(obj)  # where it is believed to be
        shape = self.geometry[obj]
        yaw = pose.yaw + axis
        half = half_extent(shape, axis)
        centre = np.array(
            [pose.position[0], pose.position[1], pose.position[2] + shape.size[2] / 2]
        )
        grip_z = pose.position[2] + min(shape.size[2] / 2, FINGER_HALF[2] + 0.004)
        missed = self.oracle._chance(self.faults.grasp, "grasp")
        if missed:
            self.oracle.record_fault("grasp", obj, None, f"the grasp of {obj} missed")
            # The hand comes down 3 cm beside the object and closes on air.
            angle = math.radians(yaw + 90.0)
            offset = np.array([0.03 * math.cos(angle), 0.03 * math.sin(angle), 0.0])
        else:
            offset = np.zeros(3)
        travel = self._travel_height()
        # Open just wide enough: the planner's collision facts assume the fingers
        # stand no farther out than half the object + a finger radius (§V.B).
        self._fingers(half + FINGER_HALF[0] + CLEARANCE)
        self._move([*self._hand()[:2], travel])
        self._move([centre[0] + offset[0], centre[1] + offset[1], travel], yaw)
        self._move([centre[0] + offset[0], centre[1] + offset[1], grip_z + offset[2]])
        self._fingers(half + FINGER_HALF[0] - SQUEEZE)
        self._settle(0.4)
        self.held = obj
        self._move([centre[0] + offset[0], centre[1] + offset[1], travel])
        self._settle(0.2)
        if not self._lifted(obj):
            self.held = None
            self._fingers(half + FINGER_HALF[0] + CLEARANCE)
            self._settle(0.3)
            return
        body = self._body(obj)
        self.grip_axis = axis
        self.grip_offset = np.array(self.data.xpos[body]) - self._hand_body()
        self.grip_yaw = self._pose(obj).yaw - self.hand_yaw

    def put_down(self, obj: str, pose: Pose) -> None:
        self.oracle.actions += 1
        if self.held != obj:
            return
        shape = self.geometry[obj]
        target_yaw = pose.yaw - self.grip_yaw
        x, y, z = pose.position
        self._sync_oracle()
        travel = self._travel_height()
        hand = self._hand()
        if self.oracle._chance(self.faults.drop, "drop"):
            t = float(self.oracle.rng.uniform(0.2, 0.8))
            spot = self.oracle._land(obj, hand[0] + t * (x - hand[0]), hand[1] + t * (y - hand[1]))
            self._release_over(spot, travel, "drop", f"{obj} fell at {_xy(spot)} while carried")
            return
        if self.oracle._chance(self.faults.misplace, "misplace"):
            off = self.oracle.misplaced_spot(obj, pose)
            if off is not None:
                self._release_over(
                    off, travel, "misplace", f"{obj} released at {_xy(off)}, off its target"
                )
                return
        centre_z = z + shape.size[2] / 2 + 0.002
        goal = np.array([x, y, centre_z]) - self._rotated_offset(target_yaw)
        self._move([*hand[:2], travel])
        self._move([goal[0], goal[1], travel], target_yaw)
        self._move(goal)
        self._release()
        self._move([goal[0], goal[1], travel])
        self._settle(0.3)

    def between_actions(self, upcoming: Sequence[Pose] = ()) -> None:
        if self.held is not None:
            return
        self._sync_oracle()
        before = dict(self.oracle.poses)
        self.oracle.between_actions(upcoming)
        for name, pose in self.oracle.poses.items():
            if name in self.oracle.injected_objects and name not in before:
                if self.obstacles_used == OBSTACLES:
                    continue  # no parked body left for it
                self.obstacles_used += 1
                self.body_names[name] = f"_obstacle{self.obstacles_used}"
                self._teleport(name, pose)
            elif name in before and pose != before[name]:
                self._teleport(name, pose)
        self._settle(0.3)

    def render(self, width: int = 480, height: int = 360) -> np.ndarray | None:
        """An oblique view of the whole workspace (RGB, ``height × width × 3``)
        from a fixed camera (:attr:`overview`), like the paper's photographs of
        Fig. 4; None where no OpenGL context can be made
        (MuJoCo imported before ``MUJOCO_GL`` was set, no EGL): frames then fall
        back to drawings from above."""
        if self.renderer is False:
            return None
        if self.renderer is None:
            try:
                self.renderer = self.mujoco.Renderer(self.model, height, width)
            except Exception as exc:  # the GL back end's own errors vary
                logger.warning("MuJoCo cannot render here (%s); frames are drawn instead", exc)
                self.renderer = False
                return None
        camera = self.mujoco.MjvCamera()
        camera.lookat[:], camera.distance = self.overview
        camera.elevation = -40.0
        camera.azimuth = self.overview_azimuth
        self.renderer.update_scene(self.data, camera=camera)
        self._draw_targets(self.renderer.scene)
        image: np.ndarray = self.renderer.render()
        return image

    def show_targets(self, targets: Mapping[str, Pose]) -> None:
        """Draw these target poses (goal object → pose) in every render from now
        on, as translucent boxes of the objects' sizes in their colours: a frame
        then shows where each object should go (nothing collides with them)."""
        self.targets = dict(targets)

    def _draw_targets(self, scene: Any) -> None:
        mujoco = self.mujoco
        for name, pose in self.targets.items():
            shape = self.geometry.get(name)
            if shape is None or scene.ngeom >= scene.maxgeom:
                continue
            colour = rgba(rendered_colour(self.scene, name))
            red, green, blue, _ = (float(v) for v in colour.split())
            x, y, z = pose.position
            half = np.array(shape.size, dtype=float) / 2
            matrix = np.zeros(9)
            w, qx, qy, qz = _wxyz(pose)
            mujoco.mju_quat2Mat(matrix, np.array([w, qx, qy, qz], dtype=float))
            kind = (
                mujoco.mjtGeom.mjGEOM_CYLINDER
                if shape.shape == "cylinder"
                else mujoco.mjtGeom.mjGEOM_BOX
            )
            size = np.array([half[0], half[2], 0.0]) if shape.shape == "cylinder" else half
            mujoco.mjv_initGeom(
                scene.geoms[scene.ngeom],
                kind,
                size,
                np.array([x, y, z + half[2]], dtype=float),
                matrix,
                np.array([red, green, blue, 0.3], dtype=np.float32),
            )
            scene.ngeom += 1

    def top_image(self) -> np.ndarray:
        """The table from straight above through the orthographic camera ``top``
        (1 px = 1 mm, bottom-left corner at ``self.top_camera.origin``), with the
        hand parked beside the table first so that it hides nothing."""
        self.park()
        if self.top_renderer is None:
            width, height = self.top_size
            self.top_renderer = self.mujoco.Renderer(self.model, height, width)
        hidden = self.mujoco.MjvOption()
        for group in self.hidden_from_top:
            hidden.geomgroup[group] = 0
        self.top_renderer.update_scene(self.data, camera="_top", scene_option=hidden)
        image: np.ndarray = self.top_renderer.render()
        return image

    def park(self) -> None:
        """Move the hand (and what it holds) beside the table, out of the top view."""
        (_, y0), (x1, y1) = self.oracle.region
        travel = self._travel_height()
        hand = self._hand()
        home = [x1 + 0.12, (y0 + y1) / 2, travel]
        if math.dist(hand, home) < 1e-6:
            return
        self._move([*hand[:2], travel])
        self._move(home)
        self._settle(0.1)

    def record_video(self, path: Path, fps: float = VIDEO_FPS) -> None:
        """From now on, write what the overview camera sees to ``path`` (MP4 at
        ``fps`` frames per second, :attr:`video_speed` times faster than
        simulated time) until :meth:`close`."""
        from demoplan.execution.encoder import FrameEncoder

        self.video = FrameEncoder(path, VIDEO_SIZE, fps)
        self.video_every = self.video_speed / fps
        self.video_due = self.simulated

    def close(self) -> None:
        """Finish a video being recorded, and free the renderers' GL contexts;
        OSError if ffmpeg stopped taking frames on the way or did not finish the
        file (its exit status: :class:`~demoplan.execution.encoder.FrameEncoder`)."""
        try:
            if self.video is not None:
                video, self.video = self.video, None
                video.close()
        finally:
            for renderer in (self.renderer, self.top_renderer):
                if renderer:
                    renderer.close()
            self.renderer = self.top_renderer = None
        if self.video_failed is not None:
            failed, self.video_failed = self.video_failed, None
            raise OSError(failed)

    # -- helpers -------------------------------------------------------------------------

    def _rotated_offset(self, hand_yaw: float) -> np.ndarray:
        """The grasped object's centre offset from the hand, turned with the hand."""
        turn = math.radians(hand_yaw - self.hand_yaw)
        c, s = math.cos(turn), math.sin(turn)
        ox, oy, oz = self.grip_offset
        return np.array([c * ox - s * oy, s * ox + c * oy, oz])

    def _release_over(self, spot: Pose, travel: float, kind: str, detail: str) -> None:
        """Carry the held object low over ``spot`` and let go (a drop or a misplacement)."""
        assert self.held is not None
        obj = self.held
        shape = self.geometry[obj]
        hand = self._hand()
        yaw = spot.yaw - self.grip_yaw
        above = np.array(
            [spot.position[0], spot.position[1], spot.position[2] + shape.size[2] / 2 + 0.012]
        )
        goal = above - self._rotated_offset(yaw)
        self._move([*hand[:2], travel])
        self._move([goal[0], goal[1], travel], yaw)
        self._move(goal)
        self._release()
        self._move([goal[0], goal[1], travel])
        self._settle(0.3)
        self.oracle.record_fault(kind, obj, spot, detail)

    def why_not_graspable(self, obj: str) -> str | None:
        """Why this gripper cannot take ``obj`` (too thin or too wide for every
        grasp it allows), or None."""
        shape = self.geometry[obj]
        if shape.size[2] < MIN_GRASP_HEIGHT:
            return (
                f"is {1000 * shape.size[2]:.0f} mm tall; the simulated gripper's pads lift "
                f"objects from {1000 * MIN_GRASP_HEIGHT:.0f} mm"
            )
        axes = next((o.grasps for o in self.scene.objects if o.name == obj), (0.0, 90.0))
        if all(2 * half_extent(shape, axis) > MAX_GRASP_WIDTH for axis in axes):
            return (
                f"is {100 * min(2 * half_extent(shape, a) for a in axes):.0f} cm across every "
                f"grasp it allows; the simulated gripper opens to {100 * MAX_GRASP_WIDTH:.0f} cm"
            )
        return None

    @property
    def injected(self) -> list[InjectedFault]:
        """The faults injected so far, as they happened."""
        return self.oracle.injected

    def _sync_oracle(self) -> None:
        self.oracle.poses = {n: self._pose(n) for n in self._active() if n != self.held}
        for name in self.oracle.injected_objects[: self.obstacles_used]:
            self.oracle.geometry[name] = OBSTACLE
        self.oracle.held = self.held

    def _teleport(self, name: str, pose: Pose) -> None:
        body = self._body(name)
        joint = self.model.body_jntadr[body]
        address = self.model.jnt_qposadr[joint]
        velocity = self.model.jnt_dofadr[joint]
        half = (self.geometry.get(name) or OBSTACLE).size[2] / 2
        x, y, z = pose.position
        self.data.qpos[address : address + 3] = [x, y, z + half + 0.001]
        self.data.qpos[address + 3 : address + 7] = _wxyz(pose)
        self.data.qvel[velocity : velocity + 6] = 0.0
        self.mujoco.mj_forward(self.model, self.data)
        if name in self.oracle.injected_objects:
            self.geometry[name] = OBSTACLE


def _xy(pose: Pose) -> str:
    return f"({pose.position[0]:.3f}, {pose.position[1]:.3f})"


def _ffmpeg_problem(exc: OSError) -> str:
    """Why ffmpeg took no more frames, in words: imageio-ffmpeg's message
    starts with the pipe's error and goes on with ffmpeg's command line."""
    first = (str(exc).strip().splitlines() or [""])[0]
    if "Broken pipe" in first or isinstance(exc, BrokenPipeError):
        return "ffmpeg stopped taking frames"
    return first or "ffmpeg stopped taking frames"
