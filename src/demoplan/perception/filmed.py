"""A demonstration filmed from above, for tests, docs and examples: camera frames
of the blocks and of the teacher's hand moving them (the input of
:func:`demoplan.perception.sequence.demonstration_from_frames`).

Blocks are drawn by :func:`~demoplan.perception.synthetic.render_blocks`
(anti-aliased squares; a block standing higher drawn later, over the ones
under it). The hand is a large skin-coloured shape — an arm from the image's
top edge and a palm at its end, anti-aliased — and each step of the
demonstration is filmed as the hand reaching in to the block, covering it,
carrying it (the block under the palm, a corner showing), putting it down at
the step's pose and withdrawing out of view; ``still`` frames of the blocks
alone follow every move (and open the film). Shading and sensor noise are
added to every frame (a generator seeded by ``rng``): the frames are
deterministic.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from demoplan.model import Demonstration, ObjectGeometry, Pose, Step
from demoplan.perception.camera import Camera
from demoplan.perception.opencv import cv2
from demoplan.perception.synthetic import COLOURS, SyntheticBlock, render_blocks
from demoplan.rotations import quat_from_yaw

__all__ = ["SKIN", "FilmSettings", "random_demonstration", "render_demonstration", "render_hand"]

SKIN = (214, 150, 118)
"""The hand's colour (RGB): skin, well apart from the table's chroma."""


@dataclass(frozen=True, slots=True)
class FilmSettings:
    """How a demonstration is filmed: the image size, frames per stretch of a
    move (reaching in, carrying, withdrawing), still frames after each move and
    at the start, the hand's size (m), sensor noise (grey levels) and shading."""

    width: int = 500
    height: int = 400
    move_frames: int = 4
    still_frames: int = 3
    palm_radius: float = 0.045
    arm_width: float = 0.07
    noise: float = 3.0
    shading: float = 0.15
    supersample: int = 16
    """Samples per pixel on a side: at 4 (16 samples) a block's edge lies on a
    quarter-pixel grid, and a block turned by less than a degree is measured
    up to 0.15° off; at 16 the renderer's steps are below the detector's."""


def render_hand(
    image: np.ndarray, camera: Camera, palm: tuple[float, float], settings: FilmSettings
) -> None:
    """Draw the hand (arm from above the image's top edge to ``palm``, world x y)
    over ``image`` (float RGB, in place), anti-aliased (8× supersampled edges)."""
    height, width = image.shape[:2]
    scale = 8  # cv2's fixed-point shift: 3 bits of sub-pixel position
    u, v = camera.to_pixels(*palm)
    row = height - v
    radius = settings.palm_radius * camera.px_per_m
    half_arm = settings.arm_width * camera.px_per_m / 2
    mask = np.zeros((height, width), dtype=np.uint8)
    arm = np.array(
        [[u - half_arm, row], [u + half_arm, row], [u + half_arm, -50], [u - half_arm, -50]]
    )
    cv2.fillPoly(mask, [np.rint(arm * scale).astype(np.int32)], 255, cv2.LINE_AA, shift=3)
    cv2.circle(
        mask,
        (round(u * scale), round(row * scale)),
        round(radius * scale),
        255,
        -1,
        cv2.LINE_AA,
        shift=3,
    )
    alpha = mask.astype(float)[..., None] / 255.0
    image[:] = image * (1 - alpha) + np.asarray(SKIN, dtype=float) * alpha


def _frame(
    blocks: Sequence[SyntheticBlock],
    camera: Camera,
    palm: tuple[float, float] | None,
    settings: FilmSettings,
    generator: np.random.Generator,
) -> np.ndarray:
    clean = render_blocks(
        blocks,
        camera,
        settings.width,
        settings.height,
        noise=0.0,
        shading=0.0,
        supersample=settings.supersample,
        rng=0,  # each block's tint drawn alike in every frame
    )
    image = clean.astype(float)
    if palm is not None:
        render_hand(image, camera, palm, settings)
    if settings.shading:
        ramp = 1.0 - settings.shading * (
            np.linspace(0, 1, settings.width)[None, :] * 0.6
            + np.linspace(0, 1, settings.height)[:, None] * 0.4
        )
        image *= ramp[..., None]
    if settings.noise:
        image += generator.normal(0.0, settings.noise, image.shape)
    frame: np.ndarray = np.clip(np.rint(image), 0, 255).astype(np.uint8)
    return frame


def _path(
    start: tuple[float, float], end: tuple[float, float], count: int
) -> list[tuple[float, float]]:
    """``count`` points evenly along ``start`` → ``end``, ``end`` the last (``start`` not)."""
    return [
        (start[0] + (end[0] - start[0]) * k / count, start[1] + (end[1] - start[1]) * k / count)
        for k in range(1, count + 1)
    ]


def render_demonstration(
    demo: Demonstration,
    camera: Camera,
    settings: FilmSettings = FilmSettings(),
    *,
    rng: int = 0,
) -> list[np.ndarray]:
    """The frames (RGB ``uint8``) of ``demo`` filmed from above by ``camera``:
    every moved object must have an initial pose and be a colour of
    :data:`~demoplan.perception.synthetic.COLOURS` (its type, else its name
    without a trailing number) and a box (its x extent is the side)."""
    generator = np.random.default_rng(rng)
    geometry = demo.geometry()
    types = dict(demo.types)
    poses: dict[str, tuple[float, float, float, float]] = {}  # x, y, z, yaw
    order: list[str] = []  # drawing order: the last put down is drawn last
    for name, pose in demo.initial:
        x, y, z = pose.position
        poses[name] = (x, y, z, 0.0 if pose.rpy is None else pose.rpy[2])
        order.append(name)
    missing = [n for n in demo.moved_objects if n not in poses or n not in geometry]
    if missing:
        raise ValueError(f"{', '.join(missing)}: an initial pose and a size needed to film")

    def colour(name: str) -> str:
        return types.get(name, name.rstrip("0123456789"))

    def scene(
        held: str | None = None, at: tuple[float, float] | None = None
    ) -> list[SyntheticBlock]:
        shown = sorted(order, key=lambda n: poses[n][2])
        blocks = [
            SyntheticBlock(colour(n), *poses[n][:2], poses[n][3], geometry[n].size[0])
            for n in shown
            if n != held
        ]
        if held is not None and at is not None:  # under the palm, a corner showing
            side = geometry[held].size[0]
            lower = (at[0] + 0.3 * side, at[1] - settings.palm_radius + 0.2 * side)
            blocks.append(SyntheticBlock(colour(held), *lower, poses[held][3], side))
        return blocks

    outside = camera.to_world(0.0, settings.height + 60.0 + settings.palm_radius * camera.px_per_m)
    frames = [
        _frame(scene(), camera, None, settings, generator) for _ in range(settings.still_frames)
    ]
    n = settings.move_frames
    for step in demo.steps:
        x0, y0 = poses[step.object][:2]
        x1, y1, z1 = step.pose.position
        yaw = 0.0 if step.pose.rpy is None else step.pose.rpy[2]
        for palm in _path((x0, outside[1]), (x0, y0), n):  # reaching in
            frames.append(_frame(scene(), camera, palm, settings, generator))
        for palm in _path((x0, y0), (x1, y1), n):  # carrying
            frames.append(_frame(scene(step.object, palm), camera, palm, settings, generator))
        poses[step.object] = (x1, y1, z1, yaw)
        order.remove(step.object)
        order.append(step.object)
        for palm in _path((x1, y1), (x1, outside[1]), n):  # withdrawing
            frames.append(_frame(scene(), camera, palm, settings, generator))
        frames += [
            _frame(scene(), camera, None, settings, generator) for _ in range(settings.still_frames)
        ]
    return frames


def random_demonstration(
    seed: int,
    count: int,
    moves: int,
    side: float = 0.04,
    area: tuple[tuple[float, float], tuple[float, float]] = ((0.06, 0.36), (0.06, 0.26)),
) -> Demonstration:
    """``count`` blocks (at most 5) of distinct colours of ``side`` at random
    poses, centres within ``area`` (x range, y range; m), then ``moves`` moves
    of a block with nothing on it: to a free spot on the table, or (half the
    time) squarely onto another top block (within 5 mm, turned by up to 3°).
    Seeded by ``seed``: the same demonstration every time."""
    rng = np.random.default_rng(seed)
    poses: dict[str, tuple[float, float, float, float]] = {}
    names = [str(c) for c in rng.permutation(list(COLOURS))[:count]]

    def free(x: float, y: float, ignore: str) -> bool:
        return all(
            math.dist((x, y), p[:2]) > side * math.sqrt(2) + 0.006
            for n, p in poses.items()
            if n != ignore
        )

    def spot(ignore: str) -> tuple[float, float] | None:
        for _ in range(200):
            x, y = float(rng.uniform(*area[0])), float(rng.uniform(*area[1]))
            if free(x, y, ignore):
                return x, y
        return None

    for name in names:
        place = spot(name)
        if place is None:
            raise ValueError(f"no room for {count} blocks in {area}")
        poses[name] = (*place, 0.0, float(rng.uniform(-45, 45)))
    initial = tuple((n, Pose((p[0], p[1], 0.0), quat_from_yaw(p[3]))) for n, p in poses.items())

    def on_top(name: str) -> bool:
        x, y, z, _ = poses[name]
        return not any(
            o != name and p[2] > z + 0.01 and math.dist(p[:2], (x, y)) < side
            for o, p in poses.items()
        )

    steps = []
    for _ in range(moves):
        movable = [n for n in names if on_top(n)]
        block = movable[int(rng.integers(len(movable)))]
        targets = [n for n in movable if n != block]
        if targets and rng.random() < 0.5:
            below = targets[int(rng.integers(len(targets)))]
            bx, by, bz, byaw = poses[below]
            offset = rng.uniform(-0.005, 0.005, 2)
            pose = (bx + offset[0], by + offset[1], bz + side, byaw + float(rng.uniform(-3, 3)))
        else:
            place = spot(block)
            if place is None:
                continue
            pose = (*place, 0.0, float(rng.uniform(-45, 45)))
        poses[block] = pose
        steps.append(Step(block, Pose(pose[:3], quat_from_yaw(pose[3]))))
    objects = tuple((n, ObjectGeometry("box", (side,) * 3)) for n in names)
    return Demonstration(f"generated-{seed}", tuple(steps), objects=objects, initial=initial)
