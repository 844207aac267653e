"""Cluttered household layouts for the arm, and what the arm does with them:
its check before it moves (the run's pre-check) against its first attempt
to carry each object (shared by tests/execution/test_arm_layouts.py and
benchmarks/arm_grasps.py).

A layout is a few household objects — boxes, cylinders and spheres 3–12 cm,
0.05–1 kg — standing at random, each with a random place to be put, in front
of an arm standing at the origin and facing +x: 18–65 cm from its base, so
that some stand or go beyond its reach. Objects and places keep at least
:data:`GAP` between their outlines: the room a planner's gripper needs beside
an object (the planner refuses grasps that have less)."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Literal

import numpy as np

from demoplan.documents.masses import MAX_DENSITY
from demoplan.model import ObjectGeometry, Pose
from demoplan.rotations import quat_from_yaw
from demoplan.scenes.scene import Scene, SceneObject

GAP = 0.05
"""m between the outlines (circles round them) of any two objects or places."""
SIZES = (0.03, 0.12)  # m: each extent
MASSES = (0.05, 1.0)  # kg, log-uniform
DISTANCES = (0.18, 0.65)  # m from the arm's base
ANGLES = (-70.0, 70.0)  # deg either side of the arm's front
BASE_CLEARANCE = 0.08  # m: no object within this of the base's centre (plus its own radius)


@dataclass(frozen=True, slots=True)
class Item:
    """An object of a layout: its name, shape, where it stands and where it
    goes, and the grasp (finger axis, deg) a plan takes it by: either of the
    scene's default two, as a planner, which knows nothing of the jaws'
    stroke, may choose."""

    name: str
    geometry: ObjectGeometry
    start: Pose
    place: Pose
    grasp: float


def _shape(rng: np.random.Generator) -> ObjectGeometry:
    kind = str(rng.choice(["box", "cylinder", "sphere"]))
    while True:
        if kind == "box":
            size = tuple(float(v) for v in rng.uniform(*SIZES, 3))
        elif kind == "cylinder":
            diameter, height = (float(v) for v in rng.uniform(*SIZES, 2))
            size = (diameter, diameter, height)
        else:
            diameter = float(rng.uniform(*SIZES))
            size = (diameter, diameter, diameter)
        mass = math.exp(rng.uniform(math.log(MASSES[0]), math.log(MASSES[1])))
        shape = ObjectGeometry(kind, (size[0], size[1], size[2]), mass)
        if mass / shape.volume <= MAX_DENSITY:  # no solid is denser than osmium
            return shape


def _radius(shape: ObjectGeometry) -> float:
    return math.hypot(shape.size[0], shape.size[1]) / 2


def layout(seed: int, objects: int = 3) -> tuple[Item, ...]:
    """A layout of ``objects`` household objects drawn from ``seed`` (module docstring)."""
    rng = np.random.default_rng(seed)
    taken: list[tuple[float, float, float]] = []  # x, y, radius of every object and place

    def spot(radius: float) -> Pose:
        while True:
            distance = float(rng.uniform(*DISTANCES))
            angle = math.radians(float(rng.uniform(*ANGLES)))
            x, y = distance * math.cos(angle), distance * math.sin(angle)
            if distance < BASE_CLEARANCE + radius:
                continue
            if all(math.hypot(x - ox, y - oy) >= radius + r + GAP for ox, oy, r in taken):
                taken.append((x, y, radius))
                return Pose((x, y, 0.0), quat_from_yaw(float(rng.uniform(-90.0, 90.0))))

    items = []
    for index in range(objects):
        shape = _shape(rng)
        start = spot(_radius(shape))
        place = spot(_radius(shape))
        grasp = float(rng.choice([0.0, 90.0]))
        items.append(Item(f"{shape.shape}{index}", shape, start, place, grasp))
    return tuple(items)


def scene_of(items: tuple[Item, ...]) -> Scene:
    """The layout as a scene, the arm at the origin facing +x."""
    return Scene(
        objects=tuple(SceneObject(i.name, i.start, i.geometry) for i in items),
        robot=(0.0, 0.0, 0.0),
    )


Outcome = Literal["refused", "carried", "not grasped", "not placed"]


@dataclass(frozen=True, slots=True)
class Attempt:
    """One object of a layout: the pre-check's answer (``refused``: why) and,
    where it accepted, the first attempt's outcome; the arm's simulated time
    while the check ran (none: it did not move) and the wall time of the carry."""

    item: Item
    outcome: Outcome
    refused: str | None
    moved_while_checking: float
    seconds: float


def attempt_all(items: tuple[Item, ...]) -> list[Attempt]:
    """For each object of the layout in turn: the arm's pre-check (as a run's:
    :func:`demoplan.execution.executor._check_feasible` asks the world what it
    can grasp and reach), and where it accepts, the first grasp and put-down."""
    from demoplan.execution.arm import ArmWorld

    world = ArmWorld(scene_of(items))
    attempts = []
    try:
        for item in items:
            before = world.simulated
            why = (
                world.why_not_graspable(item.name)
                or world.why_not_reachable(item.name, item.start)
                or world.why_not_reachable(item.name, item.place)
            )
            moved = world.simulated - before
            if why is not None:
                attempts.append(Attempt(item, "refused", why, moved, 0.0))
                continue
            started = time.perf_counter()
            world.grasp(item.name, item.grasp, world.observe().poses[item.name])
            outcome: Outcome = "carried"
            if world.observe().held != item.name:
                outcome = "not grasped"
            else:
                world.put_down(item.name, item.place)
                seen = world.observe()
                pose = seen.poses.get(item.name)
                if (
                    seen.held is not None
                    or pose is None
                    or math.dist(pose.position[:2], item.place.position[:2]) > 0.01
                ):
                    outcome = "not placed"
            attempts.append(Attempt(item, outcome, None, moved, time.perf_counter() - started))
            if outcome != "carried":
                break  # the layout is no longer what it was: the rest is not tried
    finally:
        world.close()
    return attempts
