"""An exact, deterministic world (``--sim kinematic``), with faults injected on demand.

Objects are where the last action put them, to the micrometre; a grasp lifts
the object, a put-down releases it at the commanded pose. Faults
(:mod:`demoplan.execution.faults`) are drawn from a seeded generator, so a run
with the same seed is the same run.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence

import numpy as np

from demoplan.execution.faults import Faults, InjectedFault
from demoplan.execution.world import Observation
from demoplan.model import LEVEL_TOLERANCE, SUPPORT_FRACTION, ObjectGeometry, Pose, footprint
from demoplan.rotations import quat_from_yaw
from demoplan.scenes.geometry import bounding_radius, finger_offset
from demoplan.scenes.scene import Scene

__all__ = ["OBSTACLE", "KinematicWorld"]

OBSTACLE = ObjectGeometry("box", (0.04, 0.04, 0.04))
"""The object a ``block`` fault puts on a target."""
MISPLACE_NEAR, MISPLACE_FAR = 0.015, 0.05
"""How far (m) from its target a ``misplace`` fault releases an object."""
MAX_BLOCKS = 2
DISPLACEMENT = 0.05  # m: a person moves an object at least this far


class KinematicWorld:
    """The scene's objects as exact poses; see the module docstring."""

    name = "kinematic"

    def __init__(
        self,
        scene: Scene,
        faults: Faults = Faults(),
        seed: int | None = 0,
        schedule: Mapping[int, str] | None = None,
    ):
        self.poses: dict[str, Pose] = {obj.name: obj.pose for obj in scene.objects}
        self.geometry: dict[str, ObjectGeometry] = {}
        for obj in scene.objects:
            if obj.geometry is None:
                raise ValueError(f"{obj.name}: geometry unknown (complete the scene first)")
            self.geometry[obj.name] = obj.geometry
        self.gripper = scene.gripper
        shapes = dict(scene.landmark_geometry)
        self.platforms = [  # landmarks with a size: what falls on one lands on its top
            (
                footprint(shapes[name], pose.position, pose.yaw),
                pose.position[2] + shapes[name].size[2],
            )
            for name, pose in scene.landmarks
            if name in shapes
        ]
        self.faults = faults
        self.rng = np.random.default_rng(seed)
        self.held: str | None = None
        self.picked_from: Pose | None = None
        self.injected: list[InjectedFault] = []  # as they happened, for reports and tests
        self.blocks = 0
        self.injected_objects: list[str] = []  # obstacles a block fault put in, in order
        # Where a fault may put things: a world with a robot that reaches only
        # part of the table says which (x, y) it reaches; None: anywhere.
        self.reachable: Callable[[float, float], bool] | None = None
        # Faults at given actions (1-based count of grasps and put-downs): a test
        # injects exactly one kind exactly where it wants it.
        self.schedule = dict(schedule or {})
        self.actions = 0
        if scene.table is not None:
            self.region = scene.table
        else:
            xs = [p.position[0] for p in self.poses.values()]
            ys = [p.position[1] for p in self.poses.values()]
            self.region = ((min(xs) - 0.25, min(ys) - 0.25), (max(xs) + 0.25, max(ys) + 0.25))

    # -- the World protocol -------------------------------------------------------------

    def observe(self) -> Observation:
        return Observation(dict(self.poses), self.held, dict(self.geometry))

    def grasp(self, obj: str, axis: float, where: Pose | None = None) -> None:
        self.actions += 1
        if self.held is not None or obj not in self.poses or self._on_top_of(obj):
            return  # nothing to grasp, or something stands on it: the hand closes on air
        if self._chance(self.faults.grasp, "grasp"):
            self.record_fault("grasp", obj, None, f"the grasp of {obj} missed")
            return
        self.picked_from = self.poses.pop(obj)
        self.held = obj

    def put_down(self, obj: str, pose: Pose) -> None:
        self.actions += 1
        if self.held != obj:
            return
        start = self.picked_from or pose
        if self._chance(self.faults.drop, "drop"):
            t = float(self.rng.uniform(0.2, 0.8))
            point = [a + t * (b - a) for a, b in zip(start.position, pose.position, strict=True)]
            landed = self._land(obj, point[0], point[1])
            self.record_fault("drop", obj, landed, f"{obj} fell at {_xy(landed)} while carried")
        elif self._chance(self.faults.misplace, "misplace") and (
            spot := self.misplaced_spot(obj, pose)
        ):
            self.poses[obj] = spot
            self.record_fault(
                "misplace", obj, spot, f"{obj} released at {_xy(spot)}, off its target"
            )
        else:
            self.poses[obj] = pose
        self.held = None
        self.picked_from = None

    def between_actions(self, upcoming: Sequence[Pose] = ()) -> None:
        if self.held is None and self._chance(self.faults.displace, "displace"):
            movable = sorted(
                o for o in self.poses if not self._on_top_of(o) and o not in self.injected_objects
            )
            if movable:
                obj = movable[int(self.rng.integers(len(movable)))]
                before = self.poses.pop(obj)
                (x0, y0), (x1, y1) = self.region
                landed = self._land(
                    obj,
                    float(self.rng.uniform(x0, x1)),
                    float(self.rng.uniform(y0, y1)),
                    before.yaw,
                )
                if math.dist(landed.position, before.position) < DISPLACEMENT:
                    self.poses[obj] = before  # no clear spot away from it: no fault
                else:
                    self.record_fault(
                        "displace", obj, landed, f"a person moved {obj} to {_xy(landed)}"
                    )
        if (
            self.held is None
            and upcoming
            and self.blocks < MAX_BLOCKS
            and self._chance(self.faults.block, "block")
        ):
            # The next target an obstacle can stand on: on the table and free (a
            # target on a stack waits for what will hold it up).
            free = [
                t
                for t in upcoming
                if t.position[2] < 0.005
                and self._clear(t.position[0], t.position[1], OBSTACLE, 0.002, reach=False)
            ]
            if free:
                target = free[0]
                self.blocks += 1
                name = f"obstacle{self.blocks}"
                while name in self.geometry:  # a scene object may have that name
                    name = f"{name}_"
                self.geometry[name] = OBSTACLE
                self.injected_objects.append(name)
                self.poses[name] = Pose(
                    (target.position[0], target.position[1], 0.0), quat_from_yaw(0.0)
                )
                placed = self.poses[name]
                self.record_fault("block", name, placed, f"{name} appeared at {_xy(placed)}")

    # -- faults ---------------------------------------------------------------------------

    def record_fault(self, kind: str, obj: str, where: Pose | None, detail: str) -> None:
        """Note an injected fault at the current action."""
        position = None
        if where is not None:
            x, y, z = where.position
            position = (float(x), float(y), float(z))
        self.injected.append(InjectedFault(kind, self.actions, obj, position, detail))

    def misplaced_spot(self, obj: str, target: Pose) -> Pose | None:
        """A clear spot on the table 1.5–5 cm from ``target`` (a misplacement the
        executor sees as *misplaced*), or None when there is none; the search
        starts at a random direction."""
        shape = self.geometry[obj]
        start = float(self.rng.uniform(0, 2 * math.pi))
        x, y = target.position[0], target.position[1]
        (x0, y0), (x1, y1) = self.region
        for distance in np.arange(MISPLACE_NEAR, MISPLACE_FAR + 1e-9, 0.005):
            for k in range(24):
                angle = start + 2 * math.pi * k / 24
                px, py = x + distance * math.cos(angle), y + distance * math.sin(angle)
                if x0 <= px <= x1 and y0 <= py <= y1 and self._clear(px, py, shape, 0.002):
                    yaw = target.yaw + float(self.rng.uniform(-10, 10))
                    z = self._ground(px, py, shape, yaw)
                    if z is not None:
                        return Pose((px, py, z), quat_from_yaw(yaw))
        return None

    # -- helpers --------------------------------------------------------------------------

    def _chance(self, probability: float, kind: str = "") -> bool:
        if kind and self.schedule.get(self.actions) == kind:
            del self.schedule[self.actions]
            return True
        return probability > 0 and float(self.rng.random()) < probability

    def _on_top_of(self, obj: str) -> list[str]:
        """The objects standing on ``obj``: at the level of its top, their outline
        over at least :data:`~demoplan.model.SUPPORT_FRACTION` of theirs on its
        outline (the support rule of docs/scenes.md, as the planner has it)."""
        pose, shape = self.poses[obj], self.geometry[obj]
        top = pose.position[2] + shape.size[2]
        below = footprint(shape, pose.position, pose.yaw)
        standing = []
        for other, p in self.poses.items():
            if other == obj or abs(p.position[2] - top) >= LEVEL_TOLERANCE:
                continue
            if p.position[2] <= pose.position[2] + shape.size[2] / 2:
                continue
            upper = footprint(self.geometry[other], p.position, p.yaw)
            if upper.intersection(below).area >= SUPPORT_FRACTION * upper.area:
                standing.append(other)
        return standing

    def _reach(self, shape: ObjectGeometry) -> float:
        """How far from its centre grasping ``shape`` needs room (fingers included)."""
        fingers = max(finger_offset(shape, axis, self.gripper) for axis in (0.0, 90.0))
        return max(bounding_radius(shape), fingers + self.gripper.finger_radius)

    def _clear(
        self, x: float, y: float, shape: ObjectGeometry, margin: float, reach: bool = True
    ) -> bool:
        """No object within reach of (x, y): none in the way of grasping ``shape``
        there, nor of grasping the others (``reach=False``: just not overlapping);
        and the robot reaches the spot (:attr:`reachable`)."""
        if self.reachable is not None and not self.reachable(x, y):
            return False
        for other, pose in self.poses.items():
            other_shape = self.geometry[other]
            needed = bounding_radius(shape) + bounding_radius(other_shape)
            if reach:
                needed = max(
                    self._reach(shape) + bounding_radius(other_shape),
                    self._reach(other_shape) + bounding_radius(shape),
                )
            if math.dist((x, y), pose.position[:2]) < needed + margin:
                return False
        return True

    def _ground(self, x: float, y: float, shape: ObjectGeometry, yaw: float) -> float | None:
        """Where ``shape`` standing at (x, y) turned ``yaw`` rests: the top of
        the landmark (a tray, a box) under all of it, else the table (0); None
        where it would lie across a landmark's edge."""
        outline = footprint(shape, (x, y), yaw)
        height = 0.0
        for platform, top in self.platforms:
            covered = outline.intersection(platform).area
            if covered >= outline.area * (1.0 - 1e-6):
                height = max(height, top)
            elif covered > 0.0:
                return None
        return height

    def _land(self, obj: str, x: float, y: float, yaw: float | None = None) -> Pose:
        """Put ``obj`` at the clear spot nearest (x, y), on the table or on the
        top of a landmark under it (:meth:`_ground`), turned by up to 10° from
        ``yaw`` (default: as it was when picked up)."""
        shape = self.geometry[obj]
        if yaw is None:
            yaw = self.picked_from.yaw if self.picked_from is not None else 0.0
        yaw += float(self.rng.uniform(-10, 10))
        (x0, y0), (x1, y1) = self.region
        best = None
        for radius in np.arange(0.0, 0.6, 0.005):
            count = max(1, int(2 * math.pi * radius / 0.005))
            for k in range(count):
                angle = 2 * math.pi * k / count
                px, py = x + radius * math.cos(angle), y + radius * math.sin(angle)
                if x0 <= px <= x1 and y0 <= py <= y1 and self._clear(px, py, shape, 0.002):
                    z = self._ground(px, py, shape, yaw)
                    if z is not None:
                        best = (px, py, z)
                        break
            if best is not None:
                break
        if best is None:  # a full table: leave it where it is asked to be
            best = (x, y, self._ground(x, y, shape, yaw) or 0.0)
        pose = Pose(best, quat_from_yaw(yaw))
        self.poses[obj] = pose
        return pose


def _xy(pose: Pose) -> str:
    return f"({pose.position[0]:.3f}, {pose.position[1]:.3f})"
